#!/usr/bin/env bash
# README command 1: set up (packages, build, data), then the main job on the embedded corpus:
# freeze partial pairs (paper Tab. 1 protocol) from CGAL's meshes, run every registered method,
# and write the report next to the paper's numbers. Outputs go to out/ (git-ignored).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
pairs="${REGBENCH_MAIN_PAIRS:-100}"
jobs="${REGBENCH_JOBS:-$(nproc)}"
bash "$root/scripts/setup.sh"
out="$root/out"
mkdir -p "$out"
bin="$root/build/app/regbench"
start=$(date +%s)
"$bin" generate --protocol partial --dataset cgal --split test --pairs "$pairs" --seed 1 \
  --out "$out/partial_cgal_test.h5"
"$bin" inspect "$out/partial_cgal_test.h5" > "$out/partial_cgal_test.inspect.txt"
"$bin" run --pairs "$out/partial_cgal_test.h5" --methods all --jobs "$jobs" \
  --out "$out/partial_cgal_test.jsonl"
"$bin" report "$out/partial_cgal_test.jsonl" --paper table1_modelnet_partial:same_category \
  --out "$out/partial_cgal_test.report.md"
"$bin" report "$out/partial_cgal_test.jsonl" --format csv --out "$out/partial_cgal_test.report.csv"
cat "$out/partial_cgal_test.report.md"
echo "[main_job] $pairs pairs, all methods, $(( $(date +%s) - start )) s; outputs in $out"

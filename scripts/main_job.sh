#!/usr/bin/env bash
# README command 1: set up (packages, build, data), then `regbench reproduce --quick`: every
# table of the OGMM paper on the data present (the embedded mesh corpus and the indoor
# simulation stand in for ModelNet40 / 7Scenes / ICL-NUIM, and every table says so), written
# into one folder (Markdown, LaTeX, CSV, JSON, HTML). A second invocation continues a killed one.
# REGBENCH_JOBS (default nproc) pairs run in parallel; REGBENCH_REPRODUCE_ARGS adds flags, e.g.
# "--modelnet40 /data/modelnet40_ply_hdf5_2048" or "--pairs 50". Builds only the regbench binary.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs="${REGBENCH_JOBS:-$(nproc)}"
# The main job needs the `regbench` binary only; tests and benchmarks are built by
# scripts/test.sh (about half of a cold build's compile time).
# Only the packages that build needs are installed (scripts/install_deps.sh --main).
REGBENCH_MAIN_ONLY=1 REGBENCH_BUILD_TARGETS="${REGBENCH_BUILD_TARGETS:-regbench}" \
  bash "$root/scripts/setup.sh"
out="$root/out/reproduce"
start=$(date +%s)
# shellcheck disable=SC2086
"$root/build/app/regbench" reproduce --quick --jobs "$jobs" --out "$out" \
  ${REGBENCH_REPRODUCE_ARGS:-}
head -n 40 "$out/tables.md"
echo "[main_job] reproduce --quick: $(( $(date +%s) - start )) s; report folder $out," \
  "HTML report $out/report.html"

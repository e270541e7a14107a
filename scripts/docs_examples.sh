#!/usr/bin/env bash
# Produces the output of every command block in README.md and docs/ that shows output, so the
# documentation can be regenerated instead of edited by hand, and checked (CTest docs_examples:
# scripts/check_docs_examples.py compares each documented block with a fresh transcript).
#
#   scripts/docs_examples.sh [--fast] [--build DIR] OUTDIR [NAME...]
#
# Each example runs in OUTDIR/work (so every path it prints is relative: out/...), and its
# transcript goes to OUTDIR/NAME.txt: each command as the documentation shows it ("$ regbench
# ..."), then what it printed (stdout and stderr). A documented block is tied to its example by
# the line `<!-- docs_examples: NAME -->` just above it.
#
# Examples (fast: seconds; slow: minutes, run when asked for by name or without --fast):
#   align       (fast) generate the embedded-corpus pairs, export pair 88 as PLY, align it
#   score       (fast) transforms of Open3D's Python ICP scored and reported beside icp
#   deepgmr_import (fast) DeepGMR stand-ins (scripts/deepgmr_standin.py): import, generate, run
#   versus      (fast) fgr against icp on the same pairs: report --versus
#   versus_python (fast) the same from Python: regbench.compare_methods
#   python_run  (slow) Open3D's Python ICP beside icp and cpd in one regbench.run
#   quick_run   (slow) the main job: reproduce --quick, its Tab. 1 and where the report is
#   estimate    (fast) a small reproduce --quick folder sized for a 32-task array
#               (scripts/estimate_full_run.py; docs/cluster.md)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
fast=0
build="$root/build"
while [ $# -gt 0 ]; do
  case "$1" in
  --fast) fast=1; shift ;;
  --build) build="$2"; shift 2 ;;
  *) break ;;
  esac
done
[ $# -ge 1 ] || { echo "usage: $0 [--fast] [--build DIR] OUTDIR [NAME...]" >&2; exit 2; }
outdir="$(mkdir -p "$1" && cd "$1" && pwd)"
shift
wanted=("$@")
if [ ${#wanted[@]} -eq 0 ]; then
  wanted=(align score deepgmr_import versus versus_python estimate)
  [ "$fast" = 1 ] || wanted+=(python_run quick_run)
fi
bin="$build/app/regbench"
[ -x "$bin" ] || { echo "$0: $bin not built" >&2; exit 1; }
work="$outdir/work"
rm -rf "$work"  # fresh: every example regenerates what it uses
mkdir -p "$work/out"
cd "$work"
transcript=""

# show 'DISPLAYED COMMAND': prints "$ DISPLAYED COMMAND" into the transcript, then runs it with
# `regbench` meaning the built binary; its output follows. A failing command fails the script.
show() {
  printf '$ %s\n' "$1" >>"$transcript"
  local cmd="${1//regbench /\"\$bin\" }"
  if ! (eval "$cmd") >>"$transcript" 2>&1; then
    echo "$0: command failed: $1 (transcript $transcript)" >&2
    tail -20 "$transcript" >&2
    exit 1
  fi
}
# quiet COMMAND: set-up a documented block does not show (not in the transcript).
quiet() {
  local cmd="${1//regbench /\"\$bin\" }"
  (eval "$cmd") >/dev/null 2>&1 || { echo "$0: set-up failed: $1" >&2; exit 1; }
}

pairs() {  # the embedded-corpus pairs most examples use (100 test pairs, partial, seed 1)
  [ -f out/partial_cgal_test.h5 ] || quiet "regbench generate --protocol partial --dataset cgal \
--split test --pairs 100 --seed 1 --out out/partial_cgal_test.h5"
}

example_align() {
  pairs
  rm -rf out/pairs_ply T.txt aligned.ply
  show "regbench export out/partial_cgal_test.h5 --out out/pairs_ply --format ply"
  show "regbench align out/pairs_ply/0088_src.ply out/pairs_ply/0088_tgt.ply --method icp \\
      --gt out/pairs_ply/0088_gt.txt --out T.txt --save-aligned aligned.ply"
}

example_score() {
  pairs
  rm -f out/partial_cgal_icp.jsonl out/py_icp* out/py_icp_scored.jsonl out/py_icp_csv_scored.jsonl
  show "regbench run --pairs out/partial_cgal_test.h5 --methods icp --out out/partial_cgal_icp.jsonl -q"
  show "PYTHONPATH=build/python /usr/bin/python3 scripts/example_open3d_icp.py \\
      out/partial_cgal_test.h5 --transforms out/py_icp"
  show "regbench score --pairs out/partial_cgal_test.h5 --transforms out/py_icp.jsonl \\
      --method open3d-py-icp --out out/py_icp_scored.jsonl"
  show "regbench score --pairs out/partial_cgal_test.h5 --transforms out/py_icp.csv \\
      --method open3d-py-icp-csv --out out/py_icp_csv_scored.jsonl"
  show "regbench report out/partial_cgal_icp.jsonl out/py_icp_scored.jsonl out/py_icp_csv_scored.jsonl"
}

example_deepgmr_import() {
  rm -rf ck/deepgmr-noisy noisy.h5 noisy.jsonl
  quiet "/usr/bin/python3 scripts/deepgmr_standin.py ."
  show "regbench import-checkpoint modelnet_noisy.pth --from deepgmr --out ck/deepgmr-noisy"
  show "regbench generate --dataset modelnet_noisy.h5 --pairing stored --pairs all --out noisy.h5"
  show "regbench run --pairs noisy.h5 --methods deepgmr-noicp --params '{\"deepgmr-noicp\": \
{\"checkpoint\": \"ck/deepgmr-noisy\"}}' --out noisy.jsonl -q"
  show "regbench report noisy.jsonl"
}

versus_rows() {  # icp and fgr on the embedded-corpus pairs
  pairs
  [ -f out/icp_fgr.jsonl ] || quiet "regbench run --pairs out/partial_cgal_test.h5 --methods icp,fgr \
--out out/icp_fgr.jsonl -q"
}

example_versus() {
  versus_rows
  show "regbench report out/icp_fgr.jsonl --versus fgr,icp"
}

example_versus_python() {
  versus_rows
  show "PYTHONPATH=build/python /usr/bin/python3 -c '
import regbench
(r,) = regbench.compare_methods(\"out/icp_fgr.jsonl\", \"fgr\", \"icp\")
for m in r[\"metrics\"]:
    print(m[\"metric\"], round(m[\"diff_mean\"], 4), [round(m[\"ci_lo\"], 4), round(m[\"ci_hi\"], 4)],
          \"p=%.2g\" % m[\"p_value\"], m[\"wins\"], m[\"ties\"], m[\"losses\"])'"
}

example_python_run() {
  pairs
  rm -f out/py_icp_run.jsonl
  show "PYTHONPATH=build/python /usr/bin/python3 scripts/example_open3d_icp.py \\
      out/partial_cgal_test.h5 out/py_icp_run.jsonl"
}

example_quick_run() {
  rm -rf out/reproduce out/reproduce.lock
  show "regbench reproduce --quick --jobs 2 --out out/reproduce"
  show "sed -n '/^### Tab. 1/,/^### Tab. 2/p' out/reproduce/tables.md | head -n 16"
}

example_estimate() {
  rm -rf out/qsmall out/qsmall.lock
  quiet "regbench reproduce --quick --tables table1 --pairs 4 --methods identity,icp,ogmm \
--out out/qsmall"
  show "/usr/bin/python3 scripts/estimate_full_run.py out/qsmall --tasks 32 --cores 1"
}

# The examples call scripts/ and build/python by relative path, as the documentation shows them.
ln -sfn "$root/scripts" scripts
ln -sfn "$build" build
for name in "${wanted[@]}"; do
  if ! declare -F "example_$name" >/dev/null; then
    echo "$0: no example '$name'" >&2
    exit 2
  fi
  transcript="$outdir/$name.txt"
  : >"$transcript"
  start=$(date +%s)
  "example_$name"
  echo "[docs_examples] $name: $(( $(date +%s) - start )) s -> $transcript"
done

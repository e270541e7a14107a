#!/usr/bin/env bash
# Held-out evaluation of the learned checkpoints against ICP (docs/learned-methods.md, README):
# 200 pairs per set from the embedded corpus's *test* split (training uses `train`, validation
# `val`), seed 7: `partial` with independent and with shared pairing, and `jitter` (partial
# with noise). Rows, one report per set and a summary table land in OUT.
# Usage: scripts/eval_learned.sh OUT [PAIRS] [more `run` arguments, e.g. --params JSON]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="${REGBENCH_BIN:-$root/build/app/regbench}"
out="${1:?usage: scripts/eval_learned.sh OUT [PAIRS] [run arguments]}"
pairs="${2:-200}"
shift $(( $# < 2 ? $# : 2 ))
mkdir -p "$out"
# rgm takes about 2 s a pair (its four-match pipeline): most of the script's time.
methods=identity,icp,deepgmr,deepgmr-noicp,ogmm,ogmm-noicp,omnet,rienet,rgm,regtr
for set in partial:independent partial:shared jitter:independent; do
    protocol="${set%%:*}" pairing="${set##*:}"
    name="${protocol}_${pairing}"
    file="$out/$name.h5"
    [[ -f "$file" ]] || "$bin" generate --protocol "$protocol" --dataset cgal --split test \
        --pairs "$pairs" --seed 7 --pairing "$pairing" --out "$file"
    "$bin" run --pairs "$file" --methods "$methods" --jobs "${REGBENCH_JOBS:-2}" --force \
        --out "$out/$name.jsonl" "$@"
    "$bin" report "$out/$name.jsonl" --out "$out/$name.md"
    echo "== $name: $out/$name.md"
done

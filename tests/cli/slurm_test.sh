#!/usr/bin/env bash
# Stands up a real single-node Slurm (slurm_cluster.sh: slurmctld + slurmd + munge on loopback,
# private ports, everything under a temporary directory), submits
# scripts/slurm/regbench-array.sbatch with its defaults for a small benchmark (4 array tasks +
# the afterok merge job), waits, and checks that the merged result equals a single-process run
# at `run --timeout 120`, the script's default and reproduce's (timing fields aside). Stops
# every daemon it started.
# Usage: slurm_test.sh REGBENCH SOURCE_DIR. Exit 77 (CTest: skipped) with the reason printed
# when the Slurm/munge packages are absent or the test is not run as root (slurmd needs root).
set -uo pipefail
bin="$1"
src="$2"
# shellcheck source=tests/cli/slurm_cluster.sh
source "$(dirname "${BASH_SOURCE[0]}")/slurm_cluster.sh"

cd "$B/out"
"$bin" generate --protocol partial --dataset procedural --split test --pairs 8 --seed 1 \
  --out "$B/out/pairs.h5" >/dev/null 2>&1 || fail "generate"
ids="$(PAIRS="$B/out/pairs.h5" METHODS=identity,icp OUT="$B/out/res" SHARDS=4 REGBENCH="$bin" \
  bash "$src/scripts/slurm/regbench-array.sbatch")" || fail "submission failed: $ids"
merge_id="$(echo "$ids" | awk '/^merge/ {print $2}')"
[ -n "$merge_id" ] || fail "no merge job id in: $ids"
state="$(wait_job "$merge_id" 300)"
[ "$state" = COMPLETED ] || fail "merge job $merge_id ended in state '$state'"

"$bin" run --pairs "$B/out/pairs.h5" --methods identity,icp --out "$B/out/single.jsonl" -q \
  --timeout 120 2>/dev/null || fail "single-process run"
strip() { sed -E 's/"(cpu_)?seconds":[^,]*,//g; s/"machine":\{([^{}]|\{[^{}]*\})*\},?//g' "$1"; }
diff <(strip "$B/out/single.jsonl") <(strip "$B/out/res/merged.jsonl") >/dev/null ||
  fail "merged result differs from the single-process run"
[ "$(wc -l <"$B/out/res/merged.jsonl")" -eq 16 ] || fail "merged result is not 16 rows"
echo "ok: 4 Slurm array tasks + afterok merge = single-process run (16 rows)"

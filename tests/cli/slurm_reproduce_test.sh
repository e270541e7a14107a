#!/usr/bin/env bash
# `regbench reproduce` on a real single-node Slurm (slurm_cluster.sh): submits
# scripts/slurm/regbench-reproduce.sbatch for a quick plan of four tables (Tab. 1's two
# experiments, Tab. 4's shipped ablation checkpoints, Tab. 6's timing row and the overlap sweep,
# so result files of experiments, variants, timing variants and a sweep all go through the
# shards; 4 pairs each, 10 in the sweep, 3 methods) in 4 array tasks between the prepare and the
# afterok render job, waits, and checks that the tables and result rows equal a one-machine run
# of the same plan, timing aside (compare_reports.py); then loses one shard's file and checks
# that the same command again redoes those calls only.
# Usage: slurm_reproduce_test.sh REGBENCH SOURCE_DIR. Exit 77 (CTest: skipped) with the reason
# printed when the Slurm/munge packages are absent or the test is not run as root.
set -uo pipefail
bin="$1"
src="$2"
# shellcheck source=tests/cli/slurm_cluster.sh
source "$(dirname "${BASH_SOURCE[0]}")/slurm_cluster.sh"

start=$(date +%s)
cd "$B/out" || fail "no $B/out"
args=(--quick --tables table1,table4,table6,supp_overlap --pairs 4 --methods identity,icp,ogmm)
ids="$(OUT="$B/out/rep" SHARDS=4 REGBENCH="$bin" \
  bash "$src/scripts/slurm/regbench-reproduce.sbatch" "${args[@]}")" ||
  fail "submission failed: $ids"
render_id="$(echo "$ids" | awk '/^render/ {print $2}')"
[ -n "$render_id" ] || fail "no render job id in: $ids"
# The one-machine run while the scheduler works (the node has as many cores as the machine).
"$bin" reproduce "${args[@]}" --out "$B/out/one" >/dev/null 2>"$B/out/one.log" ||
  fail "one-machine run: $(tail -5 "$B/out/one.log")"
state="$(wait_job "$render_id" 420)"
[ "$state" = COMPLETED ] || fail "render job $render_id ended in state '$state'"
for i in 0 1 2 3; do
  [ -f "$B/out/rep/shards/$i-of-4/tab1_same.jsonl" ] || fail "array task $i wrote no shard"
done
python3 "$src/tests/cli/compare_reports.py" "$B/out/one" "$B/out/rep" ||
  fail "the Slurm run's tables differ from the one-machine run's"

# A task that lost its work (here shard 2's Tab. 1 same-category rows: pair 2, 3 methods) is
# redone by the same command again, and nothing else is.
rm "$B/out/rep/shards/2-of-4/tab1_same.jsonl"
ids="$(OUT="$B/out/rep" SHARDS=4 REGBENCH="$bin" \
  bash "$src/scripts/slurm/regbench-reproduce.sbatch" "${args[@]}")" ||
  fail "resubmission failed: $ids"
render_id="$(echo "$ids" | awk '/^render/ {print $2}')"
state="$(wait_job "$render_id" 300)"
[ "$state" = COMPLETED ] || fail "resubmitted render job $render_id ended in state '$state'"
logs="$B/out/rep/slurm-logs"
grep -q "^reproduce --prepare: 0 pair files generated" "$logs/prepare.log" ||
  fail "the resubmitted prepare generated pairs"
grep -q ": 3 calls run into" "$logs/shard-2.log" || fail "shard 2 did not redo exactly its 3 calls"
for i in 0 1 3; do
  grep -q ": 0 calls run into" "$logs/shard-$i.log" || fail "shard $i redid calls"
done
python3 "$src/tests/cli/compare_reports.py" "$B/out/one" "$B/out/rep" ||
  fail "the resubmitted run's tables differ from the one-machine run's"
echo "ok: prepare + 4 Slurm array tasks + afterok render = one-machine run; the same command" \
  "again redid only a lost shard file ($(($(date +%s) - start)) s)"

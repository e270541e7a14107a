#!/usr/bin/env bash
# `reproduce --prepare / --shard i/n / --render` (experiments/reproduce_steps.hpp) as plain
# processes sharing one folder, as several machines would, without Slurm.
# Usage: reproduce_shards.sh REGBENCH SOURCE_DIR SCENARIO
#   steps           prepare, 3 concurrent shards, render: tables and results equal to a
#                   one-machine run's (timing aside); a rerun shard or prepare redoes nothing,
#                   a shard that lost rows runs only those
#   refusals        bad --shard (exit 2), steps out of order or with other options, render of
#                   missing, doubled or mixed shards: each refused naming the cause or the rows
#   array_defaults  scripts/slurm/regbench-array.sbatch's shard and merge steps with their
#                   default settings produce rows a `reproduce` folder resumes as its own
set -uo pipefail
bin="$1"
src="$2"
scenario="$3"
T="$(mktemp -d /tmp/regbench_shards_XXXXXX)"
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
# Runs regbench, stderr to $T/err; the exit status is kept.
rb() { "$bin" "$@" 2>"$T/err" >"$T/outp"; }
expect_fail() {  # CODE PATTERN ARGS...: exits with CODE and says PATTERN on stderr
  local code="$1" pattern="$2"
  shift 2
  rb "$@"
  local got=$?
  [ "$got" -eq "$code" ] || fail "regbench $* exited $got, not $code: $(cat "$T/err")"
  grep -qF -- "$pattern" "$T/err" || fail "regbench $* did not say '$pattern': $(cat "$T/err")"
}
cd "$T" || exit 1

case "$scenario" in
steps)
  args=(--quick --tables table1 --pairs 4 --methods identity,icp)
  rb reproduce "${args[@]}" --out one || fail "one-machine run: $(cat "$T/err")"
  rb reproduce "${args[@]}" --out shared --prepare || fail "prepare: $(cat "$T/err")"
  [ -f shared/pairs/tab1_same.h5 ] && [ -f shared/pairs/tab1_cross.h5 ] && [ -f shared/shards/plan.json ] ||
    fail "prepare wrote no pair files or plan record: $(ls -R shared)"
  [ ! -e shared/tables.md ] && [ -z "$(ls shared/results)" ] || fail "prepare ran calls or rendered"
  rb reproduce "${args[@]}" --out shared --prepare || fail "second prepare: $(cat "$T/err")"
  grep -q "0 pair files generated" "$T/err" || fail "a second prepare generated pairs: $(cat "$T/err")"
  # Three "machines" at once on the shared folder.
  pids=()
  for i in 0 1 2; do
    "$bin" reproduce "${args[@]}" --out shared --shard "$i/3" >"shard$i.out" 2>"shard$i.err" &
    pids+=($!)
  done
  for i in 0 1 2; do wait "${pids[$i]}" || fail "shard $i/3: $(cat "shard$i.err")"; done
  grep -q "^shard results: .*/shared/shards/1-of-3$" shard1.out || fail "shard 1 said: $(cat shard1.out)"
  [ ! -e shared/tables.md ] || fail "a shard rendered the tables"
  # A rerun shard redoes nothing; one that lost rows runs only those.
  rb reproduce "${args[@]}" --out shared --shard 1/3 || fail "rerun shard: $(cat "$T/err")"
  grep -q ": 0 calls run into" "$T/err" || fail "a rerun shard ran calls again: $(cat "$T/err")"
  f=shared/shards/0-of-3/tab1_same.jsonl  # pairs 0 and 3, two methods: 4 rows
  [ "$(wc -l <"$f")" -eq 4 ] || fail "$f has $(wc -l <"$f") rows, not 4"
  head -1 "$f" >"$T/keep" && cp "$T/keep" "$f"
  rb reproduce "${args[@]}" --out shared --shard 0/3 || fail "resumed shard: $(cat "$T/err")"
  grep -q ": 3 calls run into" "$T/err" || fail "the resumed shard did not run exactly 3 calls: $(cat "$T/err")"
  rb reproduce "${args[@]}" --out shared --render || fail "render: $(cat "$T/err")"
  grep -q "^tables: .*/shared/tables.md$" "$T/outp" || fail "render printed: $(cat "$T/outp")"
  grep -q "0 calls run" "$T/err" || fail "render ran calls: $(cat "$T/err")"
  python3 "$src/tests/cli/compare_reports.py" one shared || fail "tables differ"
  echo "ok: prepare + 3 concurrent shards + render = one-machine run; reruns redo nothing"
  ;;
refusals)
  args=(--quick --tables table1 --pairs 2 --methods identity)
  for bad in 5/4 0/0 4/4 -1/2 1/ /2 abc 1/2x " 1/2"; do
    expect_fail 2 "--shard must be i/n" reproduce "${args[@]}" --out r --shard "$bad"
  done
  expect_fail 2 "excludes" reproduce "${args[@]}" --out r --prepare --render
  expect_fail 2 "excludes" reproduce "${args[@]}" --out r --shard 0/2 --render
  expect_fail 1 "is not prepared for shards" reproduce "${args[@]}" --out r --shard 0/2
  expect_fail 1 "is not prepared for shards" reproduce "${args[@]}" --out r --render
  rb reproduce "${args[@]}" --out r --prepare || fail "prepare: $(cat "$T/err")"
  expect_fail 1 "prepared with --pairs 2, this --shard step has 3" \
    reproduce --quick --tables table1 --pairs 3 --methods identity --out r --shard 0/2
  expect_fail 1 "prepared with --timeout 120.0, this --shard step has 60.0" \
    reproduce "${args[@]}" --timeout 60 --out r --shard 0/2
  expect_fail 1 "prepared with --methods" \
    reproduce --quick --tables table1 --pairs 2 --methods icp --out r --prepare
  expect_fail 1 "no shard results" reproduce "${args[@]}" --out r --render
  # Shard 1 of 2 never ran: every file names its missing rows (pair 1) and the shard.
  rb reproduce "${args[@]}" --out r --shard 0/2 || fail "shard 0/2: $(cat "$T/err")"
  expect_fail 1 "2 result file(s) do not merge" reproduce "${args[@]}" --out r --render
  grep -qF "tab1_same: " "$T/err" && grep -qF "tab1_cross: " "$T/err" ||
    fail "render did not name both files: $(cat "$T/err")"
  grep -qF "1 of 2 rows missing (pair 1 identity)" "$T/err" || fail "rows not named: $(cat "$T/err")"
  grep -qF "1-of-2 never ran" "$T/err" || fail "the missing shard not named: $(cat "$T/err")"
  [ ! -e r/tables.md ] || fail "an incomplete render wrote tables.md"
  # A row doubled into the other shard's file.
  rb reproduce "${args[@]}" --out r --shard 1/2 || fail "shard 1/2: $(cat "$T/err")"
  cat r/shards/0-of-2/tab1_same.jsonl >>r/shards/1-of-2/tab1_same.jsonl
  expect_fail 1 "duplicate row for pair 0, method 'identity'" reproduce "${args[@]}" --out r --render
  grep -qF "1 result file(s) do not merge" "$T/err" || fail "not one file: $(cat "$T/err")"
  # The shard refuses to resume a file holding another shard's rows; without it, it redoes it.
  rb reproduce "${args[@]}" --out r --shard 1/2 && fail "shard 1/2 resumed another shard's rows"
  rm r/shards/1-of-2/tab1_same.jsonl
  rb reproduce "${args[@]}" --out r --shard 1/2 || fail "shard 1/2 redone: $(cat "$T/err")"
  grep -q ": 1 calls run into" "$T/err" || fail "shard 1/2 did not redo just its 1 call: $(cat "$T/err")"
  # A shard folder of another count.
  mkdir r/shards/0-of-3
  expect_fail 1 "holds shards of several counts" reproduce "${args[@]}" --out r --render
  rmdir r/shards/0-of-3
  rb reproduce "${args[@]}" --out r --render || fail "final render: $(cat "$T/err")"
  [ -f r/tables.md ] || fail "the final render wrote no tables.md"
  echo "ok: bad --shard exit 2; unprepared, mismatched, incomplete, doubled, mixed refused"
  ;;
array_defaults)
  # The array script's shard and merge steps as Slurm would start them, TIMEOUT left unset.
  args=(--quick --tables table1 --pairs 3 --methods identity,icp)
  rb reproduce "${args[@]}" --out r --prepare || fail "prepare: $(cat "$T/err")"
  for id in tab1_same tab1_cross; do
    mkdir "a_$id"  # the script's submission step makes OUT
    for i in 0 1; do
      env -u TIMEOUT SLURM_JOB_ID=1 SLURM_ARRAY_TASK_ID=$i REGBENCH_STEP=shard \
        PAIRS="r/pairs/$id.h5" METHODS=identity,icp OUT="a_$id" SHARDS=2 REGBENCH="$bin" \
        bash "$src/scripts/slurm/regbench-array.sbatch" 2>"$T/err" ||
        fail "array shard $i of $id: $(cat "$T/err")"
    done
    env -u TIMEOUT SLURM_JOB_ID=2 REGBENCH_STEP=merge PAIRS="r/pairs/$id.h5" METHODS=identity,icp \
      OUT="a_$id" SHARDS=2 REGBENCH="$bin" bash "$src/scripts/slurm/regbench-array.sbatch" \
      2>"$T/err" || fail "array merge of $id: $(cat "$T/err")"
    cp "a_$id/merged.jsonl" "r/results/$id.jsonl"
  done
  # reproduce resumes only rows of its own settings (--timeout 120 by default): every merged
  # row must be kept, no call redone.
  rb reproduce "${args[@]}" --out r ||
    fail "reproduce refused the array's rows (its defaults disagree): $(cat "$T/err")"
  grep -q "(0 pair files generated, 0 calls run)" "$T/err" ||
    fail "reproduce redid calls of the array's rows: $(cat "$T/err")"
  echo "ok: the array script's default rows resume in reproduce as they are"
  ;;
*)
  fail "unknown scenario '$scenario'"
  ;;
esac

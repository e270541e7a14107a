#!/usr/bin/env bash
# CLI reliability scenarios (CTest runs one per test): tests/cli/reliability.sh REGBENCH SCENARIO
#   concurrent  two runs on one --out: the second is refused naming the first's pid, the
#               first's result is complete
#   fsize       a file-size limit (RLIMIT_FSIZE, SIGXFSZ ignored) during generate, import,
#               run and export: non-zero exit without a signal, nothing at the final path
#   sigint      Ctrl-C prints the safe rows and the resume command; running that command
#               gives the same rows as an uninterrupted run
#   orphans     kill -9 of a run with --timeout leaves no forked worker alive (by pid)
#   outputs     --out equal to the input, a directory or /dev/null is refused; export into
#               a non-empty folder is refused
set -uo pipefail
bin="$1"
scenario="$2"
work="$(mktemp -d "${TMPDIR:-/tmp}/regbench_cli_${scenario}_XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
fail() { echo "FAIL [$scenario]: $*" >&2; exit 1; }

# A small frozen benchmark from the built-in procedural shapes (no data files needed).
"$bin" generate --protocol partial --dataset procedural --split test --pairs 8 --seed 1 \
  --out pairs.h5 >/dev/null 2>&1 || fail "generate"
# CPD with many iterations and tol 0: slow enough (~1 s per call) to be interrupted reliably.
slow='{"cpd": {"maxiter": 250, "tol": 0}}'

wait_for_rows() {  # wait_for_rows FILE N: until FILE has N lines (max ~120 s)
  for _ in $(seq 1 1200); do
    [ -f "$1" ] && [ "$(wc -l <"$1")" -ge "$2" ] && return 0
    sleep 0.1
  done
  fail "no $2 rows in $1"
}

case "$scenario" in
concurrent)
  "$bin" run --pairs pairs.h5 --methods cpd --params "$slow" --out r.jsonl -q 2>first.err &
  first=$!
  wait_for_rows r.jsonl.part 1
  # Freeze the first run while the second tries, so a fast machine cannot let the first
  # finish (and release its lock) before the second starts.
  kill -STOP "$first" 2>/dev/null || fail "first run ended before the check could start"
  if "$bin" run --pairs pairs.h5 --methods identity --out r.jsonl -q 2>second.err; then
    kill -CONT "$first"
    fail "second writer was not refused: $(cat second.err)"
  fi
  kill -CONT "$first"
  grep -q "pid $first" second.err || fail "refusal does not name pid $first: $(cat second.err)"
  wait "$first" || fail "first run failed: $(cat first.err)"
  [ "$(wc -l <r.jsonl)" -eq 8 ] || fail "first run's result has $(wc -l <r.jsonl) rows, not 8"
  grep -c '"method":"cpd"' r.jsonl | grep -qx 8 || fail "result mixed with the second run"
  ;;
fsize)
  check_limited() {  # check_limited NAME FINAL_PATH KB CMD...: run CMD under a KB file limit
    local name="$1" final="$2" kb="$3"
    shift 3
    (trap '' XFSZ; ulimit -f "$kb"; "$@") >"$name.out" 2>&1
    local rc=$?
    [ "$rc" -ne 0 ] || fail "$name: exit 0 under a file-size limit"
    [ "$rc" -lt 128 ] || fail "$name: died by signal $((rc - 128))"
    [ ! -e "$final" ] || fail "$name: $final exists after a failed write"
    grep -q "$final" "$name.out" || fail "$name: message does not name $final: $(cat "$name.out")"
  }
  check_limited generate big.h5 64 "$bin" generate --protocol partial --dataset procedural \
    --split test --pairs 40 --seed 1 --out big.h5
  "$bin" export pairs.h5 --out xyz >/dev/null 2>&1 || fail "export"
  check_limited import imported.h5 64 "$bin" import --xyz-dir xyz --out imported.h5
  check_limited run r.jsonl 4 "$bin" run --pairs pairs.h5 --methods identity,icp --out r.jsonl -q
  check_limited export exported 16 "$bin" export pairs.h5 --out exported
  if ls -a | grep -q '\.tmp\.'; then fail "temporary files left: $(ls -a)"; fi
  ;;
sigint)
  "$bin" run --pairs pairs.h5 --methods cpd --params "$slow" --out full.jsonl -q 2>/dev/null \
    || fail "uninterrupted run"
  "$bin" run --pairs pairs.h5 --methods cpd --params "$slow" --out r.jsonl -q 2>int.err &
  pid=$!
  wait_for_rows r.jsonl.part 2
  kill -INT "$pid"
  wait "$pid"
  rc=$?
  [ "$rc" -eq 130 ] || fail "exit status $rc after SIGINT, expected 130 (killed by SIGINT)"
  grep -q "rows are safe in r.jsonl.part" int.err || fail "no safe-rows line: $(cat int.err)"
  cmd="$(sed -n 's/^resume with: regbench //p' int.err)"
  [ -n "$cmd" ] || fail "no resume command: $(cat int.err)"
  eval "\"$bin\" $cmd -q" 2>resume.err || fail "resume command failed: $(cat resume.err)"
  # Same rows as the uninterrupted run, timing aside (CPD is deterministic).
  strip() { sed -E 's/"(cpu_)?seconds":[^,]*,//g; s/"machine":\{[^}]*\},?//g' "$1"; }
  diff <(strip full.jsonl) <(strip r.jsonl) >/dev/null || fail "resumed result differs"
  ;;
orphans)
  # One call lasts minutes (100,000 iterations): without PR_SET_PDEATHSIG it would outlive the
  # 5 s this check waits.
  "$bin" run --pairs pairs.h5 --methods cpd --params '{"cpd": {"maxiter": 100000, "tol": 0}}' \
    --timeout 600 --out r.jsonl -q 2>/dev/null &
  pid=$!
  child=""
  for _ in $(seq 1 600); do
    child="$(cat /proc/"$pid"/task/*/children 2>/dev/null | tr ' ' '\n' | grep -v '^$' | head -1)"
    [ -n "$child" ] && break
    sleep 0.1
  done
  [ -n "$child" ] || fail "no forked worker seen"
  kill -9 "$pid"
  wait "$pid" 2>/dev/null
  for _ in $(seq 1 50); do
    state="$(awk '{print $3}' /proc/"$child"/stat 2>/dev/null)"
    if [ -z "$state" ] || [ "$state" = Z ]; then echo "ok [$scenario]"; exit 0; fi
    sleep 0.1
  done
  fail "worker $child still alive (state $state) after its parent was killed"
  ;;
outputs)
  cp pairs.h5 before.h5
  "$bin" run --pairs pairs.h5 --methods identity --out pairs.h5 -q 2>e1 && fail "--out = --pairs"
  grep -q "same file as the input" e1 || fail "message: $(cat e1)"
  cmp -s pairs.h5 before.h5 || fail "pair file changed"
  mkdir d
  "$bin" run --pairs pairs.h5 --methods identity --out d -q 2>e2 && fail "--out DIR accepted"
  grep -q "is a directory" e2 || fail "message: $(cat e2)"
  [ -z "$(ls -A d)" ] && [ ! -e d.part ] || fail "debris next to the directory"
  "$bin" generate --protocol partial --dataset procedural --split test --pairs 2 --seed 1 \
    --out /dev/null 2>e3 && fail "--out /dev/null accepted"
  [ -c /dev/null ] || fail "/dev/null replaced"
  "$bin" export pairs.h5 --out xyz 2>/dev/null || fail "export"
  "$bin" export pairs.h5 --out xyz 2>e4 && fail "export into a non-empty folder accepted"
  grep -q "not empty" e4 || fail "message: $(cat e4)"
  ;;
*)
  fail "unknown scenario"
  ;;
esac
echo "ok [$scenario]"

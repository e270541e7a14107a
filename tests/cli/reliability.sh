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
#   links       a symbolic or hard link pre-placed at OUT.lock or OUT.part is refused naming
#               the path, and the file it points to keeps its bytes
#   writers     compare --json, import, score, merge, report and generate --out onto an input
#               are refused and the input keeps its bytes; score, report --out, generate,
#               compare --json, merge, export, import, reproduce and train beside a running
#               `run` on the same path are refused naming its pid
#   xfsz        a file-size limit without the caller ignoring SIGXFSZ: every writer ends with
#               a message naming the file, no signal, nothing at the final path, no temporary
#   usage       numeric flags that would switch a check off (NaN, negative, zero) and unknown
#               metric names: exit 2 and one line naming the flag and the value
#   hostile     JSON nested 1M levels deep (compare), coordinates of 1e30 (align gicp):
#               refused naming the file, never a signal; NaN points of a PLY dropped with a
#               count, or refused with --nan-points refuse; train --config nested 1M deep or
#               not an object refused naming the file
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

# limited XFSZ NAME FINAL KB CMD...: CMD under a file-size limit of KB kilobytes must fail
# cleanly: non-zero exit, no signal, nothing at FINAL, a message naming FINAL (in NAME.out).
# XFSZ: ignore-xfsz (the caller ignores SIGXFSZ first) or keep-xfsz
# (the default disposition: regbench ignores the signal itself).
limited() {
  local xfsz="$1" name="$2" final="$3" kb="$4"
  shift 4
  (if [ "$xfsz" = ignore-xfsz ]; then trap '' XFSZ; fi; ulimit -f "$kb"; "$@") >"$name.out" 2>&1
  local rc=$?
  [ "$rc" -ne 0 ] || fail "$name: exit 0 under a file-size limit"
  [ "$rc" -lt 128 ] || fail "$name: died by signal $((rc - 128))"
  [ ! -e "$final" ] || fail "$name: $final exists after a failed write"
  grep -q "$final" "$name.out" || fail "$name: message does not name $final: $(cat "$name.out")"
}

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
  limited ignore-xfsz generate big.h5 64 "$bin" generate --protocol partial --dataset procedural \
    --split test --pairs 40 --seed 1 --out big.h5
  "$bin" export pairs.h5 --out xyz >/dev/null 2>&1 || fail "export"
  limited ignore-xfsz import imported.h5 64 "$bin" import --xyz-dir xyz --out imported.h5
  limited ignore-xfsz run r.jsonl 4 "$bin" run --pairs pairs.h5 --methods identity,icp --out r.jsonl -q
  limited ignore-xfsz export exported 16 "$bin" export pairs.h5 --out exported
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
  strip() { sed -E 's/"(cpu_)?seconds":[^,]*,//g; s/"machine":\{([^{}]|\{[^{}]*\})*\},?//g' "$1"; }
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
links)
  # Expected: the bytes of each link target are the ones written here before the run, since
  # regbench must refuse the link rather than write through it.
  cp pairs.h5 before.h5
  echo "victim bytes" >victim.txt
  ln -s pairs.h5 r.jsonl.lock
  "$bin" run --pairs pairs.h5 --methods identity --out r.jsonl -q 2>e1 && fail "symlink lock accepted"
  grep -q "r.jsonl.lock" e1 || fail "message does not name the lock: $(cat e1)"
  cmp -s pairs.h5 before.h5 || fail "the pair file behind the lock link changed"
  rm r.jsonl.lock
  ln victim.txt r.jsonl.lock
  "$bin" run --pairs pairs.h5 --methods identity --out r.jsonl -q 2>e2 && fail "hard-linked lock accepted"
  grep -q "r.jsonl.lock" e2 || fail "message does not name the lock: $(cat e2)"
  rm r.jsonl.lock
  for resume in "" --resume; do
    ln -s victim.txt r.jsonl.part
    "$bin" run --pairs pairs.h5 --methods identity --out r.jsonl -q $resume 2>e3 \
      && fail "symlink .part accepted ($resume)"
    grep -q "r.jsonl.part" e3 || fail "message does not name the .part: $(cat e3)"
    rm r.jsonl.part
    ln victim.txt r.jsonl.part
    "$bin" run --pairs pairs.h5 --methods identity --out r.jsonl -q $resume 2>e4 \
      && fail "hard-linked .part accepted ($resume)"
    grep -q "r.jsonl.part" e4 || fail "message does not name the .part: $(cat e4)"
    rm r.jsonl.part
  done
  [ "$(cat victim.txt)" = "victim bytes" ] || fail "link target overwritten: $(cat victim.txt)"
  [ ! -e r.jsonl ] || fail "a result was written"
  ;;
writers)
  "$bin" run --pairs pairs.h5 --methods identity --out base.jsonl -q 2>/dev/null || fail "run"
  cp base.jsonl base.before
  "$bin" compare base.jsonl base.jsonl --json base.jsonl >/dev/null 2>e1 \
    && fail "compare --json onto its input accepted"
  grep -q "same file as the input" e1 || fail "message: $(cat e1)"
  cmp -s base.jsonl base.before || fail "compare replaced its input"
  "$bin" export pairs.h5 --out xyz >/dev/null 2>&1 || fail "export"
  victim="$(ls xyz/*.xyz 2>/dev/null | head -1)"
  [ -n "$victim" ] || victim="$(find xyz -type f | head -1)"
  cp "$victim" victim.before
  "$bin" import --xyz-dir xyz --out "$victim" 2>e2 && fail "import --out onto an input accepted"
  grep -q "same file as the input" e2 || fail "message: $(cat e2)"
  cmp -s "$victim" victim.before || fail "import replaced its input"
  # score, merge and report with --out equal to one of their inputs: refused, input unchanged.
  for k in 0 1 2 3 4 5 6 7; do
    echo "{\"pair\": $k, \"transform\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}"
  done >T.jsonl
  cp T.jsonl T.before
  cp pairs.h5 pairs.before
  onto_input() {  # onto_input NAME FILE BEFORE CMD...: CMD must be refused and FILE unchanged
    local name="$1" file="$2" before="$3"
    shift 3
    "$@" >"$name.out" 2>&1 && fail "$name onto its input $file accepted"
    grep -q "same file as the input" "$name.out" || fail "$name: $(cat "$name.out")"
    cmp -s "$file" "$before" || fail "$name replaced its input $file"
  }
  onto_input score-transforms T.jsonl T.before "$bin" score --pairs pairs.h5 --transforms T.jsonl \
    --method ext --out T.jsonl
  onto_input score-pairs pairs.h5 pairs.before "$bin" score --pairs pairs.h5 \
    --transforms T.jsonl --method ext --out pairs.h5
  onto_input merge base.jsonl base.before "$bin" merge base.jsonl --pairs pairs.h5 \
    --methods identity --out base.jsonl
  onto_input merge-pairs pairs.h5 pairs.before "$bin" merge base.jsonl --pairs pairs.h5 \
    --methods identity --out pairs.h5
  onto_input report base.jsonl base.before "$bin" report base.jsonl --out base.jsonl
  # generate --out onto a file of its own dataset folder replaced that PLY with a pair file.
  "$bin" export pairs.h5 --out plyd --format ply >/dev/null 2>&1 || fail "export ply"
  cp plyd/0000_src.ply ply.before
  "$bin" generate --protocol partial --dataset plyd --split all --pairs 2 --seed 1 --points 500 \
    --out plyd/0000_src.ply >gen.out 2>&1 && fail "generate onto its dataset accepted"
  grep -q "lies inside the input plyd" gen.out || fail "generate: $(cat gen.out)"
  cmp -s plyd/0000_src.ply ply.before || fail "generate replaced a file of its dataset"
  # Every writer beside a running `run` on the same path is refused naming its pid.
  "$bin" run --pairs pairs.h5 --methods cpd --params "$slow" --out busy.jsonl -q 2>first.err &
  first=$!
  wait_for_rows busy.jsonl.part 1
  kill -STOP "$first" 2>/dev/null || fail "first run ended before the check could start"
  refused() {  # refused NAME CMD...: CMD must fail naming the running run's pid
    local name="$1"
    shift
    if "$@" >"$name.out" 2>&1; then kill -CONT "$first"; fail "$name beside a run was accepted"; fi
    grep -q "pid $first" "$name.out" || { kill -CONT "$first"; fail "$name: $(cat "$name.out")"; }
  }
  refused score "$bin" score --pairs pairs.h5 --transforms T.jsonl --method ext --out busy.jsonl
  refused report "$bin" report base.jsonl --out busy.jsonl
  refused compare "$bin" compare base.jsonl base.jsonl --json busy.jsonl
  refused generate "$bin" generate --protocol partial --dataset procedural --split test \
    --pairs 2 --seed 1 --out busy.jsonl
  refused merge "$bin" merge base.jsonl --pairs pairs.h5 --methods identity --out busy.jsonl
  refused export "$bin" export pairs.h5 --out busy.jsonl
  refused import "$bin" import --xyz-dir xyz --out busy.jsonl
  refused reproduce "$bin" reproduce --quick --tables table1 --out busy.jsonl
  [ ! -e busy.jsonl ] || { kill -CONT "$first"; fail "a refused writer created busy.jsonl"; }
  if "$bin" train --help 2>/dev/null | grep -- --model >/dev/null; then  # a build without LibTorch has a stub train
    refused train "$bin" train --model ogmm-tiny --max-steps 1 --out busy.jsonl
  fi
  kill -CONT "$first"
  wait "$first" || fail "first run failed: $(cat first.err)"
  grep -c '"method":"cpd"' busy.jsonl | grep -qx 8 || fail "the run's result was replaced"
  # Two scores on one --out: the second, started while the first holds the lock, is refused.
  # (The lock is held by a stopped run above; here by a stopped score would need a slow score,
  # so the same pid rule is checked through the run.)
  ;;
xfsz)
  "$bin" run --pairs pairs.h5 --methods identity --out base.jsonl -q 2>/dev/null || fail "run"
  for k in 0 1 2 3 4 5 6 7; do
    echo "{\"pair\": $k, \"transform\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}"
  done >T.jsonl
  limited keep-xfsz generate big.h5 64 "$bin" generate --protocol partial --dataset procedural \
    --split test --pairs 40 --seed 1 --out big.h5
  limited keep-xfsz run r.jsonl 4 "$bin" run --pairs pairs.h5 --methods identity,icp --out r.jsonl -q
  limited keep-xfsz score s.jsonl 4 "$bin" score --pairs pairs.h5 --transforms T.jsonl --method ext \
    --allow-unhashed --out s.jsonl
  limited keep-xfsz compare c.json 1 "$bin" compare base.jsonl base.jsonl --json c.json
  limited keep-xfsz merge m.jsonl 4 "$bin" merge base.jsonl --pairs pairs.h5 --methods identity --out m.jsonl
  if ls -a | grep -q '\.tmp\.'; then fail "temporary files left: $(ls -a)"; fi
  ;;
usage)
  "$bin" run --pairs pairs.h5 --methods identity --out base.jsonl -q 2>/dev/null || fail "run"
  echo '{"pair": 0, "transform": [[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]]}' >T.jsonl
  usage() {  # usage FLAG VALUE CMD...: exit 2, one line naming FLAG and VALUE
    local flag="$1" value="$2"
    shift 2
    "$@" >u.out 2>u.err
    local rc=$?
    [ "$rc" -eq 2 ] || fail "$flag $value: exit $rc, expected 2: $(cat u.err)"
    [ "$(wc -l <u.err)" -eq 1 ] || fail "$flag $value: not one line: $(cat u.err)"
    grep -qF -- "$flag" u.err || fail "$flag $value: flag not named: $(cat u.err)"
    grep -qF -- "$value" u.err || fail "$flag $value: value not named: $(cat u.err)"
  }
  for a in nan -1 0 1 inf; do
    usage --alpha "$a" "$bin" compare base.jsonl base.jsonl --alpha "$a"
  done
  usage --metrics mae_R "$bin" compare base.jsonl base.jsonl --metrics mae_R
  usage --rigid-tol nan "$bin" score --pairs pairs.h5 --transforms T.jsonl --method ext \
    --out s.jsonl --rigid-tol nan
  [ ! -e s.jsonl ] || fail "score wrote rows with --rigid-tol nan"
  usage --pairs 0 "$bin" reproduce --quick --pairs 0 --out rep
  usage --timeout -1 "$bin" reproduce --quick --timeout -1 --out rep
  usage --seed -1 "$bin" reproduce --quick --seed -1 --out rep
  usage --threads 0 "$bin" align a.xyz b.xyz --method icp --threads 0
  if "$bin" train --help 2>/dev/null | grep -- --model >/dev/null; then  # a build without LibTorch has a stub train
    for flag_value in "--lr nan" "--lr -1" "--max-steps -1" "--minutes -1" "--minutes nan" \
      "--epochs 0" "--threads 0" "--seed -1"; do
      # shellcheck disable=SC2086
      usage ${flag_value% *} ${flag_value#* } "$bin" train --model ogmm-tiny --out t $flag_value
    done
    [ ! -e t ] || fail "train started with a refused flag"
  fi
  ;;
hostile)
  "$bin" run --pairs pairs.h5 --methods identity --out base.jsonl -q 2>/dev/null || fail "run"
  python3 -c 'print("[" * 1000000 + "]" * 1000000)' >deep.jsonl
  "$bin" compare base.jsonl deep.jsonl >d.out 2>&1
  rc=$?
  [ "$rc" -ne 0 ] && [ "$rc" -lt 128 ] || fail "deep JSON: exit $rc: $(tail -c 300 d.out)"
  grep -q "deep.jsonl:1: JSON nested deeper than" d.out || fail "deep JSON: $(tail -c 300 d.out)"
  # 1e30 fits in a float, but PCL's kd-tree under gicp aborted on it: refused at read time
  # naming the file and the point, by the documented limit |x| <= 1e15.
  printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n1e30 1 1\n' >huge.xyz
  printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n' >small.xyz
  for method in gicp icp; do
    "$bin" align huge.xyz small.xyz --method "$method" >h.out 2>&1
    rc=$?
    [ "$rc" -ne 0 ] && [ "$rc" -lt 128 ] || fail "$method on 1e30: exit $rc: $(cat h.out)"
    grep -q "huge.xyz" h.out && grep -q "1e15" h.out || fail "$method on 1e30: $(cat h.out)"
  done
  # NaN points of an ASCII PLY are dropped with a count the user sees (1 of 6 here).
  printf 'ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nnan 0 0\n1 1 1\n' >nan.ply
  "$bin" align nan.ply small.xyz --method identity >n.out 2>&1
  grep -q "nan.ply: dropped 1 of 6 points with NaN or Inf coordinates" n.out \
    || fail "NaN points dropped silently: $(cat n.out)"
  "$bin" align nan.ply small.xyz --method identity --nan-points refuse >n2.out 2>&1 \
    && fail "--nan-points refuse accepted a NaN point: $(cat n2.out)"
  grep -q "nan.ply: 1 of 6 points have NaN or Inf coordinates" n2.out \
    || fail "--nan-points refuse: $(cat n2.out)"
  # Within the limit, gicp ends with a result or a clean failure, never a signal.
  printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n1e15 1 1\n1 2 3\n' >edge.xyz
  "$bin" align edge.xyz small.xyz --method gicp >g.out 2>&1
  rc=$?
  [ "$rc" -lt 128 ] || fail "gicp at the limit died by signal $((rc - 128)): $(cat g.out)"
  if "$bin" train --help 2>/dev/null | grep -- --model >/dev/null; then  # a build without LibTorch has a stub train
    # train --config nested 1M levels deep died by SIGSEGV; an array was silently ignored.
    python3 -c 'print("{\"a\":" * 1000000 + "1" + "}" * 1000000)' >deep_config.json
    echo '[1, 2]' >array_config.json
    for config in deep_config.json array_config.json; do
      "$bin" train --model ogmm-tiny --config "$config" --out "t_$config" --max-steps 1 >t.out 2>&1
      rc=$?
      [ "$rc" -ne 0 ] && [ "$rc" -lt 128 ] || fail "train --config $config: exit $rc: $(tail -c 300 t.out)"
      grep -q "$config" t.out || fail "train --config $config: file not named: $(tail -c 300 t.out)"
      [ ! -e "t_$config" ] || fail "train --config $config: trained anyway"
    done
  fi
  "$bin" generate --protocol partial --dataset procedural --split test --pairs 2 --seed 1 \
    --max-translation 1e30 --out far.h5 >/dev/null 2>g2.out && fail "generate 1e30 accepted"
  grep -q "max_translation" g2.out || fail "generate message: $(cat g2.out)"
  [ ! -e far.h5 ] || fail "generate wrote far.h5"
  ;;
*)
  fail "unknown scenario"
  ;;
esac
echo "ok [$scenario]"

#!/usr/bin/env bash
# regbench-train-portable trains on exactly the pairs `regbench train` trains on: a bundle written
# by `train --write-bundle`, trained 2 steps there and resumed by `regbench train --resume` for 2
# more, gives the same metrics.csv (timing columns aside) and byte-identical weights as 4 steps
# of `regbench train` with the same flags, on CPU. Bad input
# (no bundle, a file that is not a bundle, an unknown flag) is refused with exit 1, naming it.
# Usage: portable_train.sh REGBENCH REGBENCH_TRAIN_PORTABLE
set -uo pipefail
regbench=${1:?usage: portable_train.sh REGBENCH PORTABLE}
portable=${2:?usage: portable_train.sh REGBENCH PORTABLE}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 2
fail() { echo "FAIL: $*" >&2; exit 1; }
flags=(--model ogmm-tiny --dataset procedural --val-pairs 4 --batch 2 --pairs-per-epoch 4
       --no-val-icp --seed 3)
"$regbench" train "${flags[@]}" --epochs 2 --write-bundle b.cbor || fail "--write-bundle"
"$regbench" train "${flags[@]}" --epochs 2 --out direct 2> direct.log || fail "regbench train: $(cat direct.log)"
"$portable" b.cbor --out portable --max-steps 2 2> portable.log ||
    fail "portable: $(cat portable.log)"
grep -q '"bundle": "b.cbor"' portable/last/checkpoint.json || fail "checkpoint does not name its bundle"
# Its first half, resumed by regbench train, equals the uninterrupted run of regbench train.
"$regbench" train "${flags[@]}" --epochs 2 --out portable --resume 2> resume.log ||
    fail "regbench train --resume of a portable run: $(cat resume.log)"
# Columns 1-14: everything but seconds and cpu_seconds.
cut -d, -f1-14 direct/metrics.csv > a.csv
cut -d, -f1-14 portable/metrics.csv > b.csv
[ "$(wc -l < a.csv)" -eq 3 ] || fail "expected a header and 2 validations, got: $(cat a.csv)"
diff a.csv b.csv || fail "metrics differ between regbench train and regbench-train-portable"
cmp direct/last/weights.pt portable/last/weights.pt || fail "weights differ"

expect_refused() {  # expect_refused TEXT ARGS...: exit 1 and TEXT in stderr
    local text=$1; shift
    "$portable" "$@" 2> err.txt && fail "accepted: $*"
    grep -q -- "$text" err.txt || fail "'$*' did not say '$text': $(cat err.txt)"
}
expect_refused "training bundle missing.cbor: no such file" missing.cbor --out x
echo '{"a": 1}' > not.cbor
expect_refused "training bundle not.cbor" not.cbor --out x
expect_refused "unknown argument '--bogus'" b.cbor --out x --bogus
expect_refused "--out is required" b.cbor
expect_refused "--minutes needs a positive number, got '-1'" b.cbor --out x --minutes -1
[ ! -e x ] || fail "a refused run left its output directory"
"$regbench" train "${flags[@]}" --pairs-file p.h5 --write-bundle c.cbor 2> err.txt &&
    fail "--write-bundle with --pairs-file accepted"
grep -q "not from --pairs-file" err.txt || fail "--pairs-file refusal unclear: $(cat err.txt)"
# A bundle path that cannot be written is refused by name, and no bundle replaces the --config.
"$regbench" train "${flags[@]}" --write-bundle nodir/c.cbor 2> err.txt &&
    fail "--write-bundle into a missing folder accepted"
grep -q "nodir/c.cbor" err.txt || fail "missing-folder refusal does not name the file: $(cat err.txt)"
echo '{}' > cfg.json
"$regbench" train "${flags[@]}" --config cfg.json --write-bundle cfg.json 2> err.txt &&
    fail "--write-bundle onto its --config accepted"
[ "$(cat cfg.json)" = "{}" ] || fail "--write-bundle replaced its --config"
echo "ok: regbench-train-portable trains on the pairs regbench train trains on"

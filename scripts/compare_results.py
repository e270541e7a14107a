#!/usr/bin/env python3
"""Compares two `regbench run` result files (JSONL) row by row, ignoring timing.

Rows are matched by (pair, method). Timing fields (any key named `seconds`, ending in
`_seconds`, `_ms` or `_time`, or listed with --ignore) are dropped at every nesting level
before comparing, so two runs of the same code on the same pair file compare equal.
Prints one line per (pair, method) that differs or exists on one side only, naming the
differing fields, then a summary per method. Exit status: 0 identical, 1 different,
2 bad input.

Usage: scripts/compare_results.py BEFORE.jsonl AFTER.jsonl [--ignore KEY ...] [--tol X]
"""
import argparse
import json
import math
import sys
from collections import Counter

TIMING_SUFFIXES = ("_seconds", "_ms", "_time")


def is_timing(key, extra_ignored):
    return (key == "seconds" or key.endswith(TIMING_SUFFIXES) or key in extra_ignored)


def strip(value, ignored):
    """The value with timing keys removed from every object inside it."""
    if isinstance(value, dict):
        return {k: strip(v, ignored) for k, v in value.items() if not is_timing(k, ignored)}
    if isinstance(value, list):
        return [strip(v, ignored) for v in value]
    return value


def equal(a, b, tol):
    """Exact equality, or |a - b| <= tol * max(1, |a|, |b|) for numbers when tol > 0."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(equal(a[k], b[k], tol) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(equal(x, y, tol) for x, y in zip(a, b))
    numbers = (int, float)
    if (isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool)
            and not isinstance(b, bool)):
        if a == b:
            return True
        if math.isnan(a) and math.isnan(b):
            return True
        return tol > 0 and abs(a - b) <= tol * max(1.0, abs(a), abs(b))
    return a == b


def fail(message):
    print(f"compare_results: {message}", file=sys.stderr)
    sys.exit(2)


def read_rows(path, ignored):
    """{(pair, method): row without timing} of one JSONL file; exits 2 on bad input."""
    rows = {}
    try:
        with open(path, encoding="utf-8") as f:
            for line_no, line in enumerate(f, 1):
                if not line.strip():
                    continue
                try:
                    row = json.loads(line)
                    key = (row["pair"], row["method"])
                except (json.JSONDecodeError, KeyError, TypeError) as e:
                    fail(f"{path}:{line_no}: not a result row ({e})")
                if key in rows:
                    fail(f"{path}:{line_no}: duplicate row {key}")
                rows[key] = strip(row, ignored)
    except OSError as e:
        fail(f"cannot read {path}: {e.strerror}")
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--ignore", nargs="*", default=[],
                        help="further keys to ignore at any level (e.g. git_sha)")
    parser.add_argument("--tol", type=float, default=0.0,
                        help="relative tolerance for numbers (default 0: exact)")
    args = parser.parse_args()
    ignored = set(args.ignore)
    before = read_rows(args.before, ignored)
    after = read_rows(args.after, ignored)
    differing = Counter()
    for key in sorted(before.keys() | after.keys(), key=lambda k: (k[0], k[1])):
        pair, method = key
        if key not in after:
            print(f"pair {pair} {method}: only in {args.before}")
        elif key not in before:
            print(f"pair {pair} {method}: only in {args.after}")
        else:
            a, b = before[key], after[key]
            fields = sorted(k for k in a.keys() | b.keys()
                            if not equal(a.get(k), b.get(k), args.tol))
            if not fields:
                continue
            print(f"pair {pair} {method}: {', '.join(fields)}")
        differing[method] += 1
    total = len(before.keys() | after.keys())
    if not differing:
        print(f"identical apart from timing: {total} rows")
        return 0
    summary = ", ".join(f"{m} {n}" for m, n in sorted(differing.items()))
    print(f"{sum(differing.values())} of {total} rows differ ({summary})")
    return 1


if __name__ == "__main__":
    sys.exit(main())

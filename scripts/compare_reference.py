#!/usr/bin/python3
"""Equivalence check: regbench's C++ methods against probreg reference rows.

Reads the probreg reference JSONL (scripts/probreg_reference.py; one or more files, any
number of seeds) and a regbench result JSONL (`regbench run`) made on the same pair file,
and prints, per method, mean mae_r of both and whether they agree within the tolerance of
docs/probreg-equivalence.md: |cpp - ref| <= max(rel_tol * ref, abs_tol_deg), where ref is
the mean over probreg seeds of the per-seed mean mae_r; a C++ mean inside the band of
per-seed means widened by the tolerance also passes when probreg itself is nondeterministic.

mae_r is recomputed here from the stored transforms (scale divided out, scipy Euler zyx,
no wrapping), so both sides use one metric whatever their writers did.

    /usr/bin/python3 scripts/compare_reference.py \
        --reference data/reference/probreg_partial20_seed1.jsonl \
        --candidate /tmp/eq20_cpp.jsonl --pairs /tmp/eq20.h5
"""

import argparse
import json
import os
import statistics
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probreg_reference import read_pair_file, rotation_part, euler_zyx_deg  # noqa: E402

kDefaultMap = "cpd=probreg-cpd,gmmreg=probreg-gmmreg,svr=probreg-svr,filterreg=probreg-filterreg"


def read_jsonl(path):
    rows = []
    with open(path) as f:
        for i, line in enumerate(f, 1):
            if line.strip():
                try:
                    rows.append(json.loads(line))
                except json.JSONDecodeError as e:
                    raise ValueError(f"{path}: line {i} is not JSON: {e}") from e
    return rows


def mae_r(T_gt, T_est):
    d = euler_zyx_deg(rotation_part(T_gt)[0]) - euler_zyx_deg(rotation_part(T_est)[0])
    return float(np.abs(d).mean())


def row_mae_r(row, pairs):
    if pairs is None:
        return row["metrics"]["mae_r"]
    return mae_r(pairs[row["pair"]]["T_gt"], np.asarray(row["transform"], dtype=np.float64))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reference", required=True, nargs="+", help="probreg reference JSONL file(s)")
    ap.add_argument("--candidate", required=True, help="regbench run JSONL")
    ap.add_argument("--pairs", default=None,
                    help="pair file; when given, mae_r is recomputed from the transforms")
    ap.add_argument("--map", default=kDefaultMap,
                    help="candidate=reference method names, comma-separated")
    ap.add_argument("--rel-tol", type=float, default=0.10)
    ap.add_argument("--abs-tol-deg", type=float, default=0.5)
    args = ap.parse_args(argv)

    pairs = read_pair_file(args.pairs)[1] if args.pairs else None
    ref_rows = [r for p in args.reference for r in read_jsonl(p)]
    cand_rows = read_jsonl(args.candidate)
    mapping = []
    for item in args.map.split(","):
        if "=" not in item:
            ap.error(f"--map: '{item}' is not candidate=reference")
        mapping.append(tuple(s.strip() for s in item.split("=", 1)))

    print(f"{'method':<22}{'reference':<24}{'n':>4}{'seeds':>6}{'ref':>9}{'band':>17}"
          f"{'cpp':>9}{'diff':>8}{'tol':>7}  verdict")
    failures = 0
    for cand, ref in mapping:
        c = {r["pair"]: r for r in cand_rows if r["method"] == cand}
        by_seed = {}
        for r in ref_rows:
            if r["method"] == ref:
                by_seed.setdefault(r.get("probreg_seed", 0), {})[r["pair"]] = r
        if not c or not by_seed:
            print(f"{cand:<22}{ref:<24} missing rows (candidate {len(c)}, reference seeds "
                  f"{len(by_seed)})")
            failures += 1
            continue
        common = set(c)
        for rows in by_seed.values():
            common &= set(rows)
        common = sorted(common)
        seed_means = [statistics.fmean(row_mae_r(rows[k], pairs) for k in common)
                      for rows in by_seed.values()]
        ref_mean = statistics.fmean(seed_means)
        cpp_mean = statistics.fmean(row_mae_r(c[k], pairs) for k in common)
        tol = max(args.rel_tol * ref_mean, args.abs_tol_deg)
        lo, hi = min(seed_means), max(seed_means)
        ok = abs(cpp_mean - ref_mean) <= tol or (lo - tol <= cpp_mean <= hi + tol)
        failures += 0 if ok else 1
        print(f"{cand:<22}{ref:<24}{len(common):>4}{len(seed_means):>6}{ref_mean:>9.3f}"
              f"{f'[{lo:.2f}, {hi:.2f}]':>17}{cpp_mean:>9.3f}{cpp_mean - ref_mean:>8.2f}"
              f"{tol:>7.2f}  {'PASS' if ok else 'FAIL'}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

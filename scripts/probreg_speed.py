#!/usr/bin/env python3
"""regbench's probabilistic baselines against probreg, CPU time per call, A/B interleaved.

  /usr/bin/python3 scripts/probreg_speed.py --pairs eq20.h5 --probreg-path /tmp/probreg-src \
      [--regbench build/app/regbench] [--rounds 3] [--methods cpd,gmmreg,svr,filterreg] \
      [--limit-slow 3] [--work DIR]

Each round runs, per method, probreg (scripts/probreg_reference.py, one thread) and then
regbench twice on the same pairs: with the method's defaults and with {"compat": "probreg"}
(probreg's settings: the same iterations and, for CPD and FilterReg, the same result bit for
bit; docs/probreg-equivalence.md). Both sides time each call with the process's CPU clock
(probreg: time.process_time around the registration call; regbench: the rows' cpu_seconds),
so the shared machine's load inflates neither. probreg's GMMReg and SVR take seconds a pair,
so they run on the first --limit-slow pairs only (regbench on the same pairs). Prints, per
round and method, the mean CPU seconds per call and probreg / regbench for both settings, and
the mean iterations (a per-call ratio also counts how many EM iterations each side runs).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

SLOW = {"gmmreg", "svr"}


def rows(path, prefix):
    out = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            r = json.loads(line)
            if r["method"] != prefix:
                continue
            cpu = r.get("cpu_seconds", r.get("extra", {}).get("cpu_seconds"))
            out[r["pair"]] = (cpu, r.get("iterations", 0))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pairs", required=True)
    ap.add_argument("--probreg-path", required=True)
    ap.add_argument("--regbench", default="build/app/regbench")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--methods", default="cpd,gmmreg,svr,filterreg")
    ap.add_argument("--limit-slow", type=int, default=3)
    ap.add_argument("--work", default=None)
    args = ap.parse_args(argv)
    work = args.work or tempfile.mkdtemp(prefix="probreg_speed_")
    os.makedirs(work, exist_ok=True)
    env = dict(os.environ, OMP_NUM_THREADS="1", OMP_WAIT_POLICY="PASSIVE")
    here = os.path.dirname(os.path.abspath(__file__))
    print(f"{'round':>5} {'method':<10} {'pairs':>5} {'probreg s':>10} {'default s':>10} "
          f"{'ratio':>6} {'compat s':>9} {'ratio':>6} {'iter p/d/c':>16}")
    for rnd in range(1, args.rounds + 1):
        for m in args.methods.split(","):
            limit = args.limit_slow if m in SLOW else 0
            ref = os.path.join(work, f"probreg_{m}_{rnd}.jsonl")
            subprocess.run([sys.executable, os.path.join(here, "probreg_reference.py"),
                            "--pairs", args.pairs, "--probreg-path", args.probreg_path,
                            "--methods", m, "--limit", str(limit), "--quiet", "--out", ref],
                           check=True, env=env, stdout=subprocess.DEVNULL)
            p = rows(ref, "probreg-" + m)
            got = []
            for tag, params in (("default", "{}"), ("compat", json.dumps({m: {"compat": "probreg"}}))):
                out = os.path.join(work, f"regbench_{m}_{tag}_{rnd}.jsonl")
                subprocess.run([args.regbench, "run", "--pairs", args.pairs, "--methods", m,
                                "--params", params, "--out", out, "-q", "--force"],
                               check=True, env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
                r = rows(out, m)
                got.append({k: v for k, v in r.items() if k in p})
            keys = sorted(p)
            mean = lambda d, i: statistics.fmean(d[k][i] for k in keys)  # noqa: E731
            pc, dc, cc = mean(p, 0), mean(got[0], 0), mean(got[1], 0)
            its = f"{mean(p, 1):.1f}/{mean(got[0], 1):.1f}/{mean(got[1], 1):.1f}"
            print(f"{rnd:>5} {m:<10} {len(keys):>5} {pc:>10.4f} {dc:>10.4f} {pc / dc:>6.1f} "
                  f"{cc:>9.4f} {pc / cc:>6.1f} {its:>16}", flush=True)


if __name__ == "__main__":
    main()

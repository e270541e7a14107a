#!/usr/bin/env python3
"""Predicts the CPU time of a full `regbench reproduce` from a `reproduce --quick` folder.

Every result file of the quick run (results/ID.jsonl of an experiment, results/ablation_*.jsonl
of a learned variant, results/timing_*.jsonl of a Tab. 6 row) gives each method's mean CPU
seconds per call (the rows' cpu_seconds); the full run's calls are the plan's pair counts
(experiments/plan/*.json, the rule of experiments/reproduce.cpp PairsOf with n = --pairs) times
the methods. The `-noicp` variants, which --quick leaves out, are counted at the cost of their
method with ICP. Each call also pays the harness (pair loading, metrics, the fork of an isolated
call, writing the row): with --process-cpu (user + system CPU seconds of the quick run, from
/usr/bin/time) that overhead is measured as (process CPU - the rows' CPU) / calls, else
--overhead seconds per call are assumed. Prints per result file and in total, and the wall time
on --cores otherwise idle cores.

With --tasks N it also sizes a sharded run (`reproduce --shard i/N`, the Slurm array of
scripts/slurm/regbench-reproduce.sbatch): task i runs pairs k with k % N == i of every result
file, so task 0, with ceil(pairs / N) of each, is the heaviest; it prints that task's CPU
seconds and its wall time with --cores cores per task (its --jobs), which is the array's wall
time once every task has a node, and the core-hours the array holds.

Usage: scripts/estimate_full_run.py QUICK_OUT [--plan experiments/plan] [--pairs 1000]
           [--cores 2] [--process-cpu SECONDS | --overhead 0.06] [--tasks N]
"""
import argparse
import glob
import json
import math
import os
import sys
from collections import defaultdict


def full_pairs(spec, n):
    """Pairs of an experiment in a full run on the fallbacks (PairsOf without --quick)."""
    p = spec.get("pairs", {})
    if p.get("count", 0) > 0:
        return p["count"]
    return max(p.get("min", 0), math.floor(p.get("scale", 1.0) * n))


def plan_pairs(plan_dir, n):
    """{result file stem: full-run pair count} for every experiment and variant of the plan."""
    out = {}
    for path in sorted(glob.glob(os.path.join(plan_dir, "*.json"))):
        with open(path, encoding="utf-8") as f:
            plan = json.load(f)
        for e in plan.get("experiments", []):
            out[e["id"]] = full_pairs(e, n)
        v = plan.get("variants")
        if v and v.get("pairs_of"):
            for row in v["rows"]:
                stem = ("ablation_" + v["kind"] + "_" + row["row"]).replace("+", "_")
                out[stem] = ("pairs_of", v["pairs_of"])
        for t in plan.get("timing_variants", []):
            stem = "timing_" + "".join(c if c.isalnum() or c == "-" else "_" for c in t["row"])
            out[stem] = ("pairs_of", plan["timing_of"])
    for stem, value in list(out.items()):
        if isinstance(value, tuple):
            out[stem] = out[value[1]]
    return out


def print_tasks(lines, overhead, tasks, cores, total):
    """The heaviest task of a `--shard i/tasks` array (task 0: ceil(pairs / tasks) of each file)."""
    cpu = 0.0
    for _stem, n, m, cpu_s in lines:
        share = -(-n // tasks)  # ceil
        cpu += share * (cpu_s / n + overhead * m)
    wall = cpu / cores
    print(f"{tasks} tasks x {cores} core(s): the heaviest task {cpu:.0f} s CPU, "
          f"{wall / 60:.0f} min wall; {tasks * cores * wall / 3600:.1f} core-hours held "
          f"({total / 3600:.1f} CPU-hours of work)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("quick_out")
    parser.add_argument("--plan", default=os.path.join(os.path.dirname(__file__), "..",
                                                       "experiments", "plan"))
    parser.add_argument("--pairs", type=int, default=1000)
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--process-cpu", type=float, default=None)
    parser.add_argument("--overhead", type=float, default=0.06)
    parser.add_argument("--tasks", type=int, default=0,
                        help="size an array of this many shards, --cores cores each")
    args = parser.parse_args()
    pairs = plan_pairs(args.plan, args.pairs)
    files = sorted(glob.glob(os.path.join(args.quick_out, "results", "*.jsonl")))
    if not files:
        sys.exit(f"estimate_full_run: no results/*.jsonl in {args.quick_out}")
    quick_calls, quick_cpu, full_calls, full_cpu = 0, 0.0, 0, 0.0
    lines = []
    for path in files:
        stem = os.path.basename(path)[:-len(".jsonl")]
        if stem not in pairs:
            sys.exit(f"estimate_full_run: {path}: no experiment or variant '{stem}' in {args.plan}")
        cpu = defaultdict(list)
        with open(path, encoding="utf-8") as f:
            for line in f:
                if line.strip():
                    row = json.loads(line)
                    cpu[row["method"]].append(row.get("cpu_seconds", 0.0))
        quick_calls += sum(len(v) for v in cpu.values())
        quick_cpu += sum(sum(v) for v in cpu.values())
        mean = {m: sum(v) / len(v) for m, v in cpu.items()}
        if not stem.startswith(("ablation_", "timing_")):
            for m in ("ogmm", "deepgmr"):  # the -noicp variants a full run adds
                if m in mean and m + "-noicp" not in mean:
                    mean[m + "-noicp"] = mean[m]
        n = pairs[stem]
        cpu_s = n * sum(mean.values())
        full_calls += n * len(mean)
        full_cpu += cpu_s
        lines.append((stem, n, len(mean), cpu_s))
    overhead = args.overhead
    if args.process_cpu is not None:
        overhead = max(0.0, (args.process_cpu - quick_cpu) / quick_calls)
    total = full_cpu + overhead * full_calls
    print(f"{'result file':32} {'pairs':>6} {'methods':>7} {'method CPU s':>12}")
    for stem, n, m, cpu_s in lines:
        print(f"{stem:32} {n:6d} {m:7d} {cpu_s:12.0f}")
    print(f"quick run: {quick_calls} calls, {quick_cpu:.1f} s of method CPU; harness "
          f"{overhead:.3f} s CPU per call ({'measured' if args.process_cpu is not None else 'assumed'})")
    print(f"full run: {full_calls} calls, {full_cpu:.0f} s method CPU + {overhead * full_calls:.0f} s "
          f"harness = {total:.0f} s CPU ({total / 3600:.1f} CPU-hours), "
          f"{total / 3600 / args.cores:.1f} h on {args.cores} idle cores")
    if args.tasks > 0:
        print_tasks(lines, overhead, args.tasks, args.cores, total)
    return 0


if __name__ == "__main__":
    sys.exit(main())

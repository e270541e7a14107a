#!/usr/bin/python3
"""Open3D's Python ICP as a regbench method, on top of the `regbench` Python module.

  PYTHONPATH=build/python /usr/bin/python3 scripts/example_open3d_icp.py PAIRS.h5 OUT.jsonl [--methods icp,cpd]
runs `open3d-py-icp` beside the built-in methods in one regbench.run (same rows, timing, failure
handling and resume as `regbench run`), prints each method's median wall and CPU seconds and
`regbench report OUT.jsonl` (docs/usage.md "From Python").

  PYTHONPATH=build/python /usr/bin/python3 scripts/example_open3d_icp.py PAIRS.h5 --transforms PREFIX
only writes the transforms as PREFIX.jsonl and PREFIX.csv, the two formats `regbench score`
reads (docs/usage.md "Your own method: score"; docs/metrics.md).
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np
import open3d as o3d

import regbench

reg = o3d.pipelines.registration


def open3d_py_icp(source, target):
    """Point-to-point ICP with the criteria of regbench's `icp` (1.0, 30 iterations, 1e-6)."""
    src, tgt = (o3d.geometry.PointCloud(o3d.utility.Vector3dVector(x)) for x in (source, target))
    r = reg.registration_icp(src, tgt, 1.0, np.eye(4), reg.TransformationEstimationPointToPoint(),
                             reg.ICPConvergenceCriteria(1e-6, 1e-6, 30))
    return {"transform": r.transformation, "fitness": r.fitness, "inlier_rmse": r.inlier_rmse}


def write_transforms(pairs, prefix):
    # The pairs' content hash: `regbench score` refuses transforms that record another file's.
    content_hash = regbench.PairFile(pairs).content_hash
    with open(prefix + ".jsonl", "w") as js, open(prefix + ".csv", "w") as cs:
        if content_hash:
            cs.write(f"# content_hash: {content_hash}\n")
        for pair in regbench.PairFile(pairs):
            t0 = time.perf_counter()
            T = open3d_py_icp(pair.source, pair.target)["transform"]
            s = time.perf_counter() - t0
            js.write(json.dumps({"pair": pair.index, "content_hash": content_hash,
                                 "transform": T.tolist(), "seconds": s}) + "\n")
            cs.write(",".join([str(pair.index)] + [repr(float(v)) for v in T[:3].ravel()] +
                              [repr(s)]) + "\n")


args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
args.add_argument("pairs")
args.add_argument("out", nargs="?", help="results JSONL of the run")
args.add_argument("--methods", default="icp,cpd", help="built-in methods run beside it")
args.add_argument("--transforms", metavar="PREFIX", help="only write PREFIX.jsonl/.csv")
a = args.parse_args()
if a.transforms:
    write_transforms(a.pairs, a.transforms)
    sys.exit(0)
if not a.out:
    args.error("OUT.jsonl or --transforms PREFIX is required")
s = regbench.run(a.pairs, a.methods.split(",") + [("open3d-py-icp", open3d_py_icp)], a.out, jobs=2)
print(f"wrote {s['rows_written']} rows ({s['failures']} failed) to {a.out}")
rows = regbench.read_results(a.out)  # a pandas DataFrame (python3-pandas)
print(rows.groupby("method", sort=False)[["seconds", "cpu_seconds"]].median().to_string())
cli = os.environ.get("REGBENCH_CLI", os.path.join(os.path.dirname(__file__), "../build/app/regbench"))
subprocess.run([cli, "report", a.out], check=True)

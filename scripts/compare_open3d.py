#!/usr/bin/python3
"""Per-pair CPU time of regbench's ICP and FGR beside Open3D-Python's, measured in one run.

regbench's `icp` and `fgr` call Open3D's C++ library; this script runs the same pairs through
Debian's python3-open3d (0.16, the same library version) with the same parameters, so the
difference is the harness, not the algorithm. It is a comparison tool only: regbench does not
depend on Python.

Both sides run single-threaded (OMP_NUM_THREADS=1) and are timed in CPU seconds of the
process: regbench's rows carry `cpu_seconds` (thread CPU time around the method call), and
here time.process_time() brackets the same steps (for FGR: normals, FPFH, matching; for ICP:
the ICP call). Wall time on a shared machine mostly measures the other tenants; CPU time does
not. The machine load is printed alongside.

    /usr/bin/python3 scripts/compare_open3d.py --pairs out/p100.h5 --regbench build/app/regbench

Prints a Markdown table: method, pairs, mean CPU ms (regbench), mean CPU ms (Open3D-Python),
ratio, and the largest rotation difference between the two transforms (degrees).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

os.environ["OMP_NUM_THREADS"] = "1"  # before open3d loads its OpenMP runtime
import numpy as np  # noqa: E402
import open3d as o3d  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probreg_reference import read_pair_file  # noqa: E402


def to_o3d(points):
    cloud = o3d.geometry.PointCloud()
    cloud.points = o3d.utility.Vector3dVector(np.asarray(points, dtype=np.float64))
    return cloud


def open3d_icp(source, target, p):
    reg = o3d.pipelines.registration
    criteria = reg.ICPConvergenceCriteria(
        relative_fitness=p["relative_fitness"],
        relative_rmse=p["relative_rmse"],
        max_iteration=p["max_iterations"],
    )
    t0 = time.process_time()
    result = reg.registration_icp(
        to_o3d(source), to_o3d(target), p["max_correspondence_distance"], np.eye(4),
        reg.TransformationEstimationPointToPoint(False), criteria)
    return time.process_time() - t0, np.asarray(result.transformation)


def open3d_fgr(source, target, p):
    reg = o3d.pipelines.registration
    voxel = p["voxel_size"]

    def prepare(points):
        cloud = to_o3d(points)
        if p["voxel_downsample"]:
            cloud = cloud.voxel_down_sample(voxel)
        cloud.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(
            radius=p["normal_radius_voxels"] * voxel, max_nn=p["normal_max_nn"]))
        fpfh = reg.compute_fpfh_feature(cloud, o3d.geometry.KDTreeSearchParamHybrid(
            radius=p["fpfh_radius_voxels"] * voxel, max_nn=p["fpfh_max_nn"]))
        return cloud, fpfh

    option = reg.FastGlobalRegistrationOption(
        division_factor=p["division_factor"],
        use_absolute_scale=p["use_absolute_scale"],
        decrease_mu=p["decrease_mu"],
        maximum_correspondence_distance=p["max_correspondence_distance_voxels"] * voxel,
        iteration_number=p["iteration_number"],
        tuple_scale=p["tuple_scale"],
        maximum_tuple_count=p["maximum_tuple_count"],
        tuple_test=p["tuple_test"])
    t0 = time.process_time()
    src, src_f = prepare(source)
    tgt, tgt_f = prepare(target)
    result = reg.registration_fgr_based_on_feature_matching(src, tgt, src_f, tgt_f, option)
    return time.process_time() - t0, np.asarray(result.transformation)


def rotation_diff_deg(a, b):
    r = a[:3, :3].T @ b[:3, :3]
    return float(np.degrees(np.arccos(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0))))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", required=True, help="regbench pair file (HDF5)")
    ap.add_argument("--regbench", default="build/app/regbench", help="regbench binary")
    ap.add_argument("--methods", default="icp,fgr", help="subset of icp,fgr")
    ap.add_argument("--limit", type=int, default=0, help="use only the first N pairs (0 = all)")
    args = ap.parse_args()
    methods = [m for m in args.methods.split(",") if m]
    for m in methods:
        if m not in ("icp", "fgr"):
            sys.exit(f"compare_open3d.py: --methods: unknown method '{m}' (icp, fgr)")
    if not os.path.exists(args.regbench):
        sys.exit(f"compare_open3d.py: --regbench: {args.regbench} does not exist (build it)")
    _, pairs = read_pair_file(args.pairs)
    if args.limit > 0:
        pairs = pairs[: args.limit]

    with open("/proc/loadavg") as f:
        load = f.read().split()[:3]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "rows.jsonl")
        subprocess.run([args.regbench, "run", "-q", "--threads", "1", "--jobs", "1",
                        "--pairs", args.pairs, "--methods", ",".join(methods), "--out", out],
                       check=True)
        with open(out) as f:
            rows = [json.loads(line) for line in f if line.strip()]
    runners = {"icp": open3d_icp, "fgr": open3d_fgr}
    print(f"machine load (1/5/15 min) at start: {' '.join(load)}; {os.cpu_count()} cores; "
          f"Open3D {o3d.__version__}; one thread each, CPU time")
    print()
    print("| method | pairs | regbench CPU ms/pair | Open3D-Python CPU ms/pair | ratio "
          "| max rotation diff (deg) |")
    print("|---|---|---|---|---|---|")
    for m in methods:
        mine = [r for r in rows if r["method"] == m and r["pair"] < len(pairs)]
        cpu_ours, cpu_theirs, diffs = [], [], []
        for r in mine:
            pair = pairs[r["pair"]]
            if m == "fgr":  # Open3D's tuple sampling is seeded per pair in regbench; not here
                o3d.utility.random.seed(0)
            seconds, T = runners[m](pair["source"], pair["target"], r["params"])
            cpu_theirs.append(seconds)
            cpu_ours.append(r["cpu_seconds"])
            diffs.append(rotation_diff_deg(np.asarray(r["transform"]), T))
        a, b = 1e3 * np.mean(cpu_ours), 1e3 * np.mean(cpu_theirs)
        print(f"| {m} | {len(mine)} | {a:.2f} | {b:.2f} | {b / a:.2f} | {max(diffs):.3g} |")


if __name__ == "__main__":
    main()

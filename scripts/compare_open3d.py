#!/usr/bin/python3
"""Per-pair CPU time of every regbench method, with Open3D-Python's beside ICP, ICP-pl and FGR.

regbench's `icp`, `icp-pl` and `fgr` call Open3D's C++ library; this script runs the same pairs
through Debian's python3-open3d (0.16, the same library version) with the same parameters, so
the difference is the harness, not the algorithm. The other methods' peers do not run on this
machine (probreg and the authors' OGMM/DeepGMR code are not packaged for Debian, PCL has no
Python binding there): their rows say why. It is a comparison tool only: regbench does not
depend on Python.

Both sides run single-threaded (OMP_NUM_THREADS=1) and are timed in CPU seconds of the
process: regbench's rows carry `cpu_seconds` (thread CPU time around the method call), and
here time.process_time() brackets the same steps (for FGR: normals, FPFH, matching; for ICP:
the ICP call; for ICP-pl: the target's normals and the ICP call). Wall time on a shared machine mostly measures the other tenants; CPU time does
not. The machine load is printed alongside.

    /usr/bin/python3 scripts/compare_open3d.py --pairs out/p100.h5 --regbench build/app/regbench

Prints a Markdown table: method, pairs, mean CPU ms (regbench), mean CPU ms (Open3D-Python),
ratio, and the largest rotation difference between the two transforms (degrees); `--methods`
takes regbench method names (default `all`).
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


def open3d_icp(source, target, p, point_to_plane=False):
    """Open3D's ICP as regbench's `icp` (point_to_plane: `icp-pl`, target normals timed too)."""
    reg = o3d.pipelines.registration
    criteria = reg.ICPConvergenceCriteria(
        relative_fitness=p["relative_fitness"],
        relative_rmse=p["relative_rmse"],
        max_iteration=p["max_iterations"],
    )
    t0 = time.process_time()
    tgt = to_o3d(target)
    if point_to_plane:
        tgt.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(
            radius=p["normal_radius"], max_nn=p["normal_max_nn"]))
        estimation = reg.TransformationEstimationPointToPlane()
    else:
        estimation = reg.TransformationEstimationPointToPoint(False)
    result = reg.registration_icp(to_o3d(source), tgt, p["max_correspondence_distance"],
                                  np.eye(4), estimation, criteria)
    return time.process_time() - t0, np.asarray(result.transformation)


def open3d_icp_pl(source, target, p):
    return open3d_icp(source, target, p, point_to_plane=True)


# Why the other methods have no peer figure on this machine.
NO_PEER = {
    "identity": "none needed",
    "gicp": "PCL: no Python binding in Debian",
    "ndt": "PCL: no Python binding in Debian",
    "cpd": "probreg: not packaged in Debian",
    "gmmreg": "probreg: not packaged in Debian",
    "svr": "probreg: not packaged in Debian",
    "filterreg": "probreg: not packaged in Debian",
}
LEARNED_NO_PEER = "authors' PyTorch code: not packaged in Debian"


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
    ap.add_argument("--methods", default="all",
                    help="regbench methods, comma-separated, or all (default)")
    ap.add_argument("--limit", type=int, default=0, help="use only the first N pairs (0 = all)")
    args = ap.parse_args()
    if not os.path.exists(args.regbench):
        sys.exit(f"compare_open3d.py: --regbench: {args.regbench} does not exist (build it)")
    _, pairs = read_pair_file(args.pairs)
    if args.limit > 0:
        pairs = pairs[: args.limit]

    with open("/proc/loadavg") as f:
        load = f.read().split()[:3]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "rows.jsonl")
        # regbench validates the method names and says which exist.
        subprocess.run([args.regbench, "run", "-q", "--threads", "1", "--jobs", "1",
                        "--pairs", args.pairs, "--methods", args.methods, "--out", out],
                       check=True)
        with open(out) as f:
            rows = [json.loads(line) for line in f if line.strip()]
    methods = list(dict.fromkeys(r["method"] for r in rows))  # in regbench's order
    runners = {"icp": open3d_icp, "icp-pl": open3d_icp_pl, "fgr": open3d_fgr}
    print(f"machine load (1/5/15 min) at start: {' '.join(load)}; {os.cpu_count()} cores; "
          f"Open3D {o3d.__version__}; one thread each, CPU time")
    print()
    print("| method | pairs | regbench CPU ms/pair | Open3D-Python CPU ms/pair | ratio "
          "| max rotation diff (deg) |")
    print("|---|---|---|---|---|---|")
    for m in methods:
        mine = [r for r in rows if r["method"] == m and r["pair"] < len(pairs)]
        ok = [r for r in mine if r["status"] == "ok"]
        if m not in runners:
            why = NO_PEER.get(m, LEARNED_NO_PEER)
            a = 1e3 * np.mean([r["cpu_seconds"] for r in ok]) if ok else float("nan")
            print(f"| {m} | {len(ok)} | {a:.2f} | - ({why}) | - | - |")
            continue
        cpu_ours, cpu_theirs, diffs = [], [], []
        for r in ok:
            pair = pairs[r["pair"]]
            if m == "fgr":  # Open3D's tuple sampling is seeded per pair in regbench; not here
                o3d.utility.random.seed(0)
            seconds, T = runners[m](pair["source"], pair["target"], r["params"])
            cpu_theirs.append(seconds)
            cpu_ours.append(r["cpu_seconds"])
            diffs.append(rotation_diff_deg(np.asarray(r["transform"]), T))
        a, b = 1e3 * np.mean(cpu_ours), 1e3 * np.mean(cpu_theirs)
        print(f"| {m} | {len(ok)} | {a:.2f} | {b:.2f} | {b / a:.2f} | {max(diffs):.3g} |")


if __name__ == "__main__":
    main()

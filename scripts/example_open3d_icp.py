#!/usr/bin/python3
"""An external method for `regbench score`: Open3D's Python ICP on every pair of a pair file.

Usage: /usr/bin/python3 scripts/example_open3d_icp.py PAIRS.h5 OUT_PREFIX
writes OUT_PREFIX.jsonl and OUT_PREFIX.csv (the two formats docs/metrics.md describes).
"""
import json, sys, time
import h5py, numpy as np, open3d as o3d

f = h5py.File(sys.argv[1], "r")
# The pairs' content hash (stored at generation / import): `regbench score` refuses transforms
# that record another pair file's hash.
content_hash = json.loads(f.attrs["provenance"]).get("content_hash", "")
reg = o3d.pipelines.registration
with open(sys.argv[2] + ".jsonl", "w") as js, open(sys.argv[2] + ".csv", "w") as cs:
    if content_hash:
        cs.write(f"# content_hash: {content_hash}\n")
    for k in range(len(f["pairs"])):
        g = f["pairs"][f"{k:06d}"]
        src, tgt = (o3d.geometry.PointCloud(o3d.utility.Vector3dVector(g[n][()])) for n in ("source", "target"))
        t0 = time.perf_counter()
        T = reg.registration_icp(src, tgt, 1.0, np.eye(4), reg.TransformationEstimationPointToPoint(),
                                 reg.ICPConvergenceCriteria(1e-6, 1e-6, 30)).transformation
        s = time.perf_counter() - t0
        js.write(json.dumps({"pair": k, "content_hash": content_hash, "transform": T.tolist(),
                             "seconds": s}) + "\n")
        cs.write(",".join([str(k)] + [repr(float(v)) for v in T[:3].ravel()] + [repr(s)]) + "\n")

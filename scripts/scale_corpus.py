#!/usr/bin/env python3
"""The millimetre corpus of issue 54 item 1 (docs/learned-methods.md, "Scale and normalisation").

make ROOT OUT: 7 test meshes of the embedded corpus (corpus.json, same_category/test, the first
7), 4096 area-weighted samples each (numpy default_rng(1)), centred on their centroid and scaled
to radius 1, written as OUT/unit/NAME.xyz and the same times 150 as OUT/mm/NAME.xyz.

compare UNIT.jsonl MM.jsonl [S]: per method, MAE(R) at both scales, the largest per-pair rre
difference, MAE(t) (the millimetre one divided by S, default 150), recall@(1 deg, 0.1 S),
success (rre < 5 deg, rte < 0.1 S) and failed calls, as a Markdown table.

Usage: scripts/scale_corpus.py make . /tmp/scale_corpus
       regbench generate --dataset /tmp/scale_corpus/unit --pairs 21 --seed 1 --out unit.h5
       regbench generate --dataset /tmp/scale_corpus/mm --pairs 21 --seed 1 --scale 150 --out mm.h5
       regbench run --pairs unit.h5 --methods ... --out unit.jsonl   (and mm.h5 -> mm.jsonl)
       scripts/scale_corpus.py compare unit.jsonl mm.jsonl
"""
import json
import math
import os
import sys

import numpy as np


def read_off(path):
    lines = [l.split("#")[0].strip() for l in open(path).read().split("\n")]
    lines = [l for l in lines if l]
    head = lines[0].split()
    counts, body = (head[1:], lines[1:]) if len(head) > 1 else (lines[1].split(), lines[2:])
    nv, nf = int(counts[0]), int(counts[1])
    vertices = np.array([[float(x) for x in body[i].split()[:3]] for i in range(nv)])
    faces = []
    for i in range(nv, nv + nf):
        f = [int(x) for x in body[i].split()]
        idx = f[1:1 + f[0]]
        faces += [[idx[0], idx[j], idx[j + 1]] for j in range(1, f[0] - 1)]
    return vertices, np.array(faces)


def make(root, out):
    corpus = json.load(open(os.path.join(root, "data/corpus.json")))
    files = {s["name"]: s["file"] for s in corpus["shapes"]}
    rng = np.random.default_rng(1)
    for d in ("unit", "mm"):
        os.makedirs(os.path.join(out, d), exist_ok=True)
    for name in corpus["splits"]["same_category"]["test"][:7]:
        v, f = read_off(os.path.join(root, "data/meshes", files[name]))
        a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
        tri = rng.choice(len(f), 4096, p=area / area.sum())
        u, w = rng.random(4096), rng.random(4096)
        flip = u + w > 1
        u[flip], w[flip] = 1 - u[flip], 1 - w[flip]
        p = a[tri] + u[:, None] * (b[tri] - a[tri]) + w[:, None] * (c[tri] - a[tri])
        p -= p.mean(0)
        p /= np.linalg.norm(p, axis=1).max()
        np.savetxt(os.path.join(out, "unit", name + ".xyz"), p, fmt="%.17g")
        np.savetxt(os.path.join(out, "mm", name + ".xyz"), 150.0 * p, fmt="%.17g")


def compare(unit_path, mm_path, s):
    def load(path):
        rows = {}
        for line in open(path):
            r = json.loads(line)
            rows.setdefault(r["method"], []).append(r)
        return rows

    def num(x):
        return math.nan if x is None else x

    unit, mm = load(unit_path), load(mm_path)
    print("| method | MAE(R) unit | MAE(R) mm | largest pair rre difference | MAE(t) unit | "
          "MAE(t) mm / %g | recall unit / mm | success unit / mm | failed unit / mm |" % s)
    print("|---|---:|---:|---:|---:|---:|---|---|---|")
    for method, a in unit.items():
        b = mm[method]
        col = lambda rows, k: np.array([num(r["metrics"][k]) for r in rows])
        rec = lambda rows, t: sum(1 for r in rows if num(r["metrics"]["mae_r"]) < 1
                                  and num(r["metrics"]["mae_t"]) < 0.1 * t)
        suc = lambda rows, t: sum(1 for r in rows if num(r["metrics"]["rre"]) < 5
                                  and num(r["metrics"]["rte"]) < 0.1 * t)
        fail = lambda rows: sum(1 for r in rows if r.get("status") != "ok")
        diff = np.nanmax(np.abs(col(a, "rre") - col(b, "rre")))
        print(f"| {method} | {np.nanmean(col(a, 'mae_r')):.2f} | {np.nanmean(col(b, 'mae_r')):.2f} "
              f"| {diff:.2g} | {np.nanmean(col(a, 'mae_t')):.4f} | "
              f"{np.nanmean(col(b, 'mae_t')) / s:.4f} | {rec(a, 1)} / {rec(b, s)} | "
              f"{suc(a, 1)} / {suc(b, s)} | {fail(a)} / {fail(b)} |")


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "make":
        make(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 4 and sys.argv[1] == "compare":
        compare(sys.argv[2], sys.argv[3], float(sys.argv[4]) if len(sys.argv) > 4 else 150.0)
    else:
        sys.exit(__doc__)

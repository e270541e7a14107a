#!/usr/bin/env python3
"""Stand-ins for DeepGMR's released files, for the README's "Run the authors' DeepGMR weights"
example (scripts/docs_examples.sh deepgmr_import): the real `modelnet_noisy.pth` and
`modelnet_noisy.h5` cannot be downloaded on this machine.

  deepgmr_standin.py OUT_DIR

writes OUT_DIR/modelnet_noisy.pth, the authors' DeepGMR module layout (RRI, k 20, d_model 1024,
J 16; tests/networks/authors_parity.py) with PyTorch's default initialisation under
torch.manual_seed(0), saved in the legacy (pre-1.6) torch.save format their releases use; and
OUT_DIR/modelnet_noisy.h5, 20 pairs in their test files' layout (`source`, `target` [20, 1024, 3]
float32, `transform` [20, 4, 4] float32 with target = R source + t) made from procedural
surfaces (sphere, box, torus, cylinder): a rotation drawn uniformly from SO(3), each component
of t uniform in [-0.25, 0.25], then Gaussian noise of sigma 0.01 clipped at 0.05 on both clouds
(full-range rotations and clipped noise as in DeepGMR's noisy set). Random weights register nothing: the
example shows the commands and the output format, not DeepGMR's accuracy.
Needs Debian's python3-torch, python3-h5py and python3-scipy (/usr/bin/python3).
"""
import os
import sys

import h5py
import numpy as np
import torch
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "networks"))
from authors_parity import DeepGMRLayout  # noqa: E402

PAIRS, POINTS = 20, 1024


def surface(kind, n, rng):
    """n points on a procedural surface of radius about 0.5, centred at the origin."""
    if kind == 0:  # sphere
        p = rng.normal(size=(n, 3))
        return 0.5 * p / np.linalg.norm(p, axis=1, keepdims=True)
    if kind == 1:  # box 0.8 x 0.5 x 0.3: a face chosen by area, a point on it
        half = np.array([0.4, 0.25, 0.15])
        areas = np.array([half[1] * half[2], half[0] * half[2], half[0] * half[1]])
        axis = rng.choice(3, size=n, p=areas / areas.sum())
        p = rng.uniform(-1, 1, size=(n, 3)) * half
        p[np.arange(n), axis] = half[axis] * rng.choice([-1.0, 1.0], size=n)
        return p
    u, v = rng.uniform(0, 2 * np.pi, size=(2, n))
    if kind == 2:  # torus, radii 0.35 and 0.12 (uniform in the angles, as a stand-in)
        return np.stack([(0.35 + 0.12 * np.cos(v)) * np.cos(u),
                         (0.35 + 0.12 * np.cos(v)) * np.sin(u), 0.12 * np.sin(v)], 1)
    h = rng.uniform(-0.4, 0.4, size=n)  # cylinder side, radius 0.25
    return np.stack([0.25 * np.cos(u), 0.25 * np.sin(u), h], 1)


def main(out):
    os.makedirs(out, exist_ok=True)
    torch.manual_seed(0)
    net = DeepGMRLayout(True, 20, 1024, 16)
    torch.save(net.state_dict(), os.path.join(out, "modelnet_noisy.pth"),
               _use_new_zipfile_serialization=False)
    rng = np.random.default_rng(0)
    src = np.empty((PAIRS, POINTS, 3), np.float32)
    tgt = np.empty_like(src)
    transform = np.tile(np.eye(4, dtype=np.float32), (PAIRS, 1, 1))
    for i in range(PAIRS):
        p = surface(i % 4, POINTS, rng)
        r = Rotation.random(random_state=rng).as_matrix()
        t = rng.uniform(-0.25, 0.25, size=3)
        q = p @ r.T + t
        noise = lambda: np.clip(0.01 * rng.normal(size=p.shape), -0.05, 0.05)  # noqa: E731
        src[i], tgt[i] = p + noise(), q + noise()
        transform[i, :3, :3], transform[i, :3, 3] = r, t
    with h5py.File(os.path.join(out, "modelnet_noisy.h5"), "w") as f:
        f["source"], f["target"], f["transform"] = src, tgt, transform


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: deepgmr_standin.py OUT_DIR")
    main(sys.argv[1])

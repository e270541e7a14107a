"""Shared fixtures of the regbench Python tests (run by CTest: python_* tests).

CTest sets PYTHONPATH to build/python and REGBENCH_CLI to the regbench binary; run by hand:
  PYTHONPATH=build/python REGBENCH_CLI=build/app/regbench /usr/bin/python3 -m pytest python/tests
"""
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import regbench

ROOT = pathlib.Path(__file__).resolve().parents[2]
CLI = os.environ.get("REGBENCH_CLI", str(ROOT / "build" / "app" / "regbench"))

# Keys of a row that measure time or the machine: they differ between two runs of one call.
TIMING_KEYS = ("seconds", "cpu_seconds", "machine")


def cli(*args, check=True):
    """Runs the regbench binary; returns the CompletedProcess (text)."""
    env = dict(os.environ, OMP_WAIT_POLICY="PASSIVE")
    return subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, check=check,
                          env=env)


def read_jsonl(path):
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip()]


def untimed(row):
    """A row without its timing: seconds, CPU seconds, machine load, excluded_seconds."""
    row = {k: v for k, v in row.items() if k not in TIMING_KEYS}
    row["extra"] = {k: v for k, v in row.get("extra", {}).items() if k != "excluded_seconds"}
    return row


def kabsch(a, b):
    """Least-squares rotation R and translation t with b ~ a R^T + t (NumPy SVD)."""
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    R = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return R, cb - R @ ca


def numpy_icp(source, target, iterations=10):
    """Point-to-point ICP in NumPy + scipy (nearest neighbours, Kabsch): the test's callable."""
    from scipy.spatial import cKDTree

    tree = cKDTree(target)
    T = np.eye(4)
    moved = np.array(source, dtype=float)
    for _ in range(iterations):
        _, idx = tree.query(moved)
        R, t = kabsch(moved, target[idx])
        moved = moved @ R.T + t
        step = np.eye(4)
        step[:3, :3], step[:3, 3] = R, t
        T = step @ T
    return T


@pytest.fixture(scope="session")
def pairs_path(tmp_path_factory):
    """A 4-pair file from the procedural dataset (no mesh data needed)."""
    path = tmp_path_factory.mktemp("pairs") / "pairs.h5"
    cli("generate", "--protocol", "partial", "--dataset", "procedural", "--split", "test",
        "--pairs", 4, "--seed", 3, "--out", path)
    return str(path)


@pytest.fixture(scope="session")
def pair_file(pairs_path):
    return regbench.PairFile(pairs_path)

"""methods(), align() and metrics(): equal to the CLI and to independent computations
(scipy), refusing bad arrays with clear messages, releasing the GIL."""
import json
import threading
import time

import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

import regbench
from conftest import cli, read_jsonl


def test_methods_equal_cli_listing():
    listed = json.loads(cli("methods", "--json").stdout)
    assert regbench.methods() == listed
    names = [m["name"] for m in regbench.methods()]
    assert {"identity", "icp", "cpd", "fgr"} <= set(names)
    cpd = next(m for m in regbench.methods() if m["name"] == "cpd")
    assert "maxiter" in cpd["defaults"] and "maxiter" in cpd["param_docs"]


@pytest.mark.parametrize("method,params", [("icp", {}), ("cpd", {"maxiter": 15})])
def test_align_equals_cli_run_row(pairs_path, pair_file, tmp_path, method, params):
    out = tmp_path / "cli.jsonl"
    cli("run", "--pairs", pairs_path, "--methods", method, "--params",
        json.dumps({method: params}), "--out", out, "--quiet")
    for row in read_jsonl(out):
        pair = pair_file[row["pair"]]
        r = regbench.align(pair.source, pair.target, method, params, seed=pair_file.seed,
                           pair_index=pair.index)
        assert r.status == row["status"] == "ok"
        np.testing.assert_array_equal(r.T_target_source, np.array(row["transform"]))
        assert r.iterations == row["iterations"]
        assert r.stop_reason == row["stop_reason"]
        assert r.params == row["params"]
        assert r.seconds > 0 and r.cpu_seconds >= 0 and r.cpu_scope == "thread"


def test_align_accepts_float32_and_lists(pair_file):
    pair = pair_file[0]
    r64 = regbench.align(pair.source.astype(np.float32).astype(np.float64),
                         pair.target.astype(np.float32).astype(np.float64), "icp")
    r32 = regbench.align(pair.source.astype(np.float32), pair.target.astype(np.float32), "icp")
    np.testing.assert_array_equal(r32.T_target_source, r64.T_target_source)
    rl = regbench.align(pair.source.tolist(), pair.target.tolist(), "icp")
    assert rl.status == "ok"


@pytest.mark.parametrize(
    "make,message",
    [
        (lambda s: s[:, :2], r"source must have shape \(N, 3\), got \(\d+, 2\)"),
        (lambda s: s.reshape(-1), r"source must have shape \(N, 3\), got \(\d+,\)"),
        (lambda s: s.astype(np.int64), "source must have a floating-point dtype"),
        (lambda s: np.where(np.arange(len(s))[:, None] == 5, np.nan, s),
         "source cloud has non-finite"),
        (lambda s: s[:2], r"source cloud has 2 points \(need >= 3\)"),
        (lambda s: "points", "source must have a floating-point dtype"),
    ],
)
def test_align_refuses_bad_arrays(pair_file, make, message):
    pair = pair_file[0]
    with pytest.raises(ValueError, match=message):
        regbench.align(make(np.array(pair.source)), pair.target, "icp")


def test_align_refuses_bad_method_and_params(pair_file):
    pair = pair_file[0]
    with pytest.raises(ValueError, match="unknown method 'nope'"):
        regbench.align(pair.source, pair.target, "nope")
    with pytest.raises(ValueError, match="maxiter"):
        regbench.align(pair.source, pair.target, "cpd", {"maxiter": 2.5})
    with pytest.raises(ValueError, match="unknown parameter"):
        regbench.align(pair.source, pair.target, "cpd", {"no_such_key": 1})
    with pytest.raises(ValueError, match="params must be a dict"):
        regbench.align(pair.source, pair.target, "cpd", [1, 2])
    with pytest.raises(ValueError, match="threads must be >= 1"):
        regbench.align(pair.source, pair.target, "cpd", threads=0)
    # Rows record parameters as JSON, which has no NaN or infinity: such a run used to write
    # null and then refuse its own rows on resume ("ran with other parameters").
    for bad in (float("inf"), float("-inf"), float("nan")):
        with pytest.raises(ValueError, match=r"params\.max_correspondence_distance must be finite"):
            regbench.align(pair.source, pair.target, "icp", {"max_correspondence_distance": bad})


def test_align_has_the_scale_guard_of_run():
    # run()'s guard: rienet on 200,000 points asked for 160 GB and ended in a backtrace.
    rng = np.random.default_rng(1)
    cloud = rng.standard_normal((30, 3))
    dense = {"e_step": "dense"}  # CPD's dense E-step is O(N*M) at every size
    with pytest.raises(ValueError) as e:
        regbench.align(cloud, cloud[:25], "cpd", params=dense, max_points=28)
    assert str(e.value).startswith(
        "align: cpd is O(N*M): source has 30 points, target 25, above max_points 28 (750 point "
        "pairs per iteration,")
    assert str(e.value).endswith("pass max_points=0 to run it as is (or a larger max_points), "
                                 "or downsample the clouds first")
    assert regbench.align(cloud, cloud[:25], "cpd", params=dense, max_points=30).status == "ok"
    assert regbench.align(cloud, cloud[:25], "cpd", params=dense, max_points=0).status == "ok"
    # CPD's default E-step approximates at scale: not guarded, as in run().
    assert regbench.align(cloud, cloud[:25], "cpd", max_points=28).status == "ok"
    if "rienet" in [m["name"] for m in regbench.methods()]:  # builds with LibTorch
        big = rng.standard_normal((200000, 3))
        with pytest.raises(ValueError, match="align: rienet is O\\(N\\*M\\): source has 200000 "
                                             "points, target 200000, above max_points 20000"):
            regbench.align(big, big, "rienet")


def test_align_releases_the_gil():
    """A Python thread runs while align works. The thread is woken just before the call; with
    the interpreter lock held by the call it could only run after the call's C++ work, i.e.
    later than `before + r.seconds` (r.seconds times that work alone)."""
    rng = np.random.default_rng(0)
    source = rng.normal(size=(1500, 3))
    R = Rotation.from_euler("zyx", [20, 10, 5], degrees=True).as_matrix()
    target = source @ R.T + 0.1
    go = threading.Event()
    ran_at = []

    def waiter():
        go.wait()
        ran_at.append(time.monotonic())

    t = threading.Thread(target=waiter)
    t.start()
    time.sleep(0.05)  # the waiter is blocked in go.wait()
    go.set()
    before = time.monotonic()
    r = regbench.align(source, target, "cpd", {"maxiter": 300, "tol": 1e-12})
    t.join()
    assert r.status == "ok" and r.iterations == 300
    assert ran_at[0] < before + r.seconds


def scipy_metrics(T_est, T_gt, source, target, euler="zyx", overlap=None):
    """docs/metrics.md computed independently: scipy rotations and kd-trees, NumPy."""
    R_est, R_gt, t_est, t_gt = T_est[:3, :3], T_gt[:3, :3], T_est[:3, 3], T_gt[:3, 3]
    e_est = Rotation.from_matrix(R_est).as_euler(euler, degrees=True)
    e_gt = Rotation.from_matrix(R_gt).as_euler(euler, degrees=True)
    moved = source @ R_est.T + t_est
    d_st, _ = cKDTree(target).query(moved)
    d_ts, _ = cKDTree(moved).query(target)
    cos = np.clip((np.trace(R_gt.T @ R_est) - 1) / 2, -1, 1)
    mask = np.ones(len(source), bool) if overlap is None or not overlap.any() else overlap == 1
    diff = (source[mask] @ R_est.T + t_est) - (source[mask] @ R_gt.T + t_gt)
    return {
        "mae_r": np.mean(np.abs(e_gt - e_est)),
        "mse_r": np.mean((e_gt - e_est) ** 2),
        "mae_t": np.mean(np.abs(t_gt - t_est)),
        "mse_t": np.mean((t_gt - t_est) ** 2),
        "rre": np.degrees(np.arccos(cos)),
        "rte": np.linalg.norm(t_gt - t_est),
        "ccd": np.mean(np.minimum(d_st, 0.1)) + np.mean(np.minimum(d_ts, 0.1)),
        "chamfer": np.mean(d_st**2) + np.mean(d_ts**2),
        "ccd_within_clip": bool(d_st.mean() < 0.1 and d_ts.mean() < 0.1),
        "overlap_rmse": np.sqrt(np.mean(np.sum(diff**2, axis=1))),
    }


def assert_metrics_close(got, want):
    for key, value in want.items():
        if isinstance(value, bool):
            assert got[key] == value, key
        else:
            assert got[key] == pytest.approx(value, rel=1e-7, abs=1e-9), key


@pytest.mark.parametrize("euler", ["zyx", "xyz"])
def test_metrics_equal_scipy(pair_file, euler):
    for pair in pair_file:
        T_est = regbench.align(pair.source, pair.target, "icp").T_target_source
        got = regbench.metrics(T_est, pair.T_gt, pair.source, pair.target, euler=euler,
                               source_overlap=pair.source_overlap)
        assert got["euler"] == euler
        want = scipy_metrics(T_est, pair.T_gt, pair.source, pair.target, euler,
                             pair.source_overlap)
        assert_metrics_close(got, want)
        # Every per-pair metric of docs/metrics.md is there.
        assert set(want) | {"euler"} == set(got)


def test_metrics_equal_cli_rows(pairs_path, pair_file, tmp_path):
    out = tmp_path / "icp.jsonl"
    cli("run", "--pairs", pairs_path, "--methods", "icp", "--out", out, "--quiet")
    for row in read_jsonl(out):
        pair = pair_file[row["pair"]]
        got = regbench.metrics(np.array(row["transform"]), pair.T_gt, pair.source, pair.target,
                               source_overlap=pair.source_overlap)
        for key, value in row["metrics"].items():
            assert got[key] == value, key


def test_metrics_refuses_bad_input(pair_file):
    pair = pair_file[0]
    with pytest.raises(ValueError, match=r"T_est must have shape \(4, 4\), got \(3, 3\)"):
        regbench.metrics(np.eye(3), pair.T_gt, pair.source, pair.target)
    bad = np.eye(4)
    bad[0, 3] = np.inf
    with pytest.raises(ValueError, match="T_gt has non-finite"):
        regbench.metrics(np.eye(4), bad, pair.source, pair.target)
    with pytest.raises(ValueError, match="unknown Euler convention"):
        regbench.metrics(np.eye(4), pair.T_gt, pair.source, pair.target, euler="ZYX")
    with pytest.raises(ValueError, match="target must have a floating-point dtype"):
        regbench.metrics(np.eye(4), pair.T_gt, pair.source, pair.target.astype(int))
    with pytest.raises(ValueError, match="source_overlap must be a 1-D array"):
        regbench.metrics(np.eye(4), pair.T_gt, pair.source, pair.target, source_overlap=[1, 0])

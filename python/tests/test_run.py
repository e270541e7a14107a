"""regbench.run: built-in methods as the CLI runs them, Python callables as rows that equal
`score`'s for the same transforms, failures, timeouts, resume, read_results and report."""
import faulthandler
import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import regbench
from conftest import cli, numpy_icp, read_jsonl, untimed
from test_align_metrics import assert_metrics_close, scipy_metrics


def py_icp(source, target, iterations=10):
    return numpy_icp(source, target, iterations)


def test_builtin_rows_equal_cli_run(pairs_path, tmp_path):
    params = {"cpd": {"maxiter": 10}}
    cli("run", "--pairs", pairs_path, "--methods", "icp,cpd", "--params", json.dumps(params),
        "--out", tmp_path / "cli.jsonl", "--quiet")
    summary = regbench.run(pairs_path, ["icp", "cpd"], tmp_path / "py.jsonl", params=params)
    assert summary["rows_written"] == 8 and summary["failures"] == 0
    cli_rows, py_rows = read_jsonl(tmp_path / "cli.jsonl"), read_jsonl(tmp_path / "py.jsonl")
    assert [untimed(r) for r in py_rows] == [untimed(r) for r in cli_rows]
    assert all(r["cpu_seconds"] > 0 for r in py_rows)


def test_callable_rows_equal_score_rows(pairs_path, pair_file, tmp_path):
    out = tmp_path / "py.jsonl"
    regbench.run(pair_file, [py_icp], out)
    rows = read_jsonl(out)
    assert [r["pair"] for r in rows] == list(range(len(pair_file)))
    # The same transforms through `regbench score`.
    transforms = tmp_path / "T.jsonl"
    transforms.write_text("".join(
        json.dumps({"pair": r["pair"], "transform": r["transform"],
                    "content_hash": r["data"]["content_hash"]}) + "\n" for r in rows))
    cli("score", "--pairs", pairs_path, "--transforms", transforms, "--method", "py_icp",
        "--out", tmp_path / "scored.jsonl")
    scored = read_jsonl(tmp_path / "scored.jsonl")
    drop = ("cpu_scope", "timeout")  # score has no clock of its own and runs no calls
    assert [{k: v for k, v in untimed(r).items() if k not in drop} for r in rows] == \
           [{k: v for k, v in untimed(r).items() if k not in drop} for r in scored]
    for row in rows:
        assert row["status"] == "ok" and row["method"] == "py_icp" and row["params"] == {}
        assert row["seconds"] > 0 and row["cpu_seconds"] > 0 and row["cpu_scope"] == "thread"
        assert row["extra"]["excluded_seconds"] >= 0
        # The callable's transform, and metrics that scipy computes from it.
        pair = pair_file[row["pair"]]
        T = np.array(row["transform"])
        np.testing.assert_allclose(T, numpy_icp(pair.source, pair.target), rtol=0, atol=1e-12)
        assert_metrics_close(row["metrics"],
                             scipy_metrics(T, pair.T_gt, pair.source, pair.target, "zyx",
                                           pair.source_overlap))


def test_callables_beside_builtins_named_with_params_and_extras(pair_file, tmp_path):
    def detailed(source, target, iterations):
        return {"transform": numpy_icp(source, target, iterations), "iterations": iterations,
                "stop_reason": "max_iterations", "points": len(source),
                "note": np.float32(0.5)}

    out = tmp_path / "mixed.jsonl"
    regbench.run(pair_file, ["identity", ("np-icp", detailed), py_icp], out,
                 params={"np-icp": {"iterations": 3}, "py_icp": {"iterations": 4}})
    rows = read_jsonl(out)
    assert [r["method"] for r in rows[:3]] == ["identity", "np-icp", "py_icp"]
    d = rows[1]
    assert d["params"] == {"iterations": 3} and d["iterations"] == 3
    assert d["stop_reason"] == "max_iterations"
    assert d["extra"]["points"] == len(pair_file[0].source) and d["extra"]["note"] == 0.5
    assert rows[2]["params"] == {"iterations": 4}


def test_exception_gives_failed_row_and_run_goes_on(pair_file, tmp_path):
    calls = []

    def flaky(source, target):
        calls.append(1)
        if len(calls) == 2:
            raise ValueError("no convergence on this one")
        return np.eye(4)

    def wrong_shape(source, target):
        return np.eye(3)

    def scaled(source, target):
        return np.diag([2.0, 2.0, 2.0, 1.0])

    out = tmp_path / "failing.jsonl"
    summary = regbench.run(pair_file, [flaky, wrong_shape, scaled], out)
    assert summary["failures"] == 1 + 2 * len(pair_file)
    rows = {(r["pair"], r["method"]): r for r in read_jsonl(out)}
    failed = rows[(1, "flaky")]
    assert failed["status"] == "failed"
    assert failed["message"] == "flaky: ValueError: no convergence on this one"
    assert failed["transform"] == np.eye(4).tolist()
    assert failed["metrics"]["rre"] > 0  # scored as the identity, like any failed row
    assert all(rows[(k, "flaky")]["status"] == "ok" for k in (0, 2, 3))
    assert "must have shape (4, 4), got (3, 3)" in rows[(0, "wrong_shape")]["message"]
    assert rows[(0, "scaled")]["message"] == "scaled: produced a non-rigid transform"


def test_bad_method_lists_are_refused(pair_file, tmp_path):
    out = tmp_path / "x.jsonl"
    with pytest.raises(ValueError, match="unknown method 'nope'"):
        regbench.run(pair_file, ["nope"], out)
    with pytest.raises(ValueError, match="pass it as \\(name, callable\\)"):
        regbench.run(pair_file, [lambda s, t: np.eye(4)], out)
    with pytest.raises(ValueError, match="'icp' is a built-in method"):
        regbench.run(pair_file, [("icp", py_icp)], out)
    with pytest.raises(ValueError, match="listed twice"):
        regbench.run(pair_file, [py_icp, py_icp], out)
    with pytest.raises(ValueError, match="params names method 'cpd'"):
        regbench.run(pair_file, ["icp"], out, params={"cpd": {}})
    inf = {"icp": {"max_correspondence_distance": float("inf")}}
    with pytest.raises(ValueError, match=r"params\.icp\.max_correspondence_distance must be finite"):
        regbench.run(pair_file, ["icp"], out, params=inf)
    assert not out.exists()
    # As --timeout: a finite number > 0 (a row records it as JSON, which has no inf).
    for timeout in (0, -1.0, float("inf"), float("nan"), 10**400):
        with pytest.raises(ValueError, match="timeout must be a finite number of seconds > 0 "
                                             r"\(or None\), got " + repr(timeout)[:8]):
            regbench.run(pair_file, ["icp"], out, timeout=timeout)
    with pytest.raises(TypeError, match="methods must be a list"):
        regbench.run(pair_file, 3, out)
    with pytest.raises(TypeError, match="timeout must be a number"):
        regbench.run(pair_file, "icp", out, timeout="1")
    with pytest.raises(FileNotFoundError):
        regbench.run(out.parent / "absent.h5", ["icp"], out)
    assert not out.exists()


def test_one_method_or_a_tuple_of_names(pair_file, tmp_path):
    regbench.run(pair_file, py_icp, tmp_path / "a.jsonl")
    regbench.run(pair_file, ("np", py_icp), tmp_path / "b.jsonl")
    regbench.run(pair_file, ("identity", "icp"), tmp_path / "c.jsonl")
    regbench.run(pair_file, "identity,icp", tmp_path / "d.jsonl")
    assert {r["method"] for r in read_jsonl(tmp_path / "a.jsonl")} == {"py_icp"}
    assert {r["method"] for r in read_jsonl(tmp_path / "b.jsonl")} == {"np"}
    assert [untimed(r) for r in read_jsonl(tmp_path / "c.jsonl")] == \
           [untimed(r) for r in read_jsonl(tmp_path / "d.jsonl")]


def test_timeout_runs_callables_in_a_child(pair_file, tmp_path):
    marker = tmp_path / "slept"

    def sleepy(source, target):  # hangs on its first call only (each call is a new child)
        if not marker.exists():
            marker.touch()
            time.sleep(60)
        return np.eye(4)

    def aborts(source, target):
        faulthandler.disable()  # in the forked child only: no traceback on stderr
        os.abort()

    def raises(source, target):
        raise RuntimeError("inside the child")

    out = tmp_path / "isolated.jsonl"
    regbench.run(pair_file, [py_icp, sleepy, aborts, raises], out, timeout=5)
    rows = {(r["pair"], r["method"]): r for r in read_jsonl(out)}
    assert rows[(0, "sleepy")]["message"].startswith("sleepy: exceeded timeout of 5")
    for k, pair in enumerate(pair_file):
        ok = rows[(k, "py_icp")]
        assert ok["status"] == "ok"
        np.testing.assert_array_equal(np.array(ok["transform"]),
                                      numpy_icp(pair.source, pair.target))
        assert rows[(k, "sleepy")]["status"] == ("timeout" if k == 0 else "ok")
        assert rows[(k, "aborts")]["status"] == "crashed"
        assert "crashed with signal 6" in rows[(k, "aborts")]["message"]
        assert rows[(k, "raises")]["status"] == "failed"
        assert rows[(k, "raises")]["message"] == "raises: RuntimeError: inside the child"


def test_resume_after_keyboard_interrupt_gives_the_same_file(pair_file, tmp_path):
    clean = tmp_path / "clean.jsonl"
    regbench.run(pair_file, ["icp", py_icp], clean)

    calls = []

    def interrupted(source, target):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return py_icp(source, target)

    out = tmp_path / "resumed.jsonl"
    with pytest.raises(KeyboardInterrupt):
        regbench.run(pair_file, ["icp", ("py_icp", interrupted)], out)
    assert not out.exists()
    kept = read_jsonl(str(out) + ".part")
    assert len(kept) == 5  # pairs 0 and 1, and icp on pair 2; the interrupted call is dropped
    summary = regbench.run(pair_file, ["icp", py_icp], out, resume=True)
    assert summary["rows_skipped"] == 5 and summary["rows_written"] == 3
    assert [untimed(r) for r in read_jsonl(out)] == [untimed(r) for r in read_jsonl(clean)]
    assert not os.path.exists(str(out) + ".part")


RUNNER = textwrap.dedent("""
    import os, signal, sys, time
    sys.path.insert(0, {tests!r})
    import regbench
    from conftest import numpy_icp
    calls = []
    def py_icp(source, target):
        calls.append(1)
        if {mode!r} == "kill" and len(calls) == 3:
            os.kill(os.getpid(), signal.SIGKILL)
        if {mode!r} == "sigint":
            print("call", flush=True)
            time.sleep(0.3)
        return numpy_icp(source, target)
    try:
        regbench.run({pairs!r}, ["icp", py_icp], {out!r})
    except KeyboardInterrupt:
        sys.exit(42)
""")


@pytest.mark.parametrize("mode", ["kill", "sigint"])
def test_resume_after_killed_or_interrupted_process(pairs_path, pair_file, tmp_path, mode):
    clean = tmp_path / "clean.jsonl"
    regbench.run(pair_file, ["icp", py_icp], clean)
    out = tmp_path / "out.jsonl"
    script = RUNNER.format(tests=os.path.dirname(__file__), mode=mode, pairs=pairs_path,
                           out=str(out))
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    if mode == "sigint":
        proc.stdout.readline()
        proc.stdout.readline()  # the second call is running: at least two rows are written
        proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=120)
    assert proc.returncode == (-signal.SIGKILL if mode == "kill" else 42)
    assert not out.exists()
    kept = read_jsonl(str(out) + ".part")
    assert 1 <= len(kept) < 2 * len(pair_file)
    summary = regbench.run(pair_file, ["icp", py_icp], out, resume=True)
    assert summary["rows_skipped"] == len(kept)
    assert [untimed(r) for r in read_jsonl(out)] == [untimed(r) for r in read_jsonl(clean)]


def test_resume_refuses_other_parameters(pair_file, tmp_path):
    out = tmp_path / "r.jsonl"
    regbench.run(pair_file, [py_icp], out, params={"py_icp": {"iterations": 2}})
    with pytest.raises(RuntimeError, match="ran with other parameters"):
        regbench.run(pair_file, [py_icp], out, params={"py_icp": {"iterations": 3}},
                     resume=True)


def test_read_results_and_report(pairs_path, pair_file, tmp_path):
    out = tmp_path / "both.jsonl"
    regbench.run(pair_file, ["icp", py_icp], out, jobs=2)
    rows = regbench.read_results(out, as_frame=False)
    assert rows == read_jsonl(out)
    frame = regbench.read_results(out)
    import pandas

    assert isinstance(frame, pandas.DataFrame) and len(frame) == 2 * len(pair_file)
    assert list(frame["method"][:2]) == ["icp", "py_icp"]
    np.testing.assert_array_equal(frame["metrics.mae_r"], [r["metrics"]["mae_r"] for r in rows])
    assert (frame["cpu_seconds"] > 0).all()
    table = cli("report", out).stdout
    assert "| icp |" in table and "| py_icp |" in table
    bad = tmp_path / "bad.jsonl"
    bad.write_text(open(out).readline() + "{not json\n")
    with pytest.raises(ValueError, match=f"{bad}:2"):
        regbench.read_results(bad)


# Issue 44 group 7.
def test_absurd_thread_counts_raise_instead_of_killing_the_interpreter(pair_file, tmp_path):
    pair = pair_file[0]
    for threads in (10**9, 1025):
        with pytest.raises(ValueError, match=r"threads must be in \[1, 1024\]"):
            regbench.align(pair.source, pair.target, "icp", threads=threads)
        with pytest.raises(ValueError, match=r"threads must be in \[1, 1024\]"):
            regbench.run(pair_file, ["icp"], tmp_path / "t.jsonl", threads=threads)
    assert not (tmp_path / "t.jsonl").exists()


def test_extras_too_deep_for_a_row_fail_the_call_not_the_run(pair_file, tmp_path):
    def deep(source, target):
        extra = []
        for _ in range(100):
            extra = [extra]
        return {"transform": np.eye(4), "trace": extra}

    def shallow(source, target):
        extra = []
        for _ in range(61):  # 62 nested lists inside the row and its extra: 64 levels, the limit
            extra = [extra]
        return {"transform": np.eye(4), "trace": extra}

    out = tmp_path / "deep.jsonl"
    summary = regbench.run(pair_file, [deep, shallow], out)
    assert summary["failures"] == len(pair_file)
    rows = regbench.read_results(out, as_frame=False)  # the run's own rows read back
    by_method = {}
    for r in rows:
        by_method.setdefault(r["method"], []).append(r)
    assert all(r["status"] == "failed" for r in by_method["deep"])
    assert "nested deeper than 64 levels" in by_method["deep"][0]["message"]
    assert all(r["status"] == "ok" for r in by_method["shallow"])


def test_system_exit_in_a_callable_stops_the_run_as_keyboard_interrupt(pair_file, tmp_path):
    def leaves(source, target):
        raise SystemExit(3)

    out = tmp_path / "exit.jsonl"
    with pytest.raises(KeyboardInterrupt, match="SystemExit"):
        regbench.run(pair_file, ["icp", leaves], out)
    assert not out.exists()
    assert os.path.exists(str(out) + ".part")  # the finished rows stay for resume


def test_a_transform_whose_last_row_is_not_0_0_0_1_fails_the_call(pair_file, tmp_path):
    def projective(source, target):
        T = np.eye(4)
        T[3, 0] = 0.5  # the rotation block is rigid: only the last row is wrong
        return T

    out = tmp_path / "last_row.jsonl"
    summary = regbench.run(pair_file, [projective, ("eye", lambda s, t: np.eye(4))], out)
    assert summary["failures"] == len(pair_file)
    for r in read_jsonl(out):
        if r["method"] == "projective":
            assert r["status"] == "failed"
            assert r["message"] == \
                "projective: produced a transform whose last row is not (0, 0, 0, 1)"
        else:
            assert r["status"] == "ok"


def test_method_names_that_rows_cannot_hold_are_refused_before_the_run(pair_file, tmp_path):
    def fn(source, target):
        return np.eye(4)

    def unencodable(source, target):
        return np.eye(4)

    unencodable.__name__ = "\udcff"  # os.fsdecode(b"\xff")
    out = tmp_path / "names.jsonl"
    cases = [
        (("", fn), "method name is empty"),  # left an OUT.part that resume could not read
        (("\udcff", fn), r"method name '\\udcff' cannot be encoded as UTF-8"),
        (unencodable, r"method name '\\udcff' cannot be encoded as UTF-8"),
        (("a\nb", fn), r"method name 'a\\nb' contains a control character"),
        (("a\tb", fn), r"method name 'a\\tb' contains a control character"),
        (("a,b", fn), "method name 'a,b' must not contain commas or spaces"),
    ]
    for method, message in cases:
        with pytest.raises(ValueError, match=message):
            regbench.run(pair_file, ["identity", method], out)
        assert not out.exists() and not os.path.exists(str(out) + ".part")
    regbench.run(pair_file, [("é_1", fn)], out)  # any other UTF-8 name
    assert {r["method"] for r in regbench.read_results(out, as_frame=False)} == {"é_1"}


def test_an_integer_4x4_is_a_transform(pair_file, tmp_path):
    out = tmp_path / "ints.jsonl"
    summary = regbench.run(pair_file, [("int_eye", lambda s, t: np.eye(4, dtype=np.int64)),
                                       ("list_eye", lambda s, t: np.eye(4, dtype=int).tolist()),
                                       ("bool_eye", lambda s, t: np.eye(4, dtype=bool)),
                                       "identity"], out)
    assert summary["failures"] == len(pair_file)
    rows = {(r["pair"], r["method"]): r for r in read_jsonl(out)}
    for k in range(len(pair_file)):
        for name in ("int_eye", "list_eye"):
            assert rows[(k, name)]["status"] == "ok"
            assert rows[(k, name)]["metrics"] == rows[(k, "identity")]["metrics"]
        assert rows[(k, "bool_eye")]["message"] == \
            "bool_eye: the returned transform must have a floating-point or integer dtype, " \
            "got bool"
    pair = pair_file[0]
    assert regbench.metrics(np.eye(4, dtype=np.int32), pair.T_gt, pair.source, pair.target) == \
        regbench.metrics(np.eye(4), pair.T_gt, pair.source, pair.target)


@pytest.mark.parametrize("raised", ["KeyboardInterrupt", "SystemExit"])
def test_interrupts_under_timeout_stop_the_run(pair_file, tmp_path, raised):
    # With timeout= the callable runs in a forked child: its KeyboardInterrupt or SystemExit
    # became a `failed` row and the run went on.
    def stops(source, target):
        if np.array_equal(source, pair_file[1].source):
            raise KeyboardInterrupt("stop here") if raised == "KeyboardInterrupt" \
                else SystemExit(3)
        return np.eye(4)

    assert not np.array_equal(pair_file[0].source, pair_file[1].source)
    out = tmp_path / "stopped.jsonl"
    message = "stop here" if raised == "KeyboardInterrupt" else \
        "SystemExit raised in a callable: SystemExit: 3"
    with pytest.raises(KeyboardInterrupt, match=message):
        regbench.run(pair_file, ["identity", stops], out, timeout=60)
    assert not out.exists()
    kept = read_jsonl(str(out) + ".part")
    # Pair 0 and identity on pair 1; the interrupted call is not written.
    assert [(r["pair"], r["method"]) for r in kept] == [(0, "identity"), (0, "stops"),
                                                         (1, "identity")]
    assert all(r["status"] == "ok" for r in kept)

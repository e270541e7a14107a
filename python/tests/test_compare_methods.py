"""regbench.compare_methods: method against method on common pairs (issue 41 item 1), checked
against numpy on the same rows; its p and CI come from one paired bootstrap (issue 54 item 5)
and must agree."""
import numpy as np
import pytest

import regbench
from conftest import cli, read_jsonl


@pytest.fixture(scope="module")
def two_methods(tmp_path_factory):
    d = tmp_path_factory.mktemp("versus")
    pairs, out = d / "pairs12.h5", d / "r.jsonl"
    cli("generate", "--protocol", "partial", "--dataset", "procedural", "--split", "test",
        "--pairs", 12, "--points", 200, "--seed", 5, "--out", pairs)
    cli("run", "--pairs", pairs, "--methods", "identity,icp", "--out", out, "-q")
    return out


def test_compare_methods_agrees_with_scipy(two_methods):
    rows = read_jsonl(two_methods)
    (result,) = regbench.compare_methods(two_methods, "icp", "identity")
    assert (result["method_a"], result["method_b"], result["common"]) == ("icp", "identity", 12)
    by = {m: {r["pair"]: r["metrics"] for r in rows if r["method"] == m}
          for m in ("icp", "identity")}
    for entry in result["metrics"]:
        name = entry["metric"]
        a = np.array([by["icp"][k][name] for k in range(12)])
        b = np.array([by["identity"][k][name] for k in range(12)])
        d = a - b
        assert entry["pairs"] == 12
        assert entry["diff_mean"] == pytest.approx(d.mean(), rel=1e-12, abs=1e-15)
        assert entry["mean_a"] == pytest.approx(a.mean(), rel=1e-12)
        assert (entry["wins"], entry["ties"], entry["losses"]) == \
               ((d < 0).sum(), (d == 0).sum(), (d > 0).sum())
        assert entry["ci_lo"] <= entry["diff_mean"] <= entry["ci_hi"]
        # One procedure: p <= 0.05 exactly when the CI excludes 0, and the verdict follows.
        excludes = entry["ci_lo"] > 0 or entry["ci_hi"] < 0
        assert (entry["p_value"] <= 0.05) == excludes == entry["differs"]
        assert entry["verdict"].startswith(name + (": " if excludes else ": no difference"))
    # The swapped comparison mirrors it; a method the file lacks is named with those it holds.
    (swapped,) = regbench.compare_methods([two_methods], "identity", "icp")
    assert swapped["metrics"][0]["diff_mean"] == pytest.approx(-result["metrics"][0]["diff_mean"])
    with pytest.raises(ValueError, match="no rows of method 'ogmm'; the results hold"):
        regbench.compare_methods(two_methods, "icp", "ogmm")


def test_report_versus_prints_the_same_numbers(two_methods):
    (result,) = regbench.compare_methods(two_methods, "icp", "identity")
    text = cli("report", two_methods, "--versus", "icp,identity").stdout
    assert "icp vs identity" in text
    mae_r = result["metrics"][0]
    # The compact table shows a mean without a CI to three significant digits (11.727 -> 11.7).
    assert f"| mae_r | 12 | {mae_r['mean_a']:.3g} |" in text
    bad = cli("report", two_methods, "--versus", "icp", check=False)
    assert bad.returncode == 2 and "--versus takes two" in bad.stderr

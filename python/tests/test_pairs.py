"""PairFile: what Python reads equals h5py's view of the file; bad files raise with the
C++ reader's message."""
import json
import os
import shutil

import h5py
import numpy as np
import pytest

import regbench


def text(value):
    """h5py gives fixed-length string attributes as bytes."""
    return value.decode() if isinstance(value, bytes) else value


def test_pairs_equal_h5py(pairs_path, pair_file):
    with h5py.File(pairs_path, "r") as f:
        assert len(pair_file) == len(f["pairs"]) == int(f.attrs["num_pairs"])
        provenance = json.loads(f.attrs["provenance"])
        assert pair_file.provenance == provenance
        assert pair_file.seed == provenance["seed"] == 3
        assert pair_file.dataset == provenance["dataset"]
        assert pair_file.protocol == provenance["protocol"] == "partial"
        for k, pair in enumerate(pair_file):
            g = f["pairs"][f"{k:06d}"]
            assert pair.index == k
            assert pair.source.dtype == np.float64 and pair.source.shape[1] == 3
            np.testing.assert_array_equal(pair.source, g["source"][()])
            np.testing.assert_array_equal(pair.target, g["target"][()])
            np.testing.assert_array_equal(pair.T_gt, g["T_gt"][()])
            np.testing.assert_array_equal(pair.source_overlap, g["source_overlap"][()])
            np.testing.assert_array_equal(pair.target_overlap, g["target_overlap"][()])
            assert pair.source_overlap_ratio == g.attrs["source_overlap_ratio"]
            assert pair.target_overlap_ratio == g.attrs["target_overlap_ratio"]
            assert pair.overlap == pair.source_overlap_ratio
            assert pair.shape == text(g.attrs["shape"])
            assert pair.category == text(g.attrs["category"])
            assert pair.content_hash == pair_file.content_hash
            assert pair.data == pair_file.data


def test_provenance_tag_matches_cli_rows(pairs_path, pair_file, tmp_path):
    from conftest import cli, read_jsonl

    out = tmp_path / "identity.jsonl"
    cli("run", "--pairs", pairs_path, "--methods", "identity", "--out", out, "--quiet")
    row = read_jsonl(out)[0]
    assert row["data"] == pair_file.data == pair_file[0].data
    assert row["data"]["content_hash"].startswith("fnv1a64:")


def test_indexing_and_views(pair_file):
    n = len(pair_file)
    assert pair_file[-1].index == n - 1
    with pytest.raises(IndexError):
        pair_file[n]
    with pytest.raises(IndexError):
        pair_file[-n - 1]
    assert [p.index for p in pair_file] == list(range(n))
    pair = pair_file[0]
    # Views of the PairFile's arrays, no copy: the same memory each time.
    assert np.shares_memory(pair.source, pair_file[0].source)
    assert pair.source.base is not None and not pair.source.flags.owndata
    # A view outlives the objects it came from.
    src = regbench.PairFile(pair_file.path)[1].source
    np.testing.assert_array_equal(src, pair_file[1].source)
    assert "pairs.h5" in repr(pair_file) and "Pair 0" in repr(pair)


def test_missing_file_raises_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such pair file"):
        regbench.PairFile(tmp_path / "absent.h5")


def test_damaged_file_raises_value_error_naming_it(pairs_path, tmp_path):
    bad = tmp_path / "truncated.h5"
    data = open(pairs_path, "rb").read()
    bad.write_bytes(data[: len(data) // 3])
    with pytest.raises(ValueError, match=str(bad)):
        regbench.PairFile(bad)


def test_modified_file_refused_by_content_hash(pairs_path, tmp_path):
    changed = tmp_path / "changed.h5"
    shutil.copy(pairs_path, changed)
    with h5py.File(changed, "r+") as f:
        f["pairs"]["000002"]["source"][0, 0] += 1e-3
    with pytest.raises(ValueError, match="content hash"):
        regbench.PairFile(changed)


def test_views_work_with_open3d(pair_file):
    o3d = pytest.importorskip("open3d")
    pair = pair_file[0]
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pair.source))
    np.testing.assert_array_equal(np.asarray(cloud.points), pair.source)


def test_bad_pair_named_in_the_value_error(pairs_path, tmp_path):
    bad = tmp_path / "nan.h5"
    shutil.copy(pairs_path, bad)
    with h5py.File(bad, "r+") as f:
        f["pairs"]["000002"]["source"][5, 1] = np.nan
    with pytest.raises(ValueError, match=rf"^{bad}: pair 2: .*non-finite value \(row 5\)"):
        regbench.PairFile(bad)
    # run() refuses it the same way, before writing anything.
    with pytest.raises(ValueError, match=rf"^{bad}: pair 2: "):
        regbench.run(bad, ["identity"], tmp_path / "r.jsonl")
    assert not (tmp_path / "r.jsonl").exists()

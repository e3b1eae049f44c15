"""`calbench.run(..., shard=(i, n), out=DIR)`: shard folders that `calbench merge` merges into
the bytes of the whole run; bad shards refused."""
import json
import tomllib

import numpy as np
import pytest

import calbench

CI_GUARD = "scenarios/ci-guard.toml"


def test_two_python_shards_merge_into_the_bytes_of_one_cli_run(cli, root, tmp_path):
    cli("run", CI_GUARD, "--trials", "5", "--seed", "11", "--out", tmp_path / "whole")
    with open(root / CI_GUARD, "rb") as f:
        as_dict = tomllib.load(f)
    # One shard from the file, one from the dict, with different thread counts; the second's
    # (i, n) as a numpy array.
    s0 = calbench.run(root / CI_GUARD, trials=5, seed=11, threads=1, shard=(0, 2), out=tmp_path / "s0")
    s1 = calbench.run(as_dict, trials=5, seed=11, threads=2, shard=np.array([1, 2]), out=tmp_path / "s1")
    assert s0 == tmp_path / "s0" and s1 == tmp_path / "s1"
    meta = json.loads((s1 / "shard.json").read_text())
    assert meta["shard"] == {"index": 1, "count": 2}
    assert set(meta["machine"]) == {"host", "cpu", "cores", "os"} and meta["machine"]["cores"] >= 1
    cli("merge", s1, s0, "--out", tmp_path / "merged")
    for name in ("summary.json", "trials.csv"):
        assert (tmp_path / "merged" / name).read_bytes() == (tmp_path / "whole" / name).read_bytes()


@pytest.mark.parametrize(
    "shard, match",
    [
        ((2, 2), r"shard.*\(2, 2\)"),
        ((-1, 2), "shard"),
        ((0, 0), "shard"),
        ((0,), "shard"),
        ("0/2", "shard"),
        ((True, 2), "shard"),
        ((0.0, 2), "shard"),
        (np.array([0.0, 2.0]), "shard"),
        (np.array([[0, 2]]), "shard"),
        (np.array([True, True]), "shard"),
    ],
)
def test_bad_shards_are_refused(root, tmp_path, shard, match):
    with pytest.raises(calbench.SettingError, match=match):
        calbench.run(root / CI_GUARD, trials=1, shard=shard, out=tmp_path / "s")
    assert not (tmp_path / "s").exists()


def test_a_shard_needs_out_and_no_python_methods(root, tmp_path):
    with pytest.raises(calbench.SettingError, match="out"):
        calbench.run(root / CI_GUARD, trials=1, shard=(0, 2))
    with pytest.raises(calbench.SettingError, match="out"):
        calbench.run(root / CI_GUARD, trials=1, out=tmp_path / "s")
    with pytest.raises(calbench.SettingError, match="methods"):
        calbench.run(
            root / CI_GUARD,
            trials=1,
            shard=(0, 2),
            out=tmp_path / "s",
            methods={"mine": lambda p: p.x0},
        )
    assert not (tmp_path / "s").exists()


def test_a_shard_refused_once_it_runs_leaves_no_folder_it_made(tmp_path):
    # LS cannot take the IRB 2600's parameters that positions do not determine: refused once
    # the run starts, after its checkpoint is made beside the shard folder.
    scenario = {
        "name": "all", "seed": 9, "trials": 2, "robot": {"builtin": "irb2600"},
        "errors": {"kind": "paper"}, "tracker": {"pose": [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]},
        "outliers": {"count": 0, "magnitude_mm": [0.5, 1.0]}, "compliance": {"model": "none"},
        "calibration": {"count": 25, "strategies": ["random"]}, "validation": {"count": 10},
        "identification": {"params": "all"}, "methods": [{"name": "ls"}],
    }
    with pytest.raises(calbench.Error, match="identification.params"):
        calbench.run(scenario, shard=(0, 2), out=tmp_path / "new" / "s")
    assert list(tmp_path.iterdir()) == []

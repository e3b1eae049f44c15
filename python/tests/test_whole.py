"""`calbench.run(scenario, out=DIR)` of the studies that run whole, Ban fig. 3's registration
study and an instruments study: the folder `calbench run SCENARIO --out DIR` writes, byte for
byte, which `calbench record` stores; settings they cannot take refused."""
import tomllib

import pytest

import calbench

FIG3 = "scenarios/ban-fig3.toml"

# Two instruments at 40 random poses: two cells of three trials.
INSTRUMENTS = """
name = "instruments-python"
seed = 11
trials = 3
robot = "irb2600"

[instruments_study]
poses = [40]
strategies = ["random"]
candidates = 80
validation = 10

[errors]
kind = "paper"
length_mm = 0.1
angle_rad = 0.0005

[[measurement]]
kind = "position"

[[measurement]]
kind = "distance"
noise_um = 1.0
scale_um_per_m = 1.0
"""


def _same_folders(a, b):
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    assert {"summary.json", "report.md", "scenario.toml"} <= set(names)
    for name in names:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


def _recorded(cli, out, db):
    said = cli("record", out, "--db", db).stdout
    assert f"recorded {out} as run" in said, said
    return said


def test_a_registration_study_from_python_is_the_cli_run_byte_for_byte_and_is_recorded(
    cli, root, tmp_path
):
    cli("run", FIG3, "--trials", "3", "--threads", "2", "--out", tmp_path / "cli")
    out = calbench.run(root / FIG3, trials=3, threads=1, out=tmp_path / "py")
    assert out == tmp_path / "py"
    _same_folders(tmp_path / "cli", out)
    said = _recorded(cli, out, tmp_path / "db.sqlite")
    assert "of ban-fig3 (40 entries" in said, said


def test_an_instruments_study_from_python_is_the_cli_run_byte_for_byte_and_is_recorded(
    cli, tmp_path
):
    scenario = tmp_path / "instruments.toml"
    scenario.write_text(INSTRUMENTS)
    cli("run", scenario, "--out", tmp_path / "cli")
    # From the dict of the same file, as a notebook builds it.
    out = calbench.run(tomllib.loads(INSTRUMENTS), out=tmp_path / "py")
    _same_folders(tmp_path / "cli", out)
    said = _recorded(cli, out, tmp_path / "db.sqlite")
    assert "of instruments-python (2 entries" in said, said


def test_a_registration_study_in_two_python_shards_merges_into_the_cli_run(cli, root, tmp_path):
    cli("run", FIG3, "--trials", "3", "--out", tmp_path / "cli")
    for i in range(2):
        calbench.run(root / FIG3, trials=3, shard=(i, 2), out=tmp_path / f"s{i}")
    cli("merge", tmp_path / "s0", tmp_path / "s1", "--out", tmp_path / "merged")
    _same_folders(tmp_path / "cli", tmp_path / "merged")


@pytest.mark.parametrize(
    "more, match",
    [
        ({}, "setting `out`"),
        ({"out": "x", "precision": "1%"}, "setting `precision`"),
        ({"out": "x", "methods": {"mine": lambda p: p.x0}}, "setting `methods`"),
    ],
)
def test_what_a_study_that_runs_whole_cannot_take_is_refused(root, tmp_path, more, match):
    if "out" in more:
        more["out"] = tmp_path / more["out"]
    with pytest.raises(calbench.SettingError, match=match):
        calbench.run(root / FIG3, trials=3, **more)
    assert not (tmp_path / "x").exists()

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


def test_an_instruments_trial_simulated_from_python_is_the_cli_folder_and_identifies(
    cli, tmp_path
):
    scenario = tmp_path / "instruments.toml"
    scenario.write_text(INSTRUMENTS)
    cli("simulate", scenario, "--trial", "1", "--measure", "distance", "--out", tmp_path / "cli")
    sim = calbench.simulate(scenario, trial=1, measure="distance", out=tmp_path / "py")
    for name in ("measurements.csv", "validation.csv", "truth.json"):
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "py" / name).read_bytes()
    assert sim["kind"] == "distance"
    assert sim["data"] == tmp_path / "py" / "measurements.csv"
    assert sim["q"].shape == (40, 6) and sim["validation_points"].shape == (10, 3)
    assert sim["info"]["measurement"] == 1 and sim["info"]["trial"] == 1
    assert sim["truth"] and set(sim["truth"]) == set(sim["info"]["errors"])
    # The readings are a distance file, which identify takes as data (the pivot unknown).
    rec = calbench.identify(
        sim["robot"], data=sim["data"], method="ls", validate=tmp_path / "py" / "validation.csv"
    )
    assert rec.termination == "converged", rec.termination
    before, after = rec["validation_before_mm"]["rms"], rec["validation_after_mm"]["rms"]
    assert before > 0.5 and after < 0.02, (before, after)
    # From the dict of the same file: the first entry when measure is not given.
    first = calbench.simulate(tomllib.loads(INSTRUMENTS), out=tmp_path / "first")
    assert first["kind"] == "position"


@pytest.mark.parametrize(
    "more, match",
    [
        ({}, "setting `out`"),
        ({"out": "x", "measure": "sphere"}, "setting `measure`: .* has no \\[\\[measurement\\]\\] of kind sphere \\(it has position, distance\\)"),
        ({"out": "x", "measure": "laser"}, "setting `measure`: .*laser"),
        ({"out": "x", "trial": 3}, "setting `trial`: 3 is not below the scenario's trials = 3"),
    ],
)
def test_what_an_instruments_simulation_cannot_take_is_refused(tmp_path, more, match):
    scenario = tmp_path / "instruments.toml"
    scenario.write_text(INSTRUMENTS)
    if "out" in more:
        more["out"] = tmp_path / more["out"]
    with pytest.raises(calbench.SettingError, match=match):
        calbench.simulate(scenario, **more)
    assert not (tmp_path / "x").exists()


def test_a_monte_carlo_trial_simulated_with_out_is_the_cli_folder(cli, root, tmp_path):
    cli("simulate", "scenarios/ci-guard.toml", "--trial", "2", "--out", tmp_path / "cli")
    sim = calbench.simulate(root / "scenarios/ci-guard.toml", trial=2, out=tmp_path / "py")
    for name in ("measurements.csv", "validation.csv", "truth.json"):
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "py" / name).read_bytes()
    assert sim["points"].shape[1] == 3
    with pytest.raises(calbench.SettingError, match="setting `measure`: .*not an instruments study"):
        calbench.simulate(root / "scenarios/ci-guard.toml", measure="distance")

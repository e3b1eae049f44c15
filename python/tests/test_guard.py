"""Every front end is guarded alike (docs/formats.md § 1, "Output folders"): Python's `run`
with a shard folder, `study.write` and `task` refuse the root folder, the home folder and
an input, and write nothing; `identify` refuses an identified robot that cannot be
physically right unless `allow_implausible=True`; `run(precision=...)` says where it
stopped."""
import os

import numpy as np
import pytest

import calbench

CI_GUARD = "scenarios/ci-guard.toml"


def test_a_shard_into_the_root_folder_is_refused_and_writes_nothing(root):
    before = sorted(os.listdir("/"))
    with pytest.raises(calbench.Error, match="root folder"):
        calbench.run(root / CI_GUARD, trials=2, shard=(0, 2), out="/")
    assert sorted(os.listdir("/")) == before


def test_study_write_into_home_is_refused_and_writes_nothing(root, tmp_path, monkeypatch):
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    study = calbench.run(root / CI_GUARD, trials=2)
    for target in (home, str(home), home / "." / ".." / "home"):
        with pytest.raises(calbench.Error, match="home folder"):
            study.write(target)
        assert list(home.iterdir()) == []
    with pytest.raises(calbench.Error, match="root folder"):
        study.write("/")
    # An empty path is not the root folder (it had been refused as one).
    with pytest.raises(calbench.SettingError, match="`out`: is empty"):
        study.write("")
    # A NUL byte, which no file name holds: the argument's, where the refusal was an IoError
    # naming the outputs' temporary folder.
    with pytest.raises(calbench.SettingError, match=r'`out`: "a\\0b" holds a NUL byte') as e:
        study.write("a\x00b")
    assert "partial" not in str(e.value)
    assert not os.path.exists("a")
    # An empty input path is refused naming its argument, where the refusal named none.
    robot = calbench.Robot.builtin("irb2600")
    for call, key in [(lambda: calbench.identify(robot, data=""), "data"),
                      (lambda: calbench.Robot.from_file(""), "path"),
                      (lambda: calbench.run(""), "scenario"),
                      (lambda: calbench.simulate(""), "scenario"),
                      (lambda: calbench.compare("", root / "results" / "ci-guard"), "a"),
                      (lambda: calbench.compare(root / "results" / "ci-guard", ""), "b"),
                      (lambda: calbench.task("", "lm"), "task")]:
        with pytest.raises(calbench.SettingError, match=f"`{key}`: is empty"):
            call()
    with pytest.raises(calbench.Error, match="home folder"):
        calbench.run(root / CI_GUARD, trials=2, shard=(0, 2), out=home)
    assert list(home.iterdir()) == []
    study.write(tmp_path / "fine")
    assert (tmp_path / "fine" / "summary.json").exists()


def test_writers_refuse_the_scenario_they_would_overwrite_and_another_commands_folder(
        root, tmp_path, cli):
    # A scenario named scenario.toml in the output folder is an input a whole run would
    # overwrite with its scenario.toml; an identification's folder holds another command's
    # results. `calbench run --out` refuses both, and so do the Python writers.
    folder = tmp_path / "own"
    folder.mkdir()
    scenario = folder / "scenario.toml"
    text = (root / CI_GUARD).read_text() + "# the user's own note\n"
    scenario.write_text(text)
    study = calbench.run(scenario, trials=2)
    with pytest.raises(calbench.SettingError, match="`out`: .*scenario.toml"):
        study.write(folder)
    r = cli("run", scenario, "--trials", "2", "--out", folder, ok=False)
    assert r.returncode == 1 and "scenario.toml" in r.stderr, r.stderr
    assert sorted(os.listdir(folder)) == ["scenario.toml"]
    assert scenario.read_text() == text
    # A shard writes no scenario.toml (its folder is trials.csv, records.txt, shard.json):
    # the user's file beside it is kept.
    calbench.run(scenario, trials=2, shard=(0, 2), out=folder)
    assert sorted(os.listdir(folder)) == [
        "records.txt", "scenario.toml", "shard.json", "trials.csv"]
    assert scenario.read_text() == text
    identified = tmp_path / "identified"
    identified.mkdir()
    (identified / "identified.json").write_text("{}\n")
    with pytest.raises(calbench.SettingError, match="an identification"):
        study.write(identified)
    assert sorted(os.listdir(identified)) == ["identified.json"]


def test_a_task_into_an_input_or_home_is_refused(root, tmp_path, monkeypatch):
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    with pytest.raises(calbench.Error, match="home folder"):
        calbench.task("ipa-ur10-series-a", "lm", out=home)
    assert list(home.iterdir()) == []
    data = root / "data" / "ipa-ur10-series-a"
    listing = sorted(os.listdir(data))
    with pytest.raises(calbench.Error, match="input"):
        calbench.task("ipa-ur10-series-a", "lm", out=data)
    assert sorted(os.listdir(data)) == listing


def _metres(sim):
    return sim["points"] / 1000.0


def test_identify_refuses_an_implausible_robot_unless_allowed(root):
    sim = calbench.simulate(root / CI_GUARD, trial=1)
    robot = calbench.Robot.builtin("irb2600")
    with pytest.raises(calbench.Error, match="metres") as e:
        calbench.identify(robot, q=sim["q"], points=_metres(sim), method="ls")
    assert "allow_implausible=True" in str(e.value)
    swapped = sim["points"][:, [1, 0, 2]]
    with pytest.raises(calbench.Error, match="two columns look swapped"):
        calbench.identify(robot, q=sim["q"], points=swapped, method="ls")
    with pytest.warns(UserWarning, match="kept because of allow_implausible=True"):
        kept = calbench.identify(
            robot, q=sim["q"], points=_metres(sim), method="ls", allow_implausible=True
        )
    assert any("metres" in f for f in kept["allowed_implausible"])
    good = calbench.identify(robot, q=sim["q"], points=sim["points"], method="ls")
    assert "allowed_implausible" not in good
    assert np.isfinite(good["rms_residual_mm"])


def test_run_with_precision_returns_its_shortfall(root, cli, tmp_path):
    # The shortfall is raised as a UserWarning in `calbench run --precision`'s words; it had
    # been printed by the command line alone.
    with pytest.warns(UserWarning, match=r"^precision ±0.01% not reached: stopped at the cap "
                                         r"of 10 trials") as caught:
        study = calbench.run(root / CI_GUARD, trials=10, precision="0.01%")
    r = cli("run", root / CI_GUARD, "--trials", "10", "--precision", "0.01%", "--out",
            tmp_path / "cli")
    assert f"warning: {caught[0].message}\n" in r.stderr
    stopping = study.summary["stopping"]
    assert stopping["reached"] is False and stopping["trials"] == 10
    assert stopping["trials_needed"] > 10
    assert " / " in stopping["widest_entry"]
    with pytest.raises(calbench.SettingError, match="precision"):
        calbench.run(root / CI_GUARD, trials=10, precision="5")


def test_a_registration_that_did_not_settle_warns_as_the_command_line_does(root, cli, tmp_path):
    # `calbench identify` printed that the registration did not settle; Python had said
    # nothing of it (only the identification's own non-convergence).
    calbench.simulate(root / CI_GUARD, out=tmp_path / "sim")
    data = tmp_path / "sim" / "measurements.csv"
    robot = calbench.Robot.builtin("irb2600")
    with pytest.warns(UserWarning) as caught:
        r = calbench.identify(robot, data=data, method="igg3", registration="svd",
                              options={"max_iter": 2})
    assert r["registration_termination"] == "max-rounds"
    said = [str(w.message) for w in caught if w.category is UserWarning]
    assert len(said) == 1 and said[0].startswith("svd registration and identification did "
                                                 "not settle"), said
    out = cli("identify", "--robot", "irb2600", "--data", data, "--method", "igg3",
              "--registration", "svd", "--set", "max_iter=2", "--out", tmp_path / "cli")
    assert f"warning: {said[0]}\n" in out.stderr
    # A chosen kernel residual, which the returned robot lacks, as robot.toml does.
    with pytest.warns(UserWarning, match=r"kernel residual `gp` is not in `robot`"):
        calbench.identify(robot, data=data, method="lm", models="kinematic+gp")
    out = cli("identify", "--robot", "irb2600", "--data", data, "--method", "lm", "--models",
              "kinematic+gp", "--out", tmp_path / "gp")
    assert "warning: the chosen model's kernel residual `gp` is written to kernel.json" in out.stderr


def test_with_errors_beyond_the_model_ranges_is_refused():
    robot = calbench.Robot.builtin("irb2600")
    with pytest.raises(calbench.SettingError, match="errors"):
        robot.with_errors({"a2": 1e308})
    robot.with_errors({"a2": 0.5})


def test_a_folder_named_like_an_output_file_is_refused_before_any_work(root, tmp_path):
    """`out` holding a folder named like one of the files written is refused before the work,
    with the command line's words (docs/formats.md § 1.7), by every Python writer of a folder:
    a run's shard, a registration study, `simulate` and `task`. The refusal after the work
    (the folder written whole) said "an output file of that name is to be written"."""
    early = "is a folder, where the command writes a file of that name; nothing was written"
    cases = [
        ("trials.csv", lambda out: calbench.run(
            root / CI_GUARD, trials=2000, threads=1, shard=(0, 1), out=out)),
        ("summary.json", lambda out: calbench.run(
            root / "scenarios/ban-fig3.toml", trials=2, out=out)),
        ("truth.json", lambda out: calbench.simulate(root / CI_GUARD, trial=0, out=out)),
        ("identified.json", lambda out: calbench.task("barrett-wam", "lm", out=out)),
    ]
    for name, write in cases:
        out = tmp_path / f"out-{name}"
        (out / name).mkdir(parents=True)
        with pytest.raises(calbench.SettingError, match="out") as e:
            write(out)
        assert early in str(e.value), (name, str(e.value))
        assert sorted(p.name for p in out.iterdir()) == [name], name


def test_a_shard_and_a_whole_run_refuse_each_others_folder(root, tmp_path):
    # A shard's files beside a whole run's, or a whole run's beside a shard's, would be read
    # together (a stale summary.json, a stale records.txt for `merge`): refused, as on the
    # command line, before any work.
    whole, shard = tmp_path / "whole", tmp_path / "shard"
    study = calbench.run(root / CI_GUARD, trials=2)
    study.write(whole)
    calbench.run(root / CI_GUARD, trials=2, shard=(0, 2), out=shard)
    before = {d: sorted(os.listdir(d)) for d in (whole, shard)}
    with pytest.raises(calbench.SettingError, match=r"a study's run \(summary.json\)"):
        calbench.run(root / CI_GUARD, trials=2, shard=(1, 2), out=whole)
    with pytest.raises(calbench.SettingError, match=r"a shard of a run \(shard.json\)"):
        study.write(shard)
    # A study of cells likewise: its shard into its whole run's folder.
    cells = tmp_path / "cells"
    calbench.run(root / "scenarios/ban-fig3.toml", trials=1, out=cells)
    with pytest.raises(calbench.SettingError, match=r"a study's run \(summary.json\)"):
        calbench.run(root / "scenarios/ban-fig3.toml", trials=1, shard=(0, 2), out=cells)
    assert {d: sorted(os.listdir(d)) for d in (whole, shard)} == before
    assert "shard.json" not in os.listdir(cells)


def test_two_threads_writing_one_folder_leave_one_studys_folder(root, tmp_path):
    """Two threads of one process write two studies into one folder at once: each writes
    the folder whole or is refused as another thread's folder. They had shared one temporary
    folder (named by the process), and one write failed while the other left a folder of
    both studies' files."""
    import threading

    studies = [calbench.run(root / CI_GUARD, trials=20, seed=s) for s in (1, 2)]
    alone = []
    for i, s in enumerate(studies):
        s.write(tmp_path / f"alone{i}")
        alone.append(tmp_path / f"alone{i}")
    names = sorted(p.name for p in alone[0].iterdir() if p.name != "timing.json")
    for attempt in range(3):
        out = tmp_path / f"both{attempt}"
        start = threading.Barrier(2)
        errors = []

        def write(study):
            start.wait()
            try:
                study.write(out)
            except calbench.Error as e:
                errors.append(str(e))

        threads = [threading.Thread(target=write, args=(s,)) for s in studies]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert all("another thread writes it" in e for e in errors), errors
        assert len(errors) < 2
        got = {n: (out / n).read_bytes() for n in names}
        whole = [all(got[n] == (a / n).read_bytes() for n in names) for a in alone]
        assert any(whole), (attempt, errors)
        assert not [p for p in tmp_path.iterdir() if ".partial-" in p.name]

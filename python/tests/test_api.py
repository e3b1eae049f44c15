"""The Python module against the command line: the same numbers, bytes and messages."""
import csv
import json
import math
import tomllib

import numpy as np
import pandas as pd
import pytest

import calbench

CI_GUARD = "scenarios/ci-guard.toml"


def load_scenario(root, name=CI_GUARD):
    with open(root / name, "rb") as f:
        return tomllib.load(f)


def read_measurements(path, n):
    a = np.genfromtxt(path, delimiter=",", names=True)
    q = np.stack([a[f"q{i}"] for i in range(1, n + 1)], 1)
    p = np.stack([a["x"], a["y"], a["z"]], 1)
    return q, p


@pytest.fixture(scope="module")
def simulated(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("sim")
    cli("simulate", CI_GUARD, "--trial", "1", "--out", out / "sim")
    return out / "sim"


# ----- Robot -----------------------------------------------------------------------------


def test_robot_builtin_and_its_names():
    r = calbench.Robot.builtin("irb2600")
    assert r.joint_count == 6 and r.name == "irb2600"
    names = r.parameter_names()
    assert "a1" in names and "tool.z" in names and len(names) == len(set(names))
    assert "irb2600" in calbench.robots() and "lm" in calbench.methods()
    assert "6 joints" in repr(r)


def test_fk_matches_the_cli(cli, root):
    r = calbench.Robot.builtin("irb2600")
    q = np.array([[10, -20, 30, 40, -50, 60], [0, 0, 0, 0, 0, 0]], dtype=float)
    p = r.fk(q)
    assert p.shape == (2, 3)
    text = cli("fk", "--robot", "irb2600", "--q", "10,-20,30,40,-50,60").stdout
    nums = [float(t) for t in text.replace(",", " ").replace("[", " ").replace("]", " ").split()
            if t.lstrip("-").replace(".", "", 1).replace("e-", "", 1).isdigit()]
    assert any(np.allclose(p[0], nums[i:i + 3], atol=1e-3) for i in range(len(nums) - 2)), text
    T = r.fk(q, pose=True)
    assert T.shape == (2, 4, 4)
    assert np.allclose(T[:, :3, 3], p)
    R = T[0, :3, :3]
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.allclose(T[:, 3], [0, 0, 0, 1])


def test_fk_applies_a_robot_files_whole_model_as_the_cli_does(cli, tmp_path):
    # docs/formats.md "Joint-angle harmonics", "Gravity basis": fk turns the joints by them.
    text = cli("robots", "irb2600").stdout
    joint2 = "theta = -90.0\n"
    q = [10.0, -20.0, 30.0, 40.0, -50.0, 60.0]
    rigid = calbench.Robot.builtin("irb2600").fk([q])[0]
    for extra in ("harmonics = [0.001, -0.002]", "gravity = [0.0005, 0.001, 0.002]"):
        path = tmp_path / "r.toml"
        path.write_text(text.replace(joint2, joint2 + extra + "\n", 1))
        p = calbench.Robot.from_file(path).fk([q])[0]
        out = json.loads(cli("fk", "--robot", path, "--q", ",".join(map(str, q)), "--json").stdout)
        assert np.allclose(p, out["position_mm"], atol=1e-9), extra
        assert np.linalg.norm(p - rigid) > 0.1, extra


def test_fk_warns_of_joint_values_outside_the_limits_as_the_cli_does(cli, recwarn):
    # The command line warns on stderr and prints the point; fk computes the points and warns
    # (calbench.LimitWarning, a UserWarning) naming the rows outside, where it said nothing.
    r = calbench.Robot.builtin("irb2600")
    inside, outside = [10, -20, 30, 40, -50, 60], [500, -20, 30, 40, -50, 60]
    warned = cli("fk", "--robot", "irb2600", "--q", ",".join(map(str, outside)))
    assert "warning: the joint values lie outside the robot's joint limits" in warned.stderr
    assert "outside" not in cli("fk", "--robot", "irb2600", "--q", "10,-20,30,40,-50,60").stderr
    r.fk([inside, inside])
    assert not recwarn.list
    with pytest.warns(calbench.LimitWarning,
                      match=r"outside the robot's joint limits \(q\[1\]\): in q\[1\], joint 1 "
                            r"is 500 deg, outside its limits \[-180, 180\]$") as w:
        p = r.fk([inside, outside, inside])
    assert len(w) == 1 and issubclass(calbench.LimitWarning, UserWarning)
    assert p.shape == (3, 3) and np.allclose(p[0], p[2])
    with pytest.warns(calbench.LimitWarning, match=r"q\[0\], q\[1\], q\[2\] and 2 more rows"):
        r.fk([outside] * 5, pose=True)


def test_fk_refuses_a_value_that_is_no_joint_value_at_its_row_and_column():
    # As every array argument is refused (docs/python.md, Errors); it was `q[1]`: joint 2.
    r = calbench.Robot.builtin("irb2600")
    good = [10, -20, 30, 40, -50, 60]
    for bad, says in [(math.nan, "NaN"), (math.inf, "inf"), (1e300, "")]:
        with pytest.raises(calbench.SettingError,
                           match=rf"setting `q`: row 1, column q2: .*{says}") as e:
            r.fk([good, [10, bad, 30, 40, -50, 60]])
        assert "joint 2" not in str(e.value)


def test_with_errors_moves_the_tool_and_to_toml_reads_back(tmp_path):
    r = calbench.Robot.builtin("irb2600")
    q = np.array([[10, -20, 30, 40, -50, 60]], dtype=float)
    moved = r.with_errors({"tool.z": 1.5})
    d = moved.fk(q) - r.fk(q)
    assert abs(np.linalg.norm(d) - 1.5) < 1e-9
    f = tmp_path / "robot.toml"
    f.write_text(moved.to_toml())
    back = calbench.Robot.from_file(f)
    assert np.allclose(back.fk(q), moved.fk(q), atol=1e-9)
    with pytest.raises(calbench.SettingError, match="nope"):
        r.with_errors({"nope": 1.0})
    with pytest.raises(calbench.Error):
        r.with_errors({"a1": float("nan")})
    # An integer beyond a float's range is a number, and not finite.
    for huge in (10**400, -(10**400)):
        with pytest.raises(calbench.SettingError, match=r"errors\.a1.*must be finite"):
            r.with_errors({"a1": huge})
    with pytest.raises(calbench.SettingError, match=r"errors\.a1.*must be a number"):
        r.with_errors({"a1": "1.0"})


def test_robot_from_urdf(root):
    urdfs = sorted(root.glob("examples/**/*.urdf"))
    assert urdfs, "the repository ships example URDFs under examples/"
    r = calbench.Robot.from_file(urdfs[0])
    assert r.joint_count >= 1
    assert r.fk(np.zeros((1, r.joint_count))).shape == (1, 3)


# ----- identify --------------------------------------------------------------------------


def test_identify_gives_the_cli_numbers(cli, simulated, tmp_path):
    cli("identify", "--robot", "irb2600", "--data", simulated / "measurements.csv",
        "--validate", simulated / "validation.csv", "--method", "lm", "--out", tmp_path / "id")
    ref = json.loads((tmp_path / "id" / "identified.json").read_text())
    q, p = read_measurements(simulated / "measurements.csv", 6)
    vq, vp = read_measurements(simulated / "validation.csv", 6)
    robot = calbench.Robot.builtin("irb2600")
    res = calbench.identify(robot, q, p, method="lm", validate=(vq, vp))
    assert list(res.parameters) == ref["parameters"]
    for k, v in ref["errors"].items():
        assert res.parameters[k] == pytest.approx(v, rel=1e-12, abs=1e-15), k
    assert np.allclose(res.covariance, np.array(ref["covariance"], dtype=float), rtol=1e-9)
    assert res.termination == ref["termination"]
    assert res.iterations == ref["iterations"] and res.rank == ref["rank"]
    assert res.condition_number == pytest.approx(ref["condition_number"], rel=1e-9)
    # Validation points in metres, or from another placement of the tracker (turned by 90°
    # about z and moved by a metre), cannot score the calibration: refused naming `validate`.
    moved = np.column_stack([1000.0 - vp[:, 1], vp[:, 0], vp[:, 2]])
    for bad, words in [(vp / 1000.0, "likely in metres"), (moved, "do not lie in one frame")]:
        with pytest.raises(calbench.SettingError, match=f"setting `validate`: .*{words}"):
            calbench.identify(robot, q, p, method="lm", validate=(vq, bad))
    # An array of the wrong shape is named by its place in `validate` (docs/python.md).
    for bad, name in [((vq[:, :5], vp), "validate.q"), ((vq, vp[:, :2]), "validate.points")]:
        with pytest.raises(calbench.SettingError, match=f"setting `{name}`: expected shape"):
            calbench.identify(robot, q, p, method="lm", validate=bad)
    rows = np.genfromtxt(tmp_path / "id" / "residuals.csv", delimiter=",", names=True)
    assert res.residuals.shape == (len(q), 3)
    assert np.allclose(np.linalg.norm(res.residuals, axis=1), rows["residual_after_mm"], atol=1e-9)
    for side in ("before", "after"):
        for stat, v in ref[f"validation_{side}_mm"].items():
            assert res.validation[f"{side}_mm"][stat] == pytest.approx(v, rel=1e-9)
    assert isinstance(res.robot, calbench.Robot)
    assert res.robot.name == "irb2600-calibrated"
    assert "converged" in repr(res) or res.termination in repr(res)


def test_identify_methods_options_and_registrations(simulated):
    q, p = read_measurements(simulated / "measurements.csv", 6)
    robot = calbench.Robot.builtin("irb2600")
    a = calbench.identify(robot, q, p, method="ls", options={"max_iter": 50})
    b = calbench.identify(robot, q, p, method="ls", registration="svd")
    assert a.termination == "converged" and b.registration_rounds >= 1
    with pytest.raises(calbench.SettingError, match="options.epsilon"):
        calbench.identify(robot, q, p, method="ls", options={"epsilon": 1})
    with pytest.raises(calbench.SettingError, match="unknown method"):
        calbench.identify(robot, q, p, method="newton")
    with pytest.raises(calbench.Error, match="registration"):
        calbench.identify(robot, q, p, registration="magic")
    s = calbench.identify(robot, q, p, sigma=np.full(len(q), 0.05), method="ls")
    assert s.parameters == pytest.approx(a.parameters, rel=1e-9, abs=1e-12)


def test_identify_refuses_bad_arrays(simulated):
    q, p = read_measurements(simulated / "measurements.csv", 6)
    robot = calbench.Robot.builtin("irb2600")
    with pytest.raises(calbench.SettingError, match="shape"):
        calbench.identify(robot, q[:, :5], p)
    with pytest.raises(calbench.SettingError, match="shape"):
        calbench.identify(robot, q, p[:, :2])
    with pytest.raises(calbench.SettingError, match=r"^setting `points`: 40 joint vectors but 39 rows of points"):
        calbench.identify(robot, q, p[:-1])
    bad = p.copy()
    bad[3, 1] = np.nan
    with pytest.raises(calbench.SettingError, match=r"^setting `points`: row 3, column y: NaN is not a finite"):
        calbench.identify(robot, q, bad)
    far = q.copy()
    far[2, 1] = 400.0
    with pytest.raises(calbench.SettingError, match=r"^setting `q`: row 2, column q2: 400 is outside the joint limits"):
        calbench.identify(robot, far, p)
    with pytest.raises(calbench.SettingError, match=r"^setting `q`: fewer than 3 distinct poses"):
        calbench.identify(robot, np.repeat(q[:1], 5, 0), p[:5])
    with pytest.raises(calbench.SettingError, match="`q`: a text array"):
        calbench.identify(robot, [["a"] * 6] * 3, p[:3])
    with pytest.raises(calbench.SettingError, match="`q`: not an array of numbers"):
        calbench.identify(robot, [[0.0] * 6, [0.0] * 5], p[:2])


def test_identify_full_pose_from_quaternions_and_matrices(root, tmp_path):
    sc = load_scenario(root)
    sc["tracker"]["measure"] = "pose"
    d = calbench.simulate(sc, trial=0)
    assert d["rotations"].shape == (len(d["q"]), 4)
    robot = d["robot"]
    a = calbench.identify(robot, d["q"], d["points"], rotations=d["rotations"], method="lm")
    qw, qx, qy, qz = d["rotations"].T
    R = np.stack([
        np.stack([1 - 2 * (qy**2 + qz**2), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)], -1),
        np.stack([2 * (qx * qy + qz * qw), 1 - 2 * (qx**2 + qz**2), 2 * (qy * qz - qx * qw)], -1),
        np.stack([2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx**2 + qy**2)], -1),
    ], 1)
    b = calbench.identify(robot, d["q"], d["points"], rotations=R, method="lm")
    for k in a.parameters:
        assert b.parameters[k] == pytest.approx(a.parameters[k], rel=1e-6, abs=1e-9)


def close(a, b, path="record"):
    """``a`` equals ``b`` (JSON-like values), numbers to 1e-9 relative."""
    if isinstance(b, dict):
        assert isinstance(a, dict) and set(a) == set(b), (path, set(a) ^ set(b))
        for k in b:
            close(a[k], b[k], f"{path}.{k}")
    elif isinstance(b, list):
        assert isinstance(a, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            close(x, y, f"{path}[{i}]")
    elif isinstance(b, float) and not isinstance(a, bool):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-300), path
    else:
        assert a == b, path


def test_identify_with_fix_prior_cv_returns_the_cli_record(cli, simulated, tmp_path):
    cli("identify", "--robot", "irb2600", "--data", simulated / "measurements.csv", "--method", "lm",
        "--fix", "a2,theta3", "--prior", "d2=0.1", "--prior", "a3=0.05", "--cv", "5",
        "--out", tmp_path / "id")
    ref = json.loads((tmp_path / "id" / "identified.json").read_text())
    q, p = read_measurements(simulated / "measurements.csv", 6)
    robot = calbench.Robot.builtin("irb2600")
    res = calbench.identify(robot, q, p, method="lm", fix=["a2", "theta3"],
                            prior={"d2": 0.1, "a3": 0.05}, cv=5)
    assert isinstance(res, dict) and res["data"] == "<arrays>"
    close({**res, "data": ref["data"]}, ref)
    assert res["cv"]["rms"] == pytest.approx(ref["cv"]["rms"], rel=1e-9)
    assert "a2" not in res["errors"] and res["fixed"] == ["a2", "theta3"]
    assert [m["parameter"] for m in res["priors"]] == ["d2", "a3"]
    assert list(res.parameters) == ref["parameters"]
    # The same from the file itself.
    same = calbench.identify(robot, data=simulated / "measurements.csv", method="lm",
                             fix="a2,theta3", prior={"d2": 0.1, "a3": 0.05}, cv=5)
    close(same, ref)
    assert same == calbench.identify(robot, data=simulated / "measurements.csv", method="lm", cv=5,
                                     fix=np.array(["a2", "theta3"]), prior={"d2": 0.1, "a3": 0.05})
    # A file of priors, as `--prior FILE` (its priors in the order of their names, as TOML's
    # table holds them): the record of the same priors; a bad one refused at its line.
    priors = tmp_path / "priors.toml"
    priors.write_text("d2 = 0.1\na3 = 0.05\n")
    sorted_same = calbench.identify(robot, data=simulated / "measurements.csv", method="lm",
                                    cv=5, fix="a2,theta3", prior={"a3": 0.05, "d2": 0.1})
    for path in (priors, str(priors)):
        assert sorted_same == calbench.identify(robot, data=simulated / "measurements.csv",
                                                method="lm", cv=5, fix="a2,theta3", prior=path)
    priors.write_text("d2 = 0.1\nnope = 0.05\n")
    with pytest.raises(calbench.FileError, match=r"priors.toml: line 2, key `nope`"):
        calbench.identify(robot, q, p, prior=priors)
    with pytest.raises(calbench.SettingError, match="setting `prior`: expected a dict"):
        calbench.identify(robot, q, p, prior=[("d2", 0.1)])
    with pytest.raises(calbench.SettingError, match="fix"):
        calbench.identify(robot, q, p, fix=["nope"])
    with pytest.raises(calbench.SettingError, match="setting `cv`: needs 2"):
        calbench.identify(robot, q, p, cv=1)
    with pytest.raises(calbench.SettingError, match="setting `holdout`: cannot be used with validate"):
        calbench.identify(robot, q, p, holdout="3/10", validate=(q, p))
    # The holdout as two integers, as `shard` takes them: the same record as its text.
    held = calbench.identify(robot, q, p, method="ls", holdout="3/10")
    for pair in ((3, 10), [3, 10], np.array([3, 10])):
        assert calbench.identify(robot, q, p, method="ls", holdout=pair) == held
    for bad in ((3,), (3.0, 10), (True, 10)):
        with pytest.raises(calbench.SettingError, match="setting `holdout`: expected"):
            calbench.identify(robot, q, p, holdout=bad)
    # Integers too large for a count are said to be so (0 < LAST < EVERY holds for them).
    with pytest.raises(calbench.SettingError, match="18446744073709551616 is too large for a count"):
        calbench.identify(robot, q, p, holdout=(2**64, 2**65))
    with pytest.raises(calbench.SettingError, match="`q`: is not taken with `data`"):
        calbench.identify(robot, q, p, data=simulated / "measurements.csv")


def test_fixing_every_parameter_or_naming_none_is_refused_by_its_own_name(cli, simulated, root,
                                                                           tmp_path):
    # Fixing every parameter had been refused as "setting `params`: no parameters to
    # identify", an option the user never gave; `params=[]` identified the default set.
    robot = calbench.Robot.builtin("irb2600")
    everything = ",".join(robot.parameter_names())
    q, p = read_measurements(simulated / "measurements.csv", 6)
    left = "leaves no parameter to identify"
    with pytest.raises(calbench.SettingError, match=f"setting `fix`: {left}"):
        calbench.identify(robot, q, p, fix=everything)
    got = cli("identify", "--robot", "irb2600", "--data", simulated / "measurements.csv",
              "--method", "ls", "--fix", everything, "--out", tmp_path / "id", ok=False)
    assert got.returncode != 0 and f"setting `--fix`: {left}" in got.stderr, got.stderr
    assert not (tmp_path / "id").exists()
    with pytest.raises(calbench.SettingError, match="setting `params`: names no parameter"):
        calbench.identify(robot, q, p, params=[])
    # A kind file's identification the same.
    cli("simulate", root / "scenarios" / "instruments.toml", "--measure", "plane",
        "--out", tmp_path / "sim")
    with pytest.raises(calbench.SettingError, match=f"setting `fix`: {left}"):
        calbench.identify(robot, data=tmp_path / "sim" / "measurements.csv", method="ls",
                          fix=everything)


def test_identify_a_kind_file_returns_the_cli_record(cli, root, tmp_path):
    cli("simulate", root / "scenarios" / "instruments.toml", "--measure", "plane",
        "--out", tmp_path / "sim")
    data, val = tmp_path / "sim" / "measurements.csv", tmp_path / "sim" / "validation.csv"
    cli("identify", "--robot", "irb2600", "--data", data, "--validate", val, "--method", "ls",
        "--fix", "a2", "--out", tmp_path / "id")
    ref = json.loads((tmp_path / "id" / "identified.json").read_text())
    robot = calbench.Robot.builtin("irb2600")
    res = calbench.identify(robot, data=str(data), validate=str(val), method="ls", fix=["a2"])
    close(res, ref)
    assert res["kind"] == "plane" and res.validation["after_mm"]["rms"] < 1.0
    # A tracker's arrays are None for a kind file, not missing attributes.
    for name in ("covariance", "residuals", "weights", "registration_frame"):
        assert getattr(res, name) is None, name
    assert res.robot.to_toml() == (tmp_path / "id" / "robot.toml").read_text()
    # A plane column of one value makes the robot worse: refused, or kept with allow_worse.
    text = data.read_text().splitlines()
    k = text[0].split(",").index("plane")
    rows = [text[0]] + [",".join(c if i != k else "1" for i, c in enumerate(r.split(",")))
                        for r in text[1:]]
    bad = tmp_path / "plane1.csv"
    bad.write_text("\n".join(rows) + "\n")
    with pytest.raises(calbench.FileError, match="makes the robot worse.*allow_worse=True"):
        calbench.identify(robot, data=bad, validate=val, method="lm")
    # (That robot also moved beyond what a calibration can mean: kept with both, and each
    # warns as `calbench identify` does on stderr, the options spelled as keywords.)
    with pytest.warns(UserWarning) as caught:
        kept = calbench.identify(robot, data=bad, validate=val, method="lm", allow_worse=True,
                                 allow_implausible=True)
    assert "validation RMS" in kept["allowed_worse"][0]
    said = [str(w.message) for w in caught if w.category is UserWarning]
    assert len(said) == 2, said
    assert said[0].startswith("the identification makes the robot worse (")
    assert said[0].endswith("); kept because of allow_worse=True"), said
    assert said[1].startswith("the identified robot cannot be physically right (")
    assert "kept because of allow_implausible=True: do not load it" in said[1], said


def test_refusals_name_the_options_as_each_front_end_spells_them(cli, root, tmp_path):
    # The library names the options by type: Python says `params` and `allow_rank_deficient=True`
    # where the command line says `--params` and `--allow-rank-deficient`, in the same refusal.
    cli("simulate", root / "scenarios" / "instruments.toml", "--measure", "plane",
        "--out", tmp_path / "sim")
    data = tmp_path / "sim" / "measurements.csv"
    robot = calbench.Robot.builtin("irb2600")
    with pytest.raises(calbench.FileError,
                       match="out of params, or pass allow_rank_deficient=True$"):
        calbench.identify(robot, data=data, method="ls", params=["base.x", "a2"])
    r = cli("identify", "--robot", "irb2600", "--data", data, "--method", "ls",
            "--params", "base.x,a2", "--out", tmp_path / "id", ok=False)
    assert r.returncode != 0
    assert r.stderr.rstrip().endswith("out of --params, or pass --allow-rank-deficient"), r.stderr
    with pytest.raises(calbench.SettingError, match="setting `registration`: .* holds plane"):
        calbench.identify(robot, data=data, method="ls", registration="svd")


def test_every_refusal_is_a_calbench_error(root):
    robot = calbench.Robot.builtin("irb2600")
    q = np.zeros((4, 6))
    for bad in (dict(trials=-1), dict(trials=2**70), dict(seed=-3), dict(threads=1.5),
                dict(trials=True)):
        with pytest.raises(calbench.SettingError, match=next(iter(bad))):
            calbench.run(root / CI_GUARD, **bad)
    with pytest.raises(calbench.SettingError, match="trial"):
        calbench.simulate(root / CI_GUARD, trial=-1)
    # A negative count is refused with the range the argument takes, not its integer type's.
    for call, says in [
        (lambda: calbench.run(root / CI_GUARD, trials=-1), "`trials`: must be a whole number ≥ 1, got -1"),
        (lambda: calbench.run(root / CI_GUARD, trials=0), "`trials`: must be a whole number ≥ 1, got 0"),
        (lambda: calbench.simulate(root / CI_GUARD, trial=-1), "`trial`: must be a whole number ≥ 0, got -1"),
    ]:
        with pytest.raises(calbench.SettingError, match=f"^setting {says}$"):
            call()
    with pytest.raises(calbench.SettingError, match="`q`: a complex array"):
        calbench.identify(robot, q + 1j, np.zeros((4, 3)))
    with pytest.raises(calbench.SettingError, match="`points`: a bool array"):
        calbench.identify(robot, q, np.zeros((4, 3), dtype=bool))
    with pytest.raises(calbench.SettingError, match="`q`: a bool array"):
        calbench.identifiability(robot, q.astype(bool))
    with pytest.raises(calbench.SettingError, match="`q`: a complex array"):
        robot.fk(q.astype(complex))
    with pytest.raises(calbench.SettingError, match="`q`: a bool array"):
        robot.fk(q.astype(bool))
    assert robot.fk([[0.0] * 6]).shape == (1, 3)
    with pytest.raises(calbench.SettingError, match="errors.a1"):
        robot.with_errors({"a1": True})
    with pytest.raises(calbench.SettingError, match="cv"):
        calbench.identify(robot, q, np.zeros((4, 3)), cv=-2)


@pytest.mark.parametrize("call, key", [
    (lambda r, q, p: calbench.identify(r, q, p, method=5), "method"),
    (lambda r, q, p: calbench.identify(r, q, p, method=None), "method"),
    (lambda r, q, p: calbench.identify(r, q, p, registration=5), "registration"),
    (lambda r, q, p: calbench.identify(r, q, p, options="max_iter=5"), "options"),
    (lambda r, q, p: calbench.identify(r, q, p, compliance=["c2", 3]), "compliance"),
    (lambda r, q, p: calbench.identify(r, q, p, holdout=3), "holdout"),
    (lambda r, q, p: calbench.identify(r, q, p, allow_worse="no"), "allow_worse"),
    (lambda r, q, p: calbench.identify(r, q, p, allow_rank_deficient=None),
     "allow_rank_deficient"),
    (lambda r, q, p: calbench.identify(r, q, p, allow_implausible=1), "allow_implausible"),
    (lambda r, q, p: calbench.identify(r, q, p, prior={"d2": True}), "prior.d2"),
    (lambda r, q, p: r.fk(q, pose="yes"), "pose"),
    (lambda r, q, p: r.with_errors([("a2", 0.1)]), "errors"),
    (lambda r, q, p: calbench.Robot.builtin(5), "name"),
    (lambda r, q, p: calbench.Robot.from_file(5), "path"),
    (lambda r, q, p: calbench.Robot.from_file("robots/ban-irb2600.toml", tip=5), "tip"),
    (lambda r, q, p: calbench.run(CI_GUARD, trials=2, progress="no"), "progress"),
    (lambda r, q, p: calbench.run(CI_GUARD, trials=2, shard=(0, 2), out=5), "out"),
    (lambda r, q, p: calbench.task(5), "task"),
    (lambda r, q, p: calbench.task("barrett-wam", out=5), "out"),
])
def test_an_argument_of_the_wrong_type_is_refused_naming_it(simulated, call, key):
    # A value of the wrong type is a calbench.SettingError naming the argument, never a bare
    # TypeError, and a flag is True or False, not whatever is truthy ("no" is not False).
    robot = calbench.Robot.builtin("irb2600")
    q, p = read_measurements(simulated / "measurements.csv", 6)
    with pytest.raises(calbench.SettingError, match=f"setting `{key}`"):
        call(robot, q, p)


def test_numpy_scalars_are_taken_as_their_python_twins(root, simulated):
    # An np.int64 option is an integer (not the float 50.0), an np.bool_ flag a bool, and
    # None for a seed its default.
    robot = calbench.Robot.builtin("irb2600")
    q, p = read_measurements(simulated / "measurements.csv", 6)
    want = calbench.identify(robot, q, p, options={"max_iter": 50})
    got = calbench.identify(robot, q, p, options={"max_iter": np.int64(50)}, seed=None,
                            cv_seed=None, allow_worse=np.bool_(False))
    assert got["errors"] == want["errors"]
    assert robot.fk(q[:2], pose=np.bool_(True)).shape == (2, 4, 4)
    scenario = dict(load_scenario(root), trials=np.int64(2))
    assert calbench.run(scenario).summary["trials"] == 2


# ----- simulate --------------------------------------------------------------------------


def test_simulate_gives_the_cli_measurements(cli, simulated, root):
    d = calbench.simulate(root / CI_GUARD, trial=1)
    q, p = read_measurements(simulated / "measurements.csv", 6)
    assert np.allclose(d["q"], q, atol=1e-8) and np.allclose(d["points"], p, atol=1e-8)
    vq, vp = read_measurements(simulated / "validation.csv", 6)
    assert np.allclose(d["validation_q"], vq, atol=1e-8)
    assert np.allclose(d["validation_points"], vp, atol=1e-8)
    truth = json.loads((simulated / "truth.json").read_text())
    assert d["truth"] == truth["errors"] and d["info"] == truth
    assert d["rotations"] is None
    with pytest.raises(calbench.SettingError, match="trial 16 does not exist"):
        calbench.simulate(root / CI_GUARD, trial=16)


# ----- run -------------------------------------------------------------------------------


def test_run_of_a_dict_is_the_cli_bytes(cli, root, tmp_path):
    cli("run", CI_GUARD, "--trials", "3", "--seed", "7", "--out", tmp_path / "cli")
    sc = load_scenario(root)
    first = calbench.run(sc, trials=3, seed=7)
    second = calbench.run(root / CI_GUARD, trials=3, seed=7, threads=1)
    for study in (first, second):
        assert study.summary_json() == (tmp_path / "cli" / "summary.json").read_text()
        assert study.trials_csv() == (tmp_path / "cli" / "trials.csv").read_bytes()
    assert first.summary == json.loads((tmp_path / "cli" / "summary.json").read_text())
    df = first.results
    assert isinstance(df, pd.DataFrame) and len(df) == len(first.summary["results"])
    assert {"method", "poses", "eta_mean_pct", "failures", "validation_after_mm.mean"} <= set(df.columns)
    t = first.trials
    assert len(t) == 3 * len(df) and list(t["trial"].unique()) == [0, 1, 2]
    first.write(tmp_path / "py")
    cli_files = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == cli_files
    for name in ("summary.json", "trials.csv"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    assert first.seconds > 0 and "ci-guard" in repr(first)


def test_a_sweep_whose_points_differ_in_columns_gives_the_cli_bytes(cli, root, tmp_path):
    sc = load_scenario(root)
    sc["sweep"] = [
        {"key": "tracker.measure", "values": ["position", "pose"], "zip": True},
        {"key": "identification.compliance", "values": [[], "gravity"]},
    ]
    study = calbench.run(sc, trials=2)
    t = study.trials
    pose = t["tracker.measure"] == "pose"
    assert pose.any() and not pose.all()
    for col in ("after_rms_deg", "true_c2", "identified_c2"):
        assert t.loc[pose, col].notna().all() and t.loc[~pose, col].isna().all(), col
    study.write(tmp_path / "py")
    with open(tmp_path / "py" / "trials.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert {len(r) for r in rows} == {len(rows[0])}
    cli("run", tmp_path / "py" / "scenario.toml", "--trials", "2", "--out", tmp_path / "cli")
    assert study.trials_csv() == (tmp_path / "cli" / "trials.csv").read_bytes()


def test_a_sweep_point_that_changed_nothing_is_a_user_warning(root):
    sc = load_scenario(root)
    sc["sweep"] = {"key": "outliers", "values": [
        {"count": 0, "magnitude_mm": [0.5, 1.0]},
        {"count": 0, "magnitude_mm": [2.0, 3.0]},
        {"count": 2, "magnitude_mm": [0.5, 1.0]},
    ]}
    with pytest.warns(UserWarning) as caught:
        calbench.run(sc, trials=2)
    idle = [str(w.message) for w in caught if "no effect" in str(w.message)]
    assert len(idle) == 1 and '"magnitude_mm":[2.0,3.0]' in idle[0], idle


def test_run_write_is_whole_or_nothing(root, tmp_path):
    study = calbench.run(root / CI_GUARD, trials=1, progress=True)
    blocker = tmp_path / "out"
    blocker.write_text("keep me")
    with pytest.raises(calbench.SettingError, match=r"^setting `out`: .*out exists and is not a folder"):
        study.write(blocker)
    assert blocker.read_text() == "keep me"


def test_run_refuses_bad_scenarios_naming_the_key(root):
    sc = load_scenario(root)
    sc["calibration"]["count"] = -3
    with pytest.raises(calbench.SettingError, match=r"^setting `calibration.count`: invalid value"):
        calbench.run(sc, trials=1)
    sc = load_scenario(root)
    sc["calibration"]["count"] = 3
    with pytest.raises(calbench.SettingError, match=r"`calibration.count`: 3 poses give 9 readings"):
        calbench.run(sc, trials=1)
    sc = load_scenario(root)
    sc["bogus"] = 1
    with pytest.raises(calbench.Error, match="bogus"):
        calbench.run(sc, trials=1)
    with pytest.raises(calbench.IoError, match="missing.toml"):
        calbench.run(root / "missing.toml")
    with pytest.raises(calbench.SettingError, match="threads"):
        calbench.run(root / CI_GUARD, trials=1, threads=0)
    # One bound whatever the value: -1 had been told "≥ 0", which 0 is not.
    for bad in (-1, 0):
        with pytest.raises(calbench.SettingError, match="`threads`: .*≥ 1|at least 1"):
            calbench.run(root / CI_GUARD, trials=1, threads=bad)


# ----- identifiability -------------------------------------------------------------------


def test_identifiability_matches_the_cli(cli, simulated):
    q, _ = read_measurements(simulated / "measurements.csv", 6)
    robot = calbench.Robot.builtin("irb2600")
    a = calbench.identifiability(robot, q)
    pose_file = simulated / "measurements.csv"
    ref = json.loads(cli("identifiability", "--robot", "irb2600", "--poses-file", pose_file, "--json").stdout)
    for k in ("rank", "identifiable", "unidentifiable", "groups"):
        assert a[k] == ref[k], k
    assert math.isclose(a["condition_number"], ref["condition_number"], rel_tol=1e-9)
    b = calbench.identifiability(robot, q, measure="pose")
    assert b["rank"] >= a["rank"]
    with pytest.raises(calbench.SettingError, match="measure"):
        calbench.identifiability(robot, q, measure="force")


# ----- errors ----------------------------------------------------------------------------


def test_errors_are_calbench_errors_with_the_cli_message(cli, tmp_path):
    with pytest.raises(calbench.IoError, match="no-such-robot.toml"):
        calbench.Robot.from_file(tmp_path / "no-such-robot.toml")
    # Named by the argument, `name` (it had been `robot`).
    with pytest.raises(calbench.SettingError, match=r"^setting `name`: \"r2d2\" is not a built-in robot"):
        calbench.Robot.builtin("r2d2")
    with pytest.raises(calbench.SettingError, match=r"^setting `name`: expected a built-in robot's name"):
        calbench.Robot.builtin(name=3)
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 3\n")
    msg = cli("identify", "--robot", bad, "--data", "x.csv", "--method", "ls", "--out", tmp_path / "o", ok=False).stderr
    with pytest.raises(calbench.Error) as e:
        calbench.Robot.from_file(bad)
    assert str(e.value) in msg, (str(e.value), msg)
    # A name UTF-8 cannot hold (a lone surrogate, as os.listdir gives for bytes that are not
    # UTF-8) is a SettingError naming the argument, never a bare UnicodeEncodeError.
    odd = "\udcff"
    robot = calbench.Robot.builtin("irb2600")
    for call, key in [
        (lambda: calbench.identify(robot, data="c.csv", method=odd), "method"),
        (lambda: calbench.identify(robot, data="c.csv", fix=[odd]), "fix"),
        (lambda: calbench.simulate({"name": odd}), "name"),
        (lambda: calbench.simulate({odd: 1}), "scenario"),
        (lambda: calbench.Robot.builtin(odd), "name"),
    ]:
        with pytest.raises(calbench.SettingError, match=f"setting `{key}`.*lone surrogate"):
            call()
    # A value that is no str still says what the argument should be.
    with pytest.raises(calbench.SettingError, match="expected a built-in robot's name, got int"):
        calbench.Robot.builtin(5)
    # A folder is not "no such robot file": the command line's own refusal.
    folder = tmp_path / "folder.toml"
    folder.mkdir()
    msg = cli("fk", "--robot", folder, "--q", "0,0,0,0,0,0", ok=False).stderr
    with pytest.raises(calbench.IoError) as e:
        calbench.Robot.from_file(folder)
    assert "no such" not in str(e.value) and str(e.value) in msg, (str(e.value), msg)
    for cls in (calbench.FileError, calbench.SettingError, calbench.ComputeError, calbench.IoError):
        assert issubclass(cls, calbench.Error)


def test_identify_a_socket_file_returns_the_cli_record(cli, root, tmp_path):
    # MUKCa Panda 6's calibration placement as one socket file (data/mukca/README.md), its
    # URDF chain to the ball: Python's record is the command line's.
    front = root / "data" / "mukca" / "panda_6" / "front"
    rows = ["q1,q2,q3,q4,q5,q6,q7,socket,socket_distance_mm"]
    for hole, tail in (("hole_0.csv", ",1,0"), ("hole_1.csv", ",2,50")):
        rows += [r + tail for r in (front / hole).read_text().split()]
    data = tmp_path / "panda6-front.csv"
    data.write_text("\n".join(rows) + "\n")
    urdf = root / "data" / "mukca" / "panda.urdf"
    cli("identify", "--robot", urdf, "--tip", "ball_link", "--data", data, "--method", "ls",
        "--fix", "theta7", "--out", tmp_path / "id")
    ref = json.loads((tmp_path / "id" / "identified.json").read_text())
    robot = calbench.Robot.from_file(urdf, tip="ball_link")
    assert robot.joint_count == 7
    res = calbench.identify(robot, data=data, method="ls", fix=["theta7"])
    close(res, ref)
    assert res["kind"] == "socket"
    assert res.robot.to_toml() == (tmp_path / "id" / "robot.toml").read_text()
    with pytest.raises(calbench.Error, match="ball_link"):
        calbench.Robot.from_file(urdf)


def test_a_urdf_chain_from_a_base_link_is_the_command_line_s(cli, root):
    # Robot.from_file(base=, tip=) as `calbench fk --base --tip`: the chain from panda_link2.
    urdf = root / "data" / "mukca" / "panda.urdf"
    robot = calbench.Robot.from_file(urdf, base="panda_link2", tip="panda_hand_tcp")
    assert robot.joint_count == 5
    q = [0.1, -0.2, 0.3, 0.4, 0.5]
    out = cli("fk", "--robot", urdf, "--base", "panda_link2", "--tip", "panda_hand_tcp",
              "--q", ",".join(map(str, q)), "--json").stdout
    want = json.loads(out)["position_mm"]
    got = robot.fk(np.array([q]))[0]
    assert np.allclose(got, want, rtol=0, atol=1e-9), (got, want)
    with pytest.raises(calbench.SettingError, match="`base`"):
        calbench.Robot.from_file(urdf, base=2)
    # Named by the argument given: `base` alone had been refused as `tip`.
    with pytest.raises(calbench.SettingError, match="setting `base`: .*not one"):
        calbench.Robot.from_file(root / "robots" / "ban-irb2600.toml", base="link1")


def test_a_path_in_a_scenario_dict_is_its_text(root):
    # A pathlib.Path where a scenario file writes a path's text: the same study.
    sc = load_scenario(root)
    sc.pop("compliance")  # its stiffnesses are the built-in robot's
    robot_file = root / "robots" / "ban-irb2600.toml"
    sc["robot"] = {"file": robot_file}
    a = calbench.simulate(sc, trial=0)
    sc["robot"] = {"file": str(robot_file)}
    b = calbench.simulate(sc, trial=0)
    assert np.array_equal(a["points"], b["points"]) and np.array_equal(a["q"], b["q"])

"""Arguments as a user gives them: numpy arrays of any dtype, lists, pandas frames, and
what is refused naming the argument as Python spells it."""
import tomllib
import warnings

import numpy as np
import pandas as pd
import pytest

import calbench

CI_GUARD = "scenarios/ci-guard.toml"


@pytest.fixture(scope="module")
def trial(root):
    return calbench.simulate(root / CI_GUARD, trial=0)


def test_identify_takes_frames_and_lists_as_arrays(trial):
    robot = calbench.Robot.builtin("irb2600")
    ref = calbench.identify(robot, trial["q"], trial["points"], sigma=np.full(40, 0.02))
    frame = pd.DataFrame(np.hstack([trial["q"], trial["points"]]),
                         columns=[f"q{i}" for i in range(1, 7)] + ["x", "y", "z"])
    got = calbench.identify(robot, frame.iloc[:, :6], frame[["x", "y", "z"]],
                            sigma=pd.Series([0.02] * 40))
    assert got.parameters == ref.parameters
    assert got["data"] == "<arrays>"


@pytest.mark.parametrize("name", ["sigma", "payload"])
def test_a_scalar_for_a_per_point_array_is_refused_naming_it(trial, name):
    # A scalar sigma or payload was made one row by the conversion and refused as
    # "setting `data`: 40 joint vectors but 1 rows of sigma", naming neither the argument nor
    # what was wrong with it.
    robot = calbench.Robot.builtin("irb2600")
    with pytest.raises(calbench.SettingError,
                       match=rf"^setting `{name}`: expected 1 dimensions, got shape \(\)$"):
        calbench.identify(robot, trial["q"], trial["points"], **{name: 0.02})


def test_precision_with_a_sweep_is_refused_naming_the_keyword_arguments(cli, root, tmp_path):
    # The refusal named the command line's flags (`--precision`, `--trials`) from Python.
    with open(root / CI_GUARD, "rb") as f:
        sc = tomllib.load(f)
    sc["sweep"] = {"key": "outliers.count", "values": [0, 2]}
    with pytest.raises(calbench.SettingError) as e:
        calbench.run(sc, trials=2, precision="5%")
    msg = str(e.value)
    assert msg.startswith("setting `precision`: a sweep runs the same trials at every point")
    assert "give trials instead" in msg and "--" not in msg
    swept = tmp_path / "swept.toml"
    swept.write_text((root / CI_GUARD).read_text().replace("[robot]", "[sweep]\nkey = "
                     "\"outliers.count\"\nvalues = [0, 2]\n\n[robot]"))
    err = cli("run", swept, "--precision", "5%", "--out", tmp_path / "o", ok=False).stderr
    assert "setting `--precision`: a sweep runs the same trials" in err
    assert "give --trials instead" in err and not (tmp_path / "o").exists()


def test_the_default_method_is_gauss_newton_which_converges_where_lm_stops(root):
    # `lm`'s default, Guo's fixed μ = 1, converges linearly: on the IRB 2600 of the Ban
    # scenario it stops at its 50 iterations, and the default had been `lm`, so the simplest
    # call warned of a solve that did not converge.
    t = calbench.simulate(root / "scenarios/ban-irb2600.toml", trial=0)
    robot = t["robot"]
    with pytest.warns(calbench.ConvergenceWarning):
        lm = calbench.identify(robot, t["q"], t["points"], method="lm")
    assert lm.termination == "max-iterations" and lm.iterations == 50
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = calbench.identify(robot, t["q"], t["points"])
    assert got["method"] == "ls" and got.termination == "converged", got.termination
    assert got.iterations < 10
    assert got == calbench.identify(robot, t["q"], t["points"], method="ls")


def test_a_worsening_seen_only_on_validation_arrays_names_validate(trial):
    # Calibration points of an arm with errors, validation points of the nominal one, both in
    # the base frame: the fit improves the calibration and worsens only the validation. The
    # refusal had named `points`, the calibration arrays, which are right.
    robot = calbench.Robot.builtin("irb2600")
    arm = robot.with_errors(trial["truth"])
    validate = (trial["validation_q"], robot.fk(trial["validation_q"]))
    with pytest.raises(calbench.SettingError) as e:
        calbench.identify(robot, trial["q"], arm.fk(trial["q"]), method="ls",
                          registration="known", validate=validate)
    msg = str(e.value)
    assert msg.startswith("setting `validate`: the identification makes the robot worse: "
                          "the validation RMS is "), msg
    assert msg.endswith("or pass allow_worse=True to write it with a warning"), msg


@pytest.mark.parametrize("method", ["ls", "lm", "igg3"])
def test_points_the_nominal_robot_fits_exactly_are_no_worsening(root, method):
    # Before and after, the residuals are the rounding of the points (about 1e-13 mm): a
    # rise within it had been refused as "makes the robot worse ... 0.0000 mm after against
    # 0.0000 mm before".
    robot = calbench.Robot.from_file(root / "robots/ban-irb2600.toml")
    q = np.random.default_rng(0).uniform(-2, 2, (30, 6))
    got = calbench.identify(robot, q, robot.fk(q), method=method)
    assert np.abs(np.asarray(got.residuals)).max() < 1e-9
    assert got.validation is None or got.validation["after"]["rms"] < 1e-9


def test_identifiability_and_the_solve_judge_rank_by_one_rule(root):
    # Poses within ±1° determine the arm's 27 parameters only to a scaled condition number
    # near 1e7. The analysis had kept all 27 by its pivots' remaining norms (condition
    # number 2.6e7) while the solve, counting singular values above 1e-7 of the largest,
    # found rank 26, and its refusal then said "the poses determine all 27 kinematic
    # parameters, yet the solve's rank is 26".
    robot = calbench.Robot.from_file(root / "robots/ban-irb2600.toml")
    q = np.random.default_rng(0).uniform(-1, 1, (30, 6))
    points = robot.fk(q)
    analysis = calbench.identifiability(robot, q)
    assert analysis["condition_number"] < 1e7
    with pytest.raises(calbench.SettingError,
                       match="^setting `points`: the poses determine only 26 of the 27 parameters"):
        calbench.identify(robot, q, points, method="ls")
    # What the analysis finds identifiable, the solve finds of full rank.
    kinematic = [p for p in analysis["identifiable"] if not p.startswith("base.")]
    got = calbench.identify(robot, q, points, method="ls", params=kinematic)
    assert (got.termination, got.rank) == ("converged", len(kinematic))


def test_a_bad_value_in_an_array_is_refused_naming_that_array(trial):
    # Every array given to identify was refused as `data` ("setting `data`: row 0, column
    # sigma_mm: …"), an argument the call did not have; a prior on a parameter not
    # identified as `priors.d2`, a scenario's key.
    robot = calbench.Robot.builtin("irb2600")
    q, points = trial["q"], trial["points"]
    sigma = np.full(len(q), 0.02)
    sigma[5] = -1.0
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `sigma`: row 5: -1 is not a positive standard deviation"):
        calbench.identify(robot, q, points, sigma=sigma)
    payload = np.full(len(q), 2.0)
    payload[7] = np.inf
    with pytest.raises(calbench.SettingError, match=r"^setting `payload`: row 7: inf is not a "):
        calbench.identify(robot, q, points, payload=payload)
    with pytest.raises(calbench.SettingError, match=r"^setting `rotations`: 40 joint vectors "):
        calbench.identify(robot, q, points, rotations=np.tile([1.0, 0, 0, 0], (39, 1)))
    # validate is one argument: a row of one of its arrays is refused naming that array by its
    # place in it (docs/python.md), as an array of the wrong shape is; a cell had been named
    # `validate` alone, which left q or points to guess.
    far = q[:5].copy()
    far[1, 0] = 500.0
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `validate.q`: row 1, column q1: 500"):
        calbench.identify(robot, q, points, validate=(far, points[:5]))
    gap = points[:5].copy()
    gap[4, 1] = np.nan
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `validate.points`: row 4, column y: NaN is not a finite"):
        calbench.identify(robot, q, points, validate=(q[:5], gap))
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `validate.rotations`: row 0, column qw: the quaternion"):
        calbench.identify(robot, q, points,
                          validate=(q[:5], points[:5], np.tile([2.0, 0, 0, 0], (5, 1))))
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `validate.payload`: row 0: must be a mass"):
        calbench.identify(robot, q, points, payload=np.zeros(len(q)),
                          validate=(q[:5], points[:5], None, -np.ones(5)))
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `prior`: `d2` is not among the identified parameters"):
        calbench.identify(robot, q, points, prior={"d2": 0.1}, fix=["d2"])


def test_q_or_points_alone_is_refused_naming_the_missing_one(trial):
    # Either array alone was refused as "setting `data`: give q and points, or data".
    robot = calbench.Robot.builtin("irb2600")
    with pytest.raises(calbench.SettingError, match=r"^setting `points`: missing: q is given"):
        calbench.identify(robot, trial["q"])
    with pytest.raises(calbench.SettingError, match=r"^setting `q`: missing: points is given"):
        calbench.identify(robot, points=trial["points"])
    with pytest.raises(calbench.SettingError, match=r"^setting `data`: give q and points, or data"):
        calbench.identify(robot)


def test_exact_points_from_narrow_poses_converge(root):
    # On 60 poses within ±2° the arm's parameters are determined to a condition number near
    # 1e7. On exact points the step at the fit is rounding noise of 1e-8 or more, and ls's
    # step rule of 1e-9 alone ended after up to 100 iterations, or at max-iterations; the
    # fit now ends converged at the rounding floor of its data.
    robot = calbench.Robot.from_file(root / "robots/ban-irb2600.toml")
    truth = robot.with_errors({"a2": 0.2, "alpha3": 1e-3, "d4": -0.2, "tool.x": 0.1})
    for seed in range(4):
        rng = np.random.default_rng(seed)
        q = np.array([0, 10, 20, 30, 40, 50.0]) + rng.uniform(-2, 2, (60, 6))
        points = truth.fk(q)
        for method in ["ls", "ridge", "igg3"]:
            got = calbench.identify(robot, q, points, method=method, registration="known")
            assert got.termination == "converged", (seed, method)
            assert got.iterations <= 10, (seed, method, got.iterations)
            assert got.rms_residual_mm < 1e-8, (seed, method, got.rms_residual_mm)


def test_igg3_by_mad_keeps_every_point_of_exact_full_poses_from_the_truth():
    # Started at the truth, the residuals are rounding (1e-13 mm), and σ0 by MAD, not below
    # 1e-9 of a start that is itself rounding, weighed that noise: the fit ended
    # max-iterations, or was refused as rank 12 of 25.
    robot = calbench.Robot.builtin("irb2600")
    for seed in range(3):
        rng = np.random.default_rng(seed)
        q = np.array([0, 10, 20, 30, 40, 50.0]) + rng.uniform(-2, 2, (60, 6))
        frames = robot.fk(q, pose=True)
        got = calbench.identify(robot, q, frames[:, :3, 3], rotations=frames[:, :3, :3],
                                method="igg3", options={"sigma0": "mad"}, registration="known")
        assert got.termination == "converged", seed
        assert got.iterations <= 10, (seed, got.iterations)
        assert min(got.weights) == 1.0, seed


def test_an_identification_that_did_not_converge_warns_as_the_command_line_does(
        root, cli, tmp_path):
    """``calbench.identify`` of a solve stopped at its iteration limit warns
    (``ConvergenceWarning``) with the words ``calbench identify`` prints on stderr, on a
    tracker's file and on a distance file alike; a converged one does not warn."""
    robot = calbench.Robot.builtin("irb2600")
    tracker = calbench.simulate(root / CI_GUARD, out=tmp_path / "tracker")
    distance = calbench.simulate(root / "scenarios/instruments.toml", measure="distance",
                                 out=tmp_path / "distance")
    for data in (tmp_path / "tracker" / "measurements.csv", distance["data"]):
        with pytest.warns(calbench.ConvergenceWarning) as caught:
            short = calbench.identify(robot, data=data, method="lm", options={"max_iter": 2})
        assert short.termination == "max-iterations"
        r = cli("identify", "--robot", "irb2600", "--data", data, "--method", "lm", "--set",
                "max_iter=2", "--out", tmp_path / "cli")
        (w,) = caught
        assert str(w.message).startswith("the identification ended `max-iterations` after 2 ")
        assert f"warning: {w.message}\n" in r.stderr
    with warnings.catch_warnings():
        warnings.simplefilter("error", calbench.ConvergenceWarning)
        done = calbench.identify(robot, tracker["q"], tracker["points"])
    assert done.termination == "converged"


def test_a_validation_under_a_payload_is_identified_as_from_its_files(root, tmp_path):
    # The elasto-geometric scenario validates under a 10 kg payload; arrays give it as the
    # fourth element of `validate`, and the identification is the one of the files. Without
    # it, where the calibration poses carry a payload, `validate` is refused: the validation
    # poses had been predicted with no load.
    sc = root / "scenarios" / "elastogeometric.toml"
    s = calbench.simulate(sc, 0, out=tmp_path / "sim")
    assert np.all(s["validation_payload"] == 10.0)
    common = dict(method="lm", compliance="gravity")
    files = calbench.identify(s["robot"], data=tmp_path / "sim" / "measurements.csv",
                              validate=tmp_path / "sim" / "validation.csv", **common)
    arrays = calbench.identify(
        s["robot"], s["q"], s["points"], payload=s["payload"],
        validate=(s["validation_q"], s["validation_points"], None, s["validation_payload"]),
        **common)
    assert arrays.validation["after_mm"]["rms"] == pytest.approx(
        files.validation["after_mm"]["rms"], rel=1e-6)  # the files round to 9 decimals
    for short in ((s["validation_q"], s["validation_points"]),
                  (s["validation_q"], s["validation_points"], None, None)):
        with pytest.raises(calbench.SettingError,
                           match=r"^setting `validate`: the calibration poses carry a payload"):
            calbench.identify(s["robot"], s["q"], s["points"], payload=s["payload"],
                              validate=short, **common)
    # Calibration rows read from a file with their payloads: a validation without one is
    # refused by the identification itself, arrays and files alike.
    bare = tmp_path / "bare.csv"
    bare.write_text("".join(",".join(l.split(",")[:9]) + "\n" for l in
                            (tmp_path / "sim" / "validation.csv").read_text().splitlines()))
    for short in ((s["validation_q"], s["validation_points"]), bare):
        with pytest.raises(calbench.SettingError,
                           match=r"^setting `validate`: .*gives no payload, and the calibration"):
            calbench.identify(s["robot"], data=tmp_path / "sim" / "measurements.csv",
                              validate=short, **common)
    # Without a payload for the calibration, a payload of None is none: it had been refused
    # as "expected 1 dimensions, got shape ()".
    v = (s["validation_q"], s["validation_points"])
    a = calbench.identify(s["robot"], s["q"], s["points"], validate=v, **common)
    b = calbench.identify(s["robot"], s["q"], s["points"], validate=(*v, None, None), **common)
    assert a.validation == b.validation

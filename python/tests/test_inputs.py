"""Inputs a script gives as docs/python.md says it may: labels that read like missing values,
numpy arrays in a scenario dict, callables without a name, and vectors that are not real."""
import functools
import tomllib

import numpy as np
import pandas as pd
import pytest

import calbench

CI_GUARD = "scenarios/ci-guard.toml"


def scenario(root):
    with open(root / CI_GUARD, "rb") as f:
        return tomllib.load(f)


def test_trials_keep_labels_that_read_like_missing_values(root):
    sc = scenario(root)
    sc["methods"][0]["label"] = "NA"
    sc["methods"][1]["label"] = "null"
    study = calbench.run(sc, trials=2)
    assert list(study.trials["method"].unique()) == ["NA", "null", "lm"]
    # Empty cells are still missing: ci-guard's `error` column is absent, its numbers finite.
    assert study.trials["after_rms_mm"].notna().all()


def test_a_numpy_array_in_a_scenario_dict_is_the_list_of_its_values(root):
    listed = scenario(root)
    arrays = scenario(root)
    arrays["tracker"]["pose"] = np.array(arrays["tracker"]["pose"])
    arrays["calibration"]["strategies"] = np.array(arrays["calibration"]["strategies"])
    a = calbench.run(arrays, trials=2)
    b = calbench.run(listed, trials=2)
    assert a.summary_json() == b.summary_json()
    assert a.trials_csv() == b.trials_csv()


def test_a_problem_refuses_a_vector_that_is_not_real(root):
    seen = {}

    def probe(problem):
        x = np.asarray(problem.x0, dtype=float)
        for name, bad in (("complex", x.astype(complex)), ("bool", x > 1), ("list", [True] * len(x))):
            for f in (problem.residual, problem.jacobian):
                with pytest.raises(calbench.SettingError, match="`x`") as e:
                    f(bad)
                seen[name] = str(e.value)
        return x

    study = calbench.run(scenario(root), trials=1, methods={"probe": probe})
    assert study.results.set_index("method").loc["probe", "failures"] == 0
    assert "complex" in seen["complex"] and "bool" in seen["bool"] and "bool" in seen["list"]


def test_a_task_method_without_a_name_is_refused_naming_name(root):
    def fit(problem, scale):
        return np.asarray(problem.x0) * scale

    task = root / "tasks" / "ipa-ur10-series-d.toml"
    with pytest.raises(calbench.SettingError, match="`name`.*__name__"):
        calbench.task(task, functools.partial(fit, scale=1.0), models=["kinematic"])
    with pytest.raises(calbench.SettingError, match="`name`.*empty"):
        calbench.task(task, functools.partial(fit, scale=1.0), models=["kinematic"], name="")


def test_k_is_refused_where_the_data_hold_no_orientation(cli, tmp_path):
    # docs/formats.md § 2.6.2: `--k` is refused for distance, plane and sphere files.
    sc = tmp_path / "d.toml"
    sc.write_text(
        'name = "d"\nseed = 2\ntrials = 2\nrobot = "irb2600"\n\n[instruments_study]\n'
        'poses = [30]\nstrategies = ["random"]\ncandidates = 60\nvalidation = 10\n\n'
        '[errors]\nkind = "paper"\n\n[[measurement]]\nkind = "distance"\n'
    )
    cli("simulate", sc, "--out", tmp_path / "sim")
    robot = calbench.Robot.builtin("irb2600")
    data = tmp_path / "sim" / "measurements.csv"
    assert calbench.identify(robot, data=data, method="lm").rank > 0
    with pytest.raises(calbench.SettingError, match="`options.k`.*tracker"):
        calbench.identify(robot, data=data, method="lm", options={"k": 10.0})


def test_a_fold_seed_without_folds_is_refused(root):
    # docs/formats.md § 2.6: `--cv-seed` seeds the folds of `--cv` or `--models` only.
    robot = calbench.Robot.builtin("irb2600")
    q = np.random.default_rng(1).uniform(-60.0, 60.0, (40, 6))
    p = robot.fk(q) + np.random.default_rng(2).normal(0.0, 0.01, (40, 3))
    with pytest.raises(calbench.SettingError, match="setting `cv_seed`: seeds the folds of cv or"):
        calbench.identify(robot, q, p, cv_seed=3)
    assert calbench.identify(robot, q, p, cv=4, cv_seed=3)["cv"]["k"] == 4


def test_a_dict_nested_too_deep_or_containing_itself_is_refused_naming_its_key(root):
    # A list nested 100 000 deep, or one that contains itself, overflowed the stack (SIGSEGV).
    deep = []
    for _ in range(100_000):
        deep = [deep]
    looped = []
    looped.append(looped)
    for bad in (deep, looped):
        sc = scenario(root)
        sc["description"] = bad
        with pytest.raises(calbench.SettingError, match="`description`: nests lists or dicts"):
            calbench.run(sc, trials=2)
    itself = scenario(root)
    itself["errors"] = itself
    with pytest.raises(calbench.SettingError, match="nests lists or dicts"):
        calbench.run(itself, trials=2)
    robot = calbench.Robot.builtin("irb2600")
    q = np.random.default_rng(1).uniform(-30.0, 30.0, (20, 6))
    with pytest.raises(calbench.SettingError, match="`options.max_iter`: nests"):
        calbench.identify(robot, q, robot.fk(q), method="lm", options={"max_iter": deep})


def test_a_numpy_complex_scalar_is_refused_as_a_python_complex_is(root):
    # numpy's `float` of a complex drops the imaginary part with only a ComplexWarning.
    sc = scenario(root)
    sc["tracker"]["mpe_a_um"] = np.complex128(15 + 7j)
    with pytest.raises(calbench.SettingError, match="`tracker.mpe_a_um`: complex"):
        calbench.run(sc, trials=2)
    robot = calbench.Robot.builtin("irb2600")
    with pytest.raises(calbench.SettingError, match="`errors.a1`: must be a number"):
        robot.with_errors({"a1": np.complex64(0.2 + 5j)})
    q = np.random.default_rng(1).uniform(-30.0, 30.0, (20, 6))
    with pytest.raises(calbench.SettingError, match="`prior.d2`: σ must be a number"):
        calbench.identify(robot, q, robot.fk(q), prior={"d2": np.complex128(0.1 + 1j)})


def test_a_trial_count_of_2_63_or_more_is_refused_naming_trials(root):
    # It wrapped to a negative count, refused as the scenario file's.
    # 2**64 too, where the range given was the 64-bit integer's.
    for n in (2**63, 2**64 - 1, 2**64, 10**30):
        with pytest.raises(calbench.SettingError, match=f"`trials`: must be between 1 and 1000000000, got {n}"):
            calbench.run(str(root / CI_GUARD), trials=n)


def test_a_study_seed_has_63_bits_and_identify_s_seed_64(root):
    # A study's seed is the scenario file's TOML integer; the message gives that range.
    for n in (2**63, 2**64 - 1):
        with pytest.raises(calbench.SettingError, match=r"`seed`: .* out of range \(0 to 2\^63 - 1\)"):
            calbench.run(str(root / CI_GUARD), trials=2, seed=n)
    calbench.run(str(root / CI_GUARD), trials=2, seed=2**63 - 1)
    # The same in a scenario given as a dict: it had been called "beyond the 64-bit range".
    sc = tomllib.loads((root / CI_GUARD).read_text())
    sc["seed"] = 2**63
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `seed`: must be from -2\^63 to 2\^63 - 1, the integers a "
                             r"scenario file holds$"):
        calbench.run(sc, trials=2)
    with pytest.raises(calbench.SettingError, match=r"`seed`: .* out of range \(0 to 2\^64 - 1\)"):
        calbench.identify(*_pose_data(), method="bas", seed=2**64)
    calbench.identify(*_pose_data(), method="bas", seed=2**64 - 1, options={"iterations": 5})


def _pose_data():
    robot = calbench.Robot.builtin("irb2600")
    q = np.random.default_rng(1).uniform(-30.0, 30.0, (20, 6))
    return robot, q, robot.fk(q)


def test_a_key_that_is_not_a_string_is_named_with_its_place(root):
    sc = scenario(root)
    sc[7] = 1
    with pytest.raises(calbench.SettingError, match=r"`scenario`: every key must be a string, got 7"):
        calbench.run(sc, trials=2)
    sc = scenario(root)
    sc["tracker"][(1, 2)] = 1
    with pytest.raises(calbench.SettingError, match=r"`tracker`: every key must be a string, got \(1, 2\)"):
        calbench.run(sc, trials=2)


def test_text_and_dates_are_not_numbers_and_a_shape_is_named():
    robot = calbench.Robot.builtin("irb2600")
    # Text is not a number, though numpy would read "10" as 10; nor is a date.
    for text in (np.full((4, 6), "10"), np.full((4, 6), b"10"), np.full((4, 6), "10", object)):
        with pytest.raises(calbench.SettingError, match="`q`: a text array"):
            robot.fk(text)
        with pytest.raises(calbench.SettingError, match="`q`: a text array"):
            calbench.identify(robot, text, np.zeros((4, 3)))
        with pytest.raises(calbench.SettingError, match="`q`: a text array"):
            calbench.identifiability(robot, text)
    with pytest.raises(calbench.SettingError, match="`q`: a date or time array"):
        robot.fk(np.zeros((4, 6), "datetime64[s]"))
    # A bool or a complex number among numbers is no number either: a DataFrame with a bool
    # column (an object array) and nested lists numpy would read as numbers had been taken
    # with True as 1 and False as 0.
    frame = pd.DataFrame({"q1": [True, False, True, False], "q2": [0.0, 10.0, 20.0, 30.0],
                          "q3": 0.0, "q4": 0.0, "q5": 0.0, "q6": 0.0})
    for what, mixed in [("bool", frame), ("bool", [[True, 0, 0, 0, 0, 0.0]] * 4),
                        ("bool", np.array([[np.bool_(True), 0.0, 0, 0, 0, 0]] * 4, object)),
                        ("complex", [[1j, 0, 0, 0, 0, 0.0]] * 4)]:
        with pytest.raises(calbench.SettingError, match=f"`q`: a {what} array is not taken"):
            robot.fk(mixed)
        with pytest.raises(calbench.SettingError, match=f"`q`: a {what} array is not taken"):
            calbench.identify(robot, mixed, np.zeros((4, 3)))
    # Numbers of mixed types are numbers.
    assert robot.fk([[1, 0.0, 0, 0, 0, 0]] * 4).shape == (4, 3)
    assert robot.fk(frame.astype(float)).shape == (4, 3)
    # fk names the array's shape, as identify does, not its first row.
    with pytest.raises(calbench.SettingError, match=r"`q`: expected shape \(N, 6\), got \(2, 5\)"):
        robot.fk(np.zeros((2, 5)))


def test_a_python_method_of_the_wrong_length_is_named(root):
    # Its message named no method: "the method returned 3 values for 24 parameters".
    def three(problem):
        return np.zeros(3)

    def nan(problem):
        return np.full(len(problem.x0), np.nan)

    study = calbench.run(scenario(root), trials=1, methods={"three": three, "nan": nan})
    t = study.trials
    (error,) = t[t.method == "three"]["error"]
    assert error.startswith("the method `three` returned 3 values for "), error
    (error,) = t[t.method == "nan"]["error"]
    assert error.startswith("the method `nan` returned a non-finite value for `"), error
    # Finite but no robot's: it had been counted rank-deficient with no error, and identify
    # had blamed the readings ("the identified robot cannot be physically right").
    def huge(problem):
        return np.full(len(problem.x0), 1e200)

    study = calbench.run(scenario(root), trials=1, methods={"huge": huge})
    t = study.trials
    (error,) = t[t.method == "huge"]["error"]
    assert error.startswith("the method `huge` returned an error of `"), error
    assert error.endswith("(a robot file's range), got 1e200"), error
    task = root / "tasks" / "barrett-wam.toml"
    with pytest.raises(calbench.ComputeError, match=r"^the method `huge` returned an error of `"):
        calbench.task(task, huge, models=["kinematic"])
    task = root / "tasks" / "barrett-wam.toml"
    with pytest.raises(calbench.ComputeError, match=r"^the method `three` returned 3 values for \d+ parameters$"):
        calbench.task(task, three, models=["kinematic"])
    with pytest.raises(calbench.ComputeError, match=r"^the method `mine` returned 3 values for "):
        calbench.task(task, three, models=["kinematic"], name="mine")


def test_a_scenario_dict_value_of_the_wrong_type_is_a_setting_error_naming_its_key(root, tmp_path):
    # A dict is no file: its values were refused as a FileError of `<scenario dict>`.
    sc = scenario(root)
    sc["trials"] = "ten"
    with pytest.raises(calbench.SettingError, match=r'^setting `trials`: invalid type: string "ten", expected a whole number ≥ 0$'):
        calbench.run(sc)
    sc = scenario(root)
    sc["tracker"]["mpe_a_um"] = "x"
    with pytest.raises(calbench.SettingError, match=r'^setting `tracker.mpe_a_um`: invalid type: string "x", expected a number$'):
        calbench.simulate(sc)
    # An instruments study's dict, read as TOML text: no line of that text is named.
    study = tomllib.loads(
        'name = "d"\nseed = 2\ntrials = 2\nrobot = "irb2600"\n\n[instruments_study]\n'
        'poses = [30]\nstrategies = ["random"]\ncandidates = 60\nvalidation = 10\n\n'
        '[errors]\nkind = "paper"\n\n[[measurement]]\nkind = "distance"\n'
    )
    study["measurement"][0]["noise_um"] = "loud"
    with pytest.raises(calbench.SettingError, match=r"^setting `measurement\[0\]\.noise_um`: invalid type") as e:
        calbench.run(study, out=tmp_path / "out")
    assert "line" not in str(e.value) and "<scenario dict>" not in str(e.value), e.value
    assert not (tmp_path / "out").exists()


def test_a_runs_warnings_are_python_warnings(root, tmp_path):
    # The threads capped (in memory, a shard, a study of cells) and a killed run's checkpoint
    # started over: a UserWarning with the command line's words, where they had been dropped
    # (printed on stderr only with progress=True).
    with pytest.warns(UserWarning, match="99999 threads asked for; running on 2"):
        calbench.run(root / CI_GUARD, trials=2, threads=99999)
    with pytest.warns(UserWarning, match="99999 threads asked for"):
        calbench.run(root / CI_GUARD, trials=2, threads=99999, shard=(0, 2), out=tmp_path / "s")
    with pytest.warns(UserWarning, match="99999 threads asked for"):
        calbench.run(root / "scenarios/ban-fig3.toml", trials=1, threads=99999, out=tmp_path / "f")
    out = tmp_path / "again"
    (tmp_path / ".again.checkpoint").mkdir()
    with pytest.warns(UserWarning, match="held the checkpoint of an unfinished run"):
        calbench.run(root / CI_GUARD, trials=2, shard=(0, 2), out=out)


def test_an_unknown_option_of_igg3_lists_the_weights_keys_too():
    # igg3's table feeds the ridge and the weights: the list named the ridge's keys alone.
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `options.bogus`: unknown field `bogus`, expected one of `xi`, "
                             r"`scale`, `eps`, `max_iter`, `weight`, `k0`, `k1`, `sigma0`, `per`$"):
        calbench.identify(*_pose_data(), method="igg3", options={"bogus": 1})

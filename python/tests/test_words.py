"""What the Python API says when it refuses or warns: the setting it names, the row and column
of an array's cell, the method's own name, and the caller's line for a warning."""
import numpy as np
import pandas as pd
import pytest

import calbench

def test_a_pose_count_above_the_most_names_its_key_once(ci_guard):
    # The key had been given twice: "setting `setting`: setting `validation.count`: …".
    sc = ci_guard
    for section, key in [("validation", "count"), ("calibration", "count"),
                         ("calibration", "candidates")]:
        bad = {**sc, section: {**sc[section], key: 10**9}}
        with pytest.raises(calbench.SettingError,
                           match=rf"^setting `{section}\.{key}`: must be at most 10000000 poses, "
                                 r"got 1000000000$"):
            calbench.run(bad, trials=1)


def test_a_section_given_as_a_value_is_refused_without_a_rust_type(ci_guard):
    sc = ci_guard
    sc["robot"] = "irb2600"
    with pytest.raises(calbench.SettingError) as e:
        calbench.run(sc, trials=1)
    assert str(e.value) == ('setting `robot`: invalid type: string "irb2600", expected a table '
                            "of keys"), str(e.value)


def test_a_task_method_name_with_a_control_character_is_refused(root):
    # It had reached task.json and the leaderboard; `run`'s method labels refuse it.
    task = root / "tasks" / "barrett-wam.toml"
    for name in ["fit\x1b[31m", "fit\u202e", "a\nb"]:
        with pytest.raises(calbench.SettingError, match=r"^setting `name`: .* control characters"):
            calbench.task(task, lambda p: p.x0, name=name, models=["kinematic"])


def test_readings_given_as_arrays_are_refused_as_the_points_setting():
    # A refusal of the readings as a whole had been `FileError "<arrays>": data`; the caller
    # gave `q` and `points`, no file and no `data`.
    robot = calbench.Robot.builtin("irb2600")
    q = np.random.default_rng(1).uniform(-30, 30, (40, 6))
    line = np.outer(np.arange(40.0), [1.0, 0.0, 0.0])
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `points`: registration: the measured points are \(nearly\) "
                             r"collinear"):
        calbench.identify(robot, q, line)


def test_a_missing_value_is_refused_at_its_row_and_column():
    # pandas' pd.NA (a nullable column) had failed float conversion, naming no cell; it is
    # refused as a None or a NaN is.
    robot = calbench.Robot.builtin("irb2600")
    rng = np.random.default_rng(2)
    q = pd.DataFrame(rng.uniform(-30, 30, (40, 6))).astype("Float64")
    q.iloc[3, 2] = pd.NA
    points = rng.normal(size=(40, 3)) * 500
    with pytest.raises(calbench.SettingError, match=r"^setting `q`: row 3, column q3: NaN is not"):
        calbench.identify(robot, q, points)
    listed = points.tolist()
    listed[5][1] = pd.NA
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `points`: row 5, column y: NaN is not"):
        calbench.identify(robot, q.fillna(0.0), listed)
    with pytest.raises(calbench.SettingError, match=r"^setting `sigma`: row 5: NaN is not"):
        calbench.identify(robot, q.fillna(0.0), points, sigma=[0.01] * 5 + [pd.NA] + [0.01] * 34)


def test_a_masked_value_is_refused_at_its_row_and_column():
    # numpy reads a masked array as the values under its mask, which had been taken as they
    # were (99 here); a masked cell is refused as a missing one is, and an array with nothing
    # masked is taken as its values.
    robot = calbench.Robot.builtin("irb2600")
    rng = np.random.default_rng(3)
    q = np.ma.masked_array(rng.uniform(-30, 30, (40, 6)), mask=False)
    q[4, 1] = np.ma.masked
    q.data[4, 1] = 99.0
    points = rng.normal(size=(40, 3)) * 500
    with pytest.raises(calbench.SettingError, match=r"^setting `q`: row 4, column q2: NaN is not"):
        calbench.identify(robot, q, points)
    with pytest.raises(calbench.SettingError, match=r"^setting `q`: row 4, column q2: .*NaN"):
        robot.fk(q)
    whole = np.ma.masked_array(q.data, mask=False)
    np.testing.assert_array_equal(robot.fk(whole), robot.fk(q.data))


def test_rotations_of_another_shape_name_both_accepted_shapes():
    robot = calbench.Robot.builtin("irb2600")
    q = np.zeros((4, 6))
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `rotations`: expected \(N, 4\) quaternions or "
                             r"\(N, 3, 3\) rotation matrices, got shape \(4,\)"):
        calbench.identify(robot, q, np.zeros((4, 3)), rotations=np.array([1.0, 0, 0, 0]))


def test_a_precision_that_is_no_finite_number_is_said_so(ci_guard):
    sc = ci_guard
    for bad in ["infmm", "nan%", "inf %"]:
        with pytest.raises(calbench.SettingError,
                           match=rf'^setting `precision`: "{bad}" is not a finite number;'):
            calbench.run(sc, trials=2, precision=bad)
    with pytest.raises(calbench.SettingError, match=r'^setting `precision`: "-1%" must be positive;'):
        calbench.run(sc, trials=2, precision="-1%")


def test_comparisons_split_every_interval_and_keep_their_columns_when_empty(ci_guard):
    sc = ci_guard
    study = calbench.run(sc, trials=3)
    c = study.comparisons
    assert len(c) > 0
    for name in ["diff_ci95", "ci95"]:
        for row, (lo, hi) in zip(c[name], zip(c[f"{name}_lo"], c[f"{name}_hi"])):
            assert (row is None and np.isnan(lo) and np.isnan(hi)) or [lo, hi] == list(row)
    # One method on one pose set compares nothing: the frame has the columns and no row,
    # `sweep_value` among them in a sweep, as a sweep's rows have it.
    one = {**sc, "methods": sc["methods"][:1], "sweep": {"key": "outliers.count",
                                                        "values": [0, 2]}}
    one["calibration"] = {**sc["calibration"], "strategies": ["random"]}
    empty = calbench.run(one, trials=2).comparisons
    assert len(empty) == 0
    for name in ["a", "b", "sweep_value", "metric", "diff_ci95_lo", "ci95_hi"]:
        assert name in empty.columns, list(empty.columns)
    # With rows, the columns stand in the same, documented, order (they had come sorted).
    rows = calbench.run({**sc, "sweep": one["sweep"]}, trials=2).comparisons
    assert len(rows) > 0
    assert list(rows.columns) == list(empty.columns)
    assert list(c.columns[:4]) == ["a", "b", "metric", "n"]


def test_a_run_s_warning_points_at_the_caller_s_line(ci_guard):
    # It had pointed into calbench/__init__.py.
    sc = ci_guard
    sc["sweep"] = {"key": "outliers", "values": [
        {"count": 0, "magnitude_mm": [0.5, 1.0]},
        {"count": 0, "magnitude_mm": [2.0, 3.0]},
    ]}
    with pytest.warns(UserWarning, match="no effect") as caught:
        calbench.run(sc, trials=2)
    assert {w.filename for w in caught if "no effect" in str(w.message)} == {__file__}


def test_a_limit_warning_names_the_joint_its_value_and_its_limits():
    robot = calbench.Robot.builtin("irb2600")
    with pytest.warns(calbench.LimitWarning,
                      match=r"\(q\[1\], q\[2\], q\[3\] and 1 more row\): in q\[1\], joint 2 is "
                            r"400 deg, outside its limits \[-95, 155\]$") as caught:
        robot.fk([[0, 0, 0, 0, 0, 0]] + [[0, 400, 0, 0, 0, 0]] * 4)
    assert caught[0].filename == __file__

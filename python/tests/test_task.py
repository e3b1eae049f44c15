"""``calbench.task``: a Python method enters a real-data task's open division through the
identify pipeline, scored on the task's validation rows like the command line's entries."""
import json
import os
import warnings

import numpy as np
import pytest

import calbench


def gauss_newton(problem):
    x = np.array(problem.x0, dtype=float)
    for _ in range(50):
        r = problem.residual(x)
        J = problem.jacobian(x)
        dx = np.linalg.lstsq(J, -r, rcond=None)[0]
        x = x + dx
        if np.max(np.abs(dx)) < 1e-10:
            break
    return x, "converged"


def test_a_python_method_enters_the_wam_task_in_the_open_division(root, cli, tmp_path):
    task = root / "tasks" / "barrett-wam.toml"
    # The kinematic model alone (the task's own `[models]` would compare four by CV).
    py = calbench.task(task, gauss_newton, models=["kinematic"], out=tmp_path / "py")
    j = py["task"]
    assert j["format"] == "calbench-task-1"
    assert j["task"] == "barrett-wam"
    assert j["entrant"] == "python:gauss_newton" and j["method"] == "gauss_newton"
    assert j["division"] == "open"
    assert j["models"] == ["kinematic"] and j["chosen_by"] == "given"
    assert [p["value"] for p in j["published"]] == [2.92]
    lo, hi = j["ci95"]
    assert lo < j["value"] < hi
    assert json.loads((tmp_path / "py" / "task.json").read_text()) == j
    # Recorded as the command line records an entry (its identification's method is
    # `external`, its own name the entry's).
    db = tmp_path / "calbench.sqlite"
    cli("record", tmp_path / "py", "--db", db, "--task", task)
    # The same least squares as the command line's lm, on the same rows: the same figure.
    cli("task", task, "--method", "lm", "--models", "kinematic", "--out", tmp_path / "lm")
    lm = json.loads((tmp_path / "lm" / "task.json").read_text())
    assert lm["division"] == "closed" and lm["entrant"] == "calbench"
    assert lm["task_hash"] == j["task_hash"]
    assert abs(lm["value"] - j["value"]) < 1e-3 * lm["value"], (lm["value"], j["value"])
    # A calbench method by name is the command line's entry.
    with warnings.catch_warnings():
        # It converges: no warning.
        warnings.simplefilter("error", calbench.ConvergenceWarning)
        same = calbench.task(task, "lm", models=["kinematic"])["task"]
    assert same["value"] == lm["value"] and same["division"] == "closed"


def test_a_python_method_whose_result_makes_the_robot_worse_is_named_first(root, tmp_path):
    # The task's readings are sound; the method's vector is not: the refusal names the method
    # and its result first, where it told to check the readings alone.
    def far_off(problem):
        x = np.array(problem.x0, dtype=float)
        x[0] = 50.0
        return x

    with pytest.raises(calbench.FileError,
                       match=r"by the method `far_off`, supplied from outside, makes the robot "
                             r"worse: .*Check the vector the method returns, then "
                             r"the readings") as refused:
        calbench.task(root / "tasks" / "barrett-wam.toml", far_off, models=["kinematic"],
                      out=tmp_path / "out")
    assert not (tmp_path / "out").exists()
    # No way past is offered: calbench.identify, whose allow_worse lets a worse result be
    # written, takes calbench's methods alone.
    said = str(refused.value)
    assert "allow_worse" not in said and said.endswith("swapped column).")


def test_an_entry_that_did_not_converge_warns_as_the_command_line_does(root):
    def short(problem):
        x, _ = gauss_newton(problem)
        return x, "max-iterations"

    task = root / "tasks" / "barrett-wam.toml"
    with pytest.warns(calbench.ConvergenceWarning) as caught:
        entry = calbench.task(task, short, models=["kinematic"])
    assert entry["record"]["termination"] == "max-iterations"
    (w,) = caught
    assert str(w.message).startswith("the identification ended `max-iterations` after ")
    assert "did not converge (identified.json, `termination`)" in str(w.message)
    assert issubclass(calbench.ConvergenceWarning, UserWarning)


def test_a_socket_task_runs_from_python_as_the_command_line_runs_it(root, cli, tmp_path):
    """``calbench.task`` on a socket task (docs/formats.md § 9.4) is ``calbench task``: the
    same folder, byte for byte, and the returned ``task`` and ``record`` are its files."""
    task = root / "tasks" / "mukca-panda-6.toml"
    py = calbench.task(task, "lm", out=tmp_path / "py")
    cli("task", task, "--method", "lm", "--out", tmp_path / "cli")
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert names == ["identified.json", "robot.toml", "task.json", "task.toml"]
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == names
    for name in names:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    j = json.loads((tmp_path / "cli" / "task.json").read_text())
    assert py["task"] == j and j["metric"] == "socket_spread_mm" and "socket" in j
    assert py["record"] == json.loads((tmp_path / "cli" / "identified.json").read_text())
    assert py["robot"].joint_count == 7
    # What a socket task does not take is refused, naming the setting.
    with pytest.raises(calbench.SettingError, match="method.*socket task"):
        calbench.task(task, gauss_newton)
    with pytest.raises(calbench.SettingError, match="models.*kinematic model only"):
        calbench.task(task, "lm", models=["kinematic", "beta"])


def test_a_tasks_own_models_are_compared_from_python_as_on_the_command_line(root, cli, tmp_path):
    """Without ``models``, ``calbench.task`` compares the task's own ``[models]`` (docs/formats.md
    § 9.1) as ``calbench task`` without ``--models`` does: the same folder, byte for byte.
    The IPA UR10 Series D task given two candidates, two folds and two fold seeds, written here
    so that it runs in seconds in a debug build."""
    text = (root / "tasks" / "ipa-ur10-series-d.toml").read_text()
    for rel in ["ipa-ur10.mapping.toml", "ipa-ur10-series-d.split"]:
        text = text.replace(f'"{rel}"', json.dumps(str(root / "tasks" / rel)))
    text = text.replace('"../', f'"{root}/')
    task = tmp_path / "ur10-d-two.toml"
    task.write_text(
        text + '\n[models]\ncandidates = ["kinematic", "beta"]\nfolds = 2\nfold_seeds = [0, 1]\n'
    )
    py = calbench.task(task, "lm", out=tmp_path / "py")
    cli("task", task, "--method", "lm", "--out", tmp_path / "cli")
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert {"identified.json", "task.json", "task.toml"} <= set(names)
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == names
    for name in names:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    j = json.loads((tmp_path / "cli" / "task.json").read_text())
    assert py["task"] == j
    assert j["candidates_fixed_by"] == "task" and j["chosen_by"] == "cv"
    assert j["candidates"] == ["kinematic", "beta"]
    assert j["cv_choice"]["fold_seeds"] == [0, 1]
    assert [m["model"] for m in j["cv_choice"]["models"]] == ["kinematic", "beta"]
    # Candidates the caller gives replace the task's, named as the caller's.
    given = calbench.task(task, "lm", models=["kinematic"])["task"]
    assert given["candidates"] == ["kinematic"] and given["chosen_by"] == "given"
    assert given["candidates_fixed_by"] == "caller" and given["cv_choice"] is None


def test_a_kernel_residual_entry_from_python_is_the_command_lines(root, cli, tmp_path):
    """The kernel residual term ``gp`` (docs/formats.md § 2.6.1) through the documented Python
    API: ``calbench.task`` with ``models=["kinematic", "kinematic+gp"]`` on the Barrett WAM's
    216 grid poses chooses ``gp`` by CV as ``calbench task --models kinematic,kinematic+gp``
    does, and writes the same folder byte for byte, ``kernel.json`` with it (``task.json`` but
    for who fixed the candidates: the caller, or the command line); the record's
    ``kernel_residual`` holds the file's hyperparameters."""
    task = root / "tasks" / "barrett-wam.toml"
    models = ["kinematic", "kinematic+gp"]
    # The returned robot lacks the kernel residual, as the command line's robot.toml does:
    # both say so.
    with pytest.warns(UserWarning, match=r"kernel residual `gp` is not in `robot`"):
        py = calbench.task(task, "lm", models=models, out=tmp_path / "py")
    r = cli("task", task, "--method", "lm", "--models", ",".join(models), "--out",
            tmp_path / "cli")
    assert "warning: the chosen model's kernel residual `gp` is written to kernel.json" in r.stderr
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert {"identified.json", "kernel.json", "robot.toml", "task.json"} <= set(names)
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == names
    for name in names:
        if name != "task.json":
            py_bytes = (tmp_path / "py" / name).read_bytes()
            assert py_bytes == (tmp_path / "cli" / name).read_bytes(), name
    j = json.loads((tmp_path / "cli" / "task.json").read_text())
    assert py["task"]["candidates_fixed_by"] == "caller"
    assert {**py["task"], "candidates_fixed_by": j["candidates_fixed_by"]} == j
    assert j["models"] == ["kinematic", "gp"] and j["chosen_by"] == "cv"
    record = py["record"]
    assert record == json.loads((tmp_path / "cli" / "identified.json").read_text())
    assert record["cv_best"] == "gp"
    cv = {m["model"]: m["rms"] for m in record["cv_models"]}
    assert cv["gp"] < cv["kinematic"], cv
    assert py["task"]["division"] == "open"
    kernel = json.loads((tmp_path / "cli" / "kernel.json").read_text())
    assert kernel["term"] == "gp" and kernel["hyperparameters"] == record["kernel_residual"]
    assert len(kernel["alpha_mm"]) == record["kernel_residual"]["training_rows"] == 216


def test_a_name_with_a_calbench_method_is_refused_naming_it(root, tmp_path):
    # `name` was dropped without a word when the method was calbench's own ("lm"): the entry
    # ran as `lm`, not under the name given.
    out = tmp_path / "entry"
    with pytest.raises(calbench.SettingError, match=r"^setting `name`: names a method written "
                                                    r"in Python; .* \('lm'\)$"):
        calbench.task(root / "tasks" / "barrett-wam.toml", "lm", name="mine", out=out)
    assert not out.exists()


def test_method_options_are_the_command_line_s_set(root, cli, tmp_path):
    # options={...} as `calbench task --set KEY=VALUE`: the same folder, byte for byte.
    task = root / "tasks" / "barrett-wam.toml"
    with pytest.warns(calbench.ConvergenceWarning, match="ended `max-iterations` after 3 "):
        calbench.task(task, "lm", models=["kinematic"], options={"max_iter": 3}, out=tmp_path / "py")
    cli("task", task, "--method", "lm", "--models", "kinematic", "--set", "max_iter=3",
        "--out", tmp_path / "cli")
    for name in ("identified.json", "robot.toml"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    py = json.loads((tmp_path / "py" / "task.json").read_text())
    j = json.loads((tmp_path / "cli" / "task.json").read_text())
    assert {**py, "candidates_fixed_by": j["candidates_fixed_by"]} == j
    with pytest.raises(calbench.SettingError, match=r"^setting `options.max_itr`: unknown field"):
        calbench.task(task, "lm", options={"max_itr": 3})
    with pytest.raises(calbench.SettingError, match=r"^setting `options`: a method written in Python"):
        calbench.task(task, gauss_newton, options={"max_iter": 3})
    with pytest.raises(calbench.SettingError, match=r"^setting `options`: expected a dict"):
        calbench.task(task, "lm", options=[("max_iter", 3)])
    # The method is chosen by `method`: a `name` among the options was ignored here, and
    # `--set name=…` ran that method instead of `--method`'s.
    with pytest.raises(calbench.SettingError,
                       match=r'^setting `options.name`: "ls" among the options: the method is chosen apart'):
        calbench.task(task, "lm", options={"name": "ls"})
    robot = calbench.Robot.builtin("irb2600")
    q = np.random.default_rng(3).uniform(-30.0, 30.0, (20, 6))
    with pytest.raises(calbench.SettingError, match=r'^setting `options.name`: "bogus" among'):
        calbench.identify(robot, q, robot.fk(q), method="lm", options={"name": "bogus"})
    o = cli("task", task, "--method", "lm", "--set", 'name="ls"', "--out", tmp_path / "named",
            ok=False)
    assert o.returncode == 1 and not (tmp_path / "named").exists()
    assert 'setting `--set name`: "ls" among the options' in o.stderr, o.stderr


def test_a_refusal_names_what_calbench_task_takes(root, tmp_path):
    """A refusal of an entry names ``calbench.task``'s own keywords, as ``calbench task``
    names its flags: the cross-validation among the candidate models by ``models``, whose
    folds they are (``calbench.identify`` names them ``cv``), and a way past a check that
    ``calbench.task`` does not take as ``calbench.identify``'s."""
    # 14 UR10 rows compared by the task's own two candidates on two folds: 7 training points,
    # 21 readings for the 23 parameters of `kinematic`.
    text = (root / "tasks" / "ipa-ur10-series-d.toml").read_text()
    mapping = json.dumps(str(root / "tasks" / "ipa-ur10.mapping.toml"))
    text = text.replace('"ipa-ur10.mapping.toml"', mapping)
    text = text.replace('"ipa-ur10-series-d.split"', '"few.split"').replace('"../', f'"{root}/')
    (tmp_path / "few.split").write_text("rows 632\ncalibration 0-13\nvalidation 14-631\n")
    few = tmp_path / "few.toml"
    few.write_text(text + '\n[models]\ncandidates = ["kinematic", "beta"]\nfolds = 2\nfold_seeds = [0]\n')
    with pytest.raises(calbench.SettingError) as e:
        calbench.task(few, "lm")
    assert str(e.value).startswith(
        "setting `models`: fold 1 of 2: the model `kinematic` identified on the other folds' 7 "
        "points (21 readings for 23 parameters) ended rank-deficient"
    ), e.value
    # The WAM's x and y columns swapped, a mirror image of the robot: physically implausible,
    # past which only calbench.identify goes. (Millimetres read as metres are refused before
    # any identification: validation points in another unit score no robot.)
    mapping = (root / "tasks" / "barrett-wam.mapping.toml").read_text()
    mirrored = mapping.replace('["x_t", "y_t"', '["y_t", "x_t"').replace(
        '["x_dif", "y_dif"', '["y_dif", "x_dif"')
    assert mirrored != mapping
    (tmp_path / "mirror.mapping.toml").write_text(mirrored)
    text = (root / "tasks" / "barrett-wam.toml").read_text().replace('"../', f'"{root}/')
    mirror = tmp_path / "mirror.toml"
    mirror.write_text(text.replace('"barrett-wam.mapping.toml"', '"mirror.mapping.toml"'))
    with pytest.raises(calbench.FileError, match="cannot be physically right") as e:
        calbench.task(mirror, "lm", models=["kinematic"], out=tmp_path / "out")
    assert str(e.value).endswith(
        "or pass calbench.identify's allow_implausible=True to write it with a warning"
    ), e.value
    assert not (tmp_path / "out").exists()


def test_an_out_holding_the_tasks_robot_under_a_written_name_is_refused(root, tmp_path):
    # The entry writes robot.toml (and residuals.csv, report.md, kernel.json) as the command
    # line's does; an out that holds the task's robot under that name is refused before any
    # work, where only identified.json, task.json and task.toml had been guarded and the
    # robot was written over by the calibrated one.
    robot = tmp_path / "robot.toml"
    robot.write_bytes((root / "examples" / "barrett-wam" / "wam.toml").read_bytes())
    before = robot.read_bytes()
    text = (root / "tasks" / "barrett-wam.toml").read_text().replace('"../', f'"{root}/')
    mapping = json.dumps(str(root / "tasks" / "barrett-wam.mapping.toml"))
    text = text.replace('"barrett-wam.mapping.toml"', mapping)
    text = text.replace(f'"{root}/examples/barrett-wam/wam.toml"', '"robot.toml"')
    task = tmp_path / "t.toml"
    task.write_text(text)
    with pytest.raises(calbench.SettingError, match=r"^setting `out`: .*robot\.toml is an input"):
        calbench.task(task, "lm", models=["kinematic"], out=tmp_path)
    assert robot.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["robot.toml", "t.toml"]


def test_a_task_file_at_a_path_utf8_cannot_hold_is_read_as_any_path(root, tmp_path):
    """A task file under a folder whose name is not UTF-8 (``os.listdir`` gives such bytes as
    lone surrogates) is read as ``run``'s and ``identify``'s paths are, where ``calbench.task``
    raised a bare UnicodeEncodeError; one that is not there is a calbench.Error."""
    text = (root / "tasks" / "barrett-wam.toml").read_text().replace('"../', f'"{root}/')
    mapping = json.dumps(str(root / "tasks" / "barrett-wam.mapping.toml"))
    text = text.replace('"barrett-wam.mapping.toml"', mapping)
    odd = tmp_path / os.fsdecode(b"t\xfe")
    odd.mkdir()
    (odd / "wam.toml").write_text(text)
    (tmp_path / "wam.toml").write_text(text)
    a = calbench.task(odd / "wam.toml", "lm", models=["kinematic"])
    b = calbench.task(tmp_path / "wam.toml", "lm", models=["kinematic"])
    assert a["task"]["value"] == b["task"]["value"]
    with pytest.raises(calbench.Error, match="missing.toml"):
        calbench.task(os.fspath(odd / "missing.toml"), "lm")


def test_a_robot_file_at_a_path_utf8_cannot_hold_is_read(root, tmp_path):
    """A robot file under a folder whose name is not UTF-8 is read, by ``Robot.from_file`` and
    as a task's robot, where its name had been made lossy and then called "neither a built-in
    robot nor an existing robot file"."""
    odd = tmp_path / os.fsdecode(b"r\xfe")
    odd.mkdir()
    wam = root / "examples" / "barrett-wam" / "wam.toml"
    (odd / "wam.toml").write_bytes(wam.read_bytes())
    assert calbench.Robot.from_file(odd / "wam.toml") == calbench.Robot.from_file(wam)
    text = (root / "tasks" / "barrett-wam.toml").read_text().replace('"../', f'"{root}/')
    text = text.replace(f'robot = "{root}/examples/barrett-wam/wam.toml"', 'robot = "wam.toml"')
    assert 'robot = "wam.toml"' in text
    mapping = json.dumps(str(root / "tasks" / "barrett-wam.mapping.toml"))
    (odd / "t.toml").write_text(text.replace('"barrett-wam.mapping.toml"', mapping))
    a = calbench.task(odd / "t.toml", "lm", models=["kinematic"])
    b = calbench.task(root / "tasks" / "barrett-wam.toml", "lm", models=["kinematic"])
    assert a["task"]["value"] == b["task"]["value"]

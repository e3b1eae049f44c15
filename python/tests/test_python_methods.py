"""Methods written in Python run by `calbench.run` and `calbench.task`: a Gauss–Newton in
numpy gives the η of `ls`, the problem is the weighted least squares of `ls`, and a method
that raises, is interrupted or returns another dtype is a failure or an interrupt named by
its label."""
import sys
import tomllib

import numpy as np
import pytest

import calbench

CI_GUARD = "scenarios/ci-guard.toml"


def load_scenario(root, name=CI_GUARD):
    with open(root / name, "rb") as f:
        return tomllib.load(f)


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


def test_a_python_gauss_newton_gives_the_eta_of_ls(root):
    sc = load_scenario(root)
    study = calbench.run(sc, trials=4, methods={"gn": gauss_newton})
    eta = dict(zip(study.results["method"], study.results["eta_mean_pct"]))
    assert abs(eta["gn"] - eta["ls"]) < 1e-6 * max(1.0, abs(eta["ls"])), eta
    rows = [r for r in study.summary["results"] if r["method"] == "gn"]
    assert rows[0]["failures"] == 0 and rows[0]["terminations"] == {"converged": 4}
    assert "error" in study.trials.columns
    assert study.trials["error"].isna().all()
    # The built-in methods' entries are those of a run without the Python method.
    plain = calbench.run(sc, trials=4)
    assert [r for r in study.summary["results"] if r["method"] != "gn"] == plain.summary["results"]


def test_the_problem_is_the_weighted_least_squares_of_ls(root):
    seen = {}

    def probe(problem):
        x0 = problem.x0
        r0, J = problem.residual(x0), problem.jacobian(x0)
        seen["n"] = len(problem.parameter_names)
        seen["shapes"] = (r0.shape, J.shape, problem.weights.shape, problem.rows_per_point)
        # J is the derivative of r: central differences along a few parameters.
        for k in range(0, len(x0), 5):
            h = 1e-6
            e = np.zeros_like(x0)
            e[k] = h
            fd = (problem.residual(x0 + e) - problem.residual(x0 - e)) / (2 * h)
            seen.setdefault("fd", []).append(np.max(np.abs(fd - J[:, k])) / max(1.0, np.max(np.abs(J[:, k]))))
        with pytest.raises(calbench.SettingError):
            problem.residual(x0[:-1])
        seen["repr"] = repr(problem)
        return list(x0)

    sc = load_scenario(root)
    calbench.run(sc, trials=1, methods={"probe": probe})
    (rs, js, ws, rows) = seen["shapes"]
    assert rows == 3 and ws[0] * 3 == rs[0] and js == (rs[0], seen["n"])
    assert max(seen["fd"]) < 1e-5, seen["fd"]
    assert "parameters" in seen["repr"]


def test_a_label_with_control_characters_is_refused_as_in_a_scenario(root):
    # A label names the method in every file and on the terminal: an ESC, a line break or a
    # bidirectional override in it is refused, as a scenario's `label` is.
    sc = load_scenario(root)
    for label in ["evil\x1b[31m", "two\nlines", "txt\u202eexe"]:
        with pytest.raises(calbench.SettingError, match="without control characters"):
            calbench.run(sc, trials=1, methods={label: gauss_newton})


def test_an_exception_in_a_method_is_a_failure_and_the_study_goes_on(root):
    def boom(problem):
        raise RuntimeError("deliberate, with a comma")

    def short(problem):
        return np.zeros(2)

    def bad_name(problem):
        return problem.x0, "done"

    sc = load_scenario(root)
    study = calbench.run(sc, trials=2, methods={"boom": boom, "short": short, "name": bad_name})
    by = {r["method"]: r for r in study.summary["results"]}
    assert by["boom"]["failures"] == 2 and by["short"]["failures"] == 2 and by["name"]["failures"] == 2
    assert by["ls"]["failures"] == 0
    t = study.trials
    assert set(t[t.method == "boom"]["error"]) == {"RuntimeError: deliberate, with a comma"}
    assert t[t.method == "short"]["error"].str.contains("2 values for").all()
    assert t[t.method == "name"]["error"].str.contains('unknown termination "done"').all()
    with pytest.raises(calbench.SettingError, match="taken"):
        calbench.run(sc, trials=1, methods={"ls": boom})
    with pytest.raises(calbench.SettingError, match="function"):
        calbench.run(sc, trials=1, methods={"x": 3})


def test_an_interrupt_in_a_method_ends_the_run_as_an_interrupt(root):
    # Ctrl-C inside a Python method is not a failure of its trial: the run stops calling
    # Python methods and raises KeyboardInterrupt; the next run is whole.
    calls = []

    def interrupted(problem):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return problem.x0

    sc = load_scenario(root)
    with pytest.raises(KeyboardInterrupt):
        calbench.run(sc, trials=20, threads=1, methods={"i": interrupted})
    assert len(calls) == 3
    study = calbench.run(sc, trials=2, methods={"x0": lambda p: p.x0})
    assert {r["method"]: r["failures"] for r in study.summary["results"]}["x0"] == 0

    def task_interrupted(problem):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        calbench.task(root / "tasks" / "barrett-wam.toml", task_interrupted, models=["kinematic"])


def test_sys_exit_in_a_method_ends_the_run_with_its_code(root):
    # `sys.exit` (SystemExit, no `Exception`) had been taken for a failed trial and the run
    # went on; it ends the run and is raised as it was, its code kept, as KeyboardInterrupt is.
    calls = []

    def leaves(problem):
        calls.append(1)
        if len(calls) == 2:
            sys.exit(3)
        return problem.x0

    sc = load_scenario(root)
    with pytest.raises(SystemExit) as ended:
        calbench.run(sc, trials=20, threads=1, methods={"leaves": leaves})
    assert ended.value.code == 3 and len(calls) == 2
    with pytest.raises(SystemExit):
        calbench.task(root / "tasks" / "barrett-wam.toml", lambda p: sys.exit(4),
                      models=["kinematic"])
    # An `Exception` is still the trial's failure, named in trials.csv.
    study = calbench.run(sc, trials=2, methods={"bad": lambda p: 1 / 0})
    assert {r["method"]: r["failures"] for r in study.summary["results"]}["bad"] == 2


def test_ctrl_c_during_a_run_stops_it(root):
    # SIGINT while the trials run in Rust (no Python method): KeyboardInterrupt within about
    # two chunks of trials, where the run went on to its end.
    import signal
    import threading
    import time

    # Python's own Ctrl-C handler, whatever the disposition inherited: a process started in
    # the background by a shell without job control ignores SIGINT, and Python then keeps
    # ignoring it, so the signal never reached the run and the test ran every trial.
    sc = load_scenario(root)
    timer = threading.Timer(0.5, lambda: signal.raise_signal(signal.SIGINT))
    inherited = signal.signal(signal.SIGINT, signal.default_int_handler)
    started = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            calbench.run(sc, trials=200_000, threads=1)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, inherited)
    assert time.monotonic() - started < 60


def test_a_method_returning_bools_or_complex_numbers_fails_naming_the_dtype(root):
    # Bools were taken as 0 and 1 and complex numbers cut to their real part (with numpy's
    # ComplexWarning) as if the method had returned them; now each is a failure of that method,
    # as a vector of the wrong length is, naming the method and the dtype.
    def flags(problem):
        return np.zeros(len(problem.x0), dtype=bool)

    def flag_list(problem):
        return [False] * len(problem.x0), "converged"

    def complex_(problem):
        return np.asarray(problem.x0, dtype=complex) + 1j

    sc = load_scenario(root)
    methods = {"flags": flags, "flag_list": flag_list, "cplx": complex_}
    study = calbench.run(sc, trials=2, methods=methods)
    by = {r["method"]: r for r in study.summary["results"]}
    assert [by[m]["failures"] for m in methods] == [2, 2, 2] and by["ls"]["failures"] == 0
    t = study.trials.set_index("method")["error"]
    assert set(t["flags"]) == {"the method `flags` returned a bool array (dtype bool), not real "
                               "numbers; it must return a 1-D float array (or a tuple of it and "
                               "a termination name)"}
    assert t["flag_list"].str.contains("`flag_list` returned a bool array (dtype bool)",
                                       regex=False).all()
    assert t["cplx"].str.contains("`cplx` returned a complex array (dtype complex128)",
                                  regex=False).all()
    # In a task, as a vector of the wrong length: the entry's ComputeError.
    with pytest.raises(calbench.ComputeError, match=r"`cplx` returned a complex array"):
        calbench.task(root / "tasks" / "barrett-wam.toml", complex_, models=["kinematic"],
                      name="cplx")


def test_a_method_returning_a_masked_array_fails_on_its_masked_cell(root):
    # The value under the mask had been taken as the method's; a masked cell is missing, a
    # failure of the method as a NaN is. With nothing masked, the values are taken.
    def masked(problem):
        x = np.asarray(problem.x0, dtype=float)
        return np.ma.masked_array(x, mask=[True] + [False] * (len(x) - 1))

    def unmasked(problem):
        return np.ma.masked_array(np.asarray(problem.x0, dtype=float), mask=False)

    def plain(problem):
        return np.asarray(problem.x0, dtype=float)

    sc = load_scenario(root)
    study = calbench.run(sc, trials=2, methods={"masked": masked, "unmasked": unmasked,
                                                "plain": plain})
    by = {r["method"]: r for r in study.summary["results"]}
    assert by["masked"]["failures"] == 2 and by["unmasked"]["failures"] == 0
    assert by["unmasked"]["eta_mean_pct"] == by["plain"]["eta_mean_pct"]
    t = study.trials.set_index("method")["error"]
    assert t["masked"].str.contains("the method `masked` returned a non-finite value for",
                                    regex=False).all(), t["masked"].tolist()


def test_python_methods_run_in_every_sweep_point(root):
    sc = load_scenario(root)
    sc["sweep"] = {"key": "outliers.count", "values": [0, 2]}
    study = calbench.run(sc, trials=2, methods={"gn": gauss_newton})
    df = study.results
    assert sorted(df[df.method == "gn"]["sweep_value"]) == [0, 2]

"""calbench from Python: the kinematic calibration benchmark of industrial robots, numpy in
and out, studies as pandas DataFrames (docs/python.md).

Lengths are in mm, joint values and angles in the robot's units, as on the command line.
Every error is a :class:`calbench.Error` (or a subclass) carrying the command line's message.
"""

import csv
import io
import json
import numbers
import os
import pathlib
import warnings

import numpy as np

from . import _calbench
from ._args import (
    _array,
    _count,
    _dict,
    _flag,
    _names,
    _numbers,
    _path,
    _rotations,
    _scenario,
    _text,
    _validation,
)
from ._calbench import (  # noqa: F401  (re-exported)
    ComputeError,
    ConvergenceWarning,
    Error,
    FileError,
    IoError,
    LimitWarning,
    Problem,
    Robot,
    SettingError,
)

__all__ = [
    "Robot",
    "Problem",
    "IdentifyResult",
    "Study",
    "Comparison",
    "identify",
    "task",
    "simulate",
    "run",
    "identifiability",
    "compare",
    "robots",
    "methods",
    "Error",
    "FileError",
    "SettingError",
    "ComputeError",
    "IoError",
    "LimitWarning",
    "ConvergenceWarning",
]


class IdentifyResult(dict):
    """The result of :func:`identify`: a dict of the record ``identified.json`` holds for the
    same data and options (docs/formats.md ``identify``; keys such as ``parameters``,
    ``errors``, ``covariance``, ``termination``, ``validation_after_mm``, ``cv``, ``priors``,
    ``diagnostics``, for a kind file ``instrument_unknowns``), with attributes.

    Attributes:
        parameters: dict name → identified error (mm, rad), in the order of the estimate.
        parameter_names: the identified parameters, in order.
        termination: why the iterations stopped (``converged``, ``max-iterations``, …).
        iterations, evaluations: of the identification.
        rank: numerical rank of the column-scaled, weighted Jacobian.
        condition_number: its condition number.
        sigma0: unit-weight standard deviation; rms_residual_mm: RMS point residual.
        robot: the compensated :class:`Robot` (``robot.toml``).
        validation: dict of before and after statistics (``before_mm``, ``after_mm``, and
            for full poses ``*_deg``), when the data were validated; else None.
        seconds: wall time of the identification in Rust, s.

        For a tracker's data also (None for the other kinds of data):

        covariance: ndarray (t, t), σ0² (JᵀPJ)⁻¹ at the solution (NaN where undefined).
        residuals: ndarray (N, 3), measured (registered) − predicted points after
            compensation, mm.
        weights: ndarray (N,), the final weight of each point.
        registration_frame: ndarray (4, 4), instrument → base frame.
        registration_rounds: identifications run by the registration.
    """

    def __init__(self, fields):
        super().__init__(json.loads(fields.pop("record")))
        self.parameter_names = list(self["parameters"])
        self.parameters = {n: self["errors"][n] for n in self.parameter_names}
        for key in ("termination", "iterations", "evaluations", "rank", "condition_number",
                    "sigma0", "rms_residual_mm", "registration_rounds"):
            setattr(self, key, self.get(key))
        self.validation = None
        if "validation_before_mm" in self:
            self.validation = {
                f"{side}{unit}": self[f"validation_{side}{unit}"]
                for side in ("before", "after")
                for unit in ("_mm", "_deg", "_attitude_deg")
                if f"validation_{side}{unit}" in self
            }
        if "registration_matrix" in fields:
            fields["registration_frame"] = fields.pop("registration_matrix")
        for key in ("covariance", "residuals", "weights", "registration_frame"):
            setattr(self, key, None)
        self.__dict__.update(fields)

    def __repr__(self):
        return (
            f"IdentifyResult({len(self.parameters)} parameters, {self.termination} after "
            f"{self.iterations} iterations)"
        )


def identify(
    robot,
    q=None,
    points=None,
    *,
    data=None,
    rotations=None,
    sigma=None,
    payload=None,
    method="ls",
    options=None,
    registration="identify",
    params=None,
    fix=None,
    prior=None,
    compliance=None,
    models=None,
    cv=None,
    cv_seed=None,
    validate=None,
    holdout=None,
    seed=0,
    allow_rank_deficient=False,
    allow_worse=False,
    allow_implausible=False,
):
    """Identify the errors of ``robot`` from measured points or a measurement file:
    ``calbench identify`` with the same options, as keyword arguments.

    Args:
        robot: the nominal :class:`Robot`.
        q: joint values (N, n) in the robot's units.
        points: measured points (N, 3), mm, in the instrument's frame.
        data: instead of ``q`` and ``points``, a measurement file: a tracker's (docs/formats.md
            § 5.1) or a distance, plane, sphere, socket or multi-target file (§ 5.3).
        rotations: for full-pose data, the measured orientations as unit quaternions
            (N, 4) ``[qw, qx, qy, qz]`` or rotation matrices (N, 3, 3).
        sigma: standard deviation of each point (N,), mm; points are weighed by 1/σ².
        payload: payload of each pose (N,), kg (elasto-geometric model).
        method: ``ls``, ``ridge``, ``igg3``, ``lm``, ``bas``, ``pso`` or ``bas-pso``
            (default ``ls``, Gauss–Newton; ``lm``'s default is Guo's fixed damping μ = 1,
            which converges linearly and on an IRB 2600 stops at its 50 iterations).
        options: dict of the method's options, the keys of a scenario's ``[[methods]]``
            entry (e.g. ``{"max_iter": 50}``; ``k`` for full poses).
        registration: ``identify``, ``svd``, ``wsvd`` or ``known`` (points in the base frame).
        params: the identified parameters (names; default: the identifiable set; an empty
            list is refused, as ``--params ""`` is).
        fix: parameters held at their nominal values (``--fix``).
        prior: dict name → σ of a prior on that parameter's error (``--prior``), or the
            path of a file of ``NAME = σ`` lines (``--prior FILE``).
        compliance: joint compliances identified too: ``"c2,c3"`` or ``"gravity"``.
        models: candidate models compared by K-fold cross-validation (``--models``).
        cv: K of a K-fold cross-validation (``--cv``); cv_seed: seed of its folds (default
            0; with ``cv`` or ``models`` only).
        validate: a validation measurement: a tracker's file, or ``(q, points)`` /
            ``(q, points, rotations)`` / ``(q, points, rotations or None, payload or None)``,
            the payload (N,) in kg; required with ``payload``, as the poses' loads are.
        holdout: ``"LAST/EVERY"`` or ``(last, every)``: rows held out for validation instead
            (``--holdout``).
        seed: seed of the random searches.
        allow_rank_deficient: return a result whose data do not determine every parameter
            instead of raising.
        allow_worse: return a result that makes the robot worse than the nominal one (its
            causes in ``allowed_worse``) instead of raising, with a ``UserWarning`` (the
            words ``calbench identify --allow-worse`` prints on stderr).
        allow_implausible: return a result that cannot be physically right (a length moved
            by a large share of the reach, an angle by more than 5°, points scaled against
            the nominal robot's; docs/formats.md "Physical plausibility"), its findings in
            ``allowed_implausible``, instead of raising, with a ``UserWarning`` as for
            ``allow_worse``.

    Returns:
        an :class:`IdentifyResult`: the record ``calbench identify`` writes to
        ``identified.json`` for the same data and options, as a dict. An identification
        that stopped short of convergence (``termination`` ``max-iterations``, ``diverged``
        or ``no-progress``) warns (:class:`ConvergenceWarning`, the words ``calbench
        identify`` prints on stderr); a registration that did not settle, and a chosen
        kernel residual ``gp`` that the returned ``robot`` lacks, warn (``UserWarning``).
    """
    if not isinstance(robot, Robot):
        raise SettingError("setting `robot`: expected a calbench.Robot")
    if data is not None and not isinstance(data, (str, os.PathLike)):
        raise SettingError("setting `data`: expected a path to a measurement file")
    if data is None and (q is None) != (points is None):
        given, missing = ("q", "points") if points is None else ("points", "q")
        raise SettingError(f"setting `{missing}`: missing: {given} is given without it")
    if data is None and q is None:
        raise SettingError("setting `data`: give q and points, or data (a measurement file)")
    if data is None or q is not None:
        q = _array("q", q, 2, robot.joint_count)
    if data is None or points is not None:
        points = _array("points", points, 2, 3)
    val = _validation(validate, robot.joint_count, payload is not None)
    if compliance is not None:
        compliance = ",".join(_names("compliance", compliance))
    if isinstance(prior, (str, os.PathLike)):
        prior = _path("prior", prior)
    else:
        prior = _dict("prior", prior, "a dict parameter name → σ, or the path of a file of priors")
    options = _dict("options", options, "a dict of the method's options")
    fields = _calbench.identify(
        robot,
        q,
        points,
        rotations=_rotations("rotations", rotations),
        sigma=None if sigma is None else _array("sigma", sigma, 1),
        payload=None if payload is None else _array("payload", payload, 1),
        data=None if data is None else os.fspath(data),
        method=_text("method", method, f"a method's name ({', '.join(methods())})"),
        options=options,
        registration=_text("registration", registration, "identify, svd, wsvd or known"),
        compliance=compliance,
        validate=val,
        holdout=_holdout(holdout),
        cv=_count("cv", cv),
        cv_seed=_count("cv_seed", cv_seed),
        models=_names("models", models),
        params=_names("params", params),
        fix=_names("fix", fix),
        prior=prior,
        seed=_count("seed", 0 if seed is None else seed),
        allow_rank_deficient=_flag("allow_rank_deficient", allow_rank_deficient),
        allow_worse=_flag("allow_worse", allow_worse),
        allow_implausible=_flag("allow_implausible", allow_implausible),
    )
    warning = fields.pop("warning")
    if warning is not None:
        warnings.warn(warning, ConvergenceWarning, stacklevel=2)
    for kept in fields.pop("kept"):
        warnings.warn(kept, UserWarning, stacklevel=2)
    return IdentifyResult(fields)


def simulate(scenario, trial=0, *, measure=None, out=None):
    """The measurements of one trial of a scenario, as ``calbench simulate`` writes them.

    Args:
        scenario: a path to a scenario file, or a dict shaped like the TOML file.
        trial: the trial (0-based).
        measure: an instruments study's (``[instruments_study]``) instrument whose readings
            are simulated, the first ``[[measurement]]`` entry of that kind (``"distance"``,
            ``"plane"``, …; default: the first entry); refused for any other study.
        out: a folder to write the files of ``calbench simulate --out`` to, byte for byte
            (``measurements.csv``, ``validation.csv``, ``truth.json``); required for an
            instruments study, whose readings are a measurement-kind file.

    Returns:
        a dict with ``q`` (N, n) in the robot's units, ``points`` (N, 3) mm, ``rotations``
        (N, 4) quaternions or None, ``validation_q``, ``validation_points``,
        ``validation_rotations``, ``payload`` / ``validation_payload`` when measured under
        loads, ``truth`` (dict parameter → injected error), ``robot`` (the nominal
        :class:`Robot`) and ``info`` (the rest of ``truth.json``). For an instruments
        study: ``kind``, ``data`` (the readings' file, which :func:`identify` takes as
        ``data``), ``q`` (the measured poses), the validation poses, ``truth``, ``robot``
        and ``info``.
    """
    trial = _count("trial", 0 if trial is None else trial)
    measure = _text("measure", measure, "a measurement kind", optional=True)
    out = _path("out", out, optional=True)
    res = _calbench.simulate(_scenario(scenario), trial, measure, out)
    res["info"] = json.loads(res.pop("truth_json"))
    if "data" in res:
        res["data"] = pathlib.Path(res["data"])
    return res


_COMPARISON_KEYS = ["a", "b", "metric", "n", "diff_mean", "diff_ci95", "ratio", "win_rate",
                    "p_value", "p_holm", "test", "estimate", "ci95", "margin", "verdict",
                    "trials_to_resolve"]


def _split_intervals(df):
    """``df`` with each interval column — ``ci95``, ``…_ci95``, or ``…_ci95.<name>`` as
    ``param_rmse_ci95.d2``; cells ``[lo, hi]`` or None — followed by the columns of its bounds,
    the name with ``_lo`` and ``_hi`` appended (NaN where there is no interval)."""
    import pandas as pd

    columns = {}
    for name in df.columns:
        columns[name] = df[name]
        if not any(part == "ci95" or part.endswith("_ci95") for part in str(name).split(".")):
            continue
        bounds = [
            (float(v[0]), float(v[1])) if isinstance(v, (list, tuple)) and len(v) == 2
            and v[0] is not None and v[1] is not None else (np.nan, np.nan)
            for v in df[name]
        ]
        columns[f"{name}_lo"] = pd.Series([lo for lo, _ in bounds], index=df.index, dtype=float)
        columns[f"{name}_hi"] = pd.Series([hi for _, hi in bounds], index=df.index, dtype=float)
    return pd.DataFrame(columns, index=df.index)


class Study:
    """A finished study (:func:`run`), held in memory.

    Attributes:
        summary: the dict of ``summary.json``.
        results: a pandas DataFrame of ``summary["results"]``, one row per method × poses
            × sweep point; nested statistics become dotted columns (``eta.a1.mean``), and
            each 95 % interval ``…_ci95`` also its bounds ``…_ci95_lo``, ``…_ci95_hi``.
        comparisons: a pandas DataFrame of ``summary["comparisons"]``, the paired
            comparisons of the entries that share their draws.
        trials: a pandas DataFrame of ``trials.csv``.
        seconds: the run's wall time (s).
    """

    def __init__(self, handle):
        self._run = handle
        self.summary = json.loads(handle.summary_json())
        self.seconds = handle.seconds
        self._results = None
        self._comparisons = None
        self._trials = None

    @property
    def results(self):
        """The summary's entries as a DataFrame (pandas is imported on first use); each
        interval column (``…_ci95``, ``param_rmse_ci95.<name>``: a list ``[lo, hi]``) is
        followed by its bounds, the column's name with ``_lo`` and ``_hi`` appended."""
        if self._results is None:
            import pandas as pd

            self._results = _split_intervals(pd.json_normalize(self.summary["results"]))
        return self._results

    @property
    def comparisons(self):
        """The paired comparisons of ``summary["comparisons"]`` as a DataFrame, one row per
        comparison with the same keys (``a``, ``b``, ``metric``, ``n``, ``diff_mean``,
        ``diff_ci95``, ``ratio``, ``win_rate``, ``p_value``, ``p_holm``, and the verdict's
        ``test``, ``estimate``, ``ci95``, ``margin``, ``verdict``, ``trials_to_resolve``;
        ``sweep_value`` in a sweep, after ``b``), each interval (``diff_ci95``, ``ci95``)
        also split into its bounds (``diff_ci95_lo``, ``diff_ci95_hi``, ``ci95_lo``,
        ``ci95_hi``). A run with no comparison gives these columns and no row."""
        if self._comparisons is None:
            import pandas as pd

            rows = self.summary.get("comparisons", [])
            keys = list(_COMPARISON_KEYS)
            if "sweep_key" in self.summary or "sweep_keys" in self.summary:
                keys.insert(keys.index("b") + 1, "sweep_value")
            # The documented order, with or without rows (summary.json writes a row's keys
            # sorted); a key the list does not name after them.
            df = pd.DataFrame(rows)
            df = df.reindex(columns=keys + [c for c in df.columns if c not in keys])
            self._comparisons = _split_intervals(df)
        return self._comparisons

    @property
    def trials(self):
        """``trials.csv`` as a DataFrame (empty cells are NaN; a label such as ``"NA"`` or
        ``"null"`` stays text)."""
        if self._trials is None:
            import pandas as pd

            # Only an empty cell is missing (docs/formats.md "trials.csv"): pandas' default
            # missing-value words would turn the method labels "NA" or "null" into NaN.
            data = self.trials_csv()
            header = next(csv.reader([data.split(b"\n", 1)[0].decode()]))
            text = {c: str for c in ("method", "poses", "termination", "error") if c in header}
            na = {c: [""] for c in header}
            self._trials = pd.read_csv(io.BytesIO(data), keep_default_na=False, na_values=na, dtype=text)
        return self._trials

    def trials_csv(self):
        """The bytes of ``trials.csv``."""
        return self._run.trials_csv()

    def summary_json(self):
        """The text of ``summary.json``."""
        return self._run.summary_json()

    def write(self, out):
        """Write the folder ``out`` with the files ``calbench run --out out`` writes
        (``summary.json``, ``trials.csv``, ``timing.json``, ``report.md``, the plots), as a
        whole: nothing is half-written."""
        self._run.write(_path("out", out, "a folder"))

    def __repr__(self):
        s = self.summary
        return f"Study({s['scenario']!r}, {s['trials']} trials, {len(s['results'])} entries)"


def _holdout(holdout):
    """``holdout`` as the text ``LAST/EVERY`` of ``--holdout`` (None stays None): that text,
    or two integers (last, every) as a tuple, a list or a one-dimensional numpy array."""
    if isinstance(holdout, np.ndarray) and holdout.ndim == 1:
        holdout = holdout.tolist()
    if isinstance(holdout, (tuple, list)):
        if len(holdout) != 2 or any(
            isinstance(v, bool) or not isinstance(v, numbers.Integral) for v in holdout
        ):
            raise SettingError(
                f"setting `holdout`: expected (last, every), two integers, got {holdout!r}")
        return "/".join(str(int(v)) for v in holdout)
    return _text("holdout", holdout, 'LAST/EVERY such as "3/10", or (3, 10)', optional=True)


def _shard(shard):
    """``shard`` as (i, n) with 0 <= i < n, or a SettingError naming it: a tuple, a list or a
    one-dimensional numpy array of two integers."""
    if isinstance(shard, np.ndarray) and shard.ndim == 1:
        shard = shard.tolist()
    if (
        not isinstance(shard, (tuple, list))
        or len(shard) != 2
        or any(isinstance(v, bool) or not isinstance(v, numbers.Integral) for v in shard)
    ):
        raise SettingError(f"setting `shard`: expected (i, n), two integers, got {shard!r}")
    i, n = (int(v) for v in shard)
    if not 0 <= i < n < 2**63:
        raise SettingError(f"setting `shard`: ({i}, {n}) is not (i, n) with 0 <= i < n, e.g. (0, 8)")
    return i, n


def run(
    scenario,
    *,
    trials=None,
    seed=None,
    threads=None,
    methods=None,
    progress=False,
    shard=None,
    out=None,
    precision=None,
):
    """Run a study: a Monte-Carlo study is ``calbench run`` without the files; a
    registration study (``[registration_study]``) or an instruments study
    (``[instruments_study]``) is ``calbench run SCENARIO --out DIR``, into the folder ``out``
    (the same bytes as the command line's, its ``summary.json``, ``report.md``, plots and
    ``scenario.toml``, which ``calbench record`` stores).

    Args:
        scenario: a path to a scenario file, or a dict shaped like the TOML file.
        trials: override the number of trials.
        seed: override the master seed.
        threads: worker threads (default: one per core).
        methods: dict label → function benchmarked beside the scenario's methods on the
            same trials, measurements and validation poses. The function receives a
            :class:`Problem` (``parameter_names``, ``x0``, ``weights``, ``residual(x)``,
            ``jacobian(x)``) and returns the parameter vector, or (vector, termination name).
            An exception fails that trial of that method (counted in ``failures``, its message
            in the ``error`` column of ``trials``) and the study goes on. Python methods run
            one at a time under the GIL while the rest of each trial runs in parallel.
        progress: draw a progress bar on a terminal.
        shard: ``(i, n)``: run only share ``i`` of ``n`` of the (sweep point × trial) work,
            as ``calbench run --shard i/n``, into the shard folder ``out`` (required), which
            ``calbench merge`` merges with the other shards into the bytes of the whole run.
            Not with ``methods`` (the merge rebuilds the scenario from its text).
        out: the shard folder (only with ``shard``); for a registration or instruments
            study, its folder (required).
        precision: ``"0.5%"`` or ``"0.002mm"``: run until every entry's mean validation
            error after calibration has a 95 % interval at most that wide, ``trials`` the
            cap (``calbench run --precision``); ``study.summary["stopping"]`` says where it
            stopped and, short of the target, the widest entry and the trials it would need.

    Returns:
        a :class:`Study`; ``study.summary`` equals the command line's ``summary.json`` for
        the same scenario and options. With ``shard``, and for a registration or instruments
        study: the folder written, a ``pathlib.Path``.
    """
    if methods is not None and not isinstance(methods, dict):
        raise SettingError("setting `methods`: expected a dict label → function")
    if precision is not None and not isinstance(precision, str):
        raise SettingError('setting `precision`: expected a target such as "0.5%" or "0.002mm"')
    if shard is not None and precision is not None:
        raise SettingError("setting `precision`: not with `shard` (a shard runs its share whole)")
    whole = _calbench.study_kind(_scenario(scenario)) != "monte-carlo"
    if whole:
        _check_whole(methods, precision, out)
    elif shard is not None:
        if out is None:
            raise SettingError("setting `out`: a run with `shard` writes a shard folder; give out=")
        if methods:
            raise SettingError(
                "setting `shard`: not with `methods` written in Python (calbench merge "
                "rebuilds the scenario from its text, which cannot hold them)"
            )
    else:
        if out is not None:
            raise SettingError(
                "setting `out`: only with `shard` (write a whole run with study.write(dir))"
            )
        handle = _calbench.run(
            _scenario(scenario),
            trials=_count("trials", trials, least=1, most=_calbench.MAX_TRIALS),
            seed=_count("seed", seed, bits=63),
            threads=_count("threads", threads, least=1),
            methods=methods,
            progress=_flag("progress", progress),
            precision=None if precision is None else str(precision),
        )
        return Study(handle)
    # A folder written as the command line writes it: a shard of a Monte-Carlo study, or a
    # registration or instruments study (or its shard).
    (_calbench.run_whole if whole else _calbench.run_shard)(
        _scenario(scenario),
        _path("out", out, "a folder"),
        trials=_count("trials", trials, least=1, most=_calbench.MAX_TRIALS),
        seed=_count("seed", seed, bits=63),
        threads=_count("threads", threads, least=1),
        progress=_flag("progress", progress),
        shard=None if shard is None else _shard(shard),
    )
    return pathlib.Path(out)


def _check_whole(methods, precision, out):
    """The options :func:`run` refuses for a registration or instruments study."""
    if methods:
        raise SettingError(
            "setting `methods`: a registration or instruments study runs its own methods; "
            "methods written in Python run in a Monte-Carlo study"
        )
    if precision is not None:
        raise SettingError(
            "setting `precision`: a registration or instruments study runs its `trials` draws "
            "in every cell"
        )
    if out is None:
        raise SettingError(
            "setting `out`: a registration or instruments study writes its folder (the files "
            "of `calbench run --out`); give out="
        )


def identifiability(robot, q, measure="position", *, between_poses=None, planes=None,
                    spheres=None):
    """Which parameters of ``robot`` poses ``q`` (N, n; robot's units) can identify.

    Args:
        robot: a :class:`Robot`.
        q: joint values (N, n).
        measure: ``position`` or ``pose`` (the tracker), or another instrument's kind:
            ``distance``, ``plane``, ``sphere``, ``socket``, ``multi-target`` (``--measure``).
        between_poses: ``distance``: lengths between consecutive poses, not from a pivot.
        planes: ``plane``: the number of planes (default 3); the poses are on them in turn.
        spheres: ``sphere``: the number of spheres (default 1), likewise.

    Returns:
        a dict with ``rank``, ``parameters`` (their number), ``identifiable`` and
        ``unidentifiable`` (names), ``groups`` (dependent groups of names) and
        ``condition_number`` (column-scaled), and for another instrument ``measure`` and
        ``instrument_unknowns`` (its pivot, planes or spheres, projected out) and
        ``undetermined_instrument_unknowns`` (those the poses leave free by themselves), as
        ``calbench identifiability --json --poses-file``.
    """
    if not isinstance(robot, Robot):
        raise SettingError("setting `robot`: expected a calbench.Robot")
    measure = _text("measure", measure, "a measure such as \"position\" or \"distance\"")
    # Each instrument option is read by one kind only: given with another, it is refused.
    for name, value, kind in (("between_poses", between_poses, "distance"),
                              ("planes", planes, "plane"), ("spheres", spheres, "sphere")):
        if value is not None and measure != kind:
            raise SettingError(f"setting `{name}`: is read only with measure=\"{kind}\"")
    return _calbench.identifiability(
        robot, _array("q", q, 2, robot.joint_count), measure,
        False if between_poses is None else _flag("between_poses", between_poses),
        3 if planes is None else _count("planes", planes, least=1),
        1 if spheres is None else _count("spheres", spheres, least=1))


def robots():
    """The names of the built-in robots."""
    return list(_calbench.catalogue()["robots"])


def methods():
    """The names of the built-in identification methods."""
    return list(_calbench.catalogue()["methods"])


class Comparison:
    """Run B against run A (its baseline) by the rules of ``calbench check``: what
    :func:`compare` returns, and what ``calbench compare`` writes to its pages.

    Attributes:
        metrics: a pandas DataFrame, one row per metric ``check`` guards, in A's order:
            ``entry``, ``metric``, ``a``, ``b``, ``diff`` (b − a), ``status``
            (``regression``, ``unresolved``, ``changed, within tolerance``, ``improved``,
            ``no change``), ``diff_ci_lo`` / ``diff_ci_hi`` (the Holm-adjusted interval of
            the change), ``p_value``, ``p_holm``, ``paired`` (trial by trial), ``trials_needed``
            (for an unresolved metric, trials per run that would resolve it, else None) and
            ``higher_is_better``. A metric of an entry only in A is a regression with ``b``
            NaN.
        only_in_a, only_in_b: the entries (``method / poses [/ sweep value]``) of one run only.
        regressions: the number of regressions (``calbench check`` fails when it is not 0).
        unresolved: the number of unresolved metrics (``check --strict`` fails on them too).
        verdict: the sentence the compare page leads with.
        scenario_note: the page's warning when A and B ran different scenarios (by name,
            or by their settings where both folders say what they ran), which
            ``calbench check`` refuses to compare; None when they ran one.
        tolerance: the allowed relative worsening.
    """

    def __init__(self, fields, tolerance):
        import pandas as pd

        self.metrics = pd.DataFrame(fields["metrics"], columns=_COMPARE_COLUMNS)
        self.only_in_a = list(fields["only_in_a"])
        self.only_in_b = list(fields["only_in_b"])
        self.regressions = int(fields["regressions"])
        self.unresolved = int((self.metrics["status"] == "unresolved").sum())
        self.verdict = fields["verdict"]
        self.scenario_note = fields["scenario_note"]
        self.tolerance = tolerance

    def __repr__(self):
        return (
            f"Comparison({len(self.metrics)} metrics, {self.regressions} regressions, "
            f"{self.unresolved} unresolved)"
        )


_COMPARE_COLUMNS = ["entry", "metric", "a", "b", "diff", "status", "diff_ci_lo", "diff_ci_hi",
                    "p_value", "p_holm", "paired", "trials_needed", "higher_is_better"]


def compare(a, b, *, tolerance=0.05):
    """Run ``b`` against run ``a``: ``calbench compare A B`` (and ``calbench check
    B/summary.json --baseline A/summary.json``) without the pages.

    Args:
        a: the baseline run: its folder or its ``summary.json``.
        b: the run compared with it: its folder or its ``summary.json``.
        tolerance: allowed relative worsening of each metric (0.05 = 5 %), from 0 to 10.

    Returns:
        a :class:`Comparison`: each guarded metric with its status, computed by the library
        exactly as the command line's: paired, trial by trial, when both folders hold
        ``trials.csv`` of the same scenario, seed and trials; otherwise from the summaries.
    """
    for name, value in (("a", a), ("b", b)):
        if not isinstance(value, (str, os.PathLike)):
            raise SettingError(f"setting `{name}`: expected a run's folder or its summary.json")
    if isinstance(tolerance, bool) or not isinstance(tolerance, numbers.Real):
        raise SettingError("setting `tolerance`: expected a number ≥ 0")
    try:
        tolerance = float(tolerance)
    except OverflowError:
        raise SettingError(
            f"setting `tolerance`: {tolerance} is beyond a 64-bit number; expected 0 to 10"
        ) from None
    return Comparison(_calbench.compare(os.fspath(a), os.fspath(b), tolerance), tolerance)


def task(task, method="lm", *, models=None, name=None, out=None, options=None):
    """One entry of a fixed real-data task: ``calbench task`` (docs/formats.md § 9).

    Args:
        task: a task under ``tasks/`` by name (``"barrett-wam"``, relative to the working
            folder) or the path of a task file.
        method: a method's name, or a Python function that receives a :class:`Problem`
            and returns the parameter vector, or (vector, termination name), as ``run``'s
            ``methods``. A Python function enters the open division as ``python:<name>``.
        models: candidate models (``["kinematic", "beta"]``), chosen by 5-fold
            cross-validation on the task's calibration rows alone when there are several.
            Without them (or ``[]``), the task's own ``[models]`` are compared as
            ``calbench task`` without ``--models`` compares them, else ``kinematic``.
        name: the Python method's name (default: the function's ``__name__``); refused
            with a calbench method, which is entered by its own name.
        out: a folder to write the identify outputs, ``task.json`` and ``task.toml`` (the task
            file as run) into.
        options: dict of a calbench method's options, the keys of a scenario's ``[[methods]]``
            entry (``{"max_iter": 200}``), as ``calbench task --set``; refused with a method
            written in Python.

    Returns:
        a dict: ``task`` (the content of ``task.json``), ``record`` (of ``identified.json``)
        and ``robot`` (the compensated :class:`Robot`). An identification that stopped short
        of convergence warns (:class:`ConvergenceWarning`, the words of ``calbench task``);
        its other warnings (a registration that did not settle, a result kept worse or
        implausible, a chosen kernel residual ``gp`` that ``robot`` lacks) are
        ``UserWarning``.
    """
    if models is not None:
        models = _names("models", models)
    if name is not None and not callable(method):
        raise SettingError(
            "setting `name`: names a method written in Python; a calbench method is "
            f"entered by its own name ({method!r})"
        )
    options = _dict("options", options, "a dict of the method's options")
    d = _calbench.task(
        _path("task", task, "a task's name or the path of a task file"),
        method,
        models=models,
        name=_text("name", name, "a name", optional=True),
        out=_path("out", out, "a folder", optional=True),
        options=options,
    )
    if d["warning"] is not None:
        warnings.warn(d["warning"], ConvergenceWarning, stacklevel=2)
    for kept in d["kept"]:
        warnings.warn(kept, UserWarning, stacklevel=2)
    return {
        "task": json.loads(d["task"]),
        "record": json.loads(d["record"]),
        "robot": d["robot"],
    }

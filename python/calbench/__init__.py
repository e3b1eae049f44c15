"""calbench from Python: the kinematic calibration benchmark of industrial robots, numpy in
and out, studies as pandas DataFrames (docs/python.md).

Lengths are in mm, joint values and angles in the robot's units, as on the command line.
Every error is a :class:`calbench.Error` (or a subclass) carrying the command line's message.
"""

import io
import json
import os

import numpy as np

from . import _calbench
from ._calbench import (  # noqa: F401  (re-exported)
    ComputeError,
    Error,
    FileError,
    IoError,
    Problem,
    Robot,
    SettingError,
)

__all__ = [
    "Robot",
    "Problem",
    "IdentifyResult",
    "Study",
    "identify",
    "simulate",
    "run",
    "identifiability",
    "robots",
    "methods",
    "Error",
    "FileError",
    "SettingError",
    "ComputeError",
    "IoError",
]


def _array(name, value, ndim, columns=None):
    """``value`` as a C-contiguous float64 array of ``ndim`` dimensions (and ``columns``
    columns), refused with a SettingError naming ``name`` otherwise."""
    try:
        a = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise SettingError(f"setting `{name}`: not an array of numbers ({e})") from None
    if a.ndim != ndim:
        raise SettingError(f"setting `{name}`: expected {ndim} dimensions, got shape {a.shape}")
    if columns is not None and a.shape[1] != columns:
        want = ", ".join(["N", str(columns)])
        raise SettingError(f"setting `{name}`: expected shape ({want}), got {a.shape}")
    return a


def _rotations(name, value):
    """Orientations as (N, 4) quaternions or (N, 3, 3) matrices, float64."""
    if value is None:
        return None
    a = np.ascontiguousarray(value, dtype=np.float64)
    if a.ndim == 2:
        return _array(name, a, 2, 4)
    return _array(name, a, 3)


def _scenario(scenario):
    """A path (str or os.PathLike) or a dict, as the compiled part takes it."""
    if isinstance(scenario, dict):
        return scenario
    if isinstance(scenario, (str, os.PathLike)):
        return os.fspath(scenario)
    raise SettingError("setting `scenario`: expected a path to a scenario file or a dict")


class IdentifyResult:
    """The result of :func:`identify`.

    Attributes:
        parameters: dict name → identified error (mm, rad), in the order of the estimate.
        parameter_names: the identified parameters, in order.
        covariance: ndarray (t, t), σ0² (JᵀPJ)⁻¹ at the solution (NaN where undefined).
        termination: why the iterations stopped (``converged``, ``max-iterations``, …).
        iterations, evaluations: of the identification.
        rank: numerical rank of the column-scaled, weighted Jacobian.
        condition_number: its condition number.
        sigma0: unit-weight standard deviation; rms_residual_mm: RMS point residual.
        residuals: ndarray (N, 3), measured (registered) − predicted points after
            compensation, mm.
        weights: ndarray (N,), the final weight of each point.
        robot: the compensated :class:`Robot`.
        registration_frame: ndarray (4, 4), instrument → base frame.
        validation: dict of before and after statistics (``before_mm``, ``after_mm``, and
            for full poses ``*_deg``), when ``validate`` was given; else None.
        seconds: wall time of the identification (and validation) in Rust, s.
    """

    def __init__(self, fields):
        self.__dict__.update(fields)
        self.parameter_names = list(self.parameters)

    def __repr__(self):
        return (
            f"IdentifyResult({len(self.parameters)} parameters, {self.termination} after "
            f"{self.iterations} iterations)"
        )


def identify(
    robot,
    q,
    points,
    *,
    rotations=None,
    sigma=None,
    payload=None,
    method="lm",
    options=None,
    registration="identify",
    compliance=None,
    validate=None,
    seed=0,
    allow_rank_deficient=False,
):
    """Identify the errors of ``robot`` from measured points: ``calbench identify`` on arrays.

    Args:
        robot: the nominal :class:`Robot`.
        q: joint values (N, n) in the robot's units.
        points: measured points (N, 3), mm, in the instrument's frame.
        rotations: for full-pose data, the measured orientations as unit quaternions
            (N, 4) ``[qw, qx, qy, qz]`` or rotation matrices (N, 3, 3).
        sigma: standard deviation of each point (N,), mm; points are weighed by 1/σ².
        payload: payload of each pose (N,), kg (elasto-geometric model).
        method: ``ls``, ``ridge``, ``igg3``, ``lm``, ``bas``, ``pso`` or ``bas-pso``.
        options: dict of the method's options, the keys of a scenario's ``[[methods]]``
            entry (e.g. ``{"max_iter": 50}``; ``k`` for full poses).
        registration: ``identify``, ``svd``, ``wsvd`` or ``known`` (points in the base frame).
        compliance: joint compliances identified too: ``"c2,c3"`` or ``"gravity"``.
        validate: a ``(q, points)`` or ``(q, points, rotations)`` validation measurement.
        seed: seed of the random searches.
        allow_rank_deficient: return a result whose data do not determine every parameter
            instead of raising.

    Returns:
        an :class:`IdentifyResult`, with the numbers ``calbench identify`` writes for the
        same data.
    """
    if not isinstance(robot, Robot):
        raise SettingError("setting `robot`: expected a calbench.Robot")
    q = _array("q", q, 2, robot.joint_count)
    points = _array("points", points, 2, 3)
    val = None
    if validate is not None:
        if not isinstance(validate, (tuple, list)) or len(validate) not in (2, 3):
            raise SettingError("setting `validate`: expected (q, points) or (q, points, rotations)")
        val = (
            _array("validate.q", validate[0], 2, robot.joint_count),
            _array("validate.points", validate[1], 2, 3),
            _rotations("validate.rotations", validate[2]) if len(validate) == 3 else None,
        )
    if isinstance(compliance, (list, tuple)):
        compliance = ",".join(compliance)
    fields = _calbench.identify(
        robot,
        q,
        points,
        rotations=_rotations("rotations", rotations),
        sigma=None if sigma is None else _array("sigma", sigma, 1),
        payload=None if payload is None else _array("payload", payload, 1),
        method=method,
        options=options,
        registration=registration,
        compliance=compliance,
        validate=val,
        seed=int(seed),
        allow_rank_deficient=bool(allow_rank_deficient),
    )
    return IdentifyResult(fields)


def simulate(scenario, trial=0):
    """The measurements of one trial of a scenario, as ``calbench simulate`` writes them.

    Args:
        scenario: a path to a scenario file, or a dict shaped like the TOML file.
        trial: the trial (0-based).

    Returns:
        a dict with ``q`` (N, n) in the robot's units, ``points`` (N, 3) mm, ``rotations``
        (N, 4) quaternions or None, ``validation_q``, ``validation_points``,
        ``validation_rotations``, ``payload`` / ``validation_payload`` when measured under
        loads, ``truth`` (dict parameter → injected error), ``robot`` (the nominal
        :class:`Robot`) and ``info`` (the rest of ``truth.json``).
    """
    out = _calbench.simulate(_scenario(scenario), int(trial))
    out["info"] = json.loads(out.pop("truth_json"))
    return out


class Study:
    """A finished study (:func:`run`), held in memory.

    Attributes:
        summary: the dict of ``summary.json``.
        results: a pandas DataFrame of ``summary["results"]``, one row per method × poses
            × sweep point; nested statistics become dotted columns (``eta.a1.mean``).
        trials: a pandas DataFrame of ``trials.csv``.
        seconds: the run's wall time (s).
    """

    def __init__(self, handle):
        self._run = handle
        self.summary = json.loads(handle.summary_json())
        self.seconds = handle.seconds
        self._results = None
        self._trials = None

    @property
    def results(self):
        """The summary's entries as a DataFrame (pandas is imported on first use)."""
        if self._results is None:
            import pandas as pd

            self._results = pd.json_normalize(self.summary["results"])
        return self._results

    @property
    def trials(self):
        """``trials.csv`` as a DataFrame (empty cells are NaN)."""
        if self._trials is None:
            import pandas as pd

            self._trials = pd.read_csv(io.BytesIO(self.trials_csv()))
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
        self._run.write(os.fspath(out))

    def __repr__(self):
        s = self.summary
        return f"Study({s['scenario']!r}, {s['trials']} trials, {len(s['results'])} entries)"


def run(scenario, *, trials=None, seed=None, threads=None, methods=None, progress=False):
    """Run a Monte-Carlo study: ``calbench run`` without the files.

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

    Returns:
        a :class:`Study`; ``study.summary`` equals the command line's ``summary.json`` for
        the same scenario and options.
    """
    if methods is not None and not isinstance(methods, dict):
        raise SettingError("setting `methods`: expected a dict label → function")
    handle = _calbench.run(
        _scenario(scenario),
        trials=None if trials is None else int(trials),
        seed=None if seed is None else int(seed),
        threads=None if threads is None else int(threads),
        methods=methods,
        progress=bool(progress),
    )
    return Study(handle)


def identifiability(robot, q, measure="position"):
    """Which parameters of ``robot`` poses ``q`` (N, n; robot's units) can identify.

    Args:
        robot: a :class:`Robot`.
        q: joint values (N, n).
        measure: ``position`` or ``pose``.

    Returns:
        a dict with ``rank``, ``parameters`` (their number), ``identifiable`` and
        ``unidentifiable`` (names), ``groups`` (dependent groups of names) and
        ``condition_number`` (column-scaled), as ``calbench identifiability --json``.
    """
    if not isinstance(robot, Robot):
        raise SettingError("setting `robot`: expected a calbench.Robot")
    return _calbench.identifiability(robot, _array("q", q, 2, robot.joint_count), measure)


def robots():
    """The names of the built-in robots."""
    return list(_calbench.catalogue()["robots"])


def methods():
    """The names of the built-in identification methods."""
    return list(_calbench.catalogue()["methods"])

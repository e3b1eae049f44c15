"""Argument checks of the Python front end: each turns a caller's value into what the
compiled part takes, or refuses it with a :class:`calbench.SettingError` naming the setting."""

import numbers
import os

import numpy as np

from . import _calbench
from ._calbench import SettingError

def _numbers(name, value):
    """``value`` as a C-contiguous float64 array of its own dimensions (a scalar stays 0-D,
    where ``np.ascontiguousarray`` made it one row); bool, complex, date and text arrays are
    refused naming ``name`` (their values are not joint values or millimetres; numpy would
    read ``"10"`` as 10). The check is the compiled part's, which every array argument
    passes."""
    return np.asarray(_calbench._real_array(name, value), order="C")


def _array(name, value, ndim, columns=None):
    """``value`` as a C-contiguous float64 array of ``ndim`` dimensions (and ``columns``
    columns), refused with a SettingError naming ``name`` otherwise."""
    a = _numbers(name, value)
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
    a = _numbers(name, value)
    if a.ndim == 2:
        return _array(name, a, 2, 4)
    if a.ndim != 3:
        raise SettingError(f"setting `{name}`: expected (N, 4) quaternions or (N, 3, 3) "
                           f"rotation matrices, got shape {a.shape}")
    return _array(name, a, 3)


def _count(name, value, least=0, bits=64, most=None):
    """``value`` as a non-negative integer of at most ``bits`` bits (at least ``least``, at
    most ``most``), or None; refused with a SettingError naming ``name`` otherwise (never a
    bare OverflowError or TypeError). A study's seed has 63 bits: the scenario file's TOML
    integer holds it."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise SettingError(f"setting `{name}`: expected an integer, got {type(value).__name__}")
    value = int(value)
    if value < least:
        raise SettingError(f"setting `{name}`: must be a whole number ≥ {least}, got {value}")
    if most is not None and value > most:
        raise SettingError(f"setting `{name}`: must be between {least} and {most}, got {value}")
    if value >= 2**bits:
        raise SettingError(f"setting `{name}`: {value} is out of range ({least} to 2^{bits} - 1)")
    return value


def _names(name, value):
    """A list of names: a list, tuple or 1-D numpy array of strings, or one comma-separated
    string."""
    if value is None:
        return None
    if isinstance(value, str):
        value = value.split(",")
    if isinstance(value, np.ndarray) and value.ndim == 1:
        value = value.tolist()
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
        raise SettingError(f"setting `{name}`: expected a list of names or a comma-separated string")
    return [_utf8(name, v).strip() for v in value]


def _utf8(name, value):
    """``value`` (a str), refused naming ``name`` when UTF-8 cannot hold it: a lone surrogate,
    as ``os.listdir`` or ``sys.argv`` give for a name that is not UTF-8 (it had surfaced as a
    bare UnicodeEncodeError)."""
    try:
        value.encode("utf-8")
    except UnicodeEncodeError as e:
        raise SettingError(
            f"setting `{name}`: {value!r} holds {value[e.start]!r}, a lone surrogate UTF-8 cannot "
            "hold (a name read from bytes that are not UTF-8?)"
        ) from None
    return value


def _flag(name, value):
    """``value`` as a bool: True or False (numpy's too), refused naming ``name`` otherwise
    rather than read by its truth value (``"no"`` is not False)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise SettingError(f"setting `{name}`: expected True or False, got {type(value).__name__}")


def _text(name, value, what, optional=False):
    """``value`` as a string (or None when ``optional``), refused naming ``name`` and saying
    ``what`` it should be otherwise."""
    if isinstance(value, str):
        return _utf8(name, value)
    if optional and value is None:
        return value
    raise SettingError(f"setting `{name}`: expected {what}, got {type(value).__name__}")


def _dict(name, value, what):
    """``value`` as a dict, or None; refused naming ``name`` and saying ``what`` it should
    be otherwise."""
    if value is None or isinstance(value, dict):
        return value
    raise SettingError(f"setting `{name}`: expected {what}")


def _path(name, value, what="a path", optional=False):
    """``value`` (a str or an os.PathLike) as a path string (None stays None when
    ``optional``), refused naming ``name`` otherwise."""
    if isinstance(value, (str, os.PathLike)):
        return os.fspath(value)
    if optional and value is None:
        return None
    raise SettingError(f"setting `{name}`: expected {what}, got {type(value).__name__}")


def _scenario(scenario):
    """A path (str or os.PathLike) or a dict, as the compiled part takes it."""
    if isinstance(scenario, dict):
        return scenario
    if isinstance(scenario, (str, os.PathLike)):
        return os.fspath(scenario)
    raise SettingError("setting `scenario`: expected a path to a scenario file or a dict")


def _validation(validate, joints, loaded):
    """``identify``'s ``validate``: a file's path as a string, or its arrays as the
    compiled part takes them, ``(q, points, rotations or None, payload or None)`` of a robot
    of ``joints`` joints; refused with a SettingError naming ``validate`` otherwise, and
    without a payload when the calibration poses carry one (``loaded``): the validation poses
    would be predicted with no load."""
    if validate is None:
        return None
    if isinstance(validate, (str, os.PathLike)):
        return os.fspath(validate)
    if not isinstance(validate, (tuple, list)) or len(validate) not in (2, 3, 4):
        raise SettingError(
            "setting `validate`: expected a measurement file, (q, points), "
            "(q, points, rotations) or (q, points, rotations or None, payload or None)"
        )
    payload = validate[3] if len(validate) == 4 else None
    if loaded and payload is None:
        raise SettingError(
            "setting `validate`: the calibration poses carry a payload (`payload`) and "
            "the validation poses none: give (q, points, rotations or None, payload), "
            "the payload in kg per validation pose (zeros for poses without one)"
        )
    return (
        _array("validate.q", validate[0], 2, joints),
        _array("validate.points", validate[1], 2, 3),
        _rotations("validate.rotations", validate[2]) if len(validate) > 2 else None,
        None if payload is None else _array("validate.payload", payload, 1),
    )

//! The exceptions of `calbench` and how a library error becomes one.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyUserWarning};
use pyo3::prelude::*;

create_exception!(calbench, Error, PyException, "Every error of calbench.");
create_exception!(
    calbench,
    FileError,
    Error,
    "An input file is malformed or holds a value out of range (names the file and the place)."
);
create_exception!(
    calbench,
    SettingError,
    Error,
    "A setting or an argument is out of range (names the key)."
);
create_exception!(
    calbench,
    ComputeError,
    Error,
    "A computation could not be carried out."
);
create_exception!(
    calbench,
    LimitWarning,
    PyUserWarning,
    "Joint values outside the robot's joint limits (`Robot.fk` computes it and warns)."
);
create_exception!(
    calbench,
    ConvergenceWarning,
    PyUserWarning,
    "An identification that stopped short of convergence (`calbench.task` warns, as \
     `calbench task` does)."
);
create_exception!(
    calbench,
    IoError,
    Error,
    "Reading or writing a file failed (names the file)."
);

/// How the Python module spells an option the library names: its keyword argument
/// (`fix`), or how it is turned on (`allow_worse=True`).
pub(crate) fn spell(opt: calbench::error::Opt, on: bool) -> String {
    if on {
        format!("{}=True", opt.name())
    } else {
        opt.name().to_string()
    }
}

/// How `calbench.task` spells an option the library names, as `calbench task` spells its
/// own (docs/python.md, `calbench.task`; `calbench::calibrate::task::task_option`): its
/// keywords (`method`, `models`, which `cv`'s folds are) as [`spell`] does, and an option it
/// does not take as `calbench.identify`'s (`calbench.identify's allow_implausible=True`).
pub(crate) fn task_spell(opt: calbench::error::Opt, on: bool) -> String {
    match calbench::calibrate::task::task_option(opt) {
        Ok(own) => spell(own, on),
        Err(other) => format!("calbench.identify's {}", spell(other, on)),
    }
}

/// A library error as the Python exception of its kind, with the command line's message and
/// the options as keyword arguments ([`spell`]).
pub(crate) fn err(e: calbench::Error) -> PyErr {
    err_spelled(e, spell)
}

/// [`err`] with the options as `spell` writes them ([`task_spell`] for `calbench.task`).
pub(crate) fn err_spelled(e: calbench::Error, spell: calbench::error::Spell) -> PyErr {
    let msg = e.spelled(spell);
    match e {
        calbench::Error::File { .. } => FileError::new_err(msg),
        calbench::Error::Setting { .. } | calbench::Error::Option { .. } => {
            SettingError::new_err(msg)
        }
        calbench::Error::Compute(_)
        | calbench::Error::Singular(_)
        | calbench::Error::Diverged(_) => ComputeError::new_err(msg),
        calbench::Error::Io { .. } => IoError::new_err(msg),
        _ => Error::new_err(msg),
    }
}

/// A refused argument.
pub(crate) fn setting(key: &str, msg: impl Into<String>) -> PyErr {
    err(calbench::Error::setting(key, msg.into()))
}

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

/// The path argument `key`, refused naming it when it is empty: no file has an empty name,
/// and the reader's refusal would name none.
pub(crate) fn nonempty(key: &str, path: std::path::PathBuf) -> PyResult<std::path::PathBuf> {
    match path.as_os_str().is_empty() {
        true => Err(setting(
            key,
            "is empty: no file or folder has an empty name",
        )),
        false => Ok(path),
    }
}

/// A refused argument.
pub(crate) fn setting(key: &str, msg: impl Into<String>) -> PyErr {
    err(calbench::Error::setting(key, msg.into()))
}

/// The reporter of a run started from Python: the progress bar on a terminal's stderr when
/// `progress` is asked for, and the run's warnings (the threads capped, a killed run's
/// checkpoint started over) kept, to be raised as Python warnings (`UserWarning`) on the
/// calling thread once the run returns ([`Warned::raise`]); they had been dropped without
/// `progress`, and printed on stderr with it.
pub(crate) struct Warned {
    progress: bool,
    warnings: std::sync::Mutex<Vec<String>>,
}

impl Warned {
    pub(crate) fn new(progress: bool) -> Warned {
        Warned {
            progress,
            warnings: std::sync::Mutex::new(Vec::new()),
        }
    }

    /// Raises the warnings kept, in their order (an exception where a filter makes one so).
    pub(crate) fn raise(self, py: Python<'_>) -> PyResult<()> {
        let warnings = self
            .warnings
            .into_inner()
            .unwrap_or_else(|e| e.into_inner());
        for w in warnings {
            // Without its NUL bytes, the text is a C string.
            let msg = std::ffi::CString::new(w.replace('\0', " ")).unwrap_or_default();
            // Level 2: the line that called `calbench.run`, whose body calls this module.
            PyErr::warn(py, &py.get_type::<PyUserWarning>(), &msg, 2)?;
        }
        Ok(())
    }
}

impl calbench::study::reporter::Reporter for Warned {
    fn warning(&self, text: &str) {
        let mut w = self.warnings.lock().unwrap_or_else(|e| e.into_inner());
        w.push(text.to_string());
    }

    fn progress(&self, total: u64) -> Box<dyn calbench::study::reporter::Progress + '_> {
        use calbench::study::reporter::{Silent, Terminal};
        if self.progress {
            Terminal.progress(total)
        } else {
            Silent.progress(total)
        }
    }
}

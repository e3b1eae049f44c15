//! The library's error type.

use std::path::PathBuf;

/// Everything that can go wrong in the library. Non-convergence of an identification is not an
/// error: it is reported as a termination reason.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An input file (robot, scenario, measurement, pose list) is malformed or holds a value
    /// out of range. `place` names the key, joint or line.
    #[error("{}: {place}: {msg}", file.display())]
    File {
        /// The offending file.
        file: PathBuf,
        /// Where in the file: a key path such as `joints[2].limits` or `line 14`.
        place: String,
        /// What is wrong and what is allowed.
        msg: String,
    },
    /// A setting (from a scenario, the command line or an API call) is out of range.
    #[error("setting `{key}`: {msg}")]
    Setting {
        /// The setting's key, e.g. `tracker.mpe_a_um`.
        key: String,
        /// What is wrong and what is allowed.
        msg: String,
    },
    /// A computation could not be carried out (e.g. too few reachable poses in a box).
    #[error("{0}")]
    Compute(String),
    /// Reading or writing a file failed. The message carries the operating system's; it
    /// is not also given as a `source`, so that a report of the error chain (`{:#}`) says it
    /// once.
    #[error("{}: {cause}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        cause: std::io::Error,
    },
}

/// The library's result type.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// The key of a [`Error::Setting`] (`None` for other errors): for callers that report
    /// or test which setting was refused.
    pub fn key(&self) -> Option<&str> {
        match self {
            Error::Setting { key, .. } => Some(key),
            _ => None,
        }
    }

    /// An error about a setting.
    pub fn setting(key: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Setting {
            key: key.into(),
            msg: msg.into(),
        }
    }

    /// An error about a place in an input file.
    pub fn file(
        file: impl Into<PathBuf>,
        place: impl Into<String>,
        msg: impl Into<String>,
    ) -> Self {
        Error::File {
            file: file.into(),
            place: place.into(),
            msg: msg.into(),
        }
    }

    /// `got` joint values where the robot has `dof` joints: the setting `key` refused, with
    /// `what` naming the offending values (`pose 3`, `--q`).
    pub fn joint_count(key: &str, what: impl std::fmt::Display, got: usize, dof: usize) -> Self {
        Error::setting(
            key,
            format!("{what}: {got} joint values for a {dof}-joint robot"),
        )
    }

    /// An I/O error on a path.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            cause: source,
        }
    }
}

/// Refuses a setting `v` unless it is finite and positive (the error names `key`).
pub fn finite_positive(key: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::setting(
            key,
            format!("must be finite and positive, got {v}"),
        ))
    }
}

/// Checks that setting `key` is finite and at least 0.
pub fn finite_non_negative(key: &str, v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::setting(
            key,
            format!("must be finite and non-negative, got {v}"),
        ))
    }
}

/// Checks that the count `key` is at least 1.
pub fn check_count(key: &str, n: usize) -> Result<()> {
    if n == 0 {
        Err(Error::setting(key, "must be at least 1"))
    } else {
        Ok(())
    }
}

//! calbench: a simulation-driven benchmark harness for the kinematic calibration of
//! industrial robots.
//!
//! The modules are layers, each importing only from those listed before it
//! (docs/architecture.md):
//!
//! - [`numeric`]: scalar types, frames and rotations, random streams, and the kernels
//!   (sine and cosine, Gram matrix, Cholesky, symmetric eigenvalues) behind one SIMD dispatch;
//! - [`measurement`]: what is measured ([`measurement::Measure`]), measured poses
//!   ([`measurement::Measurements`]), the measurement CSV and the import of tracker exports;
//! - [`robot`]: robot models and forward kinematics, robot files and URDF, the built-in robots,
//!   the identification Jacobian, identifiability, parameter sets and the compliance model;
//! - [`sim`]: the virtual measurement (true robot, tracker, outliers, poses, gravity sag);
//! - [`identify`]: the identification methods behind one trait;
//! - [`poses`]: measurement-pose selection (observability indices, DETMAX, IDE);
//! - [`calibrate`]: registration with identification, validation, compensation;
//! - [`study`]: scenarios and the Monte-Carlo harness;
//! - [`analysis`]: a run's summary, with every comparison and verdict decided once, and the
//!   regression rule of `check`, `compare` and `history` against a baseline;
//! - [`report`]: the output files and plots;
//! - [`runner`]: running, resuming, sharding and merging a study, through the report's writers;
//! - [`results`]: the results database (records of runs, identifications and tasks), the
//!   history of a metric across versions and the tasks' leaderboard.
#![warn(missing_docs)]

pub mod error;

pub use error::{Error, Result};

pub mod numeric;

pub mod measurement;

pub mod robot;

pub mod sim;

pub mod identify;

pub mod poses;

pub mod calibrate;

pub mod study;

pub mod analysis;

pub mod report;

pub mod runner;

pub mod results;

/// The README's Rust examples ("Adding a method"), compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

/// The folder `calbench-NAME-PID` under the system's temporary folder, created, for a unit test.
#[cfg(test)]
pub(crate) fn test_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("calbench-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Asserts, for a unit test, that the `analytic` derivative of `what` is within `tol` of its
/// central difference `fd`, relative to `1 + |fd|`.
#[cfg(test)]
#[track_caller]
pub(crate) fn assert_fd(
    analytic: numeric::Real,
    fd: numeric::Real,
    tol: numeric::Real,
    what: &str,
) {
    let near = (analytic - fd).abs() < tol * (1.0 + fd.abs());
    assert!(near, "{what}: analytic {analytic}, central difference {fd}");
}

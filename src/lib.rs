//! calbench: a simulation-driven benchmark harness for the kinematic calibration of
//! industrial robots.
//!
//! The crate follows the data flow of the project's design: robot models and forward
//! kinematics ([`kinematics`]), the identification Jacobian ([`jacobian`]) and
//! identifiability analysis, the virtual measurement, identification methods, measurement-pose
//! selection, the Monte-Carlo harness and its reports.
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

pub mod report;

/// The README's Rust examples ("Adding a method"), compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

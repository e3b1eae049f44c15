//! calbench: a simulation-driven benchmark harness for the kinematic calibration of
//! industrial robots.
//!
//! The crate follows the data flow of the project's design: robot models and forward
//! kinematics ([`kinematics`]), the identification Jacobian ([`jacobian`]) and
//! identifiability analysis, the virtual measurement, identification methods, measurement-pose
//! selection, the Monte-Carlo harness and its reports.
#![warn(missing_docs)]

pub mod error;
pub mod math;
pub mod rng;

pub use error::{Error, Result};
pub mod calibrate;
pub mod check;
pub mod compensate;
pub mod compliance;
pub mod errmodel;
pub mod identifiability;
pub mod identify;
pub mod import;
pub mod jacobian;
pub mod kinematics;
pub mod measurement;
pub mod metaheur;
pub mod montecarlo;
pub mod names;
pub mod physics;
pub mod poses;
pub mod report;
pub mod robots;
pub mod sampling;
pub mod scenario;
pub mod sim;
pub mod symeig;
pub mod urdf;

/// The README's Rust examples ("Adding a method"), compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

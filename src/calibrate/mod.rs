//! The calibration pipeline (SPEC §3 "Registration", §4): the frame registration of the
//! measured points alternating with the identification, and the validation of the
//! compensated robot. `calbench run` calls it once per trial, method and pose strategy;
//! `calbench identify` once on a measurement file.
//!
//! - [`registration`]: SVD (Kabsch/Arun) and Ban's weighted SVD of point sets;
//! - [`validation`]: validation errors of a model against true (or measured) frames;
//! - this file: [`calibrate`].

pub mod registration;
pub mod registration_study;
pub mod validation;

use crate::error::Result;
use crate::identify::{CalibrationProblem, Identified, MethodSpec};
use crate::kinematics::{Param, Robot};
use crate::math::{Frame, Vec3};
use crate::measurement::Measurements;
use crate::rng::Rng;
use registration::{register_svd, register_wsvd};

pub use validation::{validation_errors, ErrorStats, PoseErrors};

/// How the measured points are brought into the robot's base frame (FORMATS.md
/// `[registration]`, SPEC §3 "Registration").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Registration {
    /// SVD (Kabsch/Arun) of nominal against measured points, then identification.
    Svd,
    /// Ban's weighted SVD (eqs. 12–25), then identification.
    Wsvd,
    /// SVD for a first estimate, then the base parameters identified with the rest (Li 2018).
    #[default]
    Identify,
    /// The true tracker pose is used (simulation only; for real data: the points are
    /// already in the base frame).
    Known,
}

impl Registration {
    /// The name used in files and on the command line.
    pub fn as_str(self) -> &'static str {
        crate::names::static_name(&self)
    }
}

/// A compensated robot and how it was obtained.
pub struct Calibrated {
    /// The nominal robot with the identified errors added.
    pub robot: Robot,
    /// The registration: measured (instrument) coordinates → base frame.
    pub frame: Frame,
    /// The identification's result (errors in the order of the parameters passed).
    pub identified: Identified,
}

/// Registration and identification of one method on one measurement (SPEC §3
/// "Registration", §4). With `svd` and `wsvd` registration and identification alternate
/// (three rounds): the first fit absorbs part of the kinematic error into the frame, and a
/// refit on the identified model removes it. With `identify` the SVD frame is a first
/// estimate and the base parameters (which must then be among `params`) absorb the rest
/// (Li 2018). With `known` the frame is `known`.
pub fn calibrate(
    nominal: &Robot,
    params: &[Param],
    data: &Measurements,
    registration: Registration,
    known: &Frame,
    method: &MethodSpec,
    rng: &mut Rng,
) -> Result<Calibrated> {
    let chain = nominal.chain();
    let nominal_points: Vec<Vec3> = data.qs.iter().map(|q| chain.fk(q).pos).collect();
    let mut frame = match registration {
        Registration::Known => *known,
        Registration::Wsvd => register_wsvd(&nominal_points, &data.points)?.frame,
        Registration::Svd | Registration::Identify => {
            register_svd(&nominal_points, &data.points, None)?.frame
        }
    };
    let rounds = match registration {
        Registration::Svd | Registration::Wsvd => 3,
        _ => 1,
    };
    let mut round = 0;
    loop {
        let problem = CalibrationProblem::new(nominal, params, data, frame, method.k);
        let mut identified = method.method.identify(&problem, rng)?;
        crate::identify::robot::assess(&problem, &mut identified)?;
        let robot = problem.robot_with(identified.x.as_slice());
        round += 1;
        if round >= rounds {
            return Ok(Calibrated {
                robot,
                frame,
                identified,
            });
        }
        let c = robot.chain();
        let model: Vec<Vec3> = data.qs.iter().map(|q| c.fk(q).pos).collect();
        frame = match registration {
            Registration::Wsvd => register_wsvd(&model, &data.points)?.frame,
            _ => register_svd(&model, &data.points, None)?.frame,
        };
    }
}

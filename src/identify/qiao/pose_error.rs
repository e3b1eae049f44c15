//! Least squares on one of Qiao 2021's three pose-error models (§2.2–2.3, §4.2; full-pose
//! data only): `ls` with the key `error_model`. The models and their Jacobians are in
//! [`crate::identify::qiao::error_models`]; this file makes them a [`Method`].

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::identify::qiao::error_models::{ErrorModel, ERROR_MODEL};
use crate::identify::qiao::search::check_iterations;
use crate::identify::{CalibrationProblem, Identified, Method};
use crate::numeric::rng::Rng;

/// Options of `ls` with `error_model` (docs/formats.md `[[methods]]`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseErrorLs {
    /// The pose-error model.
    pub error_model: ErrorModel,
    /// Most Gauss–Newton steps; the iteration stops earlier when `max |δx| < 1e-9`. Default
    /// 10 (1 is Qiao's linear identification of models 1–2).
    #[serde(default = "default_iterations")]
    pub iterations: usize,
}

fn default_iterations() -> usize {
    10
}

impl Method for PoseErrorLs {
    fn check(&self) -> Result<()> {
        check_iterations(self.iterations)
    }

    /// Runs the Gauss–Newton iteration of
    /// [`crate::identify::qiao::error_models::identify`] (at most `iterations` steps, until
    /// `max |δx| < 1e-9`) and returns the engine's result ([`crate::identify::Termination`]):
    /// `converged`, `max-iterations`, or `diverged` when the residual became non-finite or
    /// grew without bound, which a study counts among the method's failures. An `Err` only
    /// for inconsistent inputs (position-only data, joint compliances).
    fn identify(&self, problem: &CalibrationProblem, _: &mut Rng) -> Result<Identified> {
        if problem.params.iter().any(|p| p.is_compliance()) {
            return Err(Error::setting(
                ERROR_MODEL,
                "the pose-error models (Qiao 2021 §2) are kinematic: identify joint \
                 compliances with ls, ridge, igg3, lm or a search",
            ));
        }
        let frames = problem.measured_frames(ERROR_MODEL)?;
        let fit = crate::identify::qiao::error_models::identify(
            self.error_model,
            problem.nominal,
            problem.params,
            problem.poses(),
            &frames,
            self.iterations,
            problem.k,
            problem.weights.as_deref(),
        )?;
        Ok(fit.identified)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::Termination;
    use crate::measurement::Measurements;
    use crate::numeric::rng::stream;
    use crate::numeric::{quaternion, Frame};
    use crate::robot::builtin::tx60_qiao_params;

    /// An identification whose residual overflows ends `diverged`, which a study counts among
    /// the method's failures, and not in an `Err`, which a study reports as `invalid-input`.
    /// Every measured point is 1e305 times its true distance from the base (finite, up to
    /// 6e307 mm): the squared residual overflows at the start, and a Gauss–Newton step takes
    /// the model's lengths to that size, where the forward kinematics overflow.
    #[test]
    fn a_diverging_identification_ends_diverged_not_in_an_error() {
        let nominal = crate::robot::builtin::load("tx60").expect("tx60");
        let params = tx60_qiao_params();
        let qs = crate::robot::sampling::uniform_joint_poses(&nominal, 20, &mut stream(1, "q"));
        let frames: Vec<Frame> = qs.iter().map(|q| nominal.fk(q)).collect();
        let data = Measurements {
            qs,
            points: frames.iter().map(|f| f.pos * 1e305).collect(),
            quats: Some(frames.iter().map(|f| quaternion(&f.rot)).collect()),
            ..Default::default()
        };
        let problem = CalibrationProblem::new(&nominal, &params, &data, Frame::identity(), 100.0);
        for error_model in ErrorModel::ALL {
            let method = PoseErrorLs {
                error_model,
                iterations: 10,
            };
            let out = method
                .identify(&problem, &mut stream(1, "m"))
                .unwrap_or_else(|e| panic!("{error_model}: a divergence is not an error: {e}"));
            assert_eq!(out.termination, Termination::Diverged, "{error_model}");
        }
    }
}

//! Least squares on one of Qiao 2021's three pose-error models (§2.2–2.3, §4.2; full-pose
//! data only): `ls` with the key `error_model`. The models and their Jacobians are in
//! [`crate::identify::qiao::error_models`]; this file makes them a [`Method`].

use serde::Deserialize;

use crate::error::{check_count, Error, Result};
use crate::identify::qiao::error_models::ErrorModel;
use crate::identify::{CalibrationProblem, Identified, Method, Termination};
use crate::numeric::rng::Rng;

/// Options of `ls` with `error_model` (docs/formats.md `[[methods]]`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseErrorLs {
    /// The pose-error model.
    pub error_model: ErrorModel,
    /// Gauss–Newton steps. Default 10 (1 is Qiao's linear identification of models 1–2).
    #[serde(default = "default_iterations")]
    pub iterations: usize,
}

fn default_iterations() -> usize {
    10
}

/// The last step below which the Gauss–Newton iteration counts as converged.
const STEP_TOLERANCE: f64 = 1e-9;

impl Method for PoseErrorLs {
    fn check(&self) -> Result<()> {
        check_count("iterations", self.iterations)
    }

    /// Runs all `iterations` Gauss–Newton steps ([`crate::identify::qiao::error_models::identify`]); the result
    /// is [`Termination::Converged`] when the last step's norm is below 1e-9, else
    /// [`Termination::MaxIterations`].
    fn identify(&self, problem: &CalibrationProblem, _: &mut Rng) -> Result<Identified> {
        if problem.params.iter().any(|p| p.is_compliance()) {
            return Err(Error::setting(
                "error_model",
                "the pose-error models (Qiao 2021 §2) are kinematic: identify joint \
                 compliances with ls, ridge, igg3, lm or a search",
            ));
        }
        let frames = problem.measured_frames("error_model")?;
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
        let termination = if fit.last_step < STEP_TOLERANCE {
            Termination::Converged
        } else {
            Termination::MaxIterations
        };
        Ok(Identified::plain(
            fit.x,
            self.iterations,
            self.iterations,
            termination,
            problem.data.len(),
        ))
    }
}

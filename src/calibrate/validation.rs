//! Validation of a compensated robot (SPEC §6): per-pose position and orientation errors
//! against true (or measured) frames, and their statistics.

use crate::errmodel::attitude_error_deg;
use crate::kinematics::Robot;
use crate::math::{Frame, Real};

/// Mean, RMS, max and standard deviation of a set of errors.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ErrorStats {
    /// Mean (MAE).
    pub mean: Real,
    /// Root mean square.
    pub rms: Real,
    /// Maximum.
    pub max: Real,
    /// Standard deviation (population).
    pub std: Real,
}

impl ErrorStats {
    /// The statistics of `v` (all zero for an empty slice).
    pub fn of(v: &[Real]) -> ErrorStats {
        if v.is_empty() {
            return ErrorStats::default();
        }
        let n = v.len() as Real;
        let mean = v.iter().sum::<Real>() / n;
        let rms = (v.iter().map(|x| x * x).sum::<Real>() / n).sqrt();
        let max = v.iter().cloned().fold(0.0, Real::max);
        let std = (v.iter().map(|x| (x - mean) * (x - mean)).sum::<Real>() / n).sqrt();
        ErrorStats {
            mean,
            rms,
            max,
            std,
        }
    }
}

/// Position (mm) and orientation (deg) errors of `model` against the true frames, per pose:
/// `|Δp|` and Qiao 2021's attitude error `√(Δα² + Δβ² + Δγ²)` of the fixed X-Y-Z angles
/// ([`crate::errmodel::attitude_error_deg`]), whose means over the poses are Qiao's ACPE and
/// ACAE (§4.1; FORMATS.md "summary.json").
pub fn validation_errors(
    model: &Robot,
    qs: &[Vec<Real>],
    truth: &[Frame],
) -> (Vec<Real>, Vec<Real>) {
    let c = model.chain();
    qs.iter()
        .zip(truth)
        .map(|(q, t)| {
            let f = c.fk(q);
            ((f.pos - t.pos).norm(), attitude_error_deg(t, &f))
        })
        .unzip()
}

//! Identifiability re-checked at the identified robot (docs/formats.md § 2.6.1, "Parameters
//! re-checked at the identified robot").
//!
//! `identify` chooses its parameters at the nominal robot ([`super::cv::Model`]): a parameter
//! whose Jacobian column depends exactly on the others there is left out (the Barrett WAM's
//! joint-7 harmonics and the twist before it, its nominal tracker target lying on joint 7's
//! axis). The identified robot can break such a dependency (its identified target sits off the
//! axis), but so can errors at the noise level, which break every exact dependency a little: a
//! rank test at the identified robot flags them all. The re-check is therefore a bound, not a
//! rank: a left-out parameter c is re-admitted when, at the identified robot and frame, over
//! the calibration poses, with the parameters identified and c,
//!
//! 1. its column has an effect (its norm above 1e-9 of the largest column's, the floor of
//!    [`crate::robot::identifiability::scale_columns`]),
//! 2. the normal matrix `JᵀPJ` has full numerical rank ([`bound_inverse`]), and
//! 3. its Cramér–Rao σ, `σ_c = s · √(JᵀPJ)⁻¹_cc`, is at most `B_c / k`: `B_c` the largest
//!    move a calibration can make of it ([`super::plausibility::bound`]: 5° for an angle or a
//!    harmonic, the larger of 2 % of the reach and 10 mm for a length), k =
//!    [`DETERMINABLE_SIGMAS`] = 3: the largest plausible value can be told from 0. `s` is
//!    the noise of a point of weight 1: the fit's σ0, and with `sigma_mm` in the file the
//!    larger of σ0 and the stated noise; and
//! 4. the data tell its value from 0: the Gauss–Newton step from the identified robot with c
//!    free, `x_c = ((JᵀPJ)⁻¹ JᵀP r)_c` (the other parameters are at their optimum, so this is
//!    Rao's score test), exceeds k σ_c in size.
//!
//! Points 1–3 were fixed before any figure, from the 3σ of a study's determinable errors;
//! point 4 and the convergence guard below were added after cases were seen (docs/formats.md
//! § 2.6.1 says which). A parameter without a plausibility bound (the tool's and the base's
//! angles, a compliance, a gravity-basis coefficient) is not re-admitted. When
//! the identified robot leaves an exact dependency by a parameter δ that lies m of its own σ
//! from nominal, the column of c grows like δ and σ_c ≈ s / (|δ| √n) ≈ (lever arm) / m, so a
//! dependency broken at the noise level (m ≈ 1) gives σ_c of the order of the robot's size
//! and fails point 3; a parameter the data determine but whose value is 0 fails point 4
//! (by chance, 0.27 % of the time). Candidates are taken in order and each is checked with
//! those re-admitted before it. Registration by `svd` or `wsvd` estimates the frame apart: its
//! six degrees of freedom enter the bound as the base parameters. The pipeline then identifies
//! again with them ([`super::pipeline`]), and gives the re-admission up when that
//! identification does not converge although the first did.

use nalgebra::{DMatrix, DVector};

use super::diagnostics::Subject;
use super::Registration;
use crate::error::Result;
use crate::identify::solver::{bound_inverse, by_blocks, BLOCK_POINTS, DETERMINABLE_SIGMAS};
use crate::identify::{CalibrationProblem, LeastSquares, RobotProblem};
use crate::measurement::Measurements;
use crate::numeric::normal::NormalEquations;
use crate::numeric::{nan, Real};
use crate::robot::{Param, Robot};

/// A parameter re-admitted at the identified robot.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Readmitted {
    /// Its value one Gauss–Newton step from the identified robot (mm, rad): the test of
    /// point 4 of the rule.
    #[serde(deserialize_with = "nan::real")]
    pub estimate: Real,
    /// Its name.
    pub parameter: String,
    /// Its Cramér–Rao σ at the identified robot before it was re-admitted (mm, rad).
    #[serde(deserialize_with = "nan::real")]
    pub sigma: Real,
    /// The largest σ re-admitted: its plausibility bound over [`DETERMINABLE_SIGMAS`].
    #[serde(deserialize_with = "nan::real")]
    pub threshold: Real,
}

/// What the re-check changed: the parameters re-admitted, and the fit before them.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Readmission {
    /// The RMS residual (mm) of the identification before the re-admission (`rms_residual_mm`
    /// is the one after).
    #[serde(deserialize_with = "nan::real")]
    pub before_rms_residual_mm: Real,
    /// The parameters re-admitted, in the order they were.
    pub parameters: Vec<Readmitted>,
}

/// Of `candidates` (the parameters left out at the nominal robot, [`super::cv::Model::left_out`]),
/// those re-admitted at the identified robot of the identification `id` (its priors and
/// validation are not read) registered by `registration`, by the rule of the module, in order.
pub fn readmit(
    id: &Subject,
    registration: Registration,
    candidates: &[Param],
) -> Result<Vec<(Param, Readmitted)>> {
    let c = id.calibrated;
    let noise = unit_noise(id.data, c.identified.sigma0);
    let mut out = Vec::new();
    if !(noise.is_finite() && noise >= 0.0) || candidates.is_empty() {
        return Ok(out);
    }
    let nuisance: Vec<Param> = match registration {
        Registration::Svd | Registration::Wsvd => (0..6)
            .map(Param::Base)
            .filter(|p| !id.params.contains(p))
            .collect(),
        Registration::Identify | Registration::Known => Vec::new(),
    };
    let weights = point_weights(id.data, &c.identified.weights);
    let mut current: Vec<Param> = id.params.to_vec();
    for &p in candidates {
        if current.contains(&p) || nuisance.contains(&p) {
            continue;
        }
        let Some(bound) = super::plausibility::bound(id.nominal, p) else {
            continue;
        };
        let all: Vec<Param> = current
            .iter()
            .chain(&nuisance)
            .copied()
            .chain([p])
            .collect();
        let (n, g) = normal(&c.robot, &all, id, &weights)?;
        let last = all.len() - 1;
        let largest = (0..all.len())
            .map(|i| n[(i, i)].max(0.0).sqrt())
            .fold(0.0, Real::max);
        if n[(last, last)].max(0.0).sqrt() <= 1e-9 * largest + 1e-12 {
            continue;
        }
        let Some(inv) = bound_inverse(&n) else {
            continue;
        };
        let sigma = noise * inv[(last, last)].sqrt();
        let estimate = inv.row(last).dot(&g.transpose());
        let threshold = bound / DETERMINABLE_SIGMAS;
        if sigma <= threshold && estimate.abs() > DETERMINABLE_SIGMAS * sigma {
            current.push(p);
            let parameter = p.to_string();
            out.push((
                p,
                Readmitted {
                    estimate,
                    parameter,
                    sigma,
                    threshold,
                },
            ));
        }
    }
    Ok(out)
}

/// The noise (mm) of a point of weight 1: the fit's unit-weight σ0 and, when the file states
/// each point's σ (`sigma_mm`, weighed 1/σ² scaled to a mean weight of 1), the larger of σ0
/// and the stated σ of a point of weight 1, `(mean 1/σ²)^(-1/2)`.
fn unit_noise(data: &Measurements, sigma0: Real) -> Real {
    match &data.sigma_mm {
        Some(s) if !s.is_empty() => {
            let mean = s.iter().map(|v| 1.0 / (v * v)).sum::<Real>() / s.len() as Real;
            sigma0.max(1.0 / mean.sqrt())
        }
        _ => sigma0,
    }
}

/// Each point's weight in the re-check: the file's (else 1) on the points a robust fit kept at
/// full weight, 0 on those it weighed down. A robust method's weights are per point, or with
/// IGG3's `per = "coordinate"` each point's mean over its rows, which would let a gross error
/// in one coordinate into the score at two thirds of its size; so only the points the fit
/// fully trusted enter.
fn point_weights(data: &Measurements, fitted: &[Real]) -> Vec<Real> {
    let mut w = data.weights().unwrap_or_else(|| vec![1.0; data.len()]);
    if fitted.len() == data.len() {
        for (w, &f) in w.iter_mut().zip(fitted) {
            if f < 1.0 {
                *w = 0.0;
            }
        }
    }
    w
}

/// `JᵀPJ` and `JᵀP r` of `params` at `robot` (the identified robot: errors 0) in the
/// calibration's frame, over the calibration rows, summed [`BLOCK_POINTS`] points at a time.
fn normal(
    robot: &Robot,
    params: &[Param],
    id: &Subject,
    weights: &[Real],
) -> Result<(DMatrix<Real>, DVector<Real>)> {
    let problem = CalibrationProblem::new(robot, params, id.data, id.calibrated.frame, id.k);
    let rp = RobotProblem::of(&problem)?;
    let rows = rp.size().rows_per_point;
    let mut sums = NormalEquations::new(params.len(), rows * BLOCK_POINTS);
    by_blocks(&rp, &DVector::zeros(params.len()), |points, r, j| {
        sums.add(j, r.as_slice(), &weights[points]);
    });
    Ok((sums.n().clone(), sums.g().clone()))
}

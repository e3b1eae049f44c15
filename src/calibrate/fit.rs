//! One fit of a tracker's identification, as `identify` runs it (docs/formats.md § 2.6.1,
//! "Parameters re-checked at the identified robot"): calibrate the parameters chosen at the
//! nominal robot, re-check at the identified robot those left out ([`super::recheck`]), and
//! calibrate again with the re-admitted ones when the identification settles them. The final
//! fit of [`super::pipeline`] and the fit of every fold of a cross-validation
//! ([`super::cv::cross_validate`]) go through it, so a cross-validation measures the model
//! that is finally identified, re-admitted parameters included.

use super::diagnostics::Subject;
use super::plausibility::moves;
use super::recheck::{Readmission, Recheck};
use super::{Calibrated, Registration};
use crate::error::Result;
use crate::identify::solver::DETERMINABLE_SIGMAS;
use crate::identify::Termination;
use crate::measurement::Measurements;
use crate::numeric::Real;
use crate::robot::{Param, Robot};

/// The fit kept: its calibration, the parameters it identified (the re-admitted ones last)
/// and what the re-check changed.
pub struct Fit {
    /// The calibration kept.
    pub calibrated: Calibrated,
    /// Its parameters, in the order of the estimate.
    pub params: Vec<Param>,
    /// The parameters re-admitted and the fit before them; `None`: the first fit is kept.
    pub readmitted: Option<Readmission>,
    /// Which call of the calibration was kept: 0 the first, 1 the one with the re-admitted
    /// parameters.
    pub attempt: usize,
}

/// What a fit is of: the nominal robot, the calibration rows, the registration and the
/// orientation weight (mm per rad).
pub type FitOn<'a> = (&'a Robot, &'a Measurements, Registration, Real);

/// One calibration of the given parameters, started at the given errors (empty: at the
/// nominal robot).
pub type CalibrateFrom<'a> = dyn FnMut(&[Param], &[Real]) -> Result<Calibrated> + 'a;

/// Calibrates `params` by `calibrate` (its second argument: where the Jacobian methods
/// start, [`crate::identify::MethodSpec::start`]; empty, at the nominal robot), then
/// re-checks `candidates` at the identified robot ([`Recheck::readmit`]) and calibrates again
/// with those re-admitted, started at the identified robot with the re-admitted errors at the
/// re-check's estimates: at the nominal robot, where they were left out, their columns vanish
/// and a Gauss–Newton step in them is unbounded (the ridge's and the robust ridge's, which do
/// not damp it). A re-admission the identification cannot settle (the first fit converged and
/// the second does not, or a re-admitted error ends more than 3 σ from its estimate), or one
/// that moves a robot the first fit left within the physical bounds beyond them
/// ([`moves`]: 5° for an angle, 2 % of the reach for a length), is given up: the parameters
/// are not determined in practice. `accept` may refuse each fit kept (the
/// pipeline's refusal of undetermined data).
pub fn fit_and_readmit(
    (nominal, data, registration, k): FitOn,
    params: Vec<Param>,
    candidates: &[Param],
    calibrate: &mut CalibrateFrom,
    accept: &dyn Fn(&Calibrated, &[Param]) -> Result<()>,
) -> Result<Fit> {
    let first = calibrate(&params, &[])?;
    accept(&first, &params)?;
    let keep = |calibrated, params| Fit {
        calibrated,
        params,
        readmitted: None,
        attempt: 0,
    };
    if candidates.is_empty() {
        return Ok(keep(first, params));
    }
    let on = Subject {
        nominal,
        params: &params,
        data,
        calibrated: &first,
        k,
        priors: &[],
        validation: None,
    };
    let Some(recheck) = Recheck::at(&on, registration, candidates)? else {
        return Ok(keep(first, params));
    };
    let admitted = recheck.readmit();
    if admitted.is_empty() {
        return Ok(keep(first, params));
    }
    let mut more = params.clone();
    more.extend(admitted.iter().map(|a| a.0));
    let mut start: Vec<Real> = first.identified.x.iter().copied().collect();
    start.resize(more.len(), 0.0);
    if let Some(step) = recheck.step(&more) {
        start.iter_mut().zip(step).for_each(|(x, s)| *x += s);
    }
    let second = calibrate(&more, &start)?;
    // Settled: the second fit converged where the first did, and each re-admitted error
    // ended within 3 σ of the re-check's estimate. A damped method stops on a small step,
    // which a parameter whose column the damping swamps takes even far from its optimum.
    let near_estimates = admitted.iter().enumerate().all(|(i, (_, a))| {
        let x = second.identified.x[params.len() + i];
        (x - a.estimate).abs() <= DETERMINABLE_SIGMAS * a.sigma
    });
    let settled = (second.identified.termination == Termination::Converged
        || first.identified.termination != Termination::Converged)
        && near_estimates;
    // A re-admission that takes a robot within the physical bounds beyond them moves it
    // along directions the data barely determine: given up as well.
    let strays = |c: &Calibrated, p: &[Param]| !moves(nominal, &c.robot, p, &data.qs).is_empty();
    if !settled || (strays(&second, &more) && !strays(&first, &params)) {
        return Ok(keep(first, params));
    }
    accept(&second, &more)?;
    Ok(Fit {
        readmitted: Some(Readmission {
            before_rms_residual_mm: first.identified.rms_residual,
            parameters: admitted.into_iter().map(|a| a.1).collect(),
        }),
        calibrated: second,
        params: more,
        attempt: 1,
    })
}

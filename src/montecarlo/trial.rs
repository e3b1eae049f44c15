//! One Monte-Carlo trial: a true robot, its measurement for each calibration strategy, every
//! method's identification, and the validation of each compensated robot.
//!
//! Within a trial every method and strategy sees the same true robot; each strategy's
//! measurement draws its noise and outliers from the same stream, so the draws line up pose
//! by pose (SPEC §3, FORMATS.md `run`).

use std::time::Instant;

use nalgebra::{DMatrix, DVector};

use super::study::Study;
use crate::errmodel::attitude_error_deg;
use crate::error::Result;
use crate::identify::{identify, Identified, RobotData, RobotProblem, Termination};
use crate::jacobian::{jacobian, Columns, Measure};
use crate::kinematics::{Param, Robot};
use crate::math::{Frame, Real, Vec3};
use crate::metaheur::MetaProblem;
use crate::registration::{register_svd, register_wsvd};
use crate::rng::{self, Rng};
use crate::scenario::{Identifier, MetaAlgorithm, Registration};
use crate::sim::poses::{sample_region, sample_region_keyed};
use crate::sim::tracker::quaternion_matrix;
use crate::sim::truth::draw_errors;
use crate::sim::{measure_poses, Measurement, SagFn};

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

/// What one method on one strategy's measurement gave in one trial.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Index into the scenario's methods.
    pub method: usize,
    /// Index into the scenario's strategies.
    pub strategy: usize,
    /// Identified errors, one per study parameter (mm, rad).
    pub identified: Vec<Real>,
    /// Validation position errors (mm) before compensation: statistics.
    pub before_mm: ErrorStats,
    /// … after compensation.
    pub after_mm: ErrorStats,
    /// Validation orientation errors (deg) before and after, for full-pose data.
    pub before_deg: Option<ErrorStats>,
    /// … after.
    pub after_deg: Option<ErrorStats>,
    /// Per-point validation errors before and after (kept for trial 0's plot only).
    pub per_point: Option<(Vec<Real>, Vec<Real>)>,
    /// A metaheuristic's best fitness per iteration (trial 0 only).
    pub trace: Option<Vec<Real>>,
    /// Iterations of the identification.
    pub iterations: usize,
    /// How it ended.
    pub termination: Termination,
    /// Wall time of registration and identification (s). Not part of the reproducible output.
    pub seconds: Real,
}

/// One trial's results.
#[derive(Clone, Debug)]
pub struct TrialResult {
    /// Trial index.
    pub index: usize,
    /// The injected errors, one per study parameter (0 where none was injected).
    pub truth: Vec<Real>,
    /// The Cramér–Rao trace per strategy (`None` without tracker noise).
    pub crb_trace: Vec<Option<Real>>,
    /// One outcome per strategy × method.
    pub outcomes: Vec<Outcome>,
}

/// Brings the measured points (and frames) into the base frame with `frame`.
fn to_base(m: &Measurement, frame: &Frame) -> RobotData {
    RobotData {
        qs: m.qs.clone(),
        points: m.points.iter().map(|p| frame.apply(p)).collect(),
        rotations: m.quats.as_ref().map(|qs| {
            qs.iter()
                .map(|q| frame.rot * quaternion_matrix(q))
                .collect()
        }),
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
    /// Best fitness per iteration of a metaheuristic (Qiao 2021 fig. 4); empty otherwise.
    pub trace: Vec<Real>,
}

/// An identification result for methods that are not Jacobian-based: no weights,
/// covariance or condition number.
fn plain_result(
    x: Vec<Real>,
    iterations: usize,
    termination: Termination,
    points: usize,
) -> Identified {
    Identified {
        x: DVector::from_vec(x),
        iterations,
        termination,
        weights: vec![1.0; points],
        condition_number: Real::NAN,
        covariance: DMatrix::zeros(0, 0),
        sigma0: Real::NAN,
        rms_residual: Real::NAN,
        ridge_xi: None,
    }
}

/// Runs one identifier on data already in the base frame.
fn run_identifier(
    nominal: &Robot,
    params: &[Param],
    measure: Measure,
    data: &RobotData,
    method: &Identifier,
    rng: &mut Rng,
) -> Result<(Identified, Robot, Vec<Real>)> {
    let n = data.qs.len();
    match method {
        Identifier::Jacobian { method, k } => {
            let problem =
                RobotProblem::new(nominal, params, data, measure)?.with_orientation_weight(*k)?;
            let r = identify(&problem, &DVector::zeros(params.len()), method);
            let robot = problem.robot_with(&r.x);
            Ok((r, robot, Vec::new()))
        }
        Identifier::ErrorModel {
            model,
            iterations,
            k,
        } => {
            let rots = data.rotations.as_ref().ok_or_else(|| {
                crate::Error::Compute("the pose-error models need full-pose data".into())
            })?;
            let frames: Vec<Frame> = data
                .points
                .iter()
                .zip(rots)
                .map(|(p, r)| Frame { rot: *r, pos: *p })
                .collect();
            let fit = crate::errmodel::identify(
                *model,
                nominal,
                params,
                &data.qs,
                &frames,
                *iterations,
                *k,
            )?;
            let term = if fit.last_step < 1e-9 {
                Termination::Converged
            } else {
                Termination::MaxIterations
            };
            Ok((
                plain_result(fit.x, *iterations, term, n),
                fit.robot,
                Vec::new(),
            ))
        }
        Identifier::Meta(spec) => {
            let problem = MetaProblem::new(
                nominal,
                params.to_vec(),
                data.qs.clone(),
                data.points.clone(),
                data.rotations.clone(),
                spec.k,
            )?;
            let bounds = problem.bounds(spec.bound_mm, spec.bound_rad);
            let f = |x: &[Real]| problem.fitness(x);
            let r = match &spec.algorithm {
                MetaAlgorithm::Bas(o) => crate::metaheur::bas(&f, &bounds, o, rng)?,
                MetaAlgorithm::Pso(o) => crate::metaheur::pso(&f, &bounds, o, rng)?,
                MetaAlgorithm::BasPso(o) => crate::metaheur::bas_pso(&f, &bounds, o, rng)?,
            };
            let robot = problem.robot(&r.x)?;
            let it = r.iterations;
            Ok((
                plain_result(r.x, it, Termination::MaxIterations, n),
                robot,
                r.trace,
            ))
        }
    }
}

/// Registration and identification of one method on one measurement (SPEC §3
/// "Registration", §4). With `svd` and `wsvd` registration and identification alternate
/// (three rounds): the first fit absorbs part of the kinematic error into the frame, and a
/// refit on the identified model removes it. With `identify` the SVD frame is a first
/// estimate and the base parameters (which must then be among `params`) absorb the rest
/// (Li 2018). With `known` the frame is `known`.
#[allow(clippy::too_many_arguments)]
pub fn calibrate(
    nominal: &Robot,
    params: &[Param],
    measure: Measure,
    m: &Measurement,
    registration: Registration,
    known: &Frame,
    method: &Identifier,
    rng: &mut Rng,
) -> Result<Calibrated> {
    let chain = nominal.chain();
    let nominal_points: Vec<Vec3> = m.qs.iter().map(|q| chain.fk(q).pos).collect();
    let mut frame = match registration {
        Registration::Known => *known,
        Registration::Wsvd => register_wsvd(&nominal_points, &m.points)?.frame,
        Registration::Svd | Registration::Identify => {
            register_svd(&nominal_points, &m.points, None)?.frame
        }
    };
    let rounds = match registration {
        Registration::Svd | Registration::Wsvd => 3,
        _ => 1,
    };
    let mut round = 0;
    loop {
        let data = to_base(m, &frame);
        let (identified, robot, trace) =
            run_identifier(nominal, params, measure, &data, method, rng)?;
        round += 1;
        if round >= rounds {
            return Ok(Calibrated {
                robot,
                frame,
                identified,
                trace,
            });
        }
        let c = robot.chain();
        let model: Vec<Vec3> = m.qs.iter().map(|q| c.fk(q).pos).collect();
        frame = match registration {
            Registration::Wsvd => register_wsvd(&model, &m.points)?.frame,
            _ => register_svd(&model, &m.points, None)?.frame,
        };
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

/// The Cramér–Rao trace `tr (JᵀWJ)⁻¹` for the tracker noise at the calibration poses (in the
/// base frame, with the nominal Jacobian), or `None` without noise.
pub(super) fn crb_trace(study: &Study, qs: &[Vec<Real>]) -> Option<Real> {
    let cols = Columns::new(&study.params, study.nominal.dof());
    let mut j = jacobian(&study.nominal, &cols, qs, study.measure);
    let rows = study.measure.rows();
    let chain = study.nominal.chain();
    let tracker_at = study.tracker.frame().pos;
    for (i, q) in qs.iter().enumerate() {
        let range = (chain.fk(q).pos - tracker_at).norm();
        let s = study.tracker.sigma_mm(range);
        if s <= 0.0 {
            return None;
        }
        let mut block = j.rows_mut(rows * i, 3);
        block /= s;
        if rows == 6 {
            let sa = study.scenario.tracker.angle_noise_deg.to_radians();
            if sa <= 0.0 {
                return None;
            }
            let mut b = j.rows_mut(rows * i + 3, 3);
            b /= sa;
        }
    }
    let n: DMatrix<Real> = j.transpose() * &j;
    n.try_inverse()
        .map(|inv| inv.trace())
        .filter(|t| t.is_finite())
}

/// The injected errors and the true robot of trial `index`.
pub fn true_robot(study: &Study, index: usize) -> (Vec<(Param, Real)>, Robot) {
    let seed = rng::trial_seed(study.scenario.seed, index as u64);
    let errors = draw_errors(
        &study.error_params,
        &study.scenario.errors,
        &mut rng::stream(seed, "errors"),
    );
    let robot = study.nominal.with_errors(&errors);
    (errors, robot)
}

/// The calibration poses of strategy `si` in trial `index`: the study's fixed set, or a
/// fresh draw from the trial's seed.
pub fn calibration_poses(study: &Study, si: usize, index: usize) -> Result<Vec<Vec<Real>>> {
    let sc = &study.scenario;
    if let Some(set) = &study.fixed[si] {
        return Ok(set.poses.clone());
    }
    let seed = rng::trial_seed(sc.seed, index as u64);
    let name = sc.calibration.strategies[si].name();
    let mut gp = rng::stream(seed, &format!("poses/{name}"));
    sample_region(
        &study.nominal,
        &sc.calibration.region,
        sc.calibration.count,
        &mut gp,
    )
}

/// The validation poses of trial `index`.
pub fn validation_poses(study: &Study, index: usize) -> Result<Vec<Vec<Real>>> {
    let sc = &study.scenario;
    let seed = rng::trial_seed(sc.seed, index as u64);
    let mut gv = rng::stream(seed, "validation");
    sample_region_keyed(
        &study.nominal,
        &sc.validation.region,
        sc.validation.count,
        "validation.region",
        &mut gv,
    )
}

/// The study's gravity sag as the simulator's callback (the deflected tool frame), if any.
pub fn sag_fn(study: &Study) -> Option<Box<SagFn>> {
    study
        .compliance
        .clone()
        .map(|c| Box::new(move |r: &Robot, q: &[Real]| c.deflected(r, q)) as Box<SagFn>)
}

/// Runs trial `index` of `study`.
pub fn run_trial(study: &Study, index: usize) -> Result<TrialResult> {
    let sc = &study.scenario;
    let seed = rng::trial_seed(sc.seed, index as u64);
    let (errors, truth_robot) = true_robot(study, index);
    let truth: Vec<Real> = study
        .params
        .iter()
        .map(|p| errors.iter().find(|(q, _)| q == p).map_or(0.0, |e| e.1))
        .collect();
    let sag = sag_fn(study);
    let sag_ref = sag.as_deref();

    // Validation: fresh poses, true frames of the sagging true arm, free of tracker noise.
    let vqs = validation_poses(study, index)?;
    let vtruth: Vec<Frame> = vqs
        .iter()
        .map(|q| match &sag_ref {
            Some(f) => f(&truth_robot, q),
            None => Ok(truth_robot.fk(q)),
        })
        .collect::<Result<_>>()?;
    let (before_p, before_a) = validation_errors(&study.nominal, &vqs, &vtruth);
    let full_pose = study.measure == Measure::Pose;

    let mut outcomes = Vec::new();
    let mut crb = Vec::new();
    for si in 0..sc.calibration.strategies.len() {
        let qs = calibration_poses(study, si, index)?;
        let outliers = (sc.outliers.count_for(qs.len())? > 0).then_some(&sc.outliers);
        let mut gm = rng::stream(seed, "measure");
        let m = measure_poses(
            &truth_robot,
            &qs,
            &study.tracker,
            outliers,
            sag_ref,
            &mut gm,
        )?;
        crb.push(match &study.fixed[si] {
            Some(set) => set.crb_trace,
            None => crb_trace(study, &qs),
        });
        for (mi, spec) in sc.methods.iter().enumerate() {
            let t0 = Instant::now();
            let res = calibrate(
                &study.nominal,
                &study.params,
                study.measure,
                &m,
                sc.registration,
                &study.tracker.frame(),
                &spec.method,
                &mut rng::stream(seed, &format!("method/{}", spec.label)),
            );
            let seconds = t0.elapsed().as_secs_f64();
            let mut trace = None;
            let (identified, after_p, after_a, iterations, termination) = match res {
                Ok(c) => {
                    // The compensated robot lives in the registered frame: bring the truth
                    // there through the true tracker placement (identity for `known`).
                    let map = c.frame.compose(&study.tracker.frame().inverse());
                    let seen: Vec<Frame> = vtruth.iter().map(|t| map.compose(t)).collect();
                    let (p, a) = validation_errors(&c.robot, &vqs, &seen);
                    if index == 0 && !c.trace.is_empty() {
                        trace = Some(c.trace);
                    }
                    let r = c.identified;
                    (
                        r.x.iter().copied().collect(),
                        p,
                        a,
                        r.iterations,
                        r.termination,
                    )
                }
                Err(_) => (
                    vec![Real::NAN; study.params.len()],
                    vec![Real::NAN; vqs.len()],
                    vec![Real::NAN; vqs.len()],
                    0,
                    Termination::InvalidInput,
                ),
            };
            outcomes.push(Outcome {
                method: mi,
                strategy: si,
                identified,
                before_mm: ErrorStats::of(&before_p),
                after_mm: ErrorStats::of(&after_p),
                before_deg: full_pose.then(|| ErrorStats::of(&before_a)),
                after_deg: full_pose.then(|| ErrorStats::of(&after_a)),
                trace,
                per_point: (index == 0).then(|| (before_p.clone(), after_p.clone())),
                iterations,
                termination,
                seconds,
            });
        }
    }
    Ok(TrialResult {
        index,
        truth,
        crb_trace: crb,
        outcomes,
    })
}

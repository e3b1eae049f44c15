//! One Monte-Carlo trial: a true robot, its measurement for each calibration strategy, every
//! method's identification, and the validation of each compensated robot.
//!
//! Within a trial every method and strategy sees the same true robot; each strategy's
//! measurement draws its noise and outliers from the same stream, so the draws line up pose
//! by pose (docs/formats.md `run`).

use std::time::Instant;

use super::crb;
pub use super::plan::{calibration_rows, sag_fn, sagging_payload, true_robot, unmodelled};
use super::plan::{optimised_set, Study};
use super::stats::ecdf;
use crate::calibrate::{calibrate, validation_errors_with, ErrorStats, PoseErrors};
use crate::error::Result;
use crate::identify::Termination;
use crate::measurement::Measure;
use crate::numeric::rng;
use crate::numeric::{Frame, Real};
use crate::robot::Robot;
use crate::sim::poses::{sample_region, sample_region_keyed};
use crate::sim::unmodelled::Unmodelled;
use crate::sim::{measure_poses, Reached, SagFn, Simulated};

pub use super::outcome::{OptionalStats, Outcome, TrialResult};

/// The calibration poses of strategy `si` in trial `index`: the set optimised for the trial
/// (`calibration.optimise = "trial"`), the study's fixed set, or a fresh draw from the
/// trial's seed.
pub fn calibration_poses(study: &Study, si: usize, index: usize) -> Result<Vec<Vec<Real>>> {
    let sc = &study.scenario;
    if study.per_trial[si] {
        return optimised_set(study, si, index);
    }
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

/// Measures the calibration poses `qs` on the true robot (the tracker, the study's outliers
/// and sag): once each, or, with `calibration.payloads_kg`, once per payload, every pose under
/// the first payload, then every pose under the next, and so on (the measurement then
/// records each row's payload).
///
/// With `unmodelled`, the arm reaches the rows' joint values with that error, in the order
/// measured ([`Unmodelled::actual`]).
pub fn measure_calibration(
    study: &Study,
    truth_robot: &Robot,
    qs: &[Vec<Real>],
    (sag, unmodelled): (Option<&SagFn>, Option<&Unmodelled>),
    rng: &mut crate::numeric::rng::Rng,
) -> Result<Simulated> {
    let sc = &study.scenario;
    let expanded;
    let (qs, loads) = match (&sc.calibration.payloads_kg, sagging_payload(sc)) {
        (None, None) => (qs, None),
        _ => {
            let (q, l): (Vec<_>, Vec<_>) = calibration_rows(sc, qs).into_iter().unzip();
            expanded = (q, l.into_iter().flatten().collect::<Vec<Real>>());
            (&expanded.0[..], Some(&expanded.1[..]))
        }
    };
    let outliers = (sc.outliers.count_for(qs.len())? > 0).then_some(&sc.outliers);
    let actual = unmodelled.map(|u| u.actual(qs));
    let reached = Reached {
        commanded: qs,
        actual: actual.as_deref(),
    };
    measure_poses(
        truth_robot,
        reached,
        &study.tracker,
        outliers,
        sag,
        loads,
        rng,
    )
}

/// One trial's measurements as an instrument would deliver them, with their truth
/// (`calbench simulate`): the first strategy's calibration poses and the validation poses,
/// each measured by the tracker (the calibration with the study's outliers and payloads).
pub struct SimulatedTrial {
    /// The trial.
    pub trial: usize,
    /// The trial's seed.
    pub seed: u64,
    /// The true robot's injected errors.
    pub errors: Vec<(crate::robot::Param, Real)>,
    /// The calibration measurement.
    pub calibration: Simulated,
    /// The validation measurement (no outliers).
    pub validation: Simulated,
}

/// Simulates the measurements of trial `trial` of `study`; a trial beyond the scenario's is
/// refused, naming `key`.
pub fn simulate_trial(study: &Study, trial: usize, key: &str) -> Result<SimulatedTrial> {
    let sc = &study.scenario;
    if trial >= sc.trials {
        return Err(crate::Error::setting(
            key,
            format!(
                "trial {trial} does not exist: the scenario has {} trials (0-based)",
                sc.trials
            ),
        ));
    }
    let (errors, truth) = true_robot(study, trial);
    let seed = rng::trial_seed(sc.seed, trial as u64);
    let qs = calibration_poses(study, 0, trial)?;
    let vqs = validation_poses(study, trial)?;
    let (sag, mut gm) = (sag_fn(study), rng::stream(seed, "measure"));
    let sag_ref = sag.as_deref();
    let um = unmodelled(study, trial);
    let calibration = measure_calibration(study, &truth, &qs, (sag_ref, um.as_ref()), &mut gm)?;
    // The validation measurement records its payload when the scenario measures under loads.
    let loaded = sc.calibration.payloads_kg.is_some()
        || sc.validation.payload_kg.is_some()
        || sagging_payload(sc).is_some();
    let vloads = loaded.then(|| vec![study.validation_payload(); vqs.len()]);
    let vactual = um.as_ref().map(|u| u.actual(&vqs));
    let reached = Reached {
        commanded: &vqs,
        actual: vactual.as_deref(),
    };
    let validation = measure_poses(
        &truth,
        reached,
        &study.tracker,
        None,
        sag_ref,
        vloads.as_deref(),
        &mut rng::stream(seed, "measure/validation"),
    )?;
    Ok(SimulatedTrial {
        trial,
        seed,
        errors,
        calibration,
        validation,
    })
}

impl SimulatedTrial {
    /// `truth.json` of `calbench simulate` (docs/formats.md).
    pub fn truth_json(&self, study: &Study) -> serde_json::Value {
        let sc = &study.scenario;
        let errs: serde_json::Map<String, serde_json::Value> = self
            .errors
            .iter()
            .map(|(p, e)| (p.to_string(), serde_json::json!(e)))
            .collect();
        let mut truth = serde_json::json!({
            "scenario": sc.name,
            "trial": self.trial,
            "seed": self.seed,
            "robot": study.nominal.name,
            "calibration_poses": sc.calibration.strategies[0].name(),
            "errors": errs,
            "tracker_pose": sc.tracker.pose,
            "outliers": self.calibration.truth.outliers,
            "sag_mm": self.calibration.truth.sag_mm,
            "validation_sag_mm": self.validation.truth.sag_mm,
        });
        if let Some(c) = study.true_compliance_json() {
            truth["true_compliance"] = c;
        }
        truth
    }
}

/// The searches whose best fitnesses are compared on one trial: those of strategy `si` that
/// minimise the same fitness (the same orientation weight `k` and the same pose-error model,
/// [`crate::identify::Method::fitness_model`]); `None` for a method that is not a search.
fn search_group(si: usize, spec: &crate::identify::MethodSpec) -> Option<ecdf::Group> {
    let model = spec.method.fitness_model()?;
    Some((si, spec.k.to_bits(), model.into()))
}

/// Runs trial `index` of `study`.
pub fn run_trial(study: &Study, index: usize) -> Result<TrialResult> {
    let sc = &study.scenario;
    let seed = rng::trial_seed(sc.seed, index as u64);
    let (errors, truth_robot) = true_robot(study, index);
    let true_c = study.true_compliances();
    let truth: Vec<Real> = study
        .params
        .iter()
        .map(|p| {
            errors
                .iter()
                .chain(&true_c)
                .find(|(q, _)| q == p)
                .map_or(0.0, |e| e.1)
        })
        .collect();
    let sag = sag_fn(study);
    let sag_ref = sag.as_deref();

    let um = unmodelled(study, index);

    // Validation: fresh poses, true frames of the sagging true arm (at the joint values it
    // reaches), free of tracker noise.
    let vqs = validation_poses(study, index)?;
    let vload = sc.validation.payload_kg;
    let vactual = um.as_ref().map(|u| u.actual(&vqs));
    let vtruth: Vec<Frame> = vactual
        .as_ref()
        .unwrap_or(&vqs)
        .iter()
        .map(|q| match &sag_ref {
            Some(f) => f(&truth_robot, q, vload),
            None => Ok(truth_robot.fk(q)),
        })
        .collect::<Result<_>>()?;
    let vpayload = vec![study.validation_payload(); vqs.len()];
    // Orientation errors only where the study reads them (full poses).
    let full_pose = study.measure == Measure::Pose;
    let errors_of = |robot: &Robot, qs: &[Vec<Real>], loads: Option<&[Real]>, truth: &[Frame]| {
        validation_errors_with(robot, qs, loads, truth, full_pose)
    };
    let before = errors_of(&study.nominal, &vqs, Some(&vpayload), &vtruth)?;
    let before_mm = ErrorStats::of(&before.mm);
    let before_fitted = if sc.validation.before_fitted {
        Some(fitted_before(study, &vqs, &vtruth)?)
    } else {
        None
    };
    let axis = sc.validation.axis_errors;

    let mut outcomes = Vec::new();
    // Each search's whole trace on this trial, dropped once reduced to its `SearchRun`.
    let mut searches: Vec<Option<(ecdf::Group, Vec<Real>, usize)>> = Vec::new();
    let mut crb_traces = Vec::new();
    let mut not_determinable = Vec::new();
    for si in 0..sc.calibration.strategies.len() {
        let qs = calibration_poses(study, si, index)?;
        // The fixed set's frames computed once for the study, where it has them.
        let memo = study.fixed[si].as_ref().and_then(|f| f.sag.clone());
        let served: Option<Box<SagFn>> = match (memo, sag_fn(study)) {
            (Some(memo), Some(model)) => Some(Box::new(
                move |r: &Robot, q: &[Real], load: Option<Real>| {
                    memo.get(r, q, load).map_or_else(|| model(r, q, load), Ok)
                },
            )),
            _ => None,
        };
        let cal_sag = served.as_deref().or(sag_ref);
        let m = measure_calibration(
            study,
            &truth_robot,
            &qs,
            (cal_sag, um.as_ref()),
            &mut rng::stream(seed, "measure"),
        )?;
        // The calibration rows' noise-free true frames (the orientation where the tracker
        // measures it), and the nominal robot's errors at them.
        let cal_truth: Vec<Frame> = m
            .truth
            .true_points
            .iter()
            .enumerate()
            .map(|(i, &pos)| Frame {
                rot: m
                    .truth
                    .true_rotations
                    .as_ref()
                    .map_or_else(crate::numeric::Mat3::identity, |r| r[i]),
                pos,
            })
            .collect();
        let cal_loads = m.data.payload_kg.as_deref();
        let cal_nominal = errors_of(&study.nominal, &m.data.qs, cal_loads, &cal_truth)?;
        let cal_before = ErrorStats::of(&cal_nominal.mm);
        // The bound at the rows as measured, on the robot they were measured on.
        let memo = study.fixed[si].as_ref().and_then(|f| f.crb.as_deref());
        let bounds = match memo.and_then(|memo| memo.get(&truth_robot, &m.data.qs)) {
            Some(kept) => kept,
            None => crb::bounds_at(
                &truth_robot,
                &study.params,
                &m.data.qs,
                study.measure,
                &study.tracker,
            ),
        };
        // No trace where a parameter is not estimable: its variance has no bound.
        crb_traces.push(bounds.as_ref().and_then(crb::Bounds::trace));
        not_determinable.push(crb::not_determinable(&truth, bounds.as_ref()));
        for (mi, spec) in sc.methods.iter().enumerate() {
            let t0 = Instant::now();
            let res = calibrate(
                &study.nominal,
                &study.params,
                &m.data,
                sc.registration,
                &study.tracker.frame(),
                spec,
                &mut rng::stream(seed, &format!("method/{}", spec.label)),
            );
            let seconds = t0.elapsed().as_secs_f64();
            let mut trace = None;
            let mut full_trace = None;
            let error = res.as_ref().err().map(|e| e.to_string());
            let (identified, after, cal_after, iterations, evaluations, termination) = match res {
                Ok(c) => {
                    // The compensated robot lives in the registered frame: bring the truth
                    // there through the true tracker placement (identity for `known`).
                    let map = c.frame.compose(&study.tracker.frame().inverse());
                    let seen: Vec<Frame> = vtruth.iter().map(|t| map.compose(t)).collect();
                    let e = errors_of(&c.robot, &vqs, Some(&vpayload), &seen)?;
                    let cal_seen: Vec<Frame> = cal_truth.iter().map(|t| map.compose(t)).collect();
                    let cal = errors_of(&c.robot, &m.data.qs, cal_loads, &cal_seen)?;
                    let r = c.identified;
                    full_trace = r.trace.clone().filter(|t| !t.is_empty());
                    if index == 0 {
                        trace = full_trace.clone();
                    }
                    (
                        r.x.iter().copied().collect(),
                        e,
                        cal,
                        r.iterations,
                        r.evaluations,
                        r.termination,
                    )
                }
                Err(_) => (
                    vec![Real::NAN; study.params.len()],
                    PoseErrors::failed(vqs.len()),
                    PoseErrors::failed(m.data.qs.len()),
                    0,
                    0,
                    Termination::InvalidInput,
                ),
            };
            outcomes.push(Outcome {
                method: mi,
                strategy: si,
                identified,
                before_mm,
                after_mm: ErrorStats::of(&after.mm),
                calibration_before_mm: cal_before,
                calibration_after_mm: ErrorStats::of(&cal_after.mm),
                optional: OptionalStats {
                    validation_before_deg: full_pose.then(|| ErrorStats::of(&before.deg)),
                    validation_after_deg: full_pose.then(|| ErrorStats::of(&after.deg)),
                    validation_before_attitude_deg: full_pose
                        .then(|| ErrorStats::of(&before.attitude_deg)),
                    validation_after_attitude_deg: full_pose
                        .then(|| ErrorStats::of(&after.attitude_deg)),
                    validation_before_fitted_mm: before_fitted,
                    validation_before_axis_mm: axis.then(|| ErrorStats::of_signed(&before.axis_mm)),
                    validation_after_axis_mm: axis.then(|| ErrorStats::of_signed(&after.axis_mm)),
                    validation_before_axis_abs_mm: axis
                        .then(|| ErrorStats::of(&before.axis_abs_mm)),
                    validation_after_axis_abs_mm: axis.then(|| ErrorStats::of(&after.axis_abs_mm)),
                    calibration_before_attitude_deg: full_pose
                        .then(|| ErrorStats::of(&cal_nominal.attitude_deg)),
                    calibration_after_attitude_deg: full_pose
                        .then(|| ErrorStats::of(&cal_after.attitude_deg)),
                },
                trace,
                search: None,
                per_point: (index == 0).then(|| (before.mm.clone(), after.mm.clone())),
                per_point_attitude_deg: (index == 0 && full_pose)
                    .then(|| (before.attitude_deg.clone(), after.attitude_deg.clone())),
                iterations,
                evaluations,
                termination,
                rank_deficient_expected: !study.undetermined.is_empty(),
                seconds,
                error,
            });
            let group = search_group(si, spec);
            searches.push(group.zip(full_trace).map(|(g, t)| (g, t, evaluations)));
        }
    }
    let runs: Vec<_> = searches
        .iter()
        .map(|r| r.as_ref().map(|(g, t, e)| (*g, &t[..], *e)))
        .collect();
    for (o, r) in outcomes.iter_mut().zip(ecdf::of_trial(&runs)) {
        o.search = r;
    }
    Ok(TrialResult {
        index,
        truth,
        crb_trace: crb_traces,
        not_determinable,
        outcomes,
    })
}

/// The nominal robot's position errors at the validation poses after the best rigid fit
/// (SVD, [`crate::calibrate::registration::register_svd`]) of its points to the true ones:
/// "before" as a calibration that fits the base frame to the measurements sees it (Li 2018
/// §1.1 and §3: the base frame is fitted first, then the errors are read).
fn fitted_before(study: &Study, qs: &[Vec<Real>], truth: &[Frame]) -> Result<ErrorStats> {
    let chain = study.nominal.chain();
    let nominal: Vec<_> = qs.iter().map(|q| chain.fk(q).pos).collect();
    let true_points: Vec<_> = truth.iter().map(|t| t.pos).collect();
    let fit = crate::calibrate::registration::register_svd(&nominal, &true_points, None)?;
    Ok(ErrorStats::of(&fit.residuals))
}

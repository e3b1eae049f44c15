//! A study prepared for its trials: everything that depends only on the scenario and the
//! nominal robot — the identified parameter set, the tracker, the compliance model and the
//! pose sets fixed for the study — computed once, and the optimiser that chooses a trial's set
//! when the sets are optimised per trial (docs/formats.md `run`, `calibration.optimise`; Guo
//! 2024 §3 for the optimised sets).

use crate::error::{Error, Result};
use crate::measurement::Measure;
use crate::numeric::rng;
use crate::numeric::{Frame, Real};
use crate::poses::{self, RobotPoseModel, SelectOptions, Separation};
use crate::robot::identifiability::identifiable_generic;
use crate::robot::param_sets::ends;
use crate::robot::{Param, Robot};
use crate::sim::poses::{read_calibration_poses, sample_region};
use crate::sim::sag::Compliance;
use crate::sim::settings::{ParamSelection, Region};
use crate::sim::tracker::Tracker;
use crate::sim::truth::draw_errors;
use crate::sim::unmodelled::Unmodelled;
use crate::sim::SagFn;
use crate::study::crb;
use crate::study::scenario::{OptimiseEach, PoseStrategy, Scenario};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;

/// A calibration pose set fixed for the whole study (optimised, grid or file).
#[derive(Clone, Debug)]
pub struct FixedSet {
    /// Joint values (internal units).
    pub poses: Vec<Vec<Real>>,
    /// The optimiser's objective per iteration (empty when not optimised).
    pub trace: Vec<Real>,
    /// The optimiser's scores of the chosen set, as JSON (empty for grid and file sets).
    pub scores: Option<serde_json::Value>,
    /// The true arm's deflected tool frames at the set's measured rows, when they are the
    /// same in every trial (see [`SagMemo`]).
    pub sag: Option<Arc<SagMemo>>,
    /// The Cramér–Rao variances of the set's measured rows on the true arm, when it is the
    /// same in every trial ([`crate::study::crb::Memo`]).
    pub crb: Option<Arc<crate::study::crb::Memo>>,
}

impl FixedSet {
    /// A set that is not optimised (grid, file): no trace, no scores; the sag is filled in
    /// by [`Study::new`].
    pub fn plain(poses: Vec<Vec<Real>>) -> FixedSet {
        FixedSet {
            poses,
            trace: Vec::new(),
            scores: None,
            sag: None,
            crb: None,
        }
    }
}

/// Deflected tool frames of the true arm, computed once: with a fixed pose set, a true robot
/// that is the same in every trial (errors `paper` or `none`) and a sag model, every trial
/// would otherwise run the same rapier settles again (a third of the default study's time).
/// The sag model is a pure function of the robot, the joint values and the payload, so a
/// frame served from here is the one the trial would compute.
#[derive(Debug)]
pub struct SagMemo {
    /// The true robot's parameter values the frames belong to.
    values: Vec<Real>,
    /// Frames by the bits of the joint values and of the payload.
    frames: HashMap<(Vec<u64>, Option<u64>), Frame>,
}

impl SagMemo {
    /// Computes the deflected frames of `robot` at `rows` (joint values, payload) with
    /// `sag`, on rayon (in order, so the result does not depend on the thread count).
    pub fn new(robot: &Robot, rows: &[(Vec<Real>, Option<Real>)], sag: &SagFn) -> Result<SagMemo> {
        let frames: Vec<Frame> = rows
            .par_iter()
            .map(|(q, load)| sag(robot, q, *load))
            .collect::<Result<_>>()?;
        Ok(SagMemo {
            values: robot.values.clone(),
            frames: rows
                .iter()
                .zip(frames)
                .map(|((q, load), f)| (Self::key(q, *load), f))
                .collect(),
        })
    }

    fn key(q: &[Real], load: Option<Real>) -> (Vec<u64>, Option<u64>) {
        (
            q.iter().map(|v| v.to_bits()).collect(),
            load.map(Real::to_bits),
        )
    }

    /// The frame of `robot` at `q` under `load`, if computed here (same robot values, same
    /// joint values and payload, bit for bit).
    pub fn get(&self, robot: &Robot, q: &[Real], load: Option<Real>) -> Option<Frame> {
        let same = robot.values.len() == self.values.len()
            && robot
                .values
                .iter()
                .zip(&self.values)
                .all(|(a, b)| a.to_bits() == b.to_bits());
        if !same {
            return None;
        }
        self.frames.get(&Self::key(q, load)).copied()
    }
}

/// A scenario made ready to run.
pub struct Study {
    /// The checked scenario.
    pub scenario: Scenario,
    /// The nominal robot.
    pub nominal: Robot,
    /// Position or full pose.
    pub measure: Measure,
    /// The parameters identified (identifiable ones of the joint, tool and — when the
    /// registration is identified — base parameters).
    pub params: Vec<Param>,
    /// The parameters that carry injected errors.
    pub error_params: Vec<Param>,
    /// The identified parameters that the data cannot determine (pivoted QR over generic
    /// poses): empty unless `identification.params` names such parameters, which only the
    /// methods that tolerate rank deficiency identify.
    pub undetermined: Vec<Param>,
    /// The simulated tracker.
    pub tracker: Tracker,
    /// Gravity sag, if modelled.
    pub compliance: Option<Compliance>,
    /// Per calibration strategy: the fixed pose set, or `None` when drawn per trial; for a
    /// set optimised per trial ([`Study::per_trial`]), trial 0's set, which the reports show.
    pub fixed: Vec<Option<FixedSet>>,
    /// Per calibration strategy: whether its set is optimised anew in every trial
    /// (`calibration.optimise = "trial"`, [`optimised_set`]).
    pub per_trial: Vec<bool>,
    /// The ill-conditioned parameter separation (Guo 2024 §3.1) of the first optimised
    /// strategy's candidate pool, when `calibration.separate` is set.
    pub separation: Option<Separation>,
}

/// Which model a pose optimiser scores (docs/formats.md `calibration.strategies`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScoredModel {
    /// Guo 2024's full model: every joint parameter with the tool and base parameters the
    /// study identifies (the `-full` strategies; Guo's 21 columns of eq. 7 for its 3T2R arm,
    /// which identifies no tool parameter).
    Full,
    /// Guo 2024's reconstructed model J_p (eq. 27): the joint parameters without every
    /// ill-conditioned one the separation at this GCN threshold finds
    /// ([`Separation::ill_conditioned`]), with the base and tool parameters the study
    /// identifies (`calibration.separate`).
    Separated(Real),
    /// These parameters as they are.
    Plain,
}

/// The pose model an optimiser scores over the candidate pool `pool`, its parameters and,
/// for [`ScoredModel::Separated`], the separation. `identified` are the kinematic parameters
/// the study identifies: [`ScoredModel::Plain`] scores them, the full and the separated models
/// take their base and tool parameters from them.
/// The full and the separated models are rank-deficient (Guo's GCNs of 2.9e35 and 2.3e18):
/// both are scored on their nonzero spectrum ([`RobotPoseModel::on_row_space`] over `pool`),
/// so that every one of their parameters counts and they differ by the separated ones.
pub fn optimiser_model(
    robot: &Robot,
    measure: Measure,
    pool: &[Vec<Real>],
    scored: ScoredModel,
    identified: &[Param],
) -> (RobotPoseModel, Vec<Param>, Option<Separation>) {
    let joints = robot.joint_params();
    let (mut params, sep) = match scored {
        ScoredModel::Plain => {
            let model = RobotPoseModel::new(robot, identified, measure);
            return (model, identified.to_vec(), None);
        }
        ScoredModel::Full => (joints, None),
        ScoredModel::Separated(threshold) => {
            let sep = poses::separate(robot, &joints, pool, measure, threshold);
            (sep.reduced(&joints), Some(sep))
        }
    };
    params.extend(ends(identified));
    params.sort_by_key(|p| p.index(robot.dof()));
    let model = RobotPoseModel::new(robot, &params, measure).on_row_space(pool);
    (model, params, sep)
}

/// The parameters `scenario` identifies ([`Scenario::kinematic_params`]). A list the data cannot all
/// determine is refused when a method of the scenario needs full rank
/// ([`crate::identify::Method::tolerates_rank_deficiency`]), naming the method and the
/// undetermined parameters. Also returns the parameters that pivoted QR leaves over (empty
/// for `"identifiable"`).
pub fn study_params(scenario: &Scenario, robot: &Robot) -> Result<(Vec<Param>, Vec<Param>)> {
    let measure = scenario.tracker.measure.measure();
    let params = scenario.kinematic_params(robot);
    if scenario.identification.params == ParamSelection::Identifiable {
        return Ok((params, Vec::new()));
    }
    let determined = identifiable_generic(robot, &params, measure);
    let undetermined: Vec<Param> = params
        .iter()
        .copied()
        .filter(|p| !determined.contains(p))
        .collect();
    if !undetermined.is_empty() {
        if let Some(m) = scenario
            .methods
            .iter()
            .find(|m| !m.method.tolerates_rank_deficiency())
        {
            let undetermined: Vec<String> = undetermined.iter().map(|p| p.to_string()).collect();
            let msg =
                format!(
                "method \"{}\" needs parameters the data determine, but {} of these {} are not \
                 identifiable from {} data (pivoted QR leaves over {}); use a method that \
                 tolerates rank deficiency (lm, ridge, igg3), or params = \"identifiable\"",
                m.label,
                undetermined.len(),
                params.len(),
                if measure == Measure::Pose { "full-pose" } else { "position" },
                undetermined.join(", ")
            );
            return Err(match &scenario.path {
                Some(p) => Error::file(p, "identification.params", msg),
                None => Error::setting("identification.params", msg),
            });
        }
    }
    Ok((params, undetermined))
}

impl Study {
    /// The payload (kg) of the validation poses: `validation.payload_kg`, else the
    /// compliance section's payload.
    pub fn validation_payload(&self) -> Real {
        let sc = &self.scenario;
        sc.validation.payload_kg.unwrap_or(sc.compliance.payload_kg)
    }

    /// The true joint compliances of the simulated arm (rad/(N·m), [`Param::Compliance`]):
    /// `1/k_j` of the sag model's stiffness for every revolute joint; empty without sag.
    pub fn true_compliances(&self) -> Vec<(Param, Real)> {
        self.compliance
            .as_ref()
            .map(|c| c.true_compliances(&self.nominal))
            .unwrap_or_default()
    }

    /// [`Study::true_compliances`] as JSON (`summary.json` and `truth.json` key
    /// `true_compliance`: name → rad/(N·m)); `None` without sag.
    pub fn true_compliance_json(&self) -> Option<serde_json::Value> {
        self.compliance.as_ref()?;
        Some(serde_json::Value::Object(
            self.true_compliances()
                .into_iter()
                .map(|(p, c)| (p.to_string(), serde_json::json!(c)))
                .collect(),
        ))
    }

    /// Prepares `scenario`: loads the robot, picks the parameters, builds the tracker and the
    /// compliance model, and optimises the fixed pose sets.
    pub fn new(scenario: Scenario) -> Result<Study> {
        let nominal = scenario.robot()?;
        let measure = scenario.tracker.measure.measure();
        let (mut params, undetermined) = study_params(&scenario, &nominal)?;
        // The kinematic parameters: what the pose optimisers and the Cramér–Rao bound see.
        let kinematic = params.clone();
        params.extend(
            scenario
                .identification
                .compliance
                .params(&nominal, "identification.compliance")?,
        );
        let error_params = scenario.error_params(&nominal)?;
        let tracker = Tracker::new(&scenario.tracker)?;
        let compliance = Compliance::new(&scenario.compliance, &nominal, scenario.builtin())?;

        let mut fixed = Vec::new();
        let mut separation = None;
        for (i, s) in scenario.calibration.strategies.iter().enumerate() {
            let c = &scenario.calibration;
            let set = match s {
                PoseStrategy::Random | PoseStrategy::Box => None,
                PoseStrategy::File(path) => {
                    let poses = read_calibration_poses(path, &nominal)?;
                    if let Some(n) = scenario.outliers.count.filter(|&n| n > poses.len()) {
                        let msg = format!(
                            "{n} outliers but the pose list {} gives only {} calibration poses",
                            path.display(),
                            poses.len()
                        );
                        return Err(scenario.refusal("outliers.count", msg));
                    }
                    Some(FixedSet::plain(poses))
                }
                PoseStrategy::Grid => {
                    let dof = nominal.dof() as f64;
                    let per_joint = ((c.count as f64).powf(1.0 / dof).ceil() as usize).max(2);
                    let mut g = rng::stream(scenario.seed, "grid");
                    let mut poses =
                        sample_region(&nominal, &Region::Grid { per_joint }, c.count, &mut g)?;
                    poses.truncate(c.count);
                    Some(FixedSet::plain(poses))
                }
                PoseStrategy::Optimised(_) | PoseStrategy::OptimisedFull(_) => {
                    // Per trial: trial 0's set, kept for the reports and for trial 0 itself.
                    let seed = match c.optimise {
                        OptimiseEach::Study => scenario.seed,
                        OptimiseEach::Trial => rng::trial_seed(scenario.seed, 0),
                    };
                    let (set, sep) = optimise(&scenario, &nominal, measure, &kinematic, i, seed)?;
                    if let Some(sep) = sep {
                        separation.get_or_insert(sep);
                    }
                    Some(set)
                }
            };
            fixed.push(set);
        }
        let per_trial = scenario
            .calibration
            .strategies
            .iter()
            .map(|s| {
                matches!(
                    s,
                    PoseStrategy::Optimised(_) | PoseStrategy::OptimisedFull(_)
                ) && scenario.calibration.optimise == OptimiseEach::Trial
            })
            .collect();
        let mut study = Study {
            scenario,
            nominal,
            measure,
            params,
            error_params,
            undetermined,
            tracker,
            compliance,
            fixed,
            per_trial,
            separation,
        };
        if let (true, Some(sag)) = (study.scenario.errors.kind.is_fixed(), sag_fn(&study)) {
            let (_, truth) = true_robot(&study, 0);
            let memos: Vec<Option<Arc<SagMemo>>> = study
                .fixed
                .iter()
                .zip(&study.per_trial)
                .map(|(f, &per_trial)| {
                    f.as_ref()
                        .filter(|_| !per_trial)
                        .map(|f| {
                            let rows = calibration_rows(&study.scenario, &f.poses);
                            SagMemo::new(&truth, &rows, &*sag).map(Arc::new)
                        })
                        .transpose()
                })
                .collect::<Result<_>>()?;
            for (f, m) in study.fixed.iter_mut().zip(memos) {
                if let Some(f) = f {
                    f.sag = m;
                }
            }
        }
        if study.scenario.errors.kind.is_fixed() {
            study.keep_crb();
        }
        Ok(study)
    }
}

impl Study {
    /// Computes once the Cramér–Rao variances of every fixed set that is measured the same
    /// way in every trial (not optimised per trial), on the true robot of a study whose true
    /// robot does not change between trials ([`crate::study::crb::Memo`]).
    fn keep_crb(&mut self) {
        let (_, truth) = true_robot(self, 0);
        for (f, &per_trial) in self.fixed.iter_mut().zip(&self.per_trial) {
            let Some(f) = f.as_mut().filter(|_| !per_trial) else {
                continue;
            };
            let rows: Vec<Vec<Real>> = calibration_rows(&self.scenario, &f.poses)
                .into_iter()
                .map(|(q, _)| q)
                .collect();
            let bounds = crb::bounds_at(&truth, &self.params, &rows, self.measure, &self.tracker);
            f.crb = Some(Arc::new(crb::Memo::new(&truth, &rows, bounds)));
        }
    }
}

/// Optimises strategy `si`'s pose set of `scenario` from `seed` (the study's seed, or a
/// trial's under `calibration.optimise = "trial"`): a candidate pool of
/// `calibration.candidates` drawn in `calibration.region` from the stream `optimise/{si}`,
/// then the strategy's optimiser on the model it scores (the separated one with
/// `calibration.separate`, the full one for a `-full` strategy, else `kinematic`). Returns
/// the set and the separation it was optimised on.
pub fn optimise(
    scenario: &Scenario,
    nominal: &Robot,
    measure: Measure,
    kinematic: &[Param],
    si: usize,
    seed: u64,
) -> Result<(FixedSet, Option<Separation>)> {
    let c = &scenario.calibration;
    let s = &c.strategies[si];
    let strategy = match s {
        PoseStrategy::Optimised(o) | PoseStrategy::OptimisedFull(o) => *o,
        _ => unreachable!("only the optimised strategies are optimised"),
    };
    let mut g = rng::stream(seed, &format!("optimise/{si}"));
    let pool = sample_region(nominal, &c.region, c.candidates, &mut g)?;
    let scored = match (s, c.separate) {
        (PoseStrategy::OptimisedFull(_), _) => ScoredModel::Full,
        (_, true) => ScoredModel::Separated(c.separate_threshold),
        _ => ScoredModel::Plain,
    };
    let (model, _, sep) = optimiser_model(nominal, measure, &pool, scored, kinematic);
    let mut opts = SelectOptions::new(c.count);
    opts.objective = c.objective;
    let sel = poses::select(&model, &pool, strategy, &opts, &mut g)?;
    let set = FixedSet {
        poses: sel.poses,
        trace: sel.trace,
        scores: serde_json::to_value(sel.scores).ok(),
        sag: None,
        crb: None,
    };
    Ok((set, sep))
}

/// The pose set strategy `si` optimises in trial `index` under `calibration.optimise =
/// "trial"`: [`optimise`] from the trial's seed (trial 0's is the study's `fixed` set).
pub fn optimised_set(study: &Study, si: usize, index: usize) -> Result<Vec<Vec<Real>>> {
    if index == 0 {
        if let Some(set) = &study.fixed[si] {
            return Ok(set.poses.clone());
        }
    }
    let kinematic: Vec<Param> = study
        .params
        .iter()
        .copied()
        .filter(|p| !p.is_compliance())
        .collect();
    let seed = rng::trial_seed(study.scenario.seed, index as u64);
    let (set, _) = optimise(
        &study.scenario,
        &study.nominal,
        study.measure,
        &kinematic,
        si,
        seed,
    )?;
    Ok(set.poses)
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

/// The error outside the kinematic model of trial `index` (docs/formats.md `[unmodelled]`),
/// drawn from the trial's own `unmodelled` stream; `None` when the section adds nothing.
pub fn unmodelled(study: &Study, index: usize) -> Option<Unmodelled> {
    let settings = &study.scenario.unmodelled;
    if !settings.is_active() {
        return None;
    }
    let seed = rng::trial_seed(study.scenario.seed, index as u64);
    let mut g = rng::stream(seed, "unmodelled");
    Some(Unmodelled::draw(settings, &study.nominal, &mut g))
}

/// The study's gravity sag as the simulator's callback (the deflected tool frame), if any.
pub fn sag_fn(study: &Study) -> Option<Box<SagFn>> {
    study.compliance.clone().map(|c| {
        Box::new(move |r: &Robot, q: &[Real], payload: Option<Real>| {
            c.deflected_under(r, &r.chain(), q, payload.unwrap_or(c.payload_kg()))
        }) as Box<SagFn>
    })
}

/// The rows [`super::trial::measure_calibration`] measures for the poses `qs`: each pose with the payload
/// its row passes to the sag model and records (without `calibration.payloads_kg`, the one
/// payload of [`sagging_payload`]), in the same order.
pub fn calibration_rows(sc: &Scenario, qs: &[Vec<Real>]) -> Vec<(Vec<Real>, Option<Real>)> {
    match &sc.calibration.payloads_kg {
        None => {
            let load = sagging_payload(sc);
            qs.iter().map(|q| (q.clone(), load)).collect()
        }
        Some(p) => p
            .iter()
            .flat_map(|&w| qs.iter().map(move |q| (q.clone(), Some(w))))
            .collect(),
    }
}

/// The payload every calibration row sags under without `calibration.payloads_kg`:
/// `compliance.payload_kg` when the arm sags (a compliance model) under a payload other than
/// 0, which the rows then record (docs/formats.md § 7.5) so that an identification of
/// compliances computes their torques under it; `None` otherwise (no payload).
pub fn sagging_payload(sc: &Scenario) -> Option<Real> {
    let c = &sc.compliance;
    (c.model != crate::sim::sag::ComplianceModel::None && c.payload_kg != 0.0)
        .then_some(c.payload_kg)
}

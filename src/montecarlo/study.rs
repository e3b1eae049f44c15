//! A study prepared for its trials: everything that depends only on the scenario and the
//! nominal robot — the identified parameter set, the tracker, the compliance model and the
//! optimised pose sets — computed once (FORMATS.md `run`; Guo 2024 §3 for the optimised sets).

use crate::compliance::Compliance;
use crate::error::Result;
use crate::identifiability::identifiable_generic;
use crate::jacobian::Measure;
use crate::jacobian::{jacobian, Columns};
use crate::kinematics::{Param, Robot};
use crate::math::Real;
use crate::poses::{self, RobotPoseModel, SelectOptions};
use crate::rng;
use crate::scenario::{PoseStrategy, Registration, Scenario};
use crate::sim::poses::{read_pose_list, sample_region};
use crate::sim::settings::{ErrorKind, ParamSelection, Region};
use crate::sim::tracker::Tracker;
use crate::sim::truth::selected_params;
use nalgebra::DMatrix;

/// A calibration pose set fixed for the whole study (optimised, grid or file).
#[derive(Clone, Debug)]
pub struct FixedSet {
    /// Joint values (internal units).
    pub poses: Vec<Vec<Real>>,
    /// The optimiser's objective per iteration (empty when not optimised).
    pub trace: Vec<Real>,
    /// The optimiser's scores of the chosen set, as JSON (empty for grid and file sets).
    pub scores: Option<serde_json::Value>,
    /// The Cramér–Rao trace of the set (the same in every trial; `None` without noise).
    pub crb_trace: Option<Real>,
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
    /// The simulated tracker.
    pub tracker: Tracker,
    /// Gravity sag, if modelled.
    pub compliance: Option<Compliance>,
    /// Per calibration strategy: the fixed pose set, or `None` when drawn per trial.
    pub fixed: Vec<Option<FixedSet>>,
}

/// The parameters to identify: the identifiable ones among the joint and tool parameters
/// and, with `with_base`, the six base parameters, in flat-vector order. The base parameters
/// are offered first, so a joint parameter that only duplicates the registration (d1 with
/// base.z, θ1 with base.rz) is the one left out: it cannot be told apart from the tracker's
/// placement, so no error is injected on it or identified for it.
pub fn identified_params(robot: &Robot, measure: Measure, with_base: bool) -> Vec<Param> {
    offered_first(robot, measure, with_base, |p| matches!(p, Param::Base(_)))
}

/// [`identified_params`] for measured data (`calbench identify`): the tool parameters are
/// offered right after the base, so a joint parameter that only duplicates the tool (d6 with
/// tool.z, a6 with tool.x and tool.y on a robot whose last axis carries the tool) is the one
/// left out, and the compensated robot file says where the tool really is (a probe mounted a
/// few mm away from its nominal place moves `[tool]`, not the last link).
pub fn identified_params_tool_first(
    robot: &Robot,
    measure: Measure,
    with_base: bool,
) -> Vec<Param> {
    offered_first(robot, measure, with_base, |p| {
        matches!(p, Param::Base(_) | Param::Tool(_))
    })
}

/// The identifiable parameters when those `first` selects (base ones only `with_base`) are
/// offered before the others, in flat-vector order.
fn offered_first(
    robot: &Robot,
    measure: Measure,
    with_base: bool,
    first: impl Fn(&Param) -> bool,
) -> Vec<Param> {
    let all: Vec<Param> = robot
        .params()
        .into_iter()
        .filter(|p| with_base || !matches!(p, Param::Base(_)))
        .collect();
    let head = all.iter().copied().filter(|p| first(p));
    let candidates: Vec<Param> = head
        .chain(all.iter().copied().filter(|p| !first(p)))
        .collect();
    let mut params = identifiable_generic(robot, &candidates, measure);
    params.sort_by_key(|p| p.index(robot.dof()));
    params
}

impl Study {
    /// Prepares `scenario`: loads the robot, picks the parameters, builds the tracker and the
    /// compliance model, and optimises the fixed pose sets.
    pub fn new(scenario: Scenario) -> Result<Study> {
        let nominal = scenario.robot()?;
        let measure = scenario.tracker.measure.measure();
        let with_base = scenario.registration == Registration::Identify;
        let params = identified_params(&nominal, measure, with_base);
        let error_params = match (&scenario.errors.kind, &scenario.errors.params) {
            (ErrorKind::None, _) => Vec::new(),
            (_, ParamSelection::Identifiable) => params
                .iter()
                .copied()
                .filter(|p| !matches!(p, Param::Base(_)))
                .collect(),
            (_, sel) => selected_params(&nominal, sel, measure)?,
        };
        let tracker = Tracker::new(&scenario.tracker)?;
        let compliance = Compliance::new(&scenario.compliance, &nominal, scenario.builtin())?;

        let mut fixed = Vec::new();
        for (i, s) in scenario.calibration.strategies.iter().enumerate() {
            let c = &scenario.calibration;
            let set = match s {
                PoseStrategy::Random | PoseStrategy::Box => None,
                PoseStrategy::File(path) => {
                    let poses = read_pose_list(path, &nominal)?;
                    Some(FixedSet {
                        poses,
                        trace: Vec::new(),
                        scores: None,
                        crb_trace: None,
                    })
                }
                PoseStrategy::Grid => {
                    let dof = nominal.dof() as f64;
                    let per_joint = ((c.count as f64).powf(1.0 / dof).ceil() as usize).max(2);
                    let mut g = rng::stream(scenario.seed, "grid");
                    let mut poses =
                        sample_region(&nominal, &Region::Grid { per_joint }, c.count, &mut g)?;
                    poses.truncate(c.count);
                    Some(FixedSet {
                        poses,
                        trace: Vec::new(),
                        scores: None,
                        crb_trace: None,
                    })
                }
                PoseStrategy::Optimised(strategy) => {
                    let mut g = rng::stream(scenario.seed, &format!("optimise/{i}"));
                    let pool = sample_region(&nominal, &c.region, c.candidates, &mut g)?;
                    let opt_params = if c.separate {
                        poses::separate(&nominal, &params, &pool, measure, c.separate_threshold)
                            .kept
                    } else {
                        params.clone()
                    };
                    let model = RobotPoseModel::new(&nominal, &opt_params, measure);
                    let mut opts = SelectOptions::new(c.count);
                    opts.objective = c.objective;
                    let sel = poses::select(&model, &pool, *strategy, &opts, &mut g)?;
                    Some(FixedSet {
                        poses: sel.poses,
                        trace: sel.trace,
                        scores: serde_json::to_value(sel.scores).ok(),
                        crb_trace: None,
                    })
                }
            };
            fixed.push(set);
        }
        let mut study = Study {
            scenario,
            nominal,
            measure,
            params,
            error_params,
            tracker,
            compliance,
            fixed,
        };
        let traces: Vec<Option<Real>> = study
            .fixed
            .iter()
            .map(|f| f.as_ref().and_then(|f| crb_trace(&study, &f.poses)))
            .collect();
        for (f, t) in study.fixed.iter_mut().zip(traces) {
            if let Some(f) = f {
                f.crb_trace = t;
            }
        }
        Ok(study)
    }
}

/// The Cramér–Rao trace `tr (JᵀWJ)⁻¹` for the tracker noise at the calibration poses (in the
/// base frame, with the nominal Jacobian), or `None` without noise.
pub fn crb_trace(study: &Study, qs: &[Vec<Real>]) -> Option<Real> {
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

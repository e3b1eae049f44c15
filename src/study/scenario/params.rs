//! What a scenario identifies, and whether its calibration sets can determine it.

use crate::error::{Error, Result};
use crate::robot::param_sets::{full_params, identified_params};
use crate::robot::{Param, Robot};
use crate::sim::poses::read_calibration_poses;
use crate::sim::settings::{ErrorKind, ParamSelection};
use crate::sim::truth::selected_params;

use super::{PoseStrategy, Registration, Scenario};

impl Scenario {
    /// The kinematic parameters the scenario identifies on `robot` (`identification.params`):
    /// [`identified_params`], [`full_params`] or the listed names in flat-vector order, with
    /// the base frame's six when the registration is identified with the robot.
    pub fn kinematic_params(&self, robot: &Robot) -> Vec<Param> {
        let measure = self.tracker.measure.measure();
        let with_base = self.registration == Registration::Identify;
        let mut params = match &self.identification.params {
            ParamSelection::Identifiable => return identified_params(robot, measure, with_base),
            ParamSelection::All => full_params(robot, measure, with_base),
            ParamSelection::List(names) => names.iter().filter_map(|n| Param::parse(n)).collect(),
        };
        params.sort_by_key(|p| p.index(robot.dof()));
        params
    }

    /// The parameters each trial draws an error for on `robot` (`errors`): none for
    /// `kind = "none"`, the identified ones but the base's for the default selection, else the
    /// selected ones.
    pub fn error_params(&self, robot: &Robot) -> Result<Vec<Param>> {
        let measure = self.tracker.measure.measure();
        let with_base = self.registration == Registration::Identify;
        Ok(match (&self.errors.kind, self.errors.selection()) {
            (ErrorKind::None, _) => Vec::new(),
            (_, ParamSelection::Identifiable) => identified_params(robot, measure, with_base)
                .into_iter()
                .filter(|p| !matches!(p, Param::Base(_)))
                .collect(),
            (_, sel) => selected_params(robot, &sel, measure, self.errors.key())?,
        })
    }

    /// Refuses calibration sets that give fewer readings than the scenario identifies
    /// parameters on `robot` (the kinematic ones and `identification.compliance`): every
    /// trial's identification would end rank-deficient before its first iteration, as
    /// `identify` refuses such data. The key is `calibration.count`, or
    /// `calibration.poses_file` for a pose list of too few rows, of fewer than three distinct
    /// poses ([`read_calibration_poses`]), or whose joint values look like radians for a robot
    /// in degrees ([`crate::calibrate::verdict::radians_hint`], as `identify` names that cause).
    pub(super) fn check_readings(&self, robot: &Robot) -> Result<()> {
        let compliance = self.identification.compliance.params(robot, "")?;
        let params = self.kinematic_params(robot).len() + compliance.len();
        let c = &self.calibration;
        let loads = c.payloads_kg.as_ref().map_or(1, Vec::len);
        let per_pose = loads * self.tracker.measure.measure().rows();
        for s in &c.strategies {
            let (key, poses) = match s {
                PoseStrategy::File(path) => {
                    let qs = read_calibration_poses(path, robot)?;
                    if let Some(why) = crate::calibrate::verdict::radians_hint(robot, &qs) {
                        let msg = format!("{}: {why}", path.display());
                        return Err(Error::setting("calibration.poses_file", msg));
                    }
                    ("calibration.poses_file", qs.len())
                }
                _ => ("calibration.count", c.count),
            };
            let readings = poses * per_pose;
            if readings < params {
                let under = match loads {
                    1 => String::new(),
                    n => format!(" under {n} payloads"),
                };
                let msg = format!(
                    "{poses} poses{under} give {readings} readings for the {params} parameters \
                     identified: at least {} poses are needed",
                    params.div_ceil(per_pose)
                );
                return Err(Error::setting(key, msg));
            }
        }
        Ok(())
    }

    /// The run's warnings, one line each: what the scenario sets that it does not read, a
    /// robot too small for its length unit (its joints adding up to less than
    /// 10 mm, `SMALL_ARM_MM`), and a robot in degrees whose limits look written in radians.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = self.unused_settings();
        if let Ok(robot) = self.robot() {
            out.extend(small_robot(&robot));
            out.extend(radian_limits(&robot));
        }
        out.extend(self.large_angle_errors());
        out
    }

    /// Angle errors drawn beyond what a calibration moves (`errors.angle_rad` above the 5° of
    /// "Physical plausibility", [`crate::calibrate::plausibility::ANGLE_RAD`]): degrees
    /// written for radians, a study whose η judges no calibration. A warning: a study of such
    /// errors runs.
    fn large_angle_errors(&self) -> Option<String> {
        use crate::calibrate::plausibility::ANGLE_RAD;
        let e = &self.errors;
        let drawn = !matches!(e.kind, ErrorKind::None | ErrorKind::Values);
        (drawn && e.angle_rad > ANGLE_RAD).then(|| {
            format!(
                "errors.angle_rad = {} rad ({:.1}°) draws angle errors beyond the {:.0}° a \
                 calibration moves: is it in degrees? (radians are meant)",
                crate::error::shown(e.angle_rad),
                e.angle_rad.to_degrees(),
                ANGLE_RAD.to_degrees()
            )
        })
    }

    /// What the scenario sets that it does not read: in `[calibration]`, a pose list
    /// `poses_file` without the strategy `file` and the optimisers' settings without an
    /// optimised strategy; in `[errors]`, the sizes `length_mm` and `angle_rad` with
    /// `kind = "none"` or `"values"`, and `params` with `kind = "none"`. Such a key is allowed
    /// (a scenario may keep it for another run), but a run that ignores it says so; a sweep of
    /// the key that decides (`calibration.strategies`, `errors.kind`) may read it at some of
    /// its points, and is not warned of.
    fn unused_settings(&self) -> Vec<String> {
        let swept = |key: &str| {
            let mut axes = self.sweep.iter().flat_map(|s| &s.axes);
            axes.any(|a| a.key == key)
        };
        let mut out = Vec::new();
        if !swept("calibration.strategies") {
            out.extend(self.unused_calibration());
        }
        if !swept("errors.kind") {
            out.extend(self.unused_errors());
        }
        out
    }

    /// The `[errors]` keys of [`Self::unused_settings`].
    fn unused_errors(&self) -> Vec<String> {
        let Some(toml::Value::Table(e)) = self.table.get("errors") else {
            return Vec::new();
        };
        let kind = self.errors.kind;
        let unused: &[&str] = match kind {
            ErrorKind::None => &["length_mm", "angle_rad", "params"],
            ErrorKind::Values => &["length_mm", "angle_rad"],
            _ => &[],
        };
        unused
            .iter()
            .filter(|k| e.contains_key(**k))
            .map(|k| {
                format!(
                    "errors.{k} is not used: errors.kind is \"{}\"",
                    kind.as_str()
                )
            })
            .collect()
    }

    /// The `[calibration]` keys of [`Self::unused_settings`].
    fn unused_calibration(&self) -> Vec<String> {
        let Some(toml::Value::Table(c)) = self.table.get("calibration") else {
            return Vec::new();
        };
        let strategies = &self.calibration.strategies;
        let file = strategies
            .iter()
            .any(|s| matches!(s, PoseStrategy::File(_)));
        let optimised = strategies.iter().any(|s| {
            matches!(
                s,
                PoseStrategy::Optimised(_) | PoseStrategy::OptimisedFull(_)
            )
        });
        let mut unused = Vec::new();
        if !file && c.contains_key("poses_file") {
            unused.push(("poses_file", "\"file\""));
        }
        let optimiser_keys = [
            "candidates",
            "objective",
            "separate",
            "separate_threshold",
            "optimise",
        ];
        if !optimised {
            let optimisers = "an optimised one (detmax, ide, …)";
            unused.extend(
                optimiser_keys
                    .iter()
                    .filter(|k| c.contains_key(**k))
                    .map(|k| (*k, optimisers)),
            );
        }
        unused
            .into_iter()
            .map(|(key, needs)| {
                format!(
                    "calibration.{key} is not used: no strategy of calibration.strategies is \
                     {needs}"
                )
            })
            .collect()
    }
}

/// Why the joint limits of a robot in degrees look written in radians, or `None`: every
/// revolute joint's limits within ±2π (written rounded up, as 6.2832: 1 % is allowed; a
/// robot's lower limit is below its upper, so they are not all 0). Poses drawn within them
/// barely move the arm: a study of such a robot runs, so this is a warning.
fn radian_limits(robot: &Robot) -> Option<String> {
    use crate::robot::AngleUnit;
    let bound = 1.01 * std::f64::consts::TAU;
    let revolute: Vec<_> = (0..robot.dof()).filter(|&j| robot.q_turns(j)).collect();
    let small = |j: &usize| {
        let (lo, hi) = robot.joints[*j].limits;
        lo.to_degrees().abs() <= bound && hi.to_degrees().abs() <= bound
    };
    (robot.units.angle == AngleUnit::Deg && !revolute.is_empty() && revolute.iter().all(small))
        .then(|| {
            format!(
                "robot \"{}\": every revolute joint's limits lie within ±{bound:.2}° (2π and \
                 1 %): are they written in radians? Its angle_unit is \"deg\", and poses drawn \
                 within them barely move the arm",
                robot.name
            )
        })
}

/// Below this, the lengths, offsets and travels of a robot's joints (mm, its tool's not
/// counted) are taken for a robot file written in metres and declared in millimetres: the
/// smallest arm a calibration of the papers' kind concerns reaches hundreds of millimetres.
const SMALL_ARM_MM: crate::numeric::Real = 10.0;

/// Why `robot` looks too small for its length unit, or `None`: its joints' lengths, offsets
/// and travels add up to less than [`SMALL_ARM_MM`], where a robot in metres written as if in
/// millimetres lands (a UR10's add up to 1.7 mm so). A warning, not a refusal: a study of so
/// small an arm runs, but its injected errors (0.5 mm by default) are then a share of it.
fn small_robot(robot: &Robot) -> Option<String> {
    use crate::robot::sampling::reach_bound_mm;
    let tool = robot.tool().pos.norm();
    let arm = reach_bound_mm(robot) - tool;
    (arm < SMALL_ARM_MM).then(|| {
        format!(
            "robot \"{}\": its joints' lengths, offsets and travels add up to {arm:.3} mm (its \
             tool's {tool:.1} mm not counted): are its lengths in its length_unit (\"{}\")? A \
             robot file in m declared in mm is 1000 times too small",
            robot.name,
            robot.units.length_name()
        )
    })
}

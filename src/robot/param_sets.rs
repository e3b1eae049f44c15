//! Parameter sets: which parameters an identification estimates (the identifiable ones, the
//! full model, Guo 2024's separated model, or a list), shared by `run` and `identify`.

use crate::measurement::Measure;
use crate::robot::identifiability::{identifiable_extension, identifiable_generic};
use crate::robot::{Param, Robot};

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
    // The pivoting takes the largest remaining column first, so the order decides only ties:
    // on a tilted base θ1's column is a combination of the three base rotations, and it could
    // be taken where base.rz is left out. A parameter offered first and left out replaces the
    // first other one it can stand for (the rank of the set unchanged).
    let left_out: Vec<Param> = candidates
        .iter()
        .copied()
        .filter(|p| first(p) && !params.contains(p))
        .collect();
    for f in left_out {
        if identifiable_extension(robot, &[], &[f], measure).is_empty() {
            continue; // no effect at all (a tool rotation on position data)
        }
        let stand_in = (0..params.len())
            .filter(|&i| !first(&params[i]))
            .find(|&i| {
                let others: Vec<Param> = (0..params.len())
                    .filter(|&k| k != i)
                    .map(|k| params[k])
                    .collect();
                !identifiable_extension(robot, &others, &[f], measure).is_empty()
            });
        if let Some(i) = stand_in {
            params[i] = f;
        }
    }
    params.sort_by_key(|p| p.index(robot.dof()));
    params
}

/// The base and tool parameters among `params`.
pub(crate) fn ends(params: &[Param]) -> impl Iterator<Item = Param> + '_ {
    params.iter().copied().filter(|p| p.joint().is_none())
}

/// The full model (`identification.params = "all"`): every joint parameter of the robot's
/// model ([`Robot::joint_params`], Guo 2024's 21 of eq. 7 for its 3T2R arm), identifiable or
/// not, with the tool parameters that act on the measured quantity (x, y, z for position
/// data, all six for full-pose data) and, when the registration is identified, the six base
/// parameters, in flat-vector order.
pub fn full_params(robot: &Robot, measure: Measure, with_base: bool) -> Vec<Param> {
    let mut v = robot.joint_params();
    // The tool components that move the measured quantity: the point for position data,
    // the whole frame for full-pose data; the base when the registration is identified.
    let tool = if measure == Measure::Pose { 6 } else { 3 };
    v.extend((0..tool).map(Param::Tool));
    if with_base {
        v.extend((0..6).map(Param::Base));
    }
    v.sort_by_key(|p| p.index(robot.dof()));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The base offered first keeps all six base parameters whatever the base's tilt: on a
    /// level base θ1 and base.rz tie, on a tilted one θ1's column is a combination of the three
    /// base rotations and the larger of the two was taken (θ1), so a study injected and judged
    /// an error that only the registration could tell apart.
    #[test]
    fn the_base_offered_first_is_kept_on_a_tilted_base() {
        for measure in [Measure::Position, Measure::Pose] {
            let mut robot = crate::robot::builtin::irb2600();
            let level = identified_params(&robot, measure, true);
            for (k, v) in [(3, 0.035), (4, -0.052), (5, 0.52)] {
                robot.set(Param::Base(k), v);
            }
            let tilted = identified_params(&robot, measure, true);
            assert_eq!(tilted, level, "{measure:?}");
            assert!(
                (0..6).all(|k| tilted.contains(&Param::Base(k))),
                "{tilted:?}"
            );
            assert!(!tilted.contains(&Param::Theta(0)), "{tilted:?}");
        }
    }
}

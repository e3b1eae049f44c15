//! The mass-free gravity basis: a joint's deflection under gravity written without masses.
//! Joint `j` turns by `Δq_j = Σ_l k_jl τ_jl(q)`, `τ_jl` the torque about joint `j`'s axis of
//! a weight of 1 N (straight down, −z of the world frame) at one of three points of the arm —
//! the elbow, the wrist centre and the tool point — and the coefficients `k_jl`
//! ([`Param::Gravity`], rad per N·m) free. A link's weight at a fixed place on it loads the
//! joints before it linearly in that place, so three points along the arm span the sag of
//! links whose masses sit near them, with no mass, centre of mass or stiffness given
//! (docs/formats.md "Gravity basis").
//!
//! **Points.** On a robot of `n` ≥ 4 joints the elbow is the origin of joint `n − 3`'s axis
//! frame (1-based; joint 3 of a six-axis arm, joint 4 of a seven-axis one), the wrist centre
//! that of joint `n` − 1 (joint 5, joint 6), from the chain of the robot whose offsets are
//! applied ([`crate::robot::Chain::walk_vars`]) at the commanded joint values; the tool point
//! is the tool frame's origin. A weight loads only the joints before its point: `k_jl` exists
//! for joint `j` before the elbow (l = 0), before the wrist centre (l = 1) and every joint
//! (l = 2); only revolute joints.

use crate::numeric::{Real, Vec3};
use crate::robot::compliance::masses_with;
use crate::robot::harmonics::check_terms;
use crate::robot::param::add_block_offsets;
use crate::robot::{Chain, ChainVars, JointType, Param, Robot, GRAVITY_POINTS, MAX_JOINTS};

/// Largest magnitude of a gravity-basis coefficient, rad per N·m of a 1 N weight's torque: a
/// deflection of 0.1 rad from a lever of 0.1 m. A weight close to a joint's axis exerts a small
/// torque about it at every pose, so its coefficient can be large while the deflection it gives
/// stays small (the Barrett WAM task's identified `ge3` is −0.21); still far beyond any arm's
/// sag, and small enough to stay a correction. A robot file has no poses; at identification the
/// coefficients are bounded by the deflection they give at the calibration poses instead
/// ([`crate::calibrate::plausibility::gravity_deflections`]).
pub const MAX_GRAVITY_RAD_PER_NM: Real = 1.0;

/// The torques of the basis at one pose: `τ[j][l]`, N·m.
pub type Torques = [[Real; GRAVITY_POINTS]; MAX_JOINTS];

/// The 0-based joints whose axis-frame origins are the elbow and the wrist centre of a robot
/// of `dof` joints; `None` below four joints.
pub fn points(dof: usize) -> Option<[usize; 2]> {
    (dof >= 4).then(|| [dof - 4, dof - 2])
}

/// The gravity-basis parameters of `robot`: every `(j, l)` whose weight loads joint `j`,
/// revolute joints only; empty below four joints.
pub fn params(robot: &Robot) -> Vec<Param> {
    let Some([elbow, wrist]) = points(robot.dof()) else {
        return Vec::new();
    };
    (0..robot.dof())
        .filter(|&j| robot.joints[j].kind == JointType::Revolute)
        .flat_map(|j| {
            [(j < elbow, 0), (j < wrist, 1), (true, 2)]
                .into_iter()
                .filter(|(on, _)| *on)
                .map(move |(_, l)| Param::Gravity(j, l))
        })
        .collect()
}

/// Whether any gravity-basis coefficient of `robot` is non-zero. A robot whose values do
/// not hold the block (one being built) has none.
pub fn has_gravity(robot: &Robot) -> bool {
    robot.any_term(GRAVITY_POINTS, Param::Gravity)
}

/// The basis torques at the chain variables `vars` of `chain` (a robot of at least four
/// joints; zero rows otherwise), into `tau`: `τ_jl = z_j · ((p_l − o_j) × (0, 0, −1 N))`,
/// N·m, zero where the weight does not load the joint or the joint is prismatic.
/// Allocation-free.
pub fn torques(robot: &Robot, chain: &Chain, vars: &ChainVars, tau: &mut Torques) {
    let n = robot.dof();
    for t in tau.iter_mut() {
        *t = [0.0; GRAVITY_POINTS];
    }
    let Some([elbow, wrist]) = points(n) else {
        return;
    };
    let m = masses_with(chain, |visit| chain.walk_vars(vars, visit));
    let at = [m.axes[elbow].pos, m.axes[wrist].pos, m.tool.pos];
    let down = Vec3::new(0.0, 0.0, -1.0);
    for (j, t) in tau.iter_mut().enumerate().take(n) {
        if robot.joints[j].kind != JointType::Revolute {
            continue;
        }
        let z = m.axes[j].rot.column(2).into_owned();
        let o = m.axes[j].pos;
        for (l, p) in at.iter().enumerate() {
            if l == 0 && j >= elbow || l == 1 && j >= wrist {
                continue;
            }
            t[l] = z.dot(&(p - o).cross(&down)) * 1e-3; // N·mm → N·m
        }
    }
}

/// Adds to `dv[j]` the gravity-basis offset `Σ_l k_jl τ_jl` of joint `j`, from the flat
/// parameter `values` of a robot with `dv.len()` joints and the torques `tau`.
/// Allocation-free.
#[inline]
pub fn add_offsets(values: &[Real], tau: &Torques, dv: &mut [Real]) {
    add_block_offsets(values, dv, (GRAVITY_POINTS, Param::Gravity), |j, k| {
        k.iter().zip(&tau[j]).map(|(a, b)| a * b).sum::<Real>()
    });
}

/// Checks the gravity-basis coefficients of `robot` ([`Robot::check`]): each finite and
/// within ±[`MAX_GRAVITY_RAD_PER_NM`], only on revolute joints of a robot of at least four
/// joints, and only where its weight loads the joint.
pub(crate) fn check(robot: &Robot) -> std::result::Result<(), super::ModelIssue> {
    let allowed = params(robot);
    let terms = (GRAVITY_POINTS, Param::Gravity as fn(usize, usize) -> Param);
    let bound = ("gravity", MAX_GRAVITY_RAD_PER_NM, "rad/(N·m)");
    check_terms(robot, terms, bound, |_, p| {
        (!allowed.contains(&p)).then(|| {
            format!(
                "`{p}`: the weight at that point does not load this joint (a revolute joint \
                 before the point, on a robot of at least four joints)"
            )
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The basis torque of a point is the torque its weight of 1 N exerts, computed from the
    /// joint frames of [`Chain::joint_frames`] and the tool point independently.
    #[test]
    fn torques_are_those_of_a_unit_weight() {
        let robot = crate::robot::builtin::load("irb2600").unwrap();
        let chain = robot.chain();
        let q = [0.3, -0.4, 0.5, 0.2, -0.7, 0.9];
        let mut tau = [[0.0; GRAVITY_POINTS]; MAX_JOINTS];
        torques(&robot, &chain, &chain.variables(&q), &mut tau);
        let frames = chain.joint_frames(&q);
        let tool = chain.fk(&q).pos;
        let pts = [frames[2].pos, frames[4].pos, tool];
        for j in 0..6 {
            for (l, p) in pts.iter().enumerate() {
                let r = (p - frames[j].pos) * 1e-3;
                let f = Vec3::new(0.0, 0.0, -1.0);
                let want = if (l == 0 && j >= 2) || (l == 1 && j >= 4) {
                    0.0
                } else {
                    frames[j].rot.column(2).dot(&r.cross(&f))
                };
                assert!((tau[j][l] - want).abs() < 1e-12, "{j} {l}");
            }
        }
        // Joint 1's axis is vertical: no weight loads it.
        assert!(tau[0].iter().all(|t| t.abs() < 1e-12));
        assert!(tau[1][2].abs() > 0.1, "{:?}", tau[1]);
        let names: Vec<String> = params(&robot).iter().map(|p| p.to_string()).collect();
        assert_eq!(&names[..3], ["ge1", "gw1", "gt1"]);
        assert!(names.contains(&"gt6".to_string()) && !names.contains(&"ge3".to_string()));
        assert!(!names.contains(&"gw5".to_string()));
    }
}

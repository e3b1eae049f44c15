//! Drawing joint configurations: uniformly within the joint limits, or with the tool point
//! in a box of the workspace.

use rand::Rng as _;

use crate::numeric::rng::Rng;
use crate::numeric::{Real, Vec3};
use crate::robot::{Coupling, JointType, Param, Robot};

/// An upper bound of the distance (mm) from the origin of the base frame to the tool point
/// over every joint configuration: the sum of the lengths of the chain's translations — each
/// joint's `a` and `d`, the reach of its travel when it slides (prismatic or screw-coupled),
/// and the tool's offset. Rotations do not change lengths, so no tool point lies farther.
pub fn reach_bound_mm(robot: &Robot) -> Real {
    let travel = |j: usize| {
        let (lo, hi) = robot.joints[j].limits;
        lo.abs().max(hi.abs())
    };
    let coupled = matches!(robot.coupling, Some(Coupling::Differential { .. }));
    let mut r = 0.0;
    for (j, joint) in robot.joints.iter().enumerate() {
        r += robot.get(Param::A(j)).abs() + robot.get(Param::D(j)).abs();
        if joint.kind == JointType::Prismatic || (coupled && j < 2) {
            r += travel(j);
        }
    }
    if coupled && robot.dof() >= 2 {
        // The screw travels combine into the prismatic joint's: count both.
        r += travel(0).max(travel(1));
    }
    let tool = Vec3::new(
        robot.get(Param::Tool(0)),
        robot.get(Param::Tool(1)),
        robot.get(Param::Tool(2)),
    );
    r + tool.norm()
}

/// One joint vector drawn uniformly within the joint limits into `q` (internal units): one
/// uniform draw per joint, in joint order. Every uniform joint draw of calbench is this one.
pub fn uniform_joint_pose(robot: &Robot, rng: &mut Rng, q: &mut [Real]) {
    for (v, j) in q.iter_mut().zip(&robot.joints) {
        *v = j.limits.0 + (j.limits.1 - j.limits.0) * rng.random::<Real>();
    }
}

/// `n` joint vectors drawn uniformly within the joint limits (internal units).
pub fn uniform_joint_poses(robot: &Robot, n: usize, rng: &mut Rng) -> Vec<Vec<Real>> {
    (0..n)
        .map(|_| {
            let mut q = vec![0.0; robot.dof()];
            uniform_joint_pose(robot, rng, &mut q);
            q
        })
        .collect()
}

/// Joint vectors whose tool point (forward kinematics of `robot`) lies in the axis-aligned
/// box centred at `centre_mm` with edges `size_mm`, by rejection sampling: uniform joint
/// vectors ([`uniform_joint_pose`]) are drawn until `n` fall in the box or `max_tries` have
/// been drawn, or `give_up` have been drawn without one in the box. Returns those found, in
/// the order drawn: fewer than `n` when the box is (nearly) out of reach, which the caller
/// reports.
pub fn poses_in_box(
    robot: &Robot,
    n: usize,
    centre_mm: [Real; 3],
    size_mm: [Real; 3],
    (max_tries, give_up): (usize, usize),
    rng: &mut Rng,
) -> Vec<Vec<Real>> {
    let chain = robot.chain();
    let mut out = Vec::with_capacity(n);
    let mut q = vec![0.0; robot.dof()];
    let mut tries = 0;
    while out.len() < n && tries < max_tries {
        if tries == give_up && out.is_empty() {
            break; // hopeless: not one pose so far
        }
        tries += 1;
        uniform_joint_pose(robot, rng, &mut q);
        let p = chain.fk(&q).pos;
        if (0..3).all(|k| (p[k] - centre_mm[k]).abs() <= size_mm[k] / 2.0) {
            out.push(q.clone());
        }
    }
    out
}

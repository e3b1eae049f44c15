//! The only file that talks to rapier: a serial arm of torsional joint springs settled to static
//! equilibrium under gravity.
//!
//! The arm is a rapier multibody (`rapier3d-f64`, so that poses keep sub-nanometre resolution at
//! metre scale): a fixed root at the world origin, one dynamic body per spring joint, each joined
//! to its parent by a revolute multibody joint whose coordinate 0 is the commanded pose, so that
//! the settled coordinate is the deflection. The stiffness is rapier's passive implicit joint
//! spring (`−k·Δq`, integrated by backward Euler), which lets large time steps converge in a few
//! steps. Sleeping is off on every body (a sleeping body would freeze before equilibrium).
//!
//! Speed: each worker thread builds its world once ([`Arm`], kept in a thread-local) and reuses
//! it for every pose; a settle resets every piece of state a step reads and starts from the
//! caller's guess (the small-deflection estimate), so it gives the same bits whatever the
//! thread ran before, and two steps usually suffice. The step count is decided by the inputs
//! only, so the result is deterministic.
//!
//! Units here: the caller passes frames in mm and masses in kg; rapier works in metres, kg and
//! seconds; gravity is 9.81 m/s² along −z of the world.
//!
//! Verified facts behind these choices: `notes/rapier-compliance.md` (implicit springs rather
//! than acceleration-based motors, which scale k by a pose-dependent inertia; impulse joints
//! were biased by millimetres).

use std::cell::RefCell;
use std::ops::Range;

use rapier3d_f64::math::{Matrix, Pose, Rotation, Vector};
use rapier3d_f64::prelude::{
    GenericJoint, GenericJointBuilder, JointAxesMask, MassProperties, MultibodyJoint,
    MultibodyJointHandle, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle,
};

use crate::error::{Error, Result};
use crate::numeric::{rot_y, Frame, Mat3, Real, Vec3};
use crate::robot::MAX_JOINTS;

pub use crate::robot::compliance::GRAVITY;

/// Time step of the settling simulation, s. The springs are implicit and gravity is explicit,
/// so a step far longer than the arm's natural periods (a few ms) damps the inertial transient
/// by a factor ~(ω·dt)⁻² (below 1e-6) per step; what is left is a fixed-point iteration on
/// `K Δq = τ_g(q + Δq)`, contracting by ~‖∂τ_g/∂q‖/k (about 1e-3 on the IRB2600) per step.
const DT: Real = 100.0;

/// Fewest steps: one to settle, one more to measure the change ([`Settled::last_step_change`]).
pub const MIN_STEPS: usize = 2;

/// Most steps (reached only by arms far softer than a robot's, or started far from rest).
pub const MAX_STEPS: usize = 16;

/// The settle stops once a step moved no joint by more than this (rad). The error left is
/// about the contraction factor times this. On the IRB2600, started from the small-deflection
/// estimate, [`MIN_STEPS`] steps suffice and the settled joints match the exact equilibrium to
/// 1e-15 rad (`compliance::tests::rapier_matches_exact_equilibrium_on_irb2600`).
pub const STEP_TOLERANCE: Real = 1e-10;

/// Angular inertia floor per body, kg·m². It only shapes the transient (it keeps the joint-space
/// mass matrix positive definite when a body's masses lie on its axis, or are zero); the static
/// equilibrium does not depend on it.
const INERTIA_FLOOR: Real = 1e-3;

/// Radius (m) of the small sphere each point mass is spread over for its own inertia.
const POINT_RADIUS: Real = 0.05;

/// Most spring bodies an [`Arm`] carries (one per joint: at most [`MAX_JOINTS`]).
pub const MAX_BODIES: usize = MAX_JOINTS;

/// One spring joint and the rigid body it carries.
#[derive(Clone, Debug, Default)]
pub struct SpringBody {
    /// The joint-axis frame in the world at the commanded pose (mm): local z is the axis, the
    /// origin lies on it.
    pub axis: Frame,
    /// Torsional stiffness, N·m/rad (> 0).
    pub stiffness: Real,
    /// The point masses this body carries between this joint and the next, as a range of the
    /// `masses` slice given to [`Arm::settle`] (world position at the commanded pose in mm,
    /// mass in kg).
    pub masses: Range<usize>,
}

/// The settled arm.
#[derive(Clone, Copy, Debug)]
pub struct Settled {
    /// The tool frame in the world after settling (mm).
    pub tool: Frame,
    /// The settled coordinate of every spring joint (rad): its deflection; the first `count`
    /// entries are used ([`Settled::deflection`]).
    pub deflections: [Real; MAX_BODIES],
    /// Number of spring joints.
    pub count: usize,
    /// The largest change of a joint coordinate over the last step (rad): a convergence check.
    pub last_step_change: Real,
    /// Number of steps taken ([`MIN_STEPS`] to [`MAX_STEPS`]).
    pub steps: usize,
}

impl Settled {
    /// The settled coordinate of every spring joint (rad), base first.
    pub fn deflection(&self) -> &[Real] {
        &self.deflections[..self.count]
    }
}

/// `Ry(−90°)`: turns a frame whose z is the joint axis into one whose x is (rapier's revolute
/// multibody joint turns about the joint frame's local x).
fn z_to_x() -> Mat3 {
    rot_y(-std::f64::consts::FRAC_PI_2)
}

fn to_pose(f: &Frame) -> Pose {
    let r = &f.rot;
    let m = Matrix::from_cols(
        Vector::new(r[(0, 0)], r[(1, 0)], r[(2, 0)]),
        Vector::new(r[(0, 1)], r[(1, 1)], r[(2, 1)]),
        Vector::new(r[(0, 2)], r[(1, 2)], r[(2, 2)]),
    );
    Pose::from_parts(
        Vector::new(f.pos.x, f.pos.y, f.pos.z) * 1e-3,
        Rotation::from_mat3(&m).normalize(),
    )
}

fn to_frame(p: &Pose) -> Frame {
    let m = Matrix::from_quat(p.rotation);
    let c = [m.x_axis, m.y_axis, m.z_axis];
    let rot = Mat3::from_fn(|i, j| c[j][i]);
    let t = p.translation * 1e3;
    Frame {
        rot,
        pos: Vec3::new(t.x, t.y, t.z),
    }
}

fn lost(what: &str) -> Error {
    Error::Compute(format!("rapier lost a {what}"))
}

/// A rapier world holding a serial arm of a fixed number of spring bodies, built once and
/// reused for every pose.
///
/// [`Arm::settle`] loads a pose into the world (body poses and masses, joint frames and
/// springs) and resets every piece of state that a step reads (joint coordinates, generalized
/// and body velocities), so a settle gives the same bits whatever the world settled before:
/// the result depends on the call's inputs only, not on which poses a worker thread happened
/// to run earlier (checked by `compliance::tests::reused_rapier_world_gives_the_same_bits`).
pub struct Arm {
    world: PhysicsWorld,
    /// Per spring body: its rigid body and the multibody joint to its parent.
    links: Vec<(RigidBodyHandle, MultibodyJointHandle)>,
}

impl Arm {
    /// A world with a fixed root and `n` (1 ≤ n ≤ [`MAX_BODIES`]) dynamic bodies chained by
    /// revolute multibody joints; the geometry, masses and springs are set per pose by
    /// [`Arm::settle`].
    pub fn new(n: usize) -> Result<Arm> {
        if n == 0 || n > MAX_BODIES {
            return Err(Error::Compute(format!(
                "a rapier arm needs 1 to {MAX_BODIES} spring bodies, got {n}"
            )));
        }
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -GRAVITY);
        world.integration_parameters.dt = DT;
        world.integration_parameters.num_solver_iterations = 1;
        // No colliders: nothing for continuous collision detection to do.
        world.integration_parameters.max_ccd_substeps = 0;
        world.physics_pipeline.counters.disable();
        let mut parent = world.insert_body(RigidBodyBuilder::fixed());
        let mut links = Vec::with_capacity(n);
        for _ in 0..n {
            let body = RigidBodyBuilder::dynamic()
                .additional_mass_properties(MassProperties::new(
                    Vector::ZERO,
                    1.0,
                    Vector::splat(INERTIA_FLOOR),
                ))
                .can_sleep(false);
            let h = world.insert_body(body);
            let jh = world
                .insert_multibody_joint(parent, h, joint_data(Pose::IDENTITY))
                .ok_or_else(|| Error::Compute("rapier refused a multibody joint".into()))?;
            links.push((h, jh));
            parent = h;
        }
        Ok(Arm { world, links })
    }

    /// Number of spring bodies.
    pub fn len(&self) -> usize {
        self.links.len()
    }

    /// Always false: an arm has at least one body.
    pub fn is_empty(&self) -> bool {
        self.links.is_empty()
    }

    /// Settles the arm `bodies` (base first, `bodies.len() == self.len()`; each body hangs on
    /// the previous one, the first on the fixed world) carrying the point `masses` under gravity
    /// −z, and returns the pose of `tool` (a world frame at the commanded pose, rigidly attached
    /// to the last body) once the last step moved no joint by more than [`STEP_TOLERANCE`]
    /// ([`MIN_STEPS`] to [`MAX_STEPS`] steps; the count depends on the inputs only).
    ///
    /// `start` gives the joint coordinates (rad) the settle starts from, one per body (or empty
    /// for zero): a good guess, such as the small-deflection estimate `K⁻¹ τ_g(q)`, lets the
    /// fixed step count converge further. The static equilibrium does not depend on it.
    pub fn settle(
        &mut self,
        bodies: &[SpringBody],
        masses: &[(Vec3, Real)],
        tool: &Frame,
        start: &[Real],
    ) -> Result<Settled> {
        let n = self.links.len();
        if bodies.len() != n || !(start.is_empty() || start.len() == n) {
            return Err(Error::Compute(format!(
                "a rapier arm of {n} bodies was given {} bodies and {} start values",
                bodies.len(),
                start.len()
            )));
        }
        let mut parent_pose = Pose::IDENTITY;
        let mut deflections = [0.0; MAX_BODIES];
        for (k, (b, &(h, jh))) in bodies.iter().zip(&self.links).enumerate() {
            let frame = Frame {
                rot: b.axis.rot * z_to_x(),
                pos: b.axis.pos,
            };
            let pose = to_pose(&frame);
            let mut mp = MassProperties::new(Vector::ZERO, 0.0, Vector::splat(INERTIA_FLOOR));
            for &(p, m) in &masses[b.masses.clone()] {
                if m > 0.0 {
                    let local = pose.inverse_transform_point(Vector::new(p.x, p.y, p.z) * 1e-3);
                    let i = 0.4 * m * POINT_RADIUS * POINT_RADIUS;
                    mp += MassProperties::new(local, m, Vector::splat(i));
                }
            }
            let body = self.world.bodies.get_mut(h).ok_or_else(|| lost("body"))?;
            body.set_additional_mass_properties(mp, false);
            body.set_position(pose, false);
            body.set_linvel(Vector::ZERO, false);
            body.set_angvel(Vector::ZERO, false);

            let (mb, id) = self
                .world
                .multibody_joints
                .get_mut(jh)
                .ok_or_else(|| lost("multibody joint"))?;
            let link = mb.link_mut(id).ok_or_else(|| lost("multibody link"))?;
            // A fresh joint: coordinate exactly 0 at the commanded pose, then the start value.
            link.joint = MultibodyJoint::new(joint_data(parent_pose.inverse() * pose), false);
            // Spatial axis 3 is the angular x axis: the free axis of the revolute joint.
            link.joint.set_spring(3, b.stiffness, 0.0);
            if let Some(&s) = start.get(k) {
                link.joint.apply_displacement(&[s]);
                deflections[k] = s;
            }
            mb.generalized_velocity_mut().fill(0.0);
            parent_pose = pose;
        }
        let tool_local = parent_pose.inverse() * to_pose(tool);

        let mut last_step_change = Real::INFINITY;
        let mut steps = 0;
        while steps < MAX_STEPS && (steps < MIN_STEPS || last_step_change > STEP_TOLERANCE) {
            self.world.step();
            steps += 1;
            last_step_change = 0.0;
            for (k, (_, jh)) in self.links.iter().enumerate() {
                let (mb, id) = self
                    .world
                    .multibody_joints
                    .get(*jh)
                    .ok_or_else(|| lost("multibody joint"))?;
                let c = mb.link(id).map(|l| l.joint.coords()[3]).unwrap_or(0.0);
                last_step_change = Real::max(last_step_change, (c - deflections[k]).abs());
                deflections[k] = c;
            }
        }
        let last = self.links[n - 1].0;
        let last = self.world.bodies.get(last).ok_or_else(|| lost("body"))?;
        let tool_pose = *last.position() * tool_local;
        Ok(Settled {
            tool: to_frame(&tool_pose),
            deflections,
            count: n,
            last_step_change,
            steps,
        })
    }
}

/// A revolute multibody joint about the joint frame's local x, its frame on the parent at
/// `frame1` and on the child at the child's origin.
fn joint_data(frame1: Pose) -> GenericJoint {
    GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
        .local_frame1(frame1)
        .local_frame2(Pose::IDENTITY)
        .build()
}

thread_local! {
    /// This thread's arm, rebuilt when the number of bodies changes.
    static ARM: RefCell<Option<Arm>> = const { RefCell::new(None) };
}

/// [`Arm::settle`] on this thread's arm, which is built on first use (or when the number of
/// bodies changes) and reused for every later pose. An empty `bodies` gives `tool` unchanged.
/// Errors only if rapier refuses a joint, or on inconsistent inputs.
///
/// Apart from a rebuild, nothing is allocated by this crate per call (rapier's step allocates
/// a few small work vectors of its own).
pub fn settle(
    bodies: &[SpringBody],
    masses: &[(Vec3, Real)],
    tool: &Frame,
    start: &[Real],
) -> Result<Settled> {
    if bodies.is_empty() {
        return Ok(Settled {
            tool: *tool,
            deflections: [0.0; MAX_BODIES],
            count: 0,
            last_step_change: 0.0,
            steps: 0,
        });
    }
    ARM.with(|cell| {
        let mut slot = cell.borrow_mut();
        if slot.as_ref().map(Arm::len) != Some(bodies.len()) {
            *slot = Some(Arm::new(bodies.len())?);
        }
        match slot.as_mut() {
            Some(arm) => arm.settle(bodies, masses, tool, start),
            None => Err(lost("arm")),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn pose_conversion_round_trips() {
        let f = Frame::from_xyz_rpy([120.0, -340.5, 987.25], [0.3, -1.1, 2.5]);
        let g = to_frame(&to_pose(&f));
        assert_relative_eq!(g.rot, f.rot, epsilon = 1e-14);
        assert_relative_eq!(g.pos, f.pos, epsilon = 1e-10);
    }

    /// A horizontal pendulum: point mass m at distance l from a horizontal axis, spring k.
    /// Equilibrium k·Δθ = m·g·l·cos(Δθ) (exact, solved by fixed point here).
    #[test]
    fn horizontal_pendulum_matches_exact_equilibrium() {
        let (m, l, k) = (20.0, 800.0, 5.0e4);
        // Axis along world +y, so positive rotation lowers a mass on +x.
        let axis = Frame {
            rot: crate::numeric::rot_x(-std::f64::consts::FRAC_PI_2),
            pos: Vec3::new(0.0, 0.0, 500.0),
        };
        let bodies = [SpringBody {
            axis,
            stiffness: k,
            masses: 0..1,
        }];
        let masses = [(Vec3::new(l, 0.0, 500.0), m)];
        let tool = Frame {
            rot: Mat3::identity(),
            pos: Vec3::new(l, 0.0, 500.0),
        };
        let s = settle(&bodies, &masses, &tool, &[]).unwrap();
        let mut th: Real = 0.0;
        for _ in 0..50 {
            th = m * GRAVITY * l * 1e-3 * th.cos() / k;
        }
        assert_relative_eq!(s.deflection()[0], th, epsilon = 1e-12);
        assert!(s.last_step_change < STEP_TOLERANCE);
        assert_relative_eq!(s.tool.pos.z, 500.0 - l * th.sin(), epsilon = 1e-8);
        assert_relative_eq!(s.tool.pos.x, l * th.cos(), epsilon = 1e-8);
    }

    #[test]
    fn inconsistent_inputs_are_errors() {
        assert!(Arm::new(0).is_err());
        assert!(Arm::new(MAX_BODIES + 1).is_err());
        let mut arm = Arm::new(2).unwrap();
        let b = SpringBody {
            axis: Frame::identity(),
            stiffness: 1e4,
            masses: 0..0,
        };
        let tool = Frame::identity();
        assert!(arm
            .settle(std::slice::from_ref(&b), &[], &tool, &[])
            .is_err());
        let two = [b.clone(), b];
        assert!(arm.settle(&two, &[], &tool, &[0.0]).is_err());
        let s = arm.settle(&two, &[], &tool, &[]).unwrap();
        assert_eq!(s.deflection(), &[0.0, 0.0]);
        assert_eq!(s.steps, MIN_STEPS);
    }
}

//! The only file that talks to rapier: a serial arm of torsional joint springs settled to static
//! equilibrium under gravity (SPEC §3 "Compliance").
//!
//! The arm is a rapier multibody (`rapier3d-f64`, so that poses keep sub-nanometre resolution at
//! metre scale): a fixed root at the world origin, one dynamic body per spring joint, each joined
//! to its parent by a revolute multibody joint whose coordinate 0 is the commanded pose, so that
//! the settled coordinate is the deflection. The stiffness is rapier's passive implicit joint
//! spring (`−k·Δq`, integrated by backward Euler), which lets large time steps converge in a few
//! steps. Sleeping is off on every body (a sleeping body would freeze before equilibrium) and
//! the step count is fixed, so the result is deterministic.
//!
//! Units here: the caller passes frames in mm and masses in kg; rapier works in metres, kg and
//! seconds; gravity is 9.81 m/s² along −z of the world.
//!
//! Verified facts behind these choices: `notes/rapier-compliance.md` (implicit springs rather
//! than acceleration-based motors, which scale k by a pose-dependent inertia; impulse joints
//! were biased by millimetres).

use rapier3d_f64::math::{Matrix, Pose, Rotation, Vector};
use rapier3d_f64::prelude::{
    GenericJointBuilder, JointAxesMask, MassProperties, PhysicsWorld, RigidBodyBuilder,
};

use crate::error::{Error, Result};
use crate::math::{rot_y, Frame, Mat3, Real, Vec3};

/// Standard gravity, m/s².
pub const GRAVITY: Real = 9.81;

/// Time step of the settling simulation, s. The springs are implicit, so a step far longer than
/// the arm's natural periods (a few ms) damps each mode by a factor ~(ω·dt)² per step.
const DT: Real = 0.5;

/// Fixed number of steps: enough for the last step to move no joint by more than 1e-12 rad on
/// the IRB2600 (checked in `compliance::tests::rapier_and_linear_agree_on_irb2600`).
pub const STEPS: usize = 12;

/// Angular inertia floor per body, kg·m². It only shapes the transient (it keeps the joint-space
/// mass matrix positive definite when a body's masses lie on its axis, or are zero); the static
/// equilibrium does not depend on it.
const INERTIA_FLOOR: Real = 1e-3;

/// Radius (m) of the small sphere each point mass is spread over for its own inertia.
const POINT_RADIUS: Real = 0.05;

/// One spring joint and the rigid body it carries.
#[derive(Clone, Debug)]
pub struct SpringBody {
    /// The joint-axis frame in the world at the commanded pose (mm): local z is the axis, the
    /// origin lies on it.
    pub axis: Frame,
    /// Torsional stiffness, N·m/rad (> 0).
    pub stiffness: Real,
    /// Point masses carried by this body between this joint and the next: world position at
    /// the commanded pose (mm) and mass (kg).
    pub masses: Vec<(Vec3, Real)>,
}

/// The settled arm.
#[derive(Clone, Debug)]
pub struct Settled {
    /// The tool frame in the world after settling (mm).
    pub tool: Frame,
    /// The settled coordinate of every spring joint (rad): its deflection.
    pub deflection: Vec<Real>,
    /// The largest change of a joint coordinate over the last step (rad): a convergence check.
    pub last_step_change: Real,
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

/// Settles the arm `bodies` (base first; each body hangs on the previous one, the first on the
/// fixed world) under gravity −z and returns the pose of `tool` (a world frame at the commanded
/// pose, rigidly attached to the last body) after [`STEPS`] steps.
///
/// An empty `bodies` gives `tool` unchanged. Errors only if rapier refuses a joint. Builds a
/// fresh rapier world per call (rapier allocates; the settle is deterministic for given inputs).
pub fn settle(bodies: &[SpringBody], tool: &Frame) -> Result<Settled> {
    if bodies.is_empty() {
        return Ok(Settled {
            tool: *tool,
            deflection: Vec::new(),
            last_step_change: 0.0,
        });
    }
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, 0.0, -GRAVITY);
    world.integration_parameters.dt = DT;
    world.integration_parameters.num_solver_iterations = 1;

    let root = world.insert_body(RigidBodyBuilder::fixed());
    let mut parent = root;
    let mut parent_pose = Pose::IDENTITY;
    let mut handles = Vec::with_capacity(bodies.len());
    let mut last_pose = Pose::IDENTITY;
    for b in bodies {
        let frame = Frame {
            rot: b.axis.rot * z_to_x(),
            pos: b.axis.pos,
        };
        let pose = to_pose(&frame);
        let mut mp = MassProperties::new(Vector::ZERO, 0.0, Vector::splat(INERTIA_FLOOR));
        for &(p, m) in &b.masses {
            if m > 0.0 {
                let local = pose.inverse_transform_point(Vector::new(p.x, p.y, p.z) * 1e-3);
                let i = 0.4 * m * POINT_RADIUS * POINT_RADIUS;
                mp += MassProperties::new(local, m, Vector::splat(i));
            }
        }
        let body = RigidBodyBuilder::dynamic()
            .pose(pose)
            .additional_mass_properties(mp)
            .can_sleep(false);
        let h = world.insert_body(body);
        let joint = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
            .local_frame1(parent_pose.inverse() * pose)
            .local_frame2(Pose::IDENTITY)
            .build();
        let jh = world
            .insert_multibody_joint(parent, h, joint)
            .ok_or_else(|| Error::Compute("rapier refused a multibody joint".into()))?;
        let (mb, id) = world
            .multibody_joints
            .get_mut(jh)
            .ok_or_else(|| Error::Compute("rapier lost a multibody joint".into()))?;
        let link = mb
            .link_mut(id)
            .ok_or_else(|| Error::Compute("rapier lost a multibody link".into()))?;
        // Spatial axis 3 is the angular x axis: the free axis of the revolute joint.
        link.joint.set_spring(3, b.stiffness, 0.0);
        handles.push(jh);
        parent = h;
        parent_pose = pose;
        last_pose = pose;
    }
    let tool_local = last_pose.inverse() * to_pose(tool);

    let n = handles.len();
    let mut prev = vec![0.0; n];
    let mut coords = vec![0.0; n];
    let mut last_step_change = 0.0;
    for _ in 0..STEPS {
        world.step();
        last_step_change = 0.0;
        for (k, jh) in handles.iter().enumerate() {
            let (mb, id) = world
                .multibody_joints
                .get(*jh)
                .ok_or_else(|| Error::Compute("rapier lost a multibody joint".into()))?;
            let c = mb.link(id).map(|l| l.joint.coords()[3]).unwrap_or(0.0);
            coords[k] = c;
            last_step_change = Real::max(last_step_change, (c - prev[k]).abs());
            prev[k] = c;
        }
    }
    let last = world
        .bodies
        .get(parent)
        .ok_or_else(|| Error::Compute("rapier lost a body".into()))?;
    let tool_pose = *last.position() * tool_local;
    Ok(Settled {
        tool: to_frame(&tool_pose),
        deflection: coords,
        last_step_change,
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
            rot: crate::math::rot_x(-std::f64::consts::FRAC_PI_2),
            pos: Vec3::new(0.0, 0.0, 500.0),
        };
        let bodies = [SpringBody {
            axis,
            stiffness: k,
            masses: vec![(Vec3::new(l, 0.0, 500.0), m)],
        }];
        let tool = Frame {
            rot: Mat3::identity(),
            pos: Vec3::new(l, 0.0, 500.0),
        };
        let s = settle(&bodies, &tool).unwrap();
        let mut th: Real = 0.0;
        for _ in 0..50 {
            th = m * GRAVITY * l * 1e-3 * th.cos() / k;
        }
        assert_relative_eq!(s.deflection[0], th, epsilon = 1e-12);
        assert!(s.last_step_change < 1e-12);
        assert_relative_eq!(s.tool.pos.z, 500.0 - l * th.sin(), epsilon = 1e-8);
        assert_relative_eq!(s.tool.pos.x, l * th.cos(), epsilon = 1e-8);
    }
}

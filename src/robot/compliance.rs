//! The compliance model that identification fits (the elasto-geometric model): joint `j`
//! deflects by `c_j τ_j(q, payload)`, with `τ_j` the gravity torque of the link masses and
//! the payload (docs/formats.md, "Elasto-geometric calibration").
//!
//! **Mass model.** Link `i` (the body moved by joint `i` up to joint `i+1`) is a point mass
//! `m_i` at the midpoint of the segment between consecutive joint-frame origins
//! ([`crate::robot::Chain::joint_frames`]: the origin of joint `i`'s axis frame and that of
//! joint `i+1`; for the last link, the last joint's origin and the tool point). The payload is a
//! point mass at the tool point. Gravity is [`GRAVITY`] along −z of the world frame (the frame
//! the base frame is given in). Only revolute joints are compliant. The simulated sag of the
//! true arm ([`crate::sim::sag`]) uses the same mass model.

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::numeric::{Frame, Real, Vec3};
use crate::robot::{Chain, JointType, Param, Robot, MAX_JOINTS};

/// Standard gravity, m/s².
pub const GRAVITY: Real = 9.81;

/// The range of a mass, which the measurement files check too (so it lives in the error
/// layer below them).
pub use crate::error::{is_mass, not_a_mass, MAX_MASS_KG};

/// Which joint compliances the identification estimates (docs/formats.md `[identification]
/// compliance`, `identify --compliance`): none (the default: a kinematic model), the joints
/// gravity loads, or a list of names `c1`…`cn`.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum CompliancePick {
    /// A purely kinematic model.
    #[default]
    None,
    /// Every revolute joint whose gravity torque varies over the workspace
    /// ([`gravity_loaded_joints`]).
    Gravity,
    /// The named compliances.
    List(Vec<String>),
}

impl<'de> Deserialize<'de> for CompliancePick {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            One(String),
            Many(Vec<String>),
        }
        let expected =
            "expected \"gravity\" or a list of compliance names such as [\"c2\", \"c3\"]";
        match Raw::deserialize(d).map_err(|_| serde::de::Error::custom(expected))? {
            Raw::One(s) if s == "gravity" => Ok(CompliancePick::Gravity),
            Raw::One(s) => Err(serde::de::Error::custom(format!("{expected}, got \"{s}\""))),
            Raw::Many(v) => Ok(CompliancePick::List(v)),
        }
    }
}

impl CompliancePick {
    /// Reads the command-line form: `gravity`, or names separated by commas (`c2,c3`).
    pub fn from_arg(arg: &str) -> CompliancePick {
        if arg.trim() == "gravity" {
            CompliancePick::Gravity
        } else {
            CompliancePick::List(
                arg.split(',')
                    .map(|s| s.trim().to_string())
                    .filter(|s| !s.is_empty())
                    .collect(),
            )
        }
    }

    /// The compliance parameters picked on `robot`, in joint order. Errors (key `key`) name
    /// a name that is not `c1`…`cn`, a joint that is not revolute, a name listed twice, and a
    /// robot without link masses.
    pub fn params(&self, robot: &Robot, key: &str) -> Result<Vec<Param>> {
        if *self != CompliancePick::None && robot.link_mass_kg.is_none() {
            return Err(Error::setting(
                key,
                format!(
                    "robot \"{}\" gives no link masses (`mass_kg` on every joint of the robot \
                     file), which the compliance model needs for its gravity torques",
                    robot.name
                ),
            ));
        }
        let joints = match self {
            CompliancePick::None => return Ok(Vec::new()),
            CompliancePick::Gravity => gravity_loaded_joints(robot)?,
            CompliancePick::List(names) => {
                let mut out: Vec<usize> = Vec::with_capacity(names.len());
                for n in names {
                    let j = match Param::parse(n) {
                        Some(Param::Compliance(j)) if j < robot.dof() => j,
                        _ => {
                            return Err(Error::setting(
                                key,
                                format!(
                                    "\"{n}\" is not a compliance of robot \"{}\" (c1…c{})",
                                    robot.name,
                                    robot.dof()
                                ),
                            ))
                        }
                    };
                    if robot.joints[j].kind != JointType::Revolute {
                        return Err(Error::setting(
                            key,
                            format!(
                                "\"{n}\": joint {} is prismatic; only revolute joints are \
                                 compliant in calbench's model",
                                j + 1
                            ),
                        ));
                    }
                    if out.contains(&j) {
                        return Err(Error::setting(key, format!("\"{n}\" is listed twice")));
                    }
                    out.push(j);
                }
                out.sort_unstable();
                out
            }
        };
        Ok(joints.into_iter().map(Param::Compliance).collect())
    }
}

/// The revolute joints that gravity loads: those whose gravity torque (link masses of the
/// robot, a 10 kg payload) exceeds 1e-6 of the largest joint torque somewhere among 64 generic
/// poses, and 1e-9 of the largest torque the masses could exert at all (their weight at twice
/// the reach, [`reach_bound_mm`]). A joint whose axis stays vertical (joint 1 of a
/// floor-mounted arm) carries no gravity torque, so its compliance cannot show in a static
/// measurement; on an arm whose every revolute axis stays vertical (a SCARA) the largest
/// torque is itself rounding (of the order of 1e-16 of the second bound), which the first
/// bound alone would compare rounding against.
///
/// [`reach_bound_mm`]: crate::robot::sampling::reach_bound_mm
pub fn gravity_loaded_joints(robot: &Robot) -> Result<Vec<usize>> {
    let n = robot.dof();
    let chain = robot.chain();
    let qs = crate::robot::sampling::uniform_joint_poses(
        robot,
        64,
        &mut crate::numeric::rng::stream(0, "gravity"),
    );
    let mut peak = [0.0 as Real; MAX_JOINTS];
    let mut tau = [0.0; MAX_JOINTS];
    for q in &qs {
        gravity_torques(robot, &chain, q, 10.0, &mut tau[..n])?;
        for (p, t) in peak.iter_mut().zip(&tau[..n]) {
            *p = p.max(t.abs());
        }
    }
    let top = peak.iter().copied().fold(0.0, Real::max);
    let weight: Real = robot.link_mass_kg.iter().flatten().sum::<Real>() + 10.0;
    let most = weight * GRAVITY * 2.0 * crate::robot::sampling::reach_bound_mm(robot) * 1e-3;
    Ok((0..n)
        .filter(|&j| {
            robot.joints[j].kind == JointType::Revolute
                && peak[j] > 1e-6 * top
                && peak[j] > 1e-9 * most
        })
        .collect())
}

/// The point masses of the arm at one pose: for each link, its mass point (world, mm) and mass
/// (kg), with the payload added to the last link as a separate point. Fixed size, no allocation.
pub(crate) struct Masses {
    /// Axis frames of the joints (world, mm).
    pub(crate) axes: [Frame; MAX_JOINTS],
    /// Link mass points (world, mm).
    pub(crate) points: [Vec3; MAX_JOINTS],
    /// The tool frame (world, mm).
    pub(crate) tool: Frame,
}

/// The arm's mass points at joint values `q`: the joint axis frames, the link midpoints and
/// the tool frame (world, mm). Fixed size, no allocation.
pub(crate) fn masses(chain: &Chain, q: &[Real]) -> Masses {
    masses_with(chain, |visit| chain.walk(q, visit))
}

/// [`masses`] from a chain walk `walk` that calls its visitor at every operation.
#[inline(always)]
pub(crate) fn masses_with(
    chain: &Chain,
    walk: impl FnOnce(&mut dyn FnMut(&crate::robot::Op, &crate::numeric::Mat3, &Vec3)) -> Frame,
) -> Masses {
    let n = chain.dof();
    let mut axes = [Frame::identity(); MAX_JOINTS];
    let tool = walk(&mut |op, r, p| {
        if let Some(v) = op.var {
            axes[v] = Frame { rot: *r, pos: *p };
        }
    });
    let mut points = [Vec3::zeros(); MAX_JOINTS];
    for i in 0..n {
        let next = if i + 1 < n { axes[i + 1].pos } else { tool.pos };
        points[i] = 0.5 * (axes[i].pos + next);
    }
    Masses { axes, points, tool }
}

/// Gravity torque (N·m) about each chain variable's axis at the mass points `m`, of the link
/// masses `link_mass` (kg) and a payload (kg) at the tool point; zero for prismatic joints.
/// `τ_j = z_jᵀ (Σ_{i ≥ j} (c_i − o_j) × m_i g + (p_tool − o_j) × m_payload g)`.
pub(crate) fn gravity_torques_at(
    robot: &Robot,
    link_mass: &[Real],
    payload: Real,
    m: &Masses,
    out: &mut [Real],
) {
    let n = robot.dof();
    let g = Vec3::new(0.0, 0.0, -GRAVITY);
    for (j, out_j) in out.iter_mut().enumerate().take(n) {
        *out_j = 0.0;
        if robot.joints[j].kind != JointType::Revolute {
            continue;
        }
        let z = m.axes[j].rot.column(2).into_owned();
        let o = m.axes[j].pos;
        let mut t = (m.tool.pos - o).cross(&(g * payload));
        for (c, &mass) in m.points[j..n].iter().zip(&link_mass[j..n]) {
            t += (c - o).cross(&(g * mass));
        }
        *out_j = z.dot(&t) * 1e-3; // N·mm → N·m
    }
}

/// The gravity torques `τ_j(q, payload)` (N·m) of `robot`'s own link masses
/// ([`Robot::link_mass_kg`]) and a payload of `payload_kg` at the tool point, about each chain
/// variable's axis at joint values `q` (internal units), into `out` (one per joint; zero for
/// prismatic joints): the regressors of the elasto-geometric model, in which joint `j`
/// deflects by `c_j τ_j` ([`Param::Compliance`]). The mass model is
/// that of the simulated sag (point masses at the link midpoints). Fails when the robot gives
/// no link masses. Allocation-free.
pub fn gravity_torques(
    robot: &Robot,
    chain: &Chain,
    q: &[Real],
    payload_kg: Real,
    out: &mut [Real],
) -> Result<()> {
    let Some(mass) = robot.link_mass_kg.as_deref() else {
        return Err(Error::setting(
            "mass_kg",
            format!(
                "robot \"{}\" gives no link masses: the compliance model needs `mass_kg` on \
                 every joint of the robot file",
                robot.name
            ),
        ));
    };
    if robot.dof() > MAX_JOINTS || mass.len() != robot.dof() || q.len() != robot.dof() {
        return Err(Error::Compute(format!(
            "gravity torques of a {}-joint robot: {} masses, {} joint values \
             (at most {MAX_JOINTS} joints)",
            robot.dof(),
            mass.len(),
            q.len()
        )));
    }
    if let Some(msg) = not_a_mass(payload_kg) {
        return Err(Error::setting("payload_kg", msg));
    }
    gravity_torques_at(robot, mass, payload_kg, &masses(chain, q), out);
    Ok(())
}

/// [`gravity_torques`] from a pose's chain variables ([`Chain::variables`]) with the link
/// masses `mass` (one per joint) and a checked payload: the identification's inner loop, which
/// recomputes the torques with the current parameter estimate. Allocation-free.
pub(crate) fn gravity_torques_vars(
    robot: &Robot,
    chain: &Chain,
    vars: &crate::robot::ChainVars,
    mass: &[Real],
    payload_kg: Real,
    out: &mut [Real],
) {
    gravity_torques_at(
        robot,
        mass,
        payload_kg,
        &masses_with(chain, |visit| chain.walk_vars(vars, visit)),
        out,
    );
}

/// Checks the payloads of `points` measured points (kg): one per point, each a mass
/// ([`is_mass`]).
/// Errors name the key `payload_kg` and the point.
pub fn check_payloads(loads: &[Real], points: usize) -> Result<()> {
    if loads.len() != points {
        return Err(Error::setting(
            "payload_kg",
            format!("{} payloads but {points} measured points", loads.len()),
        ));
    }
    match loads
        .iter()
        .enumerate()
        .find_map(|(i, w)| Some((i, not_a_mass(*w)?)))
    {
        Some((i, msg)) => Err(Error::setting("payload_kg", format!("point {i}: {msg}"))),
        None => Ok(()),
    }
}

/// Whether any joint compliance of `robot` is non-zero (its model then deflects under load).
pub fn is_compliant(robot: &Robot) -> bool {
    (0..robot.dof()).any(|j| robot.get(Param::Compliance(j)) != 0.0)
}

/// Adds `dv[j]` to chain variable `j` of `vars` and refreshes its sine and cosine.
pub(crate) fn deflect_vars(vars: &mut crate::robot::ChainVars, dv: &[Real]) {
    for (j, &d) in dv.iter().enumerate() {
        if d != 0.0 {
            vars.0[j] += d;
            vars.1[j] = vars.0[j].sin_cos();
        }
    }
}

//! Gravity sag of a compliant arm (docs/formats.md `[compliance]`).
//!
//! Each revolute joint is a torsional spring of stiffness `k_j` (N·m/rad); under gravity (and an
//! optional payload) the arm sags. This is the unmodelled, pose-dependent share of the
//! positioning error (about 20 % of the real error, Li 2018 §1) that geometric calibration
//! cannot remove.
//!
//! **Mass model.** Link `i` (the body moved by joint `i` up to joint `i+1`) is a point mass
//! `m_i` at the midpoint of the segment between consecutive joint-frame origins
//! ([`crate::robot::Chain::joint_frames`]: the origin of joint `i`'s axis frame and that of
//! joint `i+1`; for the last link, the last joint's origin and the tool point). The payload is a
//! point mass at the tool point. Gravity is 9.81 m/s² along −z of the world frame (the frame the
//! base frame is given in). Only revolute joints are springs: prismatic joints (ball screws) are
//! rigid, and their stiffness entries are checked but not used. With a differential coupling
//! (Guo 2024), the spring acts on the link angle ψ and the deflection is handed back as opposite
//! changes of the two screw travels that keep their sum.
//!
//! **Models.**
//! - `linear`: the small-deflection model `Δq = K⁻¹ τ_g(q)`, with
//!   `τ_g,j = z_jᵀ Σ_{i ≥ j} (c_i − o_j) × m_i g` the gravity torque about joint `j`'s axis
//!   (`z_j`, through `o_j`) of every mass downstream; the deflected tool frame is
//!   `FK(q + Δq)`.
//! - `rapier`: a rapier multibody with implicit joint springs settled to static equilibrium
//!   ([`crate::sim::rapier`]); it solves the exact equilibrium `K Δq = τ_g(q + Δq)`, so it differs
//!   from `linear` by second-order terms (well below a micrometre for realistic stiffness).
//! - `none`: no sag ([`Compliance::new`] returns `None`).

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::numeric::{Frame, Real, Vec3};
use crate::robot::compliance::{self, gravity_torques_at, masses, Masses};
use crate::robot::{builtin::Builtin, Chain, Coupling, JointType, Param, Robot};
use crate::sim::rapier::{self, SpringBody};

/// Which sag model to use (docs/formats.md `[compliance] model`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ComplianceModel {
    /// The rapier multibody settled to static equilibrium.
    Rapier,
    /// The small-deflection model `Δq = K⁻¹ τ_g(q)`.
    Linear,
    /// No sag (the default when the section is absent).
    #[default]
    None,
}

/// The `[compliance]` section of a scenario (docs/formats.md). When the section is absent, the
/// default is `model = "none"`, no overrides and no payload.
#[derive(Clone, Debug, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ComplianceSettings {
    /// The sag model.
    #[serde(default)]
    pub model: ComplianceModel,
    /// Joint stiffness per joint, N·m/rad (N/mm for prismatic joints, which are treated as
    /// rigid). Defaults to the built-in robot's values.
    pub stiffness_nm_per_rad: Option<Vec<Real>>,
    /// Link masses per joint, kg. Defaults to the built-in robot's values.
    pub link_mass_kg: Option<Vec<Real>>,
    /// Payload at the tool point, kg.
    #[serde(default)]
    pub payload_kg: Real,
}

impl ComplianceSettings {
    /// Checks the settings for a robot with `dof` joints: one value per joint, each stiffness
    /// finite and at least 1 N·m/rad (a robot file's compliance range,
    /// [`crate::robot::MAX_COMPLIANCE`]), the masses and the payload masses
    /// ([`compliance::is_mass`]). Errors name the key.
    pub fn check(&self, dof: usize) -> Result<()> {
        if let Some(k) = &self.stiffness_nm_per_rad {
            let why = ("joint", "stiffness must be a finite number ≥ 1 N·m/rad");
            let stiff = |v: Real| v * crate::robot::MAX_COMPLIANCE >= 1.0;
            per_joint("compliance.stiffness_nm_per_rad", k, dof, why, stiff)?;
        }
        if let Some(m) = &self.link_mass_kg {
            let why = format!("mass must be from 0 to {} kg", compliance::MAX_MASS_KG);
            per_joint(
                "compliance.link_mass_kg",
                m,
                dof,
                ("link", &why),
                compliance::is_mass,
            )?;
        }
        if let Some(msg) = compliance::not_a_mass(self.payload_kg) {
            return Err(Error::setting("compliance.payload_kg", msg));
        }
        Ok(())
    }
}

/// Refuses, naming `key`, a list `v` that is not one value per joint of `dof`, or whose
/// `what` (joint, link) has a value that is not finite or not `ok`: `why` it must be.
fn per_joint(
    key: &str,
    v: &[Real],
    dof: usize,
    (what, why): (&str, &str),
    ok: fn(Real) -> bool,
) -> Result<()> {
    if v.len() != dof {
        return Err(Error::setting(
            key,
            format!("needs one value per joint ({dof}), got {}", v.len()),
        ));
    }
    match v.iter().position(|&x| !(x.is_finite() && ok(x))) {
        Some(j) => Err(Error::setting(
            key,
            format!("{what} {}: {why}, got {}", j + 1, crate::error::shown(v[j])),
        )),
        None => Ok(()),
    }
}

/// A compliance model ready to deflect poses of one robot (plain numbers: `Send + Sync`).
#[derive(Clone, Debug, PartialEq)]
pub struct Compliance {
    model: ComplianceModel,
    stiffness: Vec<Real>,
    link_mass: Vec<Real>,
    payload: Real,
}

impl Compliance {
    /// Builds the model from settings, falling back on the built-in robot's documented
    /// `stiffness` and `link_mass_kg` ([`crate::robot::builtin::BUILTINS`]) where the settings give none.
    ///
    /// Returns `None` for model `none`. Errors (naming the key) on invalid settings, and when
    /// stiffness or masses are neither given nor available from `defaults`.
    pub fn new(
        s: &ComplianceSettings,
        robot: &Robot,
        defaults: Option<&Builtin>,
    ) -> Result<Option<Compliance>> {
        let dof = robot.dof();
        if s.model == ComplianceModel::None {
            // Checked all the same: a value that would be refused with a sag model is not
            // taken silently because the model is off.
            return s.check(dof).map(|()| None);
        }
        if dof > 16 {
            return Err(Error::setting(
                "compliance.model",
                "at most 16 joints are supported",
            ));
        }
        s.check(dof)?;
        let pick =
            |key: &str, given: &Option<Vec<Real>>, default: Option<&[Real]>| match (given, default)
            {
                (Some(v), _) => Ok(v.clone()),
                (None, Some(d)) if d.len() == dof => Ok(d.to_vec()),
                _ => Err(Error::setting(
                    key,
                    format!(
                        "robot \"{}\" has no built-in default: give one value per joint ({dof})",
                        robot.name
                    ),
                )),
            };
        let stiffness = pick(
            "compliance.stiffness_nm_per_rad",
            &s.stiffness_nm_per_rad,
            defaults.map(|b| b.stiffness),
        )?;
        let link_mass = pick(
            "compliance.link_mass_kg",
            &s.link_mass_kg,
            robot
                .link_mass_kg
                .as_deref()
                .or(defaults.map(|b| b.link_mass_kg)),
        )?;
        // Check the built-in defaults as well (they pass through the same rules).
        ComplianceSettings {
            model: s.model,
            stiffness_nm_per_rad: Some(stiffness.clone()),
            link_mass_kg: Some(link_mass.clone()),
            payload_kg: s.payload_kg,
        }
        .check(dof)?;
        Ok(Some(Compliance {
            model: s.model,
            stiffness,
            link_mass,
            payload: s.payload_kg,
        }))
    }

    /// Link masses in use, kg.
    pub fn link_mass_kg(&self) -> &[Real] {
        &self.link_mass
    }

    /// Payload at the tool point, kg.
    pub fn payload_kg(&self) -> Real {
        self.payload
    }

    /// The true joint compliances `1/k_j` (rad/(N·m)) of the revolute joints, as the
    /// parameters of the elasto-geometric model name them ([`Param::Compliance`]); prismatic
    /// joints, rigid here, are left out.
    pub fn true_compliances(&self, robot: &Robot) -> Vec<(Param, Real)> {
        robot
            .joints
            .iter()
            .enumerate()
            .filter(|(_, j)| j.kind == JointType::Revolute)
            .map(|(i, _)| (Param::Compliance(i), 1.0 / self.stiffness[i]))
            .collect()
    }

    fn check_robot(&self, robot: &Robot, q: &[Real]) -> Result<()> {
        if robot.dof() != self.stiffness.len() {
            return Err(Error::setting(
                "compliance.stiffness_nm_per_rad",
                format!(
                    "set up for {} joints, robot \"{}\" has {}",
                    self.stiffness.len(),
                    robot.name,
                    robot.dof()
                ),
            ));
        }
        if q.len() != robot.dof() {
            return Err(Error::Compute(format!(
                "joint vector has {} values, robot \"{}\" has {} joints",
                q.len(),
                robot.name,
                robot.dof()
            )));
        }
        if q.iter().any(|v| !v.is_finite()) {
            return Err(Error::Compute("joint vector is not finite".into()));
        }
        Ok(())
    }

    fn masses(&self, chain: &Chain, q: &[Real]) -> Masses {
        masses(chain, q)
    }

    /// Gravity torque (N·m) about each joint axis at the commanded pose; zero for prismatic
    /// joints ([`gravity_torques_at`]).
    fn torques(&self, robot: &Robot, m: &Masses, payload: Real, out: &mut [Real]) {
        gravity_torques_at(robot, &self.link_mass, payload, m, out)
    }

    /// Converts deflections of the chain variables `dc` into joint-value changes `dq` at `q`.
    fn to_joint_values(robot: &Robot, q: &[Real], dc: &[Real], dq: &mut [Real]) {
        dq.copy_from_slice(dc);
        if let Some(Coupling::Differential { l1_mm }) = robot.coupling {
            // ψ = atan((q1 − q2)/L1), ξ = (q1 + q2)/2: change ψ by dc[0], keep ξ.
            let diff = q[0] - q[1];
            let psi = (diff / l1_mm).atan() + dc[0];
            let h = 0.5 * (l1_mm * psi.tan() - diff);
            dq[0] = h;
            dq[1] = -h;
        }
    }

    /// The joint deflection `Δq = K⁻¹ τ_g(q)` of the linear model, in internal
    /// units, at joint values `q` (internal units) of `robot` (the true robot). Zero for
    /// prismatic joints. Whatever the configured model, this is the small-deflection estimate.
    pub fn joint_deflection(&self, robot: &Robot, q: &[Real]) -> Result<Vec<Real>> {
        self.check_robot(robot, q)?;
        let chain = robot.chain();
        let mut dq = vec![0.0; q.len()];
        self.linear_into(robot, &chain, q, self.payload, &mut dq);
        Ok(dq)
    }

    /// Linear model into a caller buffer (allocation-free).
    fn linear_into(
        &self,
        robot: &Robot,
        chain: &Chain,
        q: &[Real],
        payload: Real,
        dq: &mut [Real],
    ) {
        let n = robot.dof();
        let m = self.masses(chain, q);
        let mut dc = [0.0; 16];
        self.torques(robot, &m, payload, &mut dc[..n]);
        for (d, k) in dc.iter_mut().zip(&self.stiffness) {
            *d /= k;
        }
        Self::to_joint_values(robot, q, &dc[..n], dq);
    }

    /// The tool frame of `robot` (the true robot) at joint values `q` (internal units) under
    /// gravity −z of the world frame and the payload at the tool point, with the configured
    /// model.
    pub fn deflected(&self, robot: &Robot, q: &[Real]) -> Result<Frame> {
        self.check_robot(robot, q)?;
        let chain = robot.chain();
        self.deflected_with_chain(robot, &chain, q)
    }

    /// As [`Compliance::deflected`], with the robot's chain built once by the caller
    /// (`robot.chain()`); the `linear` model then allocates nothing.
    pub fn deflected_with_chain(&self, robot: &Robot, chain: &Chain, q: &[Real]) -> Result<Frame> {
        self.deflected_under(robot, chain, q, self.payload)
    }

    /// As [`Compliance::deflected_with_chain`] with a payload of `payload_kg` at the tool
    /// point in place of the configured one (a measurement under another load).
    pub fn deflected_under(
        &self,
        robot: &Robot,
        chain: &Chain,
        q: &[Real],
        payload: Real,
    ) -> Result<Frame> {
        self.check_robot(robot, q)?;
        if !(payload.is_finite() && payload >= 0.0) {
            return Err(Error::setting(
                "payload_kg",
                format!("must be a finite number ≥ 0, got {payload}"),
            ));
        }
        let n = robot.dof();
        match self.model {
            ComplianceModel::None => Ok(chain.fk(q)),
            ComplianceModel::Linear => {
                let mut dq = [0.0; 16];
                self.linear_into(robot, chain, q, payload, &mut dq[..n]);
                let mut qd = [0.0; 16];
                for j in 0..n {
                    qd[j] = q[j] + dq[j];
                }
                Ok(chain.fk(&qd[..n]))
            }
            ComplianceModel::Rapier => Ok(self.settle(robot, chain, q, payload)?.tool),
        }
    }

    /// The rapier settle at joint values `q`, started from the linear model's deflection
    /// (a deterministic function of the pose, so the result does not depend on what the
    /// thread's reused rapier world settled before). Allocation-free on our side.
    fn settle(
        &self,
        robot: &Robot,
        chain: &Chain,
        q: &[Real],
        payload: Real,
    ) -> Result<rapier::Settled> {
        let m = self.masses(chain, q);
        let mut dc = [0.0; 16];
        let n = robot.dof();
        self.torques(robot, &m, payload, &mut dc[..n]);
        for (d, k) in dc.iter_mut().zip(&self.stiffness) {
            *d /= k;
        }
        let s = self.spring_bodies(robot, &m, &dc, payload);
        rapier::settle(
            &s.bodies[..s.count],
            &s.masses[..s.mass_count],
            &m.tool,
            &s.start[..s.count],
        )
    }

    /// The rapier bodies: one per revolute joint, carrying the links up to the next revolute
    /// joint (prismatic joints are rigid); links before the first revolute joint sit on the
    /// fixed base and cannot sag. Each starts from its joint's entry of `dc`.
    fn spring_bodies(
        &self,
        robot: &Robot,
        m: &Masses,
        dc: &[Real; 16],
        payload: Real,
    ) -> SpringBodies {
        let n = robot.dof();
        let mut s = SpringBodies {
            bodies: std::array::from_fn(|_| SpringBody::default()),
            count: 0,
            masses: [(Vec3::zeros(), 0.0); 17],
            mass_count: 0,
            start: [0.0; 16],
        };
        for (i, &start) in dc.iter().enumerate().take(n) {
            if robot.joints[i].kind == JointType::Revolute {
                s.bodies[s.count] = SpringBody {
                    axis: m.axes[i],
                    stiffness: self.stiffness[i],
                    masses: s.mass_count..s.mass_count,
                };
                s.start[s.count] = start;
                s.count += 1;
            }
            if s.count > 0 {
                s.masses[s.mass_count] = (m.points[i], self.link_mass[i]);
                s.mass_count += 1;
                s.bodies[s.count - 1].masses.end = s.mass_count;
            }
        }
        if s.count > 0 {
            s.masses[s.mass_count] = (m.tool.pos, payload);
            s.mass_count += 1;
            s.bodies[s.count - 1].masses.end = s.mass_count;
        }
        s
    }
}

/// The rapier inputs of one pose (fixed size): spring bodies, the point masses they carry
/// (links and payload) and the start coordinates.
struct SpringBodies {
    bodies: [SpringBody; 16],
    count: usize,
    masses: [(Vec3, Real); 17],
    mass_count: usize,
    start: [Real; 16],
}

/// Sag statistics of one arm over random poses: the tool-point displacement (mm) between the
/// rigid and the deflected arm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SagStats {
    /// Number of poses.
    pub count: usize,
    /// Median displacement, mm.
    pub median_mm: Real,
    /// 95th percentile, mm.
    pub p95_mm: Real,
    /// Largest displacement, mm.
    pub max_mm: Real,
    /// Root mean square, mm.
    pub rms_mm: Real,
}

/// Sag statistics of `compliance` on `robot` over `qs` (internal units): the distance between
/// the rigid and the deflected tool point at each pose.
pub fn sag_stats(compliance: &Compliance, robot: &Robot, qs: &[Vec<Real>]) -> Result<SagStats> {
    if qs.is_empty() {
        return Err(Error::Compute(
            "sag statistics need at least one pose".into(),
        ));
    }
    let chain = robot.chain();
    let mut d = Vec::with_capacity(qs.len());
    for q in qs {
        let rigid = chain.fk(q);
        let bent = compliance.deflected_with_chain(robot, &chain, q)?;
        d.push((bent.pos - rigid.pos).norm());
    }
    d.sort_by(|a, b| a.total_cmp(b));
    let at = |f: Real| d[((d.len() - 1) as Real * f).round() as usize];
    Ok(SagStats {
        count: d.len(),
        median_mm: at(0.5),
        p95_mm: at(0.95),
        max_mm: d[d.len() - 1],
        rms_mm: (d.iter().map(|x| x * x).sum::<Real>() / d.len() as Real).sqrt(),
    })
}

#[cfg(test)]
mod tests;

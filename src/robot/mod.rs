//! Robot models and forward kinematics.
//!
//! A robot is a serial chain described in one of three conventions:
//!
//! | convention | link transform | source |
//! |---|---|---|
//! | [`Convention::Dh`] | `Rz(θ)·Tz(d)·Tx(a)·Rx(α)` | Li 2018 eq. 1 |
//! | [`Convention::DhBeta`] | `Rz(θ)·Tz(d)·Tx(a)·Rx(α)·Ry(β)` | Qiao 2021 eq. 1 (Hayati β) |
//! | [`Convention::Mdh`] | `Rx(α_{i-1})·Tx(a_{i-1})·Rz(θ)·Tz(d)·Ry(β)` | Ban eq. 1 (Craig + β) |
//!
//! and the whole arm is `T = T_base · A_1 ⋯ A_n · T_tool`. Every geometric constant is a named
//! parameter ([`Param`]) in one flat vector, in mm and rad, so reports, masks and CSV columns
//! share the same names (`theta1`, `d2`, `a3`, `alpha4`, `beta2`, `base.x`, `tool.rz`, …).
//!
//! Internally the chain is a list of elementary operations (rotations and translations about
//! one local axis), each carrying one parameter; forward kinematics and the identification
//! Jacobian ([`crate::robot::jacobian`]) both walk that list.

pub mod builtin;
mod chain;
pub mod compliance;
mod file;
pub mod gravity_basis;
pub mod harmonics;
pub mod identifiability;
pub mod ik;
pub mod jacobian;
mod limits;
pub mod loaded;
pub mod names;
mod normals;
mod param;
pub mod param_sets;
pub mod sampling;
pub mod urdf;

pub use crate::measurement::units::{AngleUnit, LengthUnit};
pub use chain::{Chain, ChainVars, Lanes, Op, OpKind, OpValues, MAX_OPS};
pub use file::{parse_robot_file, read_robot_file, robot_to_toml};
pub use param::{
    beyond_range, value_count, Param, GRAVITY_POINTS, HARMONIC_TERMS, MAX_HARMONIC_ORDER,
    PARAMS_PER_JOINT,
};

use crate::error::{Error, Result};
use crate::numeric::{Frame, Real};

/// Largest magnitude of a length in a robot model, mm (1 km): link lengths and offsets, base
/// and tool offsets, prismatic joint limits and screw travels, the coupling's lever.
pub const MAX_LENGTH_MM: Real = 1e6;

/// Largest magnitude of a constant angle in a robot model, rad (one turn): α, θ, β and the
/// base and tool angles.
pub const MAX_ANGLE_RAD: Real = 2.0 * std::f64::consts::PI;

/// Largest magnitude of a joint compliance, rad/(N·m) (a joint of 1 N·m/rad stiffness): far
/// above any real arm (about 1e-7 for an industrial arm's main axes).
pub const MAX_COMPLIANCE: Real = 1.0;

/// Largest magnitude of a revolute joint limit or joint value, rad (ten turns).
pub const MAX_JOINT_RAD: Real = 20.0 * std::f64::consts::PI;

/// Most joints of a robot model: the chain keeps its per-joint variables, and the Jacobian,
/// compliance and sag code their per-joint scratch, in arrays of this fixed size, so that
/// walking a chain allocates nothing.
pub const MAX_JOINTS: usize = 16;

/// The warning of forward kinematics at joint values outside the joint limits.
pub const OUTSIDE_LIMITS: &str = "the joint values lie outside the robot's joint limits";

/// What kind of number a robot-model value is, which sets its unit and its range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Quantity {
    /// A length, mm inside; at most [`MAX_LENGTH_MM`] in magnitude.
    Length,
    /// A constant angle, rad inside; at most [`MAX_ANGLE_RAD`] in magnitude.
    Angle,
    /// A revolute joint's limit or value, rad inside; at most [`MAX_JOINT_RAD`] in magnitude.
    JointAngle,
}

impl Quantity {
    fn bound(self) -> Real {
        match self {
            Quantity::Length => MAX_LENGTH_MM,
            Quantity::Angle => MAX_ANGLE_RAD,
            Quantity::JointAngle => MAX_JOINT_RAD,
        }
    }

    fn inner_unit(self) -> &'static str {
        match self {
            Quantity::Length => "mm",
            _ => "rad",
        }
    }

    fn what(self) -> &'static str {
        match self {
            Quantity::Length => "length",
            Quantity::Angle => "angle",
            Quantity::JointAngle => "joint angle",
        }
    }
}

/// Converts `raw` (in `unit`, `factor` to the internal unit) to the internal unit and checks
/// the result: finite and within the quantity's range. The check comes after the conversion,
/// so a finite value that overflows in mm is refused. The error says what is allowed, in
/// `unit` and in the internal unit.
pub(crate) fn to_internal(
    quantity: Quantity,
    raw: Real,
    factor: Real,
    unit: &str,
) -> std::result::Result<Real, String> {
    let v = raw * factor;
    let bound = quantity.bound();
    // The slack lets a bound written in other units (360° = 2π) through despite rounding.
    if v.is_finite() && v.abs() <= bound * (1.0 + 1e-12) {
        return Ok(v);
    }
    let inner = quantity.inner_unit();
    let shown = |x: Real| (x * 1e6).round() / 1e6;
    let (allowed, got) = if unit == inner {
        (
            format!("±{} {inner}", shown(bound)),
            format!("{raw:?} {unit}"),
        )
    } else {
        (
            format!(
                "±{} {unit} (±{} {inner})",
                shown(bound / factor),
                shown(bound)
            ),
            format!("{raw:?} {unit}, which is {v:?} {inner}"),
        )
    };
    Err(format!(
        "must be a finite {} within {allowed}, got {got}",
        quantity.what()
    ))
}

/// A value of a robot model that is not finite, out of range, or inconsistent.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModelIssue {
    /// Where, as in a robot file: `joint 2 (joints[1]), key `a``, `base.xyz`, `coupling.l1`.
    pub place: String,
    /// What is wrong and what is allowed.
    pub msg: String,
}

/// The place of a joint's key in a robot file, as messages name it.
pub(crate) fn joint_place(j: usize, key: &str) -> String {
    format!("joint {} (joints[{j}]), key `{key}`", j + 1)
}

/// The link-transform convention of a robot (see the module docs); `dh`, `dh_beta`, `mdh`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "snake_case")]
pub enum Convention {
    /// Standard Denavit–Hartenberg, Li 2018 eq. 1.
    Dh,
    /// Standard DH followed by Hayati's `Ry(β)`, Qiao 2021 eq. 1.
    DhBeta,
    /// Craig's modified DH followed by `Ry(β)`, Ban eq. 1.
    Mdh,
}

impl Convention {
    /// The name used in robot files.
    pub fn as_str(self) -> &'static str {
        self.into()
    }

    /// Whether the convention has a β parameter per joint.
    pub fn has_beta(self) -> bool {
        !matches!(self, Convention::Dh)
    }
}

/// The kind of a joint: which parameter its variable adds to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "lowercase")]
pub enum JointType {
    /// The joint variable adds to θ (rad inside the library).
    Revolute,
    /// The joint variable adds to d (mm inside the library).
    Prismatic,
}

/// One joint's kind and limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joint {
    /// Revolute or prismatic.
    pub kind: JointType,
    /// Range of the joint value, in internal units (rad for revolute, mm for prismatic; for
    /// the inputs of a [`Coupling`], mm).
    pub limits: (Real, Real),
}

/// The units in which a robot's file and its joint values (measurement CSV, `--q`) are given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Units {
    /// Unit of lengths.
    pub length: LengthUnit,
    /// Unit of angles.
    pub angle: AngleUnit,
}

impl Units {
    /// Degrees and millimetres, the units of the built-in robots.
    pub const DEG_MM: Units = Units {
        length: LengthUnit::Mm,
        angle: AngleUnit::Deg,
    };

    /// Factor from this length unit to mm.
    pub fn length_to_mm(self) -> Real {
        self.length.to_mm()
    }

    /// The length unit's name in robot files: `mm` or `m`.
    pub fn length_name(self) -> &'static str {
        self.length.into()
    }

    /// The angle unit's name in robot files: `deg` or `rad`.
    pub fn angle_name(self) -> &'static str {
        self.angle.into()
    }

    /// Factor from this angle unit to rad.
    pub fn angle_to_rad(self) -> Real {
        self.angle.to_rad()
    }
}

/// A coupling between actuator values and chain variables.
///
/// `Differential` is the parallel/differential ball-screw drive of Guo 2024 (§1.1, the
/// expressions under eq. 3): two horizontal screws with travels `q1 = s_x φ1 / 2π` and
/// `q2 = s_x φ2 / 2π` turn link 1 by `ψ = atan((q1 − q2) / L1)` and move it by
/// `ξ = (q1 + q2) / 2`, which is Guo's `ψ = atan(s_x(φ1 − φ2)/(2π L1))`,
/// `ξ = s_x(φ1 + φ2)/(4π)` written with screw travels. Joint 1 of the chain is then revolute
/// with variable ψ and joint 2 prismatic with variable ξ; the joint values given for joints 1
/// and 2 are the screw travels (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Coupling {
    /// Guo 2024's differential drive of joints 1 and 2 (see the type's docs); `l1_mm` is L1.
    Differential {
        /// The lever length L1 of the differential, mm.
        l1_mm: Real,
    },
}

/// A serial robot: convention, joints, the flat parameter vector and the units of its file.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    /// Name, from the file or the built-in table.
    pub name: String,
    /// Link-transform convention.
    pub convention: Convention,
    /// Joints in order from the base.
    pub joints: Vec<Joint>,
    /// All parameter values (mm, rad) in [`Param::index`] order: 5 per joint
    /// (θ, d, a, α, β), then base (x, y, z, rx, ry, rz), then tool (same).
    pub values: Vec<Real>,
    /// Units of the robot file and of joint values given by users.
    pub units: Units,
    /// Optional actuator coupling (Guo 2024's differential drive).
    pub coupling: Option<Coupling>,
    /// The joints (0-based) that carry Hayati's β when the convention has β; `None`: every
    /// joint. Guo 2024 (§1.2, the text under eq. 6) puts β on A2 alone, its one pair of
    /// adjacent parallel joints; the β of the other joints is not a parameter of its model.
    pub beta_joints: Option<Vec<usize>>,
    /// Link masses (kg), one per joint: link `i` is the body joint `i` moves, up to joint
    /// `i + 1`, a point mass at the midpoint between the two joints' origins
    /// ([`crate::robot::compliance`]). From the robot file's `mass_kg` or the built-in robot's
    /// table; `None` when neither gives them. The gravity torques of the elasto-geometric
    /// model ([`Param::Compliance`]) need them.
    pub link_mass_kg: Option<Vec<Real>>,
}

impl crate::measurement::JointSpace for Robot {
    fn name(&self) -> &str {
        &self.name
    }
    fn dof(&self) -> usize {
        Robot::dof(self)
    }
    fn q_to_user(&self, q: &[Real]) -> Vec<Real> {
        Robot::q_to_user(self, q)
    }
    fn q_from_user(&self, q: &[Real]) -> Vec<Real> {
        Robot::q_from_user(self, q)
    }
    fn limits(&self, j: usize) -> (Real, Real) {
        self.joints[j].limits
    }
    fn decimals(&self, j: usize) -> usize {
        self.q_decimals(j)
    }
    fn angle_unit(&self) -> Option<AngleUnit> {
        (0..self.dof())
            .any(|j| self.q_turns(j))
            .then_some(self.units.angle)
    }
}

impl Robot {
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The parameters that exist in this robot's model, in flat-vector order: θ, d, a, α
    /// (and β for `dh_beta` and `mdh`, on the joints of [`Robot::beta_joints`]) per joint,
    /// then the six base and six tool parameters.
    pub fn params(&self) -> Vec<Param> {
        Param::all(self.dof(), self.convention.has_beta())
            .into_iter()
            .filter(|&p| match p {
                Param::Beta(j) => self.carries_beta(j),
                _ => true,
            })
            .collect()
    }

    /// Whether joint `j` (0-based) carries a β parameter: the convention has β and the joint
    /// is one of [`Robot::beta_joints`] (every joint when that is `None`).
    pub fn carries_beta(&self, j: usize) -> bool {
        self.convention.has_beta() && self.beta_joints.as_ref().is_none_or(|v| v.contains(&j))
    }

    /// The joint parameters of the model (θ, d, a, α of every joint and the β that exist):
    /// [`Robot::params`] without base and tool, Guo 2024's 21 for its 3T2R arm (eq. 7).
    pub fn joint_params(&self) -> Vec<Param> {
        self.params()
            .into_iter()
            .filter(|p| p.joint().is_some())
            .collect()
    }

    /// The value of one parameter (mm or rad).
    pub fn get(&self, p: Param) -> Real {
        self.values[p.index(self.dof())]
    }

    /// Sets one parameter (mm or rad).
    pub fn set(&mut self, p: Param, v: Real) {
        let i = p.index(self.dof());
        self.values[i] = v;
    }

    /// A copy with `errors` (parameter, mm or rad) added to the parameter values.
    pub fn with_errors(&self, errors: &[(Param, Real)]) -> Robot {
        let mut r = self.clone();
        for &(p, e) in errors {
            let i = p.index(self.dof());
            r.values[i] += e;
        }
        r
    }

    /// The flat parameter values with `x[k]` added to value `index[k]`, written into `values`
    /// (one per flat value): the model an identification evaluates at its estimate `x`.
    pub fn values_with_added(&self, index: &[usize], x: &[Real], values: &mut [Real]) {
        values.copy_from_slice(&self.values);
        for (&i, &v) in index.iter().zip(x) {
            values[i] += v;
        }
    }

    /// Sets `chain` (compiled from this robot) to the values with `x[k]` added to value
    /// `index[k]`, written into `values` on the way ([`Robot::values_with_added`],
    /// [`Chain::set_values`]): an identification's model at its estimate, allocation-free.
    pub fn set_chain_with_added(
        &self,
        index: &[usize],
        x: &[Real],
        values: &mut [Real],
        chain: &mut Chain,
    ) {
        self.values_with_added(index, x, values);
        chain.set_values(values);
    }

    /// A copy with `x[k]` added to flat value `index[k]` ([`Robot::values_with_added`]).
    pub fn with_added(&self, index: &[usize], x: &[Real]) -> Robot {
        let mut r = self.clone();
        self.values_with_added(index, x, &mut r.values);
        r
    }

    /// The base frame in the world.
    pub fn base(&self) -> Frame {
        self.part_frame(Param::Base(0).index(self.dof()))
    }

    /// The tool frame on the flange.
    pub fn tool(&self) -> Frame {
        self.part_frame(Param::Tool(0).index(self.dof()))
    }

    fn part_frame(&self, i: usize) -> Frame {
        let v = &self.values[i..i + 6];
        Frame::from_xyz_rpy([v[0], v[1], v[2]], [v[3], v[4], v[5]])
    }

    /// Whether any value of a per-joint block of parameters (`param(joint, k)`, `k` below
    /// `terms`) is non-zero; a robot whose values do not hold the block has none.
    pub fn any_term(&self, terms: usize, param: fn(usize, usize) -> Param) -> bool {
        let dof = self.dof();
        (0..dof).any(|j| param::nonzero_block(&self.values, dof, j, (terms, param)).is_some())
    }

    /// The precompiled chain of elementary operations for the current parameter values.
    pub fn chain(&self) -> Chain {
        Chain::new(self)
    }

    /// Forward kinematics: the tool frame in the world for joint values `q` (rad / mm).
    /// Convenience over [`Chain::fk`]; hot loops should build the chain once.
    pub fn fk(&self, q: &[Real]) -> Frame {
        self.chain().fk(q)
    }

    /// Joint values converted from the robot's units (file, CSV, `--q`) to internal units.
    pub fn q_from_user(&self, q: &[Real]) -> Vec<Real> {
        q.iter()
            .zip(&self.joints)
            .enumerate()
            .map(|(i, (v, j))| v * self.q_factor(i, j.kind))
            .collect()
    }

    /// Joint values converted from internal units to the robot's units.
    pub fn q_to_user(&self, q: &[Real]) -> Vec<Real> {
        q.iter()
            .zip(&self.joints)
            .enumerate()
            .map(|(i, (v, j))| v / self.q_factor(i, j.kind))
            .collect()
    }

    /// Factor from the user unit of joint `i`'s value to the internal unit.
    fn q_factor(&self, i: usize, kind: JointType) -> Real {
        if self.q_is_length(i, kind) {
            self.units.length_to_mm()
        } else {
            self.units.angle_to_rad()
        }
    }

    /// Checks every value of the model (internal units): each parameter finite and within its
    /// range ([`MAX_LENGTH_MM`], [`MAX_ANGLE_RAD`]; joint limits [`MAX_JOINT_RAD`] or
    /// [`MAX_LENGTH_MM`]), each joint's lower limit below its upper, no β in a `dh` robot, a
    /// coupling lever that is positive and in range. [`read_robot_file`] refuses files whose
    /// robot fails this check; robots built in code can call it before they are used.
    pub fn check(&self) -> std::result::Result<(), ModelIssue> {
        let n = self.dof();
        let issue = |place: String, msg: String| ModelIssue { place, msg };
        if !(1..=MAX_JOINTS).contains(&n) {
            let msg = format!("{n} joints: 1 to {MAX_JOINTS} are supported");
            return Err(issue("joints".into(), msg));
        }
        if self.values.len() != value_count(n) {
            let (got, want) = (self.values.len(), value_count(n));
            let msg = format!("{got} parameter values for {n} joints; expected {want}");
            return Err(issue("joints".into(), msg));
        }
        for p in Param::all(n, true) {
            let v = self.get(p);
            let (place, quantity) = match p {
                Param::Theta(j) => (joint_place(j, "theta"), Quantity::Angle),
                Param::D(j) => (joint_place(j, "d"), Quantity::Length),
                Param::A(j) => (joint_place(j, "a"), Quantity::Length),
                Param::Alpha(j) => (joint_place(j, "alpha"), Quantity::Angle),
                Param::Beta(j) => (joint_place(j, "beta"), Quantity::Angle),
                Param::Base(c) | Param::Tool(c) => {
                    let part = if matches!(p, Param::Base(_)) {
                        "base"
                    } else {
                        "tool"
                    };
                    if c < 3 {
                        (format!("{part}.xyz"), Quantity::Length)
                    } else {
                        (format!("{part}.rpy"), Quantity::Angle)
                    }
                }
                Param::Compliance(_) | Param::Harmonic(..) | Param::Gravity(..) => continue,
            };
            let unit = quantity.inner_unit();
            to_internal(quantity, v, 1.0, unit).map_err(|m| issue(place.clone(), m))?;
            if matches!(p, Param::Beta(_)) && !self.convention.has_beta() && v != 0.0 {
                return Err(issue(
                    place,
                    "convention \"dh\" has no β; use \"dh_beta\" or \"mdh\"".into(),
                ));
            }
            if let Param::Beta(j) = p {
                if self.convention.has_beta() && !self.carries_beta(j) && v != 0.0 {
                    return Err(issue(
                        place,
                        format!("joint {} carries no β (see `beta_joints`)", j + 1),
                    ));
                }
            }
        }
        for (j, joint) in self.joints.iter().enumerate() {
            let quantity = if self.q_is_length(j, joint.kind) {
                Quantity::Length
            } else {
                Quantity::JointAngle
            };
            let (lo, hi) = joint.limits;
            let unit = quantity.inner_unit();
            for v in [lo, hi] {
                to_internal(quantity, v, 1.0, unit)
                    .map_err(|m| issue(joint_place(j, "limits"), m))?;
            }
            if lo >= hi {
                return Err(issue(
                    joint_place(j, "limits"),
                    format!("lower limit {lo:?} {unit} must be below upper limit {hi:?} {unit}"),
                ));
            }
        }
        if let Some(bj) = &self.beta_joints {
            if !self.convention.has_beta() {
                return Err(issue(
                    "beta_joints".into(),
                    "convention \"dh\" has no β; use \"dh_beta\" or \"mdh\"".into(),
                ));
            }
            for (k, &j) in bj.iter().enumerate() {
                if j >= n || bj[..k].contains(&j) {
                    return Err(issue(
                        "beta_joints".into(),
                        format!(
                            "must list distinct joint numbers from 1 to {n}, got {}",
                            j + 1
                        ),
                    ));
                }
            }
        }
        if let Some(m) = &self.link_mass_kg {
            if m.len() != n {
                return Err(issue(
                    "mass_kg".into(),
                    format!("{} link masses for {n} joints", m.len()),
                ));
            }
            if let Some((j, msg)) =
                (m.iter().enumerate()).find_map(|(j, v)| Some((j, compliance::not_a_mass(*v)?)))
            {
                return Err(issue(joint_place(j, "mass_kg"), msg));
            }
        }
        for j in 0..n {
            let c = self.get(Param::Compliance(j));
            if c == 0.0 {
                continue;
            }
            let place = joint_place(j, "compliance");
            if !(c.is_finite() && c.abs() <= MAX_COMPLIANCE) {
                return Err(issue(
                    place,
                    format!(
                        "must be a finite number within ±{MAX_COMPLIANCE:e} rad/(N·m), got {c:?}"
                    ),
                ));
            }
            if self.joints[j].kind != JointType::Revolute {
                return Err(issue(
                    place,
                    "only revolute joints are compliant in calbench's model".into(),
                ));
            }
            if self.link_mass_kg.is_none() {
                return Err(issue(
                    place,
                    "a compliance needs the link masses (`mass_kg` on every joint)".into(),
                ));
            }
        }
        harmonics::check(self)?;
        gravity_basis::check(self)?;
        if let Some(Coupling::Differential { l1_mm }) = self.coupling {
            to_internal(Quantity::Length, l1_mm, 1.0, "mm")
                .ok()
                .filter(|&l| l > 0.0)
                .ok_or_else(|| {
                    issue(
                        "coupling.l1".into(),
                        format!("must be a finite length > 0 within ±{MAX_LENGTH_MM} mm, got {l1_mm:?} mm"),
                    )
                })?;
            if n < 2
                || self.joints[0].kind != JointType::Revolute
                || self.joints[1].kind != JointType::Prismatic
            {
                return Err(issue(
                    "coupling".into(),
                    "a differential coupling drives a revolute joint 1 and a prismatic joint 2"
                        .into(),
                ));
            }
        }
        Ok(())
    }

    /// Joint values given in the robot's units (`--q`, a file), converted to internal units
    /// and checked after the conversion: each finite and within [`MAX_LENGTH_MM`] (prismatic
    /// joints, screw travels) or [`MAX_JOINT_RAD`] (revolute joints), so forward kinematics of
    /// the result is finite. `key` names the values in the error (e.g. `--q`).
    pub fn q_from_user_checked(&self, q: &[Real], key: &str) -> Result<Vec<Real>> {
        if q.len() != self.dof() {
            return Err(Error::joint_count(
                key,
                "the values given",
                q.len(),
                self.dof(),
            ));
        }
        q.iter()
            .enumerate()
            .map(|(i, &v)| {
                self.q_internal(i, v)
                    .map_err(|m| Error::setting(key, format!("joint {}: {m}", i + 1)))
            })
            .collect()
    }

    /// Joint `i`'s value `v` given in the robot's units, in internal units, checked as
    /// [`Robot::q_from_user_checked`] checks it; the refusal's words without a place.
    pub fn q_internal(&self, i: usize, v: Real) -> std::result::Result<Real, String> {
        let kind = self.joints[i].kind;
        let (quantity, unit) = if self.q_is_length(i, kind) {
            (Quantity::Length, self.units.length_name())
        } else {
            (Quantity::JointAngle, self.units.angle_name())
        };
        to_internal(quantity, v, self.q_factor(i, kind), unit)
    }

    /// Whether joint `i`'s value is a length (prismatic, or a screw travel of a coupling).
    fn q_is_length(&self, i: usize, kind: JointType) -> bool {
        (self.coupling.is_some() && i < 2) || kind == JointType::Prismatic
    }

    /// Whether joint `i`'s value is an angle, which a whole turn leaves at the same pose (a
    /// revolute joint but a coupling's screw travel).
    pub fn q_turns(&self, i: usize) -> bool {
        !self.q_is_length(i, self.joints[i].kind)
    }
}

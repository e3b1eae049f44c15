//! Robot models and forward kinematics (SPEC §1).
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
//! Jacobian ([`crate::jacobian`]) both walk that list.

mod chain;
mod file;
mod param;

pub use chain::{Chain, ChainVars, Op, OpKind};
pub use file::{parse_robot_file, read_robot_file, robot_to_toml};
pub use param::{Param, PARAMS_PER_JOINT};

use crate::math::{Frame, Real};

/// The link-transform convention of a robot (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
        match self {
            Convention::Dh => "dh",
            Convention::DhBeta => "dh_beta",
            Convention::Mdh => "mdh",
        }
    }

    /// Whether the convention has a β parameter per joint.
    pub fn has_beta(self) -> bool {
        !matches!(self, Convention::Dh)
    }
}

/// The kind of a joint: which parameter its variable adds to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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

/// Length unit of a robot file and its joint values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LengthUnit {
    /// Millimetres.
    Mm,
    /// Metres.
    M,
}

/// Angle unit of a robot file and its joint values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AngleUnit {
    /// Degrees.
    Deg,
    /// Radians.
    Rad,
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
        match self.length {
            LengthUnit::Mm => 1.0,
            LengthUnit::M => 1000.0,
        }
    }

    /// Factor from this angle unit to rad.
    pub fn angle_to_rad(self) -> Real {
        match self.angle {
            AngleUnit::Deg => std::f64::consts::PI / 180.0,
            AngleUnit::Rad => 1.0,
        }
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
}

impl Robot {
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The parameters that exist in this robot's model, in flat-vector order: θ, d, a, α
    /// (and β for `dh_beta` and `mdh`) per joint, then the six base and six tool parameters.
    pub fn params(&self) -> Vec<Param> {
        Param::all(self.dof(), self.convention.has_beta())
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

    /// The precompiled chain of elementary operations for the current parameter values.
    pub fn chain(&self) -> Chain {
        Chain::new(self)
    }

    /// Chain variables (the value each joint adds to θ or d) from joint values `q`
    /// (internal units). Without a coupling they are `q` itself.
    pub fn chain_values(&self, q: &[Real], out: &mut [Real]) {
        out.copy_from_slice(q);
        if let Some(Coupling::Differential { l1_mm }) = self.coupling {
            out[0] = ((q[0] - q[1]) / l1_mm).atan();
            out[1] = 0.5 * (q[0] + q[1]);
        }
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
        let coupled = self.coupling.is_some() && i < 2;
        if coupled || kind == JointType::Prismatic {
            self.units.length_to_mm()
        } else {
            self.units.angle_to_rad()
        }
    }

    /// Whether `q` (internal units) lies within the joint limits (with a tolerance of 1e-9).
    pub fn within_limits(&self, q: &[Real]) -> bool {
        q.iter()
            .zip(&self.joints)
            .all(|(v, j)| *v >= j.limits.0 - 1e-9 && *v <= j.limits.1 + 1e-9)
    }
}

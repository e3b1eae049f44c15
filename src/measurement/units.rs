//! The units of a robot file and of joint values given by users (measurement CSVs, `--q`, a
//! mapping's columns): lengths in mm or m, angles in deg or rad.

use crate::numeric::Real;

/// Length unit of a robot file and its joint values, and of a mapping's length columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "lowercase")]
pub enum LengthUnit {
    /// Millimetres.
    Mm,
    /// Metres.
    M,
}

/// Angle unit of a robot file and its joint values, and of a mapping's Euler angles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "lowercase")]
pub enum AngleUnit {
    /// Degrees.
    Deg,
    /// Radians.
    Rad,
}

impl LengthUnit {
    /// The factor to mm.
    pub fn to_mm(self) -> Real {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::M => 1000.0,
        }
    }
}

impl AngleUnit {
    /// The factor to rad.
    pub fn to_rad(self) -> Real {
        match self {
            AngleUnit::Deg => std::f64::consts::PI / 180.0,
            AngleUnit::Rad => 1.0,
        }
    }
}

//! The mapping file of `calbench import` (docs/formats.md, "Mapping file"): its keys, checked
//! and resolved into the plan [`super::import_text`] reads an export by, and the Euler
//! conventions it names.

use std::path::Path;

use serde::Deserialize;

use crate::error::{quoted, read_text, Error, Result};
use crate::measurement::units::{AngleUnit, LengthUnit};
use crate::numeric::{rot_x, rot_y, rot_z, Mat3, Real};

/// A mapping file: how to read one tracker export.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mapping {
    /// The field separator (one character; `";"`, `","`, `"\t"`).
    #[serde(default = "comma")]
    pub separator: String,
    /// The decimal mark (`"."` or `","`).
    #[serde(default = "dot")]
    pub decimal: String,
    /// The joint columns.
    pub joints: JointColumns,
    /// The measured position columns.
    pub position: PositionColumns,
    /// The measured orientation columns (full-pose data), if any.
    pub orientation: Option<OrientationColumns>,
    /// The standard deviation columns, if any.
    pub sigma: Option<SigmaColumns>,
}

fn comma() -> String {
    ",".into()
}

fn dot() -> String {
    ".".into()
}

/// A unit of a column: angles or lengths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    /// Radians.
    Rad,
    /// Degrees.
    Deg,
    /// Millimetres.
    Mm,
    /// Metres.
    M,
}

impl Unit {
    /// The angle unit it is, `None` for a length unit.
    pub(super) fn angle(self) -> Option<AngleUnit> {
        match self {
            Unit::Rad => Some(AngleUnit::Rad),
            Unit::Deg => Some(AngleUnit::Deg),
            Unit::Mm | Unit::M => None,
        }
    }

    /// As a mapping writes it.
    pub(super) fn name(self) -> &'static str {
        match self {
            Unit::Rad => "rad",
            Unit::Deg => "deg",
            Unit::Mm => "mm",
            Unit::M => "m",
        }
    }

    /// `(kind, factor to rad or mm)`.
    fn scale(self) -> (&'static str, Real) {
        match self {
            Unit::Rad => ("angle", AngleUnit::Rad.to_rad()),
            Unit::Deg => ("angle", AngleUnit::Deg.to_rad()),
            Unit::Mm => ("length", LengthUnit::Mm.to_mm()),
            Unit::M => ("length", LengthUnit::M.to_mm()),
        }
    }
}

/// `[joints]`: the joint columns, in joint order.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointColumns {
    /// Column names of q1 … qn.
    pub columns: Vec<String>,
    /// Their unit in the export.
    pub unit: Unit,
    /// Their unit in the measurement CSV: the robot file's unit (`angle_unit`; a URDF's
    /// radians). Default: `unit`. Of the same kind as `unit` (angle or length).
    pub write_unit: Option<Unit>,
}

/// `[position]`: the measured point.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PositionColumns {
    /// Column names of x, y, z.
    pub columns: [String; 3],
    /// `"mm"` or `"m"`.
    pub unit: LengthUnit,
    /// Columns added to x, y, z, in the same unit: an export that gives a target point and
    /// its measured difference.
    pub plus: Option<[String; 3]>,
}

/// How an orientation is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OrientationKind {
    /// Three Euler angles.
    Euler,
    /// Four quaternion components.
    Quaternion,
}

/// Whether Euler rotations turn about the moving (intrinsic) or the fixed (extrinsic) axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EulerFrame {
    /// About the moving axes: sequence "xyz" is R = Rx(a)·Ry(b)·Rz(c).
    Intrinsic,
    /// About the fixed axes: sequence "xyz" is R = Rz(c)·Ry(b)·Rx(a) (a robot file's `rpy`).
    Extrinsic,
}

/// `[orientation]`: the measured frame's orientation in the instrument's frame.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrientationColumns {
    /// `"euler"` or `"quaternion"`.
    pub kind: OrientationKind,
    /// The columns: three angles in the order of `sequence`, or four quaternion components
    /// in the order of `order`.
    pub columns: Vec<String>,
    /// Euler: the axis sequence, three of x, y, z with no axis twice in a row (`"xyz"`,
    /// `"zyx"`, `"zyz"`, …).
    pub sequence: Option<String>,
    /// Euler: `"intrinsic"` or `"extrinsic"`.
    pub frame: Option<EulerFrame>,
    /// Euler: `"deg"` or `"rad"`.
    pub unit: Option<AngleUnit>,
    /// Quaternion: the components' order, `"wxyz"` or `"xyzw"`.
    pub order: Option<String>,
}

/// How several standard deviation columns make one per-point σ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Combine {
    /// √(Σσ²/n): the σ of one coordinate with the same total variance (default).
    #[default]
    Rms,
    /// The largest.
    Max,
}

/// `[sigma]`: standard deviations of the measured position, one σ per point (`sigma_mm`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SigmaColumns {
    /// One column (σ of the point) or several (σ per axis), combined by `combine`.
    pub position: Vec<String>,
    /// `"mm"` or `"m"`.
    pub unit: LengthUnit,
    /// `"rms"` (default) or `"max"`.
    #[serde(default)]
    pub combine: Combine,
}

/// A checked mapping: an ASCII separator, a decimal mark, resolved conventions, no column
/// named twice.
pub(super) struct Plan {
    /// The mapping file's text, for the lines of refused keys.
    pub(super) text: String,
    /// The field separator, one ASCII byte.
    pub(super) sep: u8,
    pub(super) decimal: char,
    /// The joint columns, the factor from their unit to the written one, their unit.
    pub(super) joints: (Vec<String>, Real, Unit),
    /// The unit the joint values are written in, and the key that gives it
    /// (`joints.write_unit`, else `joints.unit`).
    pub(super) written: (Unit, &'static str),
    pub(super) position: ([String; 3], Real),
    pub(super) plus: Vec<String>,
    pub(super) orientation: Option<Orient>,
    pub(super) sigma: Option<(Vec<String>, Real, Combine)>,
}

pub(super) enum Orient {
    Euler {
        cols: Vec<String>,
        axes: [usize; 3],
        intrinsic: bool,
        scale: Real,
    },
    Quat {
        cols: Vec<String>,
        /// Position of w, x, y, z among the columns.
        at: [usize; 4],
    },
}

impl Mapping {
    /// Reads and checks a mapping file.
    pub fn load(path: &Path) -> Result<Mapping> {
        Mapping::load_plan(path).map(|(m, _)| m)
    }

    /// Reads and checks a mapping file, and resolves it.
    pub(super) fn load_plan(path: &Path) -> Result<(Mapping, Plan)> {
        let text = read_text(path)?;
        let m: Mapping = crate::error::toml_keys(path, &text)?;
        let plan = m.plan(path, text)?;
        Ok((m, plan))
    }

    /// Every column the mapping names, with its key (`position.columns[1]`), in the order of
    /// the file.
    fn named_columns(&self) -> Vec<(String, &str)> {
        let fields: [(&str, &[String]); 5] = [
            ("joints.columns", &self.joints.columns),
            ("position.columns", &self.position.columns),
            (
                "position.plus",
                self.position.plus.as_ref().map_or(&[], |p| &p[..]),
            ),
            (
                "orientation.columns",
                self.orientation.as_ref().map_or(&[], |o| &o.columns),
            ),
            (
                "sigma.position",
                self.sigma.as_ref().map_or(&[], |s| &s.position),
            ),
        ];
        fields
            .into_iter()
            .flat_map(|(key, names)| {
                names
                    .iter()
                    .enumerate()
                    .map(move |(i, n)| (format!("{key}[{i}]"), n.as_str()))
            })
            .collect()
    }

    fn plan(&self, path: &Path, text: String) -> Result<Plan> {
        let bad = |key: &str, msg: String| Error::toml_file(path, &text, key, key, msg);
        let named = self.named_columns();
        for (k, (key, name)) in named.iter().enumerate() {
            if let Some((first, _)) = named[..k].iter().find(|(_, n)| n == name) {
                return Err(bad(
                    key,
                    format!(
                        "column {} is mapped already by `{first}`: a column gives one \
                         field",
                        quoted(name)
                    ),
                ));
            }
        }
        let one_char = |key: &str, s: &str| {
            let mut c = s.chars();
            match (c.next(), c.next()) {
                (Some(ch), None) => Ok(ch),
                _ => Err(bad(key, format!("{} must be one character", quoted(s)))),
            }
        };
        let sep = one_char("separator", &self.separator)?;
        let sep = u8::try_from(sep)
            .ok()
            .filter(|b| b.is_ascii() && !matches!(b, b'"' | b'\r' | b'\n'))
            // A character of a number would split numbers apart.
            .filter(|b| !(b.is_ascii_alphanumeric() || matches!(b, b'+' | b'-' | b'.')))
            .ok_or_else(|| {
                bad(
                    "separator",
                    format!(
                        "{}: an ASCII character other than the quote, a line break, a letter, \
                         a digit, a sign and the point, which are parts of numbers",
                        quoted(&sep.to_string())
                    ),
                )
            })?;
        let decimal = one_char("decimal", &self.decimal)?;
        if !matches!(decimal, '.' | ',') || decimal == char::from(sep) {
            return Err(bad(
                "decimal",
                format!(
                    "{}: \".\" or \",\", and not the separator",
                    quoted(&decimal.to_string())
                ),
            ));
        }
        if self.joints.columns.is_empty() {
            return Err(bad("joints.columns", "names no column".into()));
        }
        let (kind, from) = self.joints.unit.scale();
        let (wkind, to) = self.joints.write_unit.unwrap_or(self.joints.unit).scale();
        let article = |k: &str| if k == "angle" { "an angle" } else { "a length" };
        let (wkind, kind) = (article(wkind), article(kind));
        if kind != wkind {
            return Err(bad(
                "joints.write_unit",
                format!("{wkind} unit for joints read in {kind} unit"),
            ));
        }
        let position = (self.position.columns.clone(), self.position.unit.to_mm());
        let orientation = self
            .orientation
            .as_ref()
            .map(|o| o.plan(path, &text))
            .transpose()?;
        let sigma = match &self.sigma {
            Some(s) if s.position.is_empty() => {
                return Err(bad("sigma.position", "names no column".into()))
            }
            Some(s) => Some((s.position.clone(), s.unit.to_mm(), s.combine)),
            None => None,
        };
        Ok(Plan {
            text,
            sep,
            decimal,
            joints: (self.joints.columns.clone(), from / to, self.joints.unit),
            written: match self.joints.write_unit {
                Some(u) => (u, "joints.write_unit"),
                None => (self.joints.unit, "joints.unit"),
            },
            position,
            plus: self.position.plus.clone().map_or(Vec::new(), Vec::from),
            orientation,
            sigma,
        })
    }
}

impl OrientationColumns {
    fn plan(&self, path: &Path, text: &str) -> Result<Orient> {
        let bad = |key: &str, msg: &str| {
            let key = format!("orientation.{key}");
            Error::toml_file(path, text, &key, &key, msg)
        };
        let n = self.columns.len();
        match self.kind {
            OrientationKind::Euler => {
                if n != 3 || self.order.is_some() {
                    return Err(bad(
                        "columns",
                        "Euler angles take three columns (and no `order`)",
                    ));
                }
                let seq = self
                    .sequence
                    .as_deref()
                    .ok_or_else(|| bad("sequence", "missing: the axis sequence, e.g. \"xyz\""))?;
                let axes: Vec<usize> = seq
                    .chars()
                    .map(|c| "xyz".find(c))
                    .collect::<Option<_>>()
                    .filter(|a: &Vec<usize>| a.len() == 3 && a[0] != a[1] && a[1] != a[2])
                    .ok_or_else(|| {
                        bad(
                            "sequence",
                            "three of x, y, z in lower case, no axis twice in a row (\"xyz\", \
                             \"zyz\"; upper case, which some libraries read as intrinsic, is not \
                             taken: `frame` says which)",
                        )
                    })?;
                let frame = self
                    .frame
                    .ok_or_else(|| bad("frame", "missing: \"intrinsic\" or \"extrinsic\""))?;
                let scale = self
                    .unit
                    .ok_or_else(|| bad("unit", "missing: \"deg\" or \"rad\""))?
                    .to_rad();
                Ok(Orient::Euler {
                    cols: self.columns.clone(),
                    axes: [axes[0], axes[1], axes[2]],
                    intrinsic: frame == EulerFrame::Intrinsic,
                    scale,
                })
            }
            OrientationKind::Quaternion => {
                if n != 4 || self.sequence.is_some() || self.frame.is_some() || self.unit.is_some()
                {
                    return Err(bad(
                        "columns",
                        "a quaternion takes four columns and `order` only",
                    ));
                }
                let at = match self.order.as_deref() {
                    Some("wxyz") => [0, 1, 2, 3],
                    Some("xyzw") => [3, 0, 1, 2],
                    _ => return Err(bad("order", "\"wxyz\" or \"xyzw\"")),
                };
                Ok(Orient::Quat {
                    cols: self.columns.clone(),
                    at,
                })
            }
        }
    }
}

/// The rotation of Euler angles `v` (rad) about `axes` (0 = x, 1 = y, 2 = z), intrinsic
/// (R = R₁(v₁)·R₂(v₂)·R₃(v₃)) or extrinsic (R = R₃(v₃)·R₂(v₂)·R₁(v₁)).
pub fn euler_matrix(axes: [usize; 3], v: [Real; 3], intrinsic: bool) -> Mat3 {
    let r = |a: usize, t: Real| match a {
        0 => rot_x(t),
        1 => rot_y(t),
        _ => rot_z(t),
    };
    let (a, b, c) = (r(axes[0], v[0]), r(axes[1], v[1]), r(axes[2], v[2]));
    if intrinsic {
        a * b * c
    } else {
        c * b * a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn euler_conventions_match_their_definitions() {
        let v = [0.3, -1.1, 2.0];
        let i = euler_matrix([0, 1, 2], v, true);
        assert_relative_eq!(i, rot_x(v[0]) * rot_y(v[1]) * rot_z(v[2]), epsilon = 1e-15);
        // Extrinsic x-y-z is the robot file's rpy (fixed X-Y-Z).
        let e = euler_matrix([0, 1, 2], v, false);
        assert_relative_eq!(e, crate::numeric::rpy_matrix(v), epsilon = 1e-12);
        // Intrinsic z-y-x equals extrinsic x-y-z with the angles reversed.
        let z = euler_matrix([2, 1, 0], [v[2], v[1], v[0]], true);
        assert_relative_eq!(z, e, epsilon = 1e-12);
    }
}

//! `calbench import`: a laser tracker's raw export turned into the measurement CSV
//! (docs/formats.md, "Mapping file").
//!
//! What a real export varies in is named by a mapping file ([`Mapping`]): the field separator
//! and decimal mark, the columns holding the joints, the measured position and orientation,
//! their units, the orientation convention (Euler axis sequence, intrinsic or extrinsic, or a
//! quaternion's component order) and the per-point standard deviations, which become the
//! `sigma_mm` weight column (weighted least squares in every method, [`Measurements::weights`]).
//! A cell that is empty or not a finite number is refused naming the file, the line and the
//! column, and so is a value the measurement CSV would refuse whatever the robot once it is in
//! the written units (an overflow, a point beyond 1 km, a σ out of range); nothing is
//! dropped. Nothing ambiguous is guessed either: a mapped column whose name the header holds
//! twice, and a mapping that names one column for two fields, are refused.
//!
//! [`Measurements::weights`]: crate::measurement::Measurements::weights

use std::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;

use super::csv::{check_coordinate, check_sigma};
use super::rows::{at_line, quoted, Dialect, Rows};
use crate::error::{read_text, shown, Error, Result};
use crate::numeric::{quaternion, rot_x, rot_y, rot_z, Mat3, Real};

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
    /// `(kind, factor to rad or mm)`.
    fn scale(self) -> (&'static str, Real) {
        match self {
            Unit::Rad => ("angle", 1.0),
            Unit::Deg => ("angle", std::f64::consts::PI / 180.0),
            Unit::Mm => ("length", 1.0),
            Unit::M => ("length", 1000.0),
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
    pub unit: Unit,
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
    pub unit: Option<Unit>,
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
    pub unit: Unit,
    /// `"rms"` (default) or `"max"`.
    #[serde(default)]
    pub combine: Combine,
}

/// A checked mapping: an ASCII separator, a decimal mark, resolved conventions, no column
/// named twice.
struct Plan {
    /// The mapping file's text, for the lines of refused keys.
    text: String,
    /// The field separator, one ASCII byte.
    sep: u8,
    decimal: char,
    joints: (Vec<String>, Real),
    position: ([String; 3], Real),
    plus: Vec<String>,
    orientation: Option<Orient>,
    sigma: Option<(Vec<String>, Real, Combine)>,
}

enum Orient {
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
    fn load_plan(path: &Path) -> Result<(Mapping, Plan)> {
        let text = read_text(path)?;
        let m: Mapping = toml::from_str(&text)
            .map_err(|e| Error::file(path, "TOML", e.to_string().trim_end()))?;
        crate::error::refuse_toml_underflow(path, &text)?;
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
            .ok_or_else(|| {
                bad(
                    "separator",
                    format!(
                        "{}: an ASCII character other than the quote and a line break",
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
        let length = |key: &str, u: Unit| match u.scale() {
            ("length", f) => Ok(f),
            _ => Err(bad(key, "must be \"mm\" or \"m\"".into())),
        };
        let position = (
            self.position.columns.clone(),
            length("position.unit", self.position.unit)?,
        );
        let orientation = self
            .orientation
            .as_ref()
            .map(|o| o.plan(path, &text))
            .transpose()?;
        let sigma = match &self.sigma {
            Some(s) if s.position.is_empty() => {
                return Err(bad("sigma.position", "names no column".into()))
            }
            Some(s) => Some((s.position.clone(), length("sigma.unit", s.unit)?, s.combine)),
            None => None,
        };
        Ok(Plan {
            text,
            sep,
            decimal,
            joints: (self.joints.columns.clone(), from / to),
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
                    .map(|c| "xyz".find(c.to_ascii_lowercase()))
                    .collect::<Option<_>>()
                    .filter(|a: &Vec<usize>| a.len() == 3 && a[0] != a[1] && a[1] != a[2])
                    .ok_or_else(|| {
                        bad(
                            "sequence",
                            "three of x, y, z, no axis twice in a row (\"xyz\", \"zyz\")",
                        )
                    })?;
                let frame = self
                    .frame
                    .ok_or_else(|| bad("frame", "missing: \"intrinsic\" or \"extrinsic\""))?;
                let unit = self
                    .unit
                    .ok_or_else(|| bad("unit", "missing: \"deg\" or \"rad\""))?;
                let scale = match unit.scale() {
                    ("angle", f) => f,
                    _ => return Err(bad("unit", "must be \"deg\" or \"rad\"")),
                };
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

/// Reads the export `raw` as `mapping` says and writes the measurement CSV `out`; returns the
/// number of rows written. The export is read by the `csv` crate as the measurement files are
/// (docs/formats.md § 5.1): quoted fields, CRLF line ends and a UTF-8 byte-order mark; its
/// header is its first line that is not blank.
pub fn import(raw: &Path, mapping_path: &Path, out: &Path) -> Result<usize> {
    let (s, rows) = import_text(raw, mapping_path)?;
    std::fs::write(out, s).map_err(|e| Error::io(out, e))?;
    Ok(rows)
}

/// Reads the export `raw` as `mapping` says: the measurement CSV's text ([`import`]) and its
/// number of rows.
pub fn import_text(raw: &Path, mapping_path: &Path) -> Result<(String, usize)> {
    let (_, plan) = Mapping::load_plan(mapping_path)?;
    let dialect = Dialect::Export {
        separator: plan.sep,
    };
    let mut t = Rows::open_with(raw, "of column names", dialect)?;
    let header = t.names.clone();
    let header_line = t.header_line;
    // A column is refused at the line of its entry (`joints.columns[2]`), named by its key.
    let find = |key: &str, entry: usize, name: &str| -> Result<usize> {
        let mut at = header.iter().enumerate().filter(|(_, h)| *h == name);
        match (at.next(), at.next()) {
            (Some((i, _)), None) => Ok(i),
            (Some((i, _)), Some((k, _))) => Err(at_line(
                raw,
                header_line,
                &format!(", column {name}"),
                format!(
                    "column \"{name}\" appears twice in the header (columns {} and {}), and \
                     the mapping's `{key}` names it: which one is meant is ambiguous",
                    i + 1,
                    k + 1
                ),
            )),
            (None, _) => Err(Error::toml_file(
                mapping_path,
                &plan.text,
                &format!("{key}[{entry}]"),
                key,
                format!(
                    "column \"{name}\" is not in the header of {} ({})",
                    raw.display(),
                    header.join(", ")
                ),
            )),
        }
    };
    let cols = |key: &str, names: &[String]| -> Result<Vec<usize>> {
        names
            .iter()
            .enumerate()
            .map(|(i, n)| find(key, i, n))
            .collect()
    };
    let jc = cols("joints.columns", &plan.joints.0)?;
    let pc = cols("position.columns", &plan.position.0)?;
    let plus = cols("position.plus", &plan.plus)?;
    let oc = match &plan.orientation {
        Some(Orient::Euler { cols: c, .. } | Orient::Quat { cols: c, .. }) => {
            cols("orientation.columns", c)?
        }
        None => Vec::new(),
    };
    let sc = match &plan.sigma {
        Some((c, ..)) => cols("sigma.position", c)?,
        None => Vec::new(),
    };

    let dof = jc.len();
    let mut s = String::with_capacity(128 * 1024);
    let optional = (plan.orientation.is_some(), plan.sigma.is_some(), false);
    super::csv::header(&mut s, dof, optional);
    let mut rows = 0;
    let mut cell = String::new();
    let mut rec = ::csv::StringRecord::new();
    let mut row = Vec::with_capacity(dof + 3);
    while let Some(line) = t.next(&mut rec)? {
        let mut num = |c: usize| -> Result<Real> {
            let f = rec.get(c).unwrap_or("");
            let place = format!(", column {}", header[c]);
            if f.is_empty() {
                return Err(at_line(raw, line, &place, "empty cell".into()));
            }
            cell.clear();
            cell.extend(
                f.chars()
                    .map(|ch| if ch == plan.decimal { '.' } else { ch }),
            );
            let v = cell
                .parse::<Real>()
                .ok()
                .filter(|v| v.is_finite() && !(plan.decimal == ',' && f.contains('.')));
            // Quoted as the export writes it, as every refusal of a cell is.
            if let Some(msg) = v.and_then(|v| crate::error::underflow(f, v)) {
                return Err(at_line(raw, line, &place, msg));
            }
            v.ok_or_else(|| {
                // A number in the other decimal mark: the mapping's `decimal` is the
                // likely cause, not the cell.
                let other = if plan.decimal == '.' { ',' } else { '.' };
                let swapped: String = f
                    .chars()
                    .map(|ch| if ch == other { '.' } else { ch })
                    .collect();
                let hint =
                    if f.contains(other) && swapped.parse::<Real>().is_ok_and(Real::is_finite) {
                        format!(
                        " with the mapping's decimal = \"{}\" (this export writes \"{other}\"?)",
                        plan.decimal
                    )
                    } else {
                        String::new()
                    };
                let f = super::rows::quoted(f);
                at_line(
                    raw,
                    line,
                    &place,
                    format!("{f} is not a finite number{hint}"),
                )
            })
        };
        row.clear();
        for &c in &jc {
            let v = num(c)?;
            let q = v * plan.joints.1;
            // No robot file takes a joint value beyond a length's range (a point's), whatever
            // its unit and kind (ten turns of a revolute joint, a prismatic joint's kilometre).
            let most = super::csv::MAX_POINT_MM;
            if !q.is_finite() || q.abs() > most {
                let why = match q.is_finite() {
                    true => format!("is beyond ±{most}, which no robot's joint reaches"),
                    false => format!("overflows: it is {q}"),
                };
                return Err(at_line(
                    raw,
                    line,
                    &format!(", column {}", header[c]),
                    format!(
                        "{} {why} after its conversion from `joints.unit` to \
                         `joints.write_unit`",
                        shown(v)
                    ),
                ));
            }
            row.push(q);
        }
        for (k, &c) in pc.iter().enumerate() {
            let v = match plus.get(k) {
                Some(&p) => num(c)? + num(p)?,
                None => num(c)?,
            } * plan.position.1;
            check_coordinate(v)
                .map_err(|m| at_line(raw, line, &format!(", column {}", header[c]), m))?;
            row.push(v);
        }
        let cells: Vec<String> = row
            .iter()
            .map(|&v| crate::measurement::csv::fixed(v, 9))
            .collect();
        s.push_str(&cells.join(","));
        if let Some(o) = &plan.orientation {
            let q = match o {
                Orient::Euler {
                    axes,
                    intrinsic,
                    scale,
                    ..
                } => {
                    let mut v = [0.0; 3];
                    for (k, &c) in oc.iter().enumerate() {
                        let read = num(c)?;
                        v[k] = read * scale;
                        // An angle beyond a turn is no tracker's reading (the sine of 1e300
                        // rad is noise).
                        if v[k].abs() > std::f64::consts::TAU * (1.0 + 1e-12) {
                            return Err(at_line(
                                raw,
                                line,
                                &format!(", column {}", header[c]),
                                format!("{} is beyond one turn", shown(read)),
                            ));
                        }
                    }
                    quaternion(&euler_matrix(*axes, v, *intrinsic))
                }
                Orient::Quat { at, .. } => {
                    let mut q = [0.0; 4];
                    for (k, &i) in at.iter().enumerate() {
                        q[k] = num(oc[i])?;
                    }
                    let n = q.iter().map(|v| v * v).sum::<Real>().sqrt();
                    if (n - 1.0).abs() > 1e-3 {
                        return Err(at_line(
                            raw,
                            line,
                            &format!(", column {}", header[oc[0]]),
                            format!("the quaternion has norm {}, not 1", shown(n)),
                        ));
                    }
                    q.map(|v| v / n)
                }
            };
            for v in q {
                let _ = write!(s, ",{}", crate::measurement::csv::fixed(v, 12));
            }
        }
        if let Some((_, scale, combine)) = &plan.sigma {
            let mut acc: Real = 0.0;
            for &c in &sc {
                let v = num(c)? * scale;
                let place = format!(", column {}", header[c]);
                if v <= 0.0 {
                    return Err(at_line(
                        raw,
                        line,
                        &place,
                        format!("standard deviation {} mm: must be positive", shown(v)),
                    ));
                }
                check_sigma(v).map_err(|m| at_line(raw, line, &place, m))?;
                acc = match combine {
                    Combine::Rms => acc + v * v,
                    Combine::Max => acc.max(v),
                };
            }
            let sigma = match combine {
                Combine::Rms => (acc / sc.len() as Real).sqrt(),
                Combine::Max => acc,
            };
            let _ = write!(s, ",{}", crate::measurement::csv::fixed(sigma, 9));
        }
        s.push('\n');
        rows += 1;
    }
    if rows == 0 {
        return Err(Error::file(
            raw,
            "rows",
            "the export has a header and no data rows",
        ));
    }
    Ok((s, rows))
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

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

mod mapping;
use mapping::Orient;
pub use mapping::{
    euler_matrix, Combine, EulerFrame, JointColumns, Mapping, OrientationColumns, OrientationKind,
    PositionColumns, SigmaColumns, Unit,
};

use super::csv::{check_coordinate, check_joints, check_sigma, user_limits};
use super::rows::{at_line, quoted, Dialect, Rows};
use super::JointSpace;
use crate::error::{shown, Error, Result};
use crate::numeric::{quaternion, Real};
/// Reads the export `raw` as `mapping` says and writes the measurement CSV `out`; returns the
/// number of rows written. The export is read by the `csv` crate as the measurement files are
/// (docs/formats.md § 5.1): quoted fields, CRLF line ends and a UTF-8 byte-order mark; its
/// header is its first line that is not blank.
pub fn import(raw: &Path, mapping_path: &Path, out: &Path) -> Result<usize> {
    let (s, lines) = import_text(raw, mapping_path, None)?;
    std::fs::write(out, s).map_err(|e| Error::io(out, e))?;
    Ok(lines.len())
}

/// Where the header read as one column holds another usual separator than `sep` (`;`, tab,
/// `,` or `|`), the words that name it: a `;` export read with `separator = ","`.
fn other_separator(header: &[String], sep: u8) -> String {
    let [only] = header else {
        return String::new();
    };
    [b';', b'\t', b',', b'|']
        .into_iter()
        .filter(|c| *c != sep)
        .find(|c| only.contains(char::from(*c)))
        .map_or(String::new(), |c| {
            format!(
                "; the header reads as one column, and holds {:?}: is the mapping's \
                 `separator` the export's?",
                char::from(c)
            )
        })
}

/// Reads the export `raw` as `mapping` says: the measurement CSV's text ([`import`]) and the
/// line of the export each of its rows was read from, by which a refusal names a reading.
/// Given the `robot` the rows are for, a joint value outside its limits is refused here, at
/// the export's column and with the value as the export writes it.
pub fn import_text(
    raw: &Path,
    mapping_path: &Path,
    robot: Option<&dyn JointSpace>,
) -> Result<(String, Vec<u64>)> {
    let (_, plan) = Mapping::load_plan(mapping_path)?;
    let (written, key) = plan.written;
    if let (Some(robot), Some(unit)) = (robot, written.angle()) {
        if let Some(takes) = robot.angle_unit().filter(|u| *u != unit) {
            let takes: &str = takes.into();
            let msg = format!(
                "writes the joint values in {}, and robot \"{}\" takes its joint angles in \
                 {takes}: they would be read as {takes}; write them in {takes}",
                written.name(),
                robot.name()
            );
            return Err(Error::toml_file(mapping_path, &plan.text, key, key, msg));
        }
    }
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
                    "column \"{name}\" is not in the header of {} ({}){}",
                    raw.display(),
                    header.join(", "),
                    other_separator(&header, plan.sep)
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
    let limits = robot
        .filter(|r| r.dof() == dof)
        .map(|r| (r, user_limits(r)));
    let mut s = String::with_capacity(128 * 1024);
    let optional = (plan.orientation.is_some(), plan.sigma.is_some(), false);
    super::csv::header(&mut s, dof, optional);
    let mut lines = Vec::new();
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
        if let Some((robot, (lo, hi))) = &limits {
            check_joints(*robot, &row, (lo, hi)).map_err(|(j, msg)| {
                let place = format!(", column {}", header[jc[j]]);
                let msg = match plan.joints.1 == 1.0 {
                    true => msg,
                    false => format!(
                        "{msg} (written {} {})",
                        quoted(rec.get(jc[j]).unwrap_or("")),
                        plan.joints.2.name()
                    ),
                };
                at_line(raw, line, &place, msg)
            })?;
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
        lines.push(line);
    }
    if lines.is_empty() {
        return Err(Error::file(
            raw,
            "rows",
            "the export has a header and no data rows",
        ));
    }
    Ok((s, lines))
}

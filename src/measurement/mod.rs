//! The one measurement type of calbench: what an instrument delivers, simulated or real.
//!
//! The simulator ([`crate::sim::measure_poses`]) produces it, the measurement CSV
//! ([`crate::measurement::csv`]) reads and writes it, and every identification method reads it
//! through [`crate::identify::CalibrationProblem`]. What only a simulation knows (which
//! points are outliers, the sag, the noise-free points) is kept beside it, in
//! [`crate::sim::SimTruth`], never inside it.

pub mod csv;
pub mod import;
pub mod kind;
pub mod kind_csv;
pub(crate) mod rows;
pub mod units;

use crate::error::{Error, Result};
use crate::numeric::{quaternion_matrix, Frame, Mat3, Real, Vec3};

/// What is measured per pose.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measure {
    /// The target point: 3 rows per pose.
    Position,
    /// The target point and the frame's orientation: 6 rows per pose.
    Pose,
}

impl Measure {
    /// Rows per pose.
    pub fn rows(self) -> usize {
        match self {
            Measure::Position => 3,
            Measure::Pose => 6,
        }
    }
}

/// What the measurement files need to know of a robot's joints: their count, the robot's
/// name (for messages), the conversion between the files' joint units and the internal ones
/// (mm, rad), and the joint limits. [`crate::robot::Robot`] is the one implementation; the
/// trait keeps this layer below the robot model.
pub trait JointSpace {
    /// The robot's name.
    fn name(&self) -> &str;
    /// Number of joints.
    fn dof(&self) -> usize;
    /// Joint values from internal units to the file's units.
    fn q_to_user(&self, q: &[Real]) -> Vec<Real>;
    /// Joint values from the file's units to internal units.
    fn q_from_user(&self, q: &[Real]) -> Vec<Real>;
    /// The limits of joint `j` (internal units).
    fn limits(&self, j: usize) -> (Real, Real);
    /// The decimals that write joint `j`'s value in the file's unit as finely as 9 decimals
    /// of a degree or a millimetre do.
    fn decimals(&self, _j: usize) -> usize {
        9
    }
    /// The unit its revolute joints' values are written in, `None` without one.
    fn angle_unit(&self) -> Option<units::AngleUnit> {
        None
    }
}

/// Measured poses: joint values, measured target points and, for full-pose data, measured
/// orientations, in the instrument's frame; optionally a standard deviation per point.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Measurements {
    /// Joint values of each pose (internal units: rad, mm).
    pub qs: Vec<Vec<Real>>,
    /// Measured target points in the instrument's frame (mm).
    pub points: Vec<Vec3>,
    /// Measured orientations `[qw, qx, qy, qz]` in the instrument's frame (full-pose data).
    pub quats: Option<Vec<[Real; 4]>>,
    /// Standard deviation of each measured point (mm), when the instrument reports one
    /// (docs/formats.md, column `sigma_mm`). The identification weighs point `i` by
    /// [`Measurements::weights`].
    pub sigma_mm: Option<Vec<Real>>,
    /// Payload at the tool point per pose (kg), when the measurement says (docs/formats.md, column
    /// `payload_kg`): the load under which the elasto-geometric model ([`crate::robot::Param::Compliance`])
    /// computes each pose's gravity torques. `None`: no payload.
    pub payload_kg: Option<Vec<Real>>,
}

/// Joint values this close (rad, or mm for a prismatic joint) are one pose to
/// [`Measurements::shared_rows`].
pub const SAME_JOINT: Real = 1e-6;

/// Measured points this close in each coordinate (mm, 0.1 µm) are one reading to
/// [`Measurements::shared_rows`]: well below a laser tracker's noise, well above a copy's
/// rounding to six decimals.
pub const SAME_POINT_MM: Real = 1e-4;

/// The grid cell (mm) [`Measurements::shared_rows`] sorts points into.
const SAME_CELL_MM: Real = 1.0;

/// Whether `a` and `b` have the same length and each value of `a` lies within `tol` of
/// `b`'s: the test of a repeated reading's joint values and measured values.
pub fn within(a: &[Real], b: &[Real], tol: Real) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// The refusal's words for validation rows that repeat calibration rows: `rows`, the pairs
/// of [`Measurements::shared_rows`] numbered as `numbered` says (`rows of the data`), the
/// first five named.
pub fn shared_rows_refusal(rows: &[(usize, usize)], numbered: &str) -> String {
    repeated_readings_refusal(rows, SAME_MEASUREMENT, numbered)
}

/// What makes two tracker rows the same measurement, as refusals say it.
pub const SAME_MEASUREMENT: &str = "the same joint values and measured point";

/// [`shared_rows_refusal`] of readings that are the same when `same` holds (`the same joint
/// values` for a socket's, which has no measured point).
pub fn repeated_readings_refusal(rows: &[(usize, usize)], same: &str, numbered: &str) -> String {
    let (cal, val) = (
        |r: usize| format!("calibration row {r}"),
        |r: usize| format!("validation row {r}"),
    );
    repeated_readings_named(rows, same, &format!("0-based {numbered}"), [&cal, &val])
}

/// [`repeated_readings_refusal`] of rows each side names in its own words (`names`: the
/// calibration's, the validation's; `line 4 of s2.csv`), as `numbered` says.
pub fn repeated_readings_named(
    rows: &[(usize, usize)],
    same: &str,
    numbered: &str,
    names: [&dyn Fn(usize) -> String; 2],
) -> String {
    format!(
        "{} validation row(s) repeat a calibration row ({same}; {numbered}): {}; a validation \
         row must not calibrate",
        rows.len(),
        pairs_named(rows, names)
    )
}

/// The words a calibration's repeated rows are refused with ([`repeated_rows_refusal`]).
pub const REPEATED_CALIBRATION: &str = "a copy counts one reading twice, and the fit would \
     state a precision it does not have (a second reading of a pose differs by the \
     instrument's noise)";

/// The words a validation's repeated rows are refused with ([`repeated_rows_refusal`]).
pub const REPEATED_VALIDATION: &str =
    "a copy weighs one point twice in the validation's figures (a second reading of a pose \
     differs by the instrument's noise)";

/// The refusal's words for rows of one file that repeat an earlier row of it: `rows`, the
/// pairs of [`Measurements::repeated_rows`] (or of a kind file's), the first five named, what
/// makes them the same (`same`: [`SAME_MEASUREMENT`] for a tracker's), and `why` a
/// copy is refused ([`REPEATED_CALIBRATION`], [`REPEATED_VALIDATION`]).
pub fn repeated_rows_refusal(rows: &[(usize, usize)], same: &str, why: &str) -> String {
    let row = |r: usize| format!("row {r}");
    repeated_rows_named(rows, same, "0-based rows", &row, why)
}

/// [`repeated_rows_refusal`] of rows named by `name` (`line 4 of s2.csv`), as `numbered` says.
pub fn repeated_rows_named(
    rows: &[(usize, usize)],
    same: &str,
    numbered: &str,
    name: &dyn Fn(usize) -> String,
    why: &str,
) -> String {
    format!(
        "{} row(s) repeat an earlier row ({same}; {numbered}): {}; {why}",
        rows.len(),
        pairs_named(rows, [name, name])
    )
}

/// The first five pairs of `rows`, each `a = b` as `names` [a's, b's] name them, and how many
/// more.
fn pairs_named(rows: &[(usize, usize)], [a, b]: [&dyn Fn(usize) -> String; 2]) -> String {
    let shown: Vec<String> = rows
        .iter()
        .take(5)
        .map(|&(x, y)| format!("{} = {}", a(x), b(y)))
        .collect();
    match rows.len() - shown.len() {
        0 => shown.join(", "),
        more => format!("{}, and {more} more", shown.join(", ")),
    }
}

impl Measurements {
    /// The pairs (calibration row, validation row) of `self` (calibration) and `val` that
    /// hold the same measurement: joint values within [`SAME_JOINT`] and a measured point
    /// within [`SAME_POINT_MM`] in each coordinate, whatever else the rows carry (an
    /// orientation, a σ, a payload). A row copied, rounded to a few decimals or nudged is
    /// thereby the same measurement; a second reading of one pose differs by the instrument's
    /// noise, micrometres. Each validation row is paired with the first calibration row it
    /// repeats, in validation-row order.
    pub fn shared_rows(&self, val: &Measurements) -> Vec<(usize, usize)> {
        self.shared_rows_where(val, |_, _| true)
    }

    /// The pairs (earlier row, row) of `self` that hold the same measurement, as
    /// [`Measurements::shared_rows`] tells them: each row that repeats an earlier one, with the
    /// first it repeats, in row order.
    pub fn repeated_rows(&self) -> Vec<(usize, usize)> {
        self.shared_rows_where(self, |first, row| first < row)
    }

    /// [`Measurements::shared_rows`], the pairs `keep` keeps.
    fn shared_rows_where(
        &self,
        val: &Measurements,
        keep: impl Fn(usize, usize) -> bool,
    ) -> Vec<(usize, usize)> {
        // The calibration rows sorted by the grid cell of their point ([`SAME_CELL_MM`]), the
        // cell computed where it is compared (an index a row, not a cell and an index: 2 000 000
        // rows hold 16 MB, not 64): a validation point's matches lie in the cells of its
        // coordinates ± the tolerance.
        let cell = |v: Real| (v / SAME_CELL_MM).floor() as i64;
        let key = |i: usize| -> [i64; 3] { self.points[i].map(cell).into() };
        let mut cells: Vec<usize> = (0..self.len()).collect();
        cells.sort_unstable_by_key(|&i| (key(i), i));
        let same = |c: usize, v: usize| {
            within(&self.qs[c], &val.qs[v], SAME_JOINT)
                && within(
                    self.points[c].as_slice(),
                    val.points[v].as_slice(),
                    SAME_POINT_MM,
                )
        };
        (0..val.len())
            .filter_map(|v| {
                let p = val.points[v];
                let span = |k: usize| [cell(p[k] - SAME_POINT_MM), cell(p[k] + SAME_POINT_MM)];
                let (xs, ys, zs) = (span(0), span(1), span(2));
                let mut first: Option<usize> = None;
                for x in xs[0]..=xs[1] {
                    for y in ys[0]..=ys[1] {
                        for z in zs[0]..=zs[1] {
                            let at = [x, y, z];
                            let from = cells.partition_point(|&c| key(c) < at);
                            for &c in cells[from..].iter().take_while(|&&c| key(c) == at) {
                                if same(c, v) && first.is_none_or(|f| c < f) {
                                    first = Some(c);
                                }
                            }
                        }
                    }
                }
                first.filter(|&c| keep(c, v)).map(|c| (c, v))
            })
            .collect()
    }

    /// Number of measured poses.
    pub fn len(&self) -> usize {
        self.qs.len()
    }

    /// True when there is no pose.
    pub fn is_empty(&self) -> bool {
        self.qs.is_empty()
    }

    /// Position only, or full pose (orientations present).
    pub fn measure(&self) -> Measure {
        if self.quats.is_some() {
            Measure::Pose
        } else {
            Measure::Position
        }
    }

    /// Per-point weights `w_i ∝ 1/σ_i²`, normalised to a mean of 1 (so that the settings of
    /// damped and regularised methods keep their meaning); `None` when no standard deviations
    /// were given (every point weighs 1).
    pub fn weights(&self) -> Option<Vec<Real>> {
        let s = self.sigma_mm.as_ref()?;
        let inv: Vec<Real> = s.iter().map(|v| 1.0 / (v * v)).collect();
        let mean = inv.iter().sum::<Real>() / inv.len().max(1) as Real;
        Some(inv.iter().map(|w| w / mean).collect())
    }

    /// The measured points and orientations in another frame: `frame` applied to every point
    /// and `frame.rot · R(q)` to every orientation (registration into the base frame).
    pub fn in_frame(&self, frame: &Frame) -> (Vec<Vec3>, Option<Vec<Mat3>>) {
        (
            self.points.iter().map(|p| frame.apply(p)).collect(),
            self.quats.as_ref().map(|qs| {
                qs.iter()
                    .map(|q| frame.rot * quaternion_matrix(q))
                    .collect()
            }),
        )
    }

    /// Checks that the lengths agree and every value is finite (standard deviations positive).
    pub fn check(&self) -> Result<()> {
        let n = self.qs.len();
        let bad = |msg: String| Err(Error::setting("measurements", msg));
        if self.points.len() != n {
            return bad(format!(
                "{n} poses but {} measured points",
                self.points.len()
            ));
        }
        if let Some(q) = &self.quats {
            if q.len() != n {
                return bad(format!("{n} poses but {} orientations", q.len()));
            }
        }
        if let Some(s) = &self.sigma_mm {
            if s.len() != n {
                return bad(format!("{n} poses but {} standard deviations", s.len()));
            }
            if let Some(i) = s.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
                return bad(format!(
                    "point {i}: the standard deviation must be finite and positive, got {}",
                    s[i]
                ));
            }
        }
        if let Some(i) = (0..n).find(|&i| {
            self.qs[i].iter().any(|v| !v.is_finite())
                || self.points[i].iter().any(|v| !v.is_finite())
        }) {
            return bad(format!("pose {i}: non-finite value"));
        }
        Ok(())
    }
}

/// Checks per-point weights: one finite, positive weight for each of `n` points (setting
/// `weights`).
pub fn check_weights(w: &[Real], n: usize) -> Result<()> {
    if w.len() != n || w.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(Error::setting(
            "weights",
            format!("need {n} finite positive weights, got {} ({w:?})", w.len()),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_are_inverse_variances_with_mean_one() {
        let m = Measurements {
            qs: vec![vec![0.0]; 3],
            points: vec![Vec3::zeros(); 3],
            quats: None,
            sigma_mm: Some(vec![0.01, 0.02, 0.01]),
            payload_kg: None,
        };
        let w = m.weights().unwrap();
        // 1/σ² = 10000, 2500, 10000; mean 7500.
        approx::assert_relative_eq!(w[0], 4.0 / 3.0, epsilon = 1e-12);
        approx::assert_relative_eq!(w[1], 1.0 / 3.0, epsilon = 1e-12);
        approx::assert_relative_eq!(w.iter().sum::<Real>(), 3.0, epsilon = 1e-12);
        assert!(m.check().is_ok());
        let mut bad = m.clone();
        bad.sigma_mm = Some(vec![0.01, 0.0, 0.01]);
        assert!(bad.check().unwrap_err().to_string().contains("point 1"));
    }

    /// A validation row is the same measurement as a calibration row when it is a copy, even
    /// rounded, nudged or carrying other columns; a second reading of the pose is not.
    #[test]
    fn shared_rows_are_copies_within_the_tolerances_whatever_else_the_rows_carry() {
        let q = |i: usize| vec![0.1 * i as Real, -0.3, 1.2 + 1e-3 * i as Real];
        // Points near the grid's cell borders, so that a match may lie in the next cell.
        let p = |i: usize| Vec3::new(1.0 - 2e-5, 250.0 * i as Real, -3.0 + 1e-5);
        let rows = |n: usize| Measurements {
            qs: (0..n).map(q).collect(),
            points: (0..n).map(p).collect(),
            ..Measurements::default()
        };
        let cal = rows(6);
        // 0: copied with an orientation; 1: rounded to 6 decimals (deg and mm, as a text
        // copy would); 2: x nudged by 3e-5 mm across a cell border; 3: a second reading, 15 µm
        // off; 4: another pose, 1e-3 rad off; 5: the point of row 4 at the joints of row 5.
        let round = |v: Real, d: i32| (v * 10f64.powi(d)).round() / 10f64.powi(d);
        let deg = |v: Real| round(v.to_degrees(), 6).to_radians();
        let mut val = Measurements {
            qs: vec![
                q(0),
                q(1).into_iter().map(deg).collect(),
                q(2),
                q(3),
                q(4).iter().map(|v| v + 1e-3).collect(),
                q(5),
            ],
            points: vec![
                p(0),
                p(1).map(|v| round(v, 6)),
                p(2) + Vec3::new(3e-5, 0.0, 0.0),
                p(3) + Vec3::new(0.0, 0.015, 0.0),
                p(4),
                p(4),
            ],
            quats: Some(vec![[1.0, 0.0, 0.0, 0.0]; 6]),
            ..Measurements::default()
        };
        assert_eq!(cal.shared_rows(&val), [(0, 0), (1, 1), (2, 2)]);
        // Either way round, and a calibration holding a row twice names its first.
        val.quats = None;
        assert_eq!(val.shared_rows(&cal), [(0, 0), (1, 1), (2, 2)]);
        let mut twice = rows(6);
        twice.qs.insert(0, q(2));
        twice.points.insert(0, p(2));
        assert_eq!(twice.shared_rows(&val), [(1, 0), (2, 1), (0, 2)]);
        assert!(rows(0).shared_rows(&val).is_empty() && cal.shared_rows(&rows(0)).is_empty());
    }
}

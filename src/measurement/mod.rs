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

/// The refusal's words for validation rows that repeat calibration rows: `rows`, the pairs
/// of [`Measurements::shared_rows`] numbered as `numbered` says (`rows of the data`), the
/// first five named.
pub fn shared_rows_refusal(rows: &[(usize, usize)], numbered: &str) -> String {
    let shown: Vec<String> = rows
        .iter()
        .take(5)
        .map(|(c, v)| format!("calibration row {c} = validation row {v}"))
        .collect();
    let more = match rows.len() - shown.len() {
        0 => String::new(),
        more => format!(", and {more} more"),
    };
    format!(
        "{} validation row(s) repeat a calibration row (the same joint values and measured \
         point; 0-based {numbered}): {}{more}; a validation row must not calibrate",
        rows.len(),
        shown.join(", ")
    )
}

impl Measurements {
    /// The pairs (calibration row, validation row) of `self` (calibration) and `val` that
    /// hold the same measurement: the same joint values, measured point and orientation, to
    /// the bit. In validation-row order.
    pub fn shared_rows(&self, val: &Measurements) -> Vec<(usize, usize)> {
        let key = |m: &Measurements, i: usize| -> Vec<u64> {
            let mut k: Vec<u64> = m.qs[i].iter().map(|v| v.to_bits()).collect();
            k.extend(m.points[i].iter().map(|v| v.to_bits()));
            if let Some(q) = &m.quats {
                k.extend(q[i].iter().map(|v| v.to_bits()));
            }
            k
        };
        let seen: std::collections::HashMap<Vec<u64>, usize> =
            (0..self.len()).rev().map(|i| (key(self, i), i)).collect();
        (0..val.len())
            .filter_map(|v| seen.get(&key(val, v)).map(|&c| (c, v)))
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
}

//! The simulated laser tracker.
//!
//! The tracker frame differs from the robot base by a rigid transform (the scenario's
//! `tracker.pose`). A measured point is the true target point expressed in the tracker frame
//! plus Gaussian noise, independent per axis, with
//! `σ = (mpe_a_um + mpe_b_um_per_m · r) / coverage` µm, `r` the distance from the tracker to
//! the point in m: the MPE of the Leica AT901/AT960, 15 µm + 6 µm/m (Li 2018 §3, Qiao 2021
//! §4), read as a `coverage`-σ bound. With `measure = "pose"` the orientation of the tool
//! frame is measured too, turned by a small random rotation whose rotation vector has
//! per-axis σ = `angle_noise_deg` (expressed in the tracker frame).

use rand::Rng as _;
use rand_distr::StandardNormal;

use super::settings::TrackerSettings;
use crate::error::Result;
use crate::measurement::Measure;
use crate::numeric::rng::Rng;
use crate::numeric::{Frame, Real, Vec3};

/// A laser tracker with its pose in the robot base frame and its noise model.
#[derive(Clone, Debug, PartialEq)]
pub struct Tracker {
    frame: Frame,
    a_mm: Real,
    b_mm_per_mm: Real,
    coverage: Real,
    measure: Measure,
    angle_sigma_rad: Real,
}

impl Tracker {
    /// A tracker from checked settings (the settings are checked here too).
    pub fn new(s: &TrackerSettings) -> Result<Tracker> {
        s.check()?;
        let d = Real::to_radians;
        let p = s.pose;
        Ok(Tracker {
            frame: Frame::from_xyz_rpy([p[0], p[1], p[2]], [d(p[3]), d(p[4]), d(p[5])]),
            // µm → mm; µm/m → mm/mm.
            a_mm: s.mpe_a_um * 1e-3,
            b_mm_per_mm: s.mpe_b_um_per_m * 1e-6,
            coverage: s.coverage,
            measure: s.measure.measure(),
            angle_sigma_rad: d(s.angle_noise_deg),
        })
    }

    /// The tracker frame in the robot base frame: maps tracker coordinates to base
    /// coordinates.
    pub fn frame(&self) -> Frame {
        self.frame
    }

    /// What the tracker measures (3 or 6 quantities a pose).
    pub fn measures(&self) -> Measure {
        self.measure
    }

    /// Per-axis σ of the orientation noise (rad; 0 for position-only measurement).
    pub fn angle_sigma_rad(&self) -> Real {
        self.angle_sigma_rad
    }

    /// Per-axis σ of the position noise (mm) at a distance of `range_mm` from the tracker.
    pub fn sigma_mm(&self, range_mm: Real) -> Real {
        (self.a_mm + self.b_mm_per_mm * range_mm) / self.coverage
    }

    /// Measures the frame `world` (the true tool frame in the base frame, sag included):
    /// returns the noisy point in the tracker frame and, for full-pose measurement, the
    /// noisy orientation as a unit quaternion `[qw, qx, qy, qz]` (qw ≥ 0) of the measured
    /// frame in the tracker frame. Allocation-free.
    pub fn measure(&self, world: &Frame, rng: &mut Rng) -> (Vec3, Option<[Real; 4]>) {
        let mut p = self.frame.apply_inverse(&world.pos);
        let sigma = self.sigma_mm(p.norm());
        if sigma > 0.0 {
            for k in 0..3 {
                let z: Real = rng.sample(StandardNormal);
                p[k] += sigma * z;
            }
        }
        let quat = match self.measure {
            Measure::Position => None,
            Measure::Pose => {
                let mut r = self.frame.rot.tr_mul(&world.rot);
                if self.angle_sigma_rad > 0.0 {
                    let mut w = Vec3::zeros();
                    for k in 0..3 {
                        let z: Real = rng.sample(StandardNormal);
                        w[k] = self.angle_sigma_rad * z;
                    }
                    r = nalgebra::Rotation3::new(w).into_inner() * r;
                }
                Some(quaternion(&r))
            }
        };
        (p, quat)
    }
}

pub use crate::numeric::{quaternion, quaternion_matrix};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;
    use crate::numeric::Mat3;
    use crate::numeric::{rotation_vector, rpy_matrix};
    use approx::assert_relative_eq;

    fn settings() -> TrackerSettings {
        TrackerSettings {
            pose: [0.0; 6],
            ..Default::default()
        }
    }

    #[test]
    fn noise_free_measurement_is_the_point_in_the_tracker_frame() {
        let s = TrackerSettings {
            pose: [2500.0, 300.0, 400.0, 10.0, -20.0, 170.0],
            mpe_a_um: 0.0,
            mpe_b_um_per_m: 0.0,
            measure: crate::sim::settings::MeasureSetting::Pose,
            ..Default::default()
        };
        let t = Tracker::new(&s).unwrap();
        let world = Frame::from_xyz_rpy([800.0, -200.0, 1200.0], [0.1, 0.2, 0.3]);
        let (p, q) = t.measure(&world, &mut stream(1, "noise"));
        // Hand computation: p = Rᵀ (x − t) with R = Rz(170°) Ry(−20°) Rx(10°).
        let r = rpy_matrix([
            10f64.to_radians(),
            (-20f64).to_radians(),
            170f64.to_radians(),
        ]);
        let want = r.transpose() * (world.pos - Vec3::new(2500.0, 300.0, 400.0));
        assert_relative_eq!(p, want, epsilon = 1e-9);
        let rm = quaternion_matrix(&q.unwrap());
        assert_relative_eq!(rm, r.transpose() * world.rot, epsilon = 1e-12);
    }

    #[test]
    fn sigma_follows_the_mpe_formula() {
        let t = Tracker::new(&settings()).unwrap();
        // (15 µm + 6 µm/m · 5 m) / 2 = 22.5 µm.
        assert_relative_eq!(t.sigma_mm(5000.0), 0.0225, epsilon = 1e-15);
        assert_relative_eq!(t.sigma_mm(0.0), 0.0075, epsilon = 1e-15);
    }

    /// Empirical per-axis σ at 1, 5 and 20 m against the setting (60 000 samples a range:
    /// the relative standard error of the estimate is about 0.3 %).
    #[test]
    fn empirical_noise_matches_the_setting_at_three_ranges() {
        let t = Tracker::new(&settings()).unwrap();
        let mut rng = stream(3, "noise");
        for range in [1000.0, 5000.0, 20000.0] {
            let dir = Vec3::new(1.0, 2.0, -2.0) / 3.0;
            let world = Frame {
                rot: Mat3::identity(),
                pos: dir * range,
            };
            let n = 20_000;
            let mut ss = 0.0;
            let mut sum = Vec3::zeros();
            for _ in 0..n {
                let (p, _) = t.measure(&world, &mut rng);
                let e = p - world.pos;
                sum += e;
                ss += e.norm_squared();
            }
            let sd = (ss / (3 * n) as Real).sqrt();
            let want = (0.015 + 0.006 * range / 1000.0) / 2.0;
            assert!(
                (sd / want - 1.0).abs() < 0.02,
                "range {range}: σ {sd} vs {want}"
            );
            // Unbiased: the mean error is within 5 standard errors of zero.
            assert!((sum / n as Real).amax() < 5.0 * want / (n as Real).sqrt());
        }
    }

    #[test]
    fn orientation_noise_has_the_set_spread() {
        let s = TrackerSettings {
            measure: crate::sim::settings::MeasureSetting::Pose,
            angle_noise_deg: 0.01,
            ..settings()
        };
        let t = Tracker::new(&s).unwrap();
        let world = Frame::from_xyz_rpy([1000.0, 0.0, 0.0], [0.3, -0.2, 1.0]);
        let mut rng = stream(4, "noise");
        let n = 20_000;
        let mut ss = 0.0;
        for _ in 0..n {
            let (_, q) = t.measure(&world, &mut rng);
            let rm = quaternion_matrix(&q.unwrap());
            ss += rotation_vector(&(rm * world.rot.transpose())).norm_squared();
        }
        let sd = (ss / (3 * n) as Real).sqrt().to_degrees();
        assert!((sd / 0.01 - 1.0).abs() < 0.03, "σ {sd}°");
    }
}

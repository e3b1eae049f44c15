//! The virtual measurement: the true robot, the laser tracker with its
//! range-dependent noise, gross outliers, measurement regions and the measurement CSV.
//!
//! - [`settings`]: the scenario sections `[errors]`, `[tracker]`, `[outliers]` and `region`.
//! - [`truth`]: the true robot's parameter errors (Guo 2024 §4.2's paper set or random sets).
//! - [`poses`]: joint configurations in a region (joint space, a Cartesian box as in Qiao
//!   2021 §4, a grid) or from a pose-list file.
//! - [`tracker`]: the tracker frame and noise model (Li 2018 §3, Qiao 2021 §4).
//! - [`csv`]: the measurement CSV of docs/formats.md, written byte-identically for a seed.
//!
//! [`measure_poses`] puts them together: for each joint configuration, the true tool frame
//! (optionally deflected by gravity sag, computed elsewhere) is measured by the tracker; then
//! a number of points is displaced as gross outliers (Ban §3).

pub mod instrument;
pub mod poses;
pub mod rapier;
pub mod sag;
pub mod settings;
pub mod tracker;
pub mod truth;
pub mod unmodelled;

pub use settings::{
    ErrorKind, ErrorSettings, MeasureSetting, OutlierSettings, ParamSelection, Region,
    TrackerSettings,
};
pub use tracker::Tracker;

use rand::Rng as _;
use rand_distr::StandardNormal;

use crate::error::{Error, Result};
pub use crate::measurement::Measurements;
use crate::numeric::rng::Rng;
use crate::numeric::{Frame, Real, Vec3};
use crate::robot::Robot;

/// What only a simulation knows about a measurement, kept beside the [`Measurements`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SimTruth {
    /// Rows displaced as gross outliers, sorted.
    pub outliers: Vec<usize>,
    /// Gravity sag of the target point per pose, `[dx, dy, dz]` in the base frame (mm);
    /// zeros for a rigid arm.
    pub sag_mm: Vec<[Real; 3]>,
    /// Noise-free target points in the base frame (mm), sag included.
    pub true_points: Vec<Vec3>,
    /// Noise-free orientations of the target frame in the base frame, sag included: kept when
    /// the tracker measures full poses (`None` for positions).
    pub true_rotations: Option<Vec<crate::numeric::Mat3>>,
}

/// One simulated measurement campaign: the data an instrument would deliver and the truth
/// behind them.
#[derive(Clone, Debug, PartialEq)]
pub struct Simulated {
    /// The measurements, as a real tracker would deliver them.
    pub data: Measurements,
    /// The simulation's truth.
    pub truth: SimTruth,
}

/// The signature of a sag model: the deflected tool frame (in the base frame) of the true
/// robot at joint values `q` under a payload (kg; `None`: the model's configured payload).
pub type SagFn = dyn Fn(&Robot, &[Real], Option<Real>) -> Result<Frame> + Sync;

/// The joint values of a measurement: those commanded (recorded in the data) and, when the
/// arm has error outside its model ([`unmodelled`]), those it reaches (the true frames'),
/// one per commanded pose.
#[derive(Clone, Copy)]
pub struct Reached<'a> {
    /// The commanded joint values.
    pub commanded: &'a [Vec<Real>],
    /// The reached ones; `None`: the commanded ones.
    pub actual: Option<&'a [Vec<Real>]>,
}

/// The commanded poses of an arm that reaches them.
impl<'a> From<&'a [Vec<Real>]> for Reached<'a> {
    fn from(commanded: &'a [Vec<Real>]) -> Self {
        Reached {
            commanded,
            actual: None,
        }
    }
}

impl<'a> From<&'a Vec<Vec<Real>>> for Reached<'a> {
    fn from(commanded: &'a Vec<Vec<Real>>) -> Self {
        commanded.as_slice().into()
    }
}

/// Measures `true_robot` at each of the poses `reached` (internal units: the joint values
/// commanded, or a [`Reached`] whose arm reaches others) with `tracker`, then displaces
/// outliers (`outliers`, if given). The true frames (and sag) are those of the reached joint
/// values, the data record the commanded ones. `sag` gives the deflected tool frame of the
/// true robot at q; `None` means a rigid arm. `payloads` gives the payload (kg) of each pose,
/// recorded in the measurement's `payload_kg` and passed to `sag`. Draws the tracker noise of
/// pose 0, 1, … in order, then the outliers, all from `rng`.
pub fn measure_poses<'a>(
    true_robot: &Robot,
    reached: impl Into<Reached<'a>>,
    tracker: &Tracker,
    outliers: Option<&OutlierSettings>,
    sag: Option<&SagFn>,
    payloads: Option<&[Real]>,
    rng: &mut Rng,
) -> Result<Simulated> {
    let reached = reached.into();
    let qs = reached.commanded;
    let actual = reached.actual.unwrap_or(qs);
    if actual.len() != qs.len() {
        return Err(Error::Compute(format!(
            "{} reached poses for {} commanded",
            actual.len(),
            qs.len()
        )));
    }
    if let Some(p) = payloads.filter(|p| p.len() != qs.len()) {
        return Err(Error::Compute(format!(
            "{} payloads for {} poses",
            p.len(),
            qs.len()
        )));
    }
    let n_out = match outliers {
        Some(o) => o.count_for(qs.len())?,
        None => 0,
    };
    let dof = true_robot.dof();
    if let Some((i, q)) = qs.iter().enumerate().find(|(_, q)| q.len() != dof) {
        return Err(Error::Compute(format!(
            "pose {i} has {} joint values, the robot has {dof} joints",
            q.len()
        )));
    }
    let chain = true_robot.chain();
    let full_pose = tracker.measures() == crate::measurement::Measure::Pose;
    let m = qs.len();
    let mut points = Vec::with_capacity(m);
    let mut quats = Vec::with_capacity(if full_pose { m } else { 0 });
    let mut sag_mm = Vec::with_capacity(m);
    let mut true_points = Vec::with_capacity(m);
    let mut true_rotations = Vec::with_capacity(if full_pose { m } else { 0 });
    for (i, q) in actual.iter().enumerate() {
        let rigid = chain.fk(q);
        let world = match sag {
            Some(f) => f(true_robot, q, payloads.map(|p| p[i]))?,
            None => rigid,
        };
        let d = world.pos - rigid.pos;
        sag_mm.push([d.x, d.y, d.z]);
        true_points.push(world.pos);
        if full_pose {
            true_rotations.push(world.rot);
        }
        let (p, quat) = tracker.measure(&world, rng);
        points.push(p);
        if let Some(qq) = quat {
            quats.push(qq);
        }
    }
    let outliers = match outliers {
        Some(o) => add_outliers(&mut points, n_out, o.magnitude_mm, rng),
        None => Vec::new(),
    };
    Ok(Simulated {
        data: Measurements {
            qs: qs.to_vec(),
            points,
            quats: full_pose.then_some(quats),
            sigma_mm: None,
            payload_kg: payloads.map(<[Real]>::to_vec),
        },
        truth: SimTruth {
            outliers,
            sag_mm,
            true_points,
            true_rotations: full_pose.then_some(true_rotations),
        },
    })
}

/// Displaces `n` distinct points (chosen uniformly; at most all of them) in uniformly random
/// directions by magnitudes drawn uniformly from `magnitude_mm = [lo, hi]` (Ban §3's gross
/// errors); returns the displaced row indices, sorted. The magnitude of each displacement is
/// exact: `|p' − p|` lies in `[lo, hi]`.
pub fn add_outliers(
    points: &mut [Vec3],
    n: usize,
    magnitude_mm: [Real; 2],
    rng: &mut Rng,
) -> Vec<usize> {
    let n = n.min(points.len());
    let mut rows = rand::seq::index::sample(rng, points.len(), n).into_vec();
    rows.sort_unstable();
    let [lo, hi] = magnitude_mm;
    for &i in &rows {
        let mag = lo + (hi - lo) * rng.random::<Real>();
        // A uniformly random direction: a normalised Gaussian vector.
        let dir = loop {
            let v = Vec3::new(
                rng.sample(StandardNormal),
                rng.sample(StandardNormal),
                rng.sample(StandardNormal),
            );
            let l = v.norm();
            if l > 1e-12 {
                break v / l;
            }
        };
        points[i] += dir * mag;
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;
    use crate::robot::sampling::uniform_joint_poses;
    use approx::assert_relative_eq;

    fn quiet_tracker() -> Tracker {
        Tracker::new(&TrackerSettings {
            pose: [2500.0, 300.0, 400.0, 0.0, 0.0, 170.0],
            mpe_a_um: 0.0,
            mpe_b_um_per_m: 0.0,
            ..Default::default()
        })
        .unwrap()
    }

    #[test]
    fn noise_free_points_are_fk_in_the_tracker_frame() {
        let robot = crate::robot::builtin::irb2600();
        let qs = uniform_joint_poses(&robot, 20, &mut stream(1, "poses"));
        let t = quiet_tracker();
        let m = measure_poses(&robot, &qs, &t, None, None, None, &mut stream(1, "noise")).unwrap();
        for (i, q) in qs.iter().enumerate() {
            let p = robot.fk(q).pos;
            assert_relative_eq!(t.frame().apply(&m.data.points[i]), p, epsilon = 1e-9);
            assert_relative_eq!(m.truth.true_points[i], p, epsilon = 1e-12);
            assert_eq!(m.truth.sag_mm[i], [0.0; 3]);
        }
        assert!(m.data.quats.is_none());
        assert!(m.truth.outliers.is_empty());
    }

    #[test]
    fn outliers_are_displaced_by_magnitudes_in_range_and_recorded() {
        let robot = crate::robot::builtin::irb2600();
        let qs = uniform_joint_poses(&robot, 50, &mut stream(2, "poses"));
        let t = quiet_tracker();
        let o = OutlierSettings {
            count: Some(8),
            fraction: None,
            magnitude_mm: [0.5, 1.0],
        };
        let m = measure_poses(
            &robot,
            &qs,
            &t,
            Some(&o),
            None,
            None,
            &mut stream(2, "noise"),
        )
        .unwrap();
        assert_eq!(m.truth.outliers.len(), 8);
        assert!(m.truth.outliers.windows(2).all(|w| w[0] < w[1]));
        for i in 0..qs.len() {
            let d = (t.frame().apply(&m.data.points[i]) - m.truth.true_points[i]).norm();
            if m.truth.outliers.contains(&i) {
                assert!((0.5 - 1e-9..=1.0 + 1e-9).contains(&d), "row {i}: {d}");
            } else {
                assert!(d < 1e-9, "row {i} moved by {d}");
            }
        }
        let too_many = OutlierSettings {
            count: Some(51),
            ..o
        };
        assert!(measure_poses(
            &robot,
            &qs,
            &t,
            Some(&too_many),
            None,
            None,
            &mut stream(2, "n")
        )
        .is_err());
    }

    #[test]
    fn outlier_directions_are_spread_and_magnitudes_uniform() {
        let mut pts = vec![Vec3::zeros(); 4000];
        let rows = add_outliers(&mut pts, 4000, [0.2, 0.4], &mut stream(5, "outliers"));
        assert_eq!(rows.len(), 4000);
        let mean_dir: Vec3 = pts.iter().map(|p| p / p.norm()).sum::<Vec3>() / 4000.0;
        assert!(mean_dir.norm() < 0.06, "{mean_dir}");
        let mean_mag = pts.iter().map(|p| p.norm()).sum::<Real>() / 4000.0;
        assert!((mean_mag - 0.3).abs() < 0.005, "{mean_mag}");
    }

    #[test]
    fn sag_is_added_to_the_true_points() {
        let robot = crate::robot::builtin::irb2600();
        let qs = uniform_joint_poses(&robot, 5, &mut stream(3, "poses"));
        let t = quiet_tracker();
        let sag = |r: &Robot, q: &[Real], _: Option<Real>| -> Result<Frame> {
            let mut f = r.fk(q);
            f.pos.z -= 0.25;
            Ok(f)
        };
        let m =
            measure_poses(&robot, &qs, &t, None, Some(&sag), None, &mut stream(3, "n")).unwrap();
        for (i, q) in qs.iter().enumerate() {
            assert_relative_eq!(m.truth.sag_mm[i][2], -0.25, epsilon = 1e-9);
            assert_relative_eq!(
                m.truth.true_points[i],
                robot.fk(q).pos - Vec3::new(0.0, 0.0, 0.25),
                epsilon = 1e-9
            );
        }
    }

    #[test]
    fn same_seed_same_measurement() {
        let robot = crate::robot::builtin::tx60();
        let qs = uniform_joint_poses(&robot, 10, &mut stream(4, "poses"));
        let t = Tracker::new(&TrackerSettings {
            measure: MeasureSetting::Pose,
            angle_noise_deg: 0.01,
            ..Default::default()
        })
        .unwrap();
        let a = measure_poses(&robot, &qs, &t, None, None, None, &mut stream(4, "noise")).unwrap();
        let b = measure_poses(&robot, &qs, &t, None, None, None, &mut stream(4, "noise")).unwrap();
        let c = measure_poses(&robot, &qs, &t, None, None, None, &mut stream(5, "noise")).unwrap();
        assert_eq!(a, b);
        assert_ne!(a.data.points, c.data.points);
        assert_eq!(a.data.quats.as_ref().map(Vec::len), Some(10));
    }
}

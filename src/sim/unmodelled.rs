//! Error outside the kinematic model (docs/formats.md `[unmodelled]`): the true arm does not
//! reach the joint values it is commanded to, by an amount no DH parameter can represent.
//!
//! Per revolute joint j, the true joint value at the commanded q_j is
//!
//! q'_j = q_j + A1_j sin(q_j + φ1_j) + A2_j sin(2 q_j + φ2_j) + s_j · b_j / 2
//!
//! - the first and second harmonics of the joint angle (A1, A2, φ1, φ2): the once- and
//!   twice-per-turn transmission error of a gear train or an encoder mounted off-centre;
//! - a backlash of width b_j whose sign depends on the direction of approach: s_j = +1 when
//!   the joint reaches q_j moving up (q_j ≥ the previous pose's value, in measurement order),
//!   −1 moving down. The first pose of each measured sequence (the calibration set, the
//!   validation set) is approached from joint values 0.
//!
//! Prismatic joints are left as they are. Each trial draws, per joint in order, A1 = σ1·N(0,
//! 1), φ1 uniform in [0, 2π), A2 = σ2·N(0, 1), φ2 uniform in [0, 2π), b = |σb·N(0, 1)|, from
//! its own random stream, so the trial's other draws do not move. A term whose amplitude is
//! zero is not added, so zero spreads leave every joint value as it is, to the bit.

use rand::Rng as _;
use rand_distr::StandardNormal;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::numeric::rng::Rng;
use crate::numeric::Real;
use crate::robot::{JointType, Robot};

/// The `[unmodelled]` section: the spreads of the per-trial unmodelled joint errors.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct UnmodelledSettings {
    /// Standard deviation (rad) of the first-harmonic amplitude A1 of each revolute joint.
    #[serde(default)]
    pub harmonic1_rad: Real,
    /// Standard deviation (rad) of the second-harmonic amplitude A2.
    #[serde(default)]
    pub harmonic2_rad: Real,
    /// Standard deviation (rad) of the backlash width b (b = |σ·N(0, 1)|).
    #[serde(default)]
    pub backlash_rad: Real,
}

impl UnmodelledSettings {
    /// Each spread finite and ≥ 0, and at most 0.1 rad (5.7°: beyond any transmission).
    pub fn check(&self) -> Result<()> {
        for (key, v) in [
            ("unmodelled.harmonic1_rad", self.harmonic1_rad),
            ("unmodelled.harmonic2_rad", self.harmonic2_rad),
            ("unmodelled.backlash_rad", self.backlash_rad),
        ] {
            if !(v.is_finite() && (0.0..=0.1).contains(&v)) {
                return Err(Error::setting(
                    key,
                    format!(
                        "{}: must be a number from 0 to 0.1 rad",
                        crate::error::shown(v)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Whether the section adds anything (any spread above zero).
    pub fn is_active(&self) -> bool {
        self.harmonic1_rad > 0.0 || self.harmonic2_rad > 0.0 || self.backlash_rad > 0.0
    }
}

/// One joint's drawn unmodelled error.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct JointError {
    /// First-harmonic amplitude A1 (rad).
    pub a1: Real,
    /// First-harmonic phase φ1 (rad).
    pub phi1: Real,
    /// Second-harmonic amplitude A2 (rad).
    pub a2: Real,
    /// Second-harmonic phase φ2 (rad).
    pub phi2: Real,
    /// Backlash width b (rad).
    pub backlash: Real,
    /// Whether the joint is revolute (only those are affected).
    pub revolute: bool,
}

impl JointError {
    /// The harmonic term A1 sin(q + φ1) + A2 sin(2q + φ2) at the commanded value `q` (terms
    /// with a zero amplitude left out).
    pub fn harmonic(&self, q: Real) -> Real {
        let mut d = 0.0;
        if self.a1 != 0.0 {
            d += self.a1 * (q + self.phi1).sin();
        }
        if self.a2 != 0.0 {
            d += self.a2 * (2.0 * q + self.phi2).sin();
        }
        d
    }

    /// The true joint value at the commanded `q`, approached from `prev`.
    pub fn actual(&self, q: Real, prev: Real) -> Real {
        if !self.revolute {
            return q;
        }
        let mut v = q;
        if self.a1 != 0.0 || self.a2 != 0.0 {
            v += self.harmonic(q);
        }
        if self.backlash != 0.0 {
            let s = if q >= prev { 1.0 } else { -1.0 };
            v += s * 0.5 * self.backlash;
        }
        v
    }
}

/// One trial's unmodelled joint errors.
#[derive(Clone, Debug, PartialEq)]
pub struct Unmodelled {
    /// Per joint, in order.
    pub joints: Vec<JointError>,
}

impl Unmodelled {
    /// Draws the errors of `robot`'s joints from `settings` with `rng` (the trial's own
    /// `unmodelled` stream): per joint A1, φ1, A2, φ2, b in that order, for every joint
    /// (prismatic ones too, unused), so a joint's draw does not depend on the others' kinds.
    pub fn draw(settings: &UnmodelledSettings, robot: &Robot, rng: &mut Rng) -> Unmodelled {
        let tau = 2.0 * std::f64::consts::PI;
        let joints = robot
            .joints
            .iter()
            .map(|j| {
                let n1: Real = rng.sample(StandardNormal);
                let phi1 = tau * rng.random::<Real>();
                let n2: Real = rng.sample(StandardNormal);
                let phi2 = tau * rng.random::<Real>();
                let nb: Real = rng.sample(StandardNormal);
                JointError {
                    a1: settings.harmonic1_rad * n1,
                    phi1,
                    a2: settings.harmonic2_rad * n2,
                    phi2,
                    backlash: (settings.backlash_rad * nb).abs(),
                    revolute: j.kind != JointType::Prismatic,
                }
            })
            .collect();
        Unmodelled { joints }
    }

    /// The joint values the true arm reaches when commanded to `qs` in this order, the first
    /// approached from joint values 0 (see the module docs).
    pub fn actual(&self, qs: &[Vec<Real>]) -> Vec<Vec<Real>> {
        let mut prev = vec![0.0; self.joints.len()];
        qs.iter()
            .map(|q| {
                let a: Vec<Real> = q
                    .iter()
                    .zip(&self.joints)
                    .zip(&prev)
                    .map(|((&v, e), &p)| e.actual(v, p))
                    .collect();
                prev.clone_from(q);
                a
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;

    fn settings(h1: Real, h2: Real, b: Real) -> UnmodelledSettings {
        UnmodelledSettings {
            harmonic1_rad: h1,
            harmonic2_rad: h2,
            backlash_rad: b,
        }
    }

    #[test]
    fn harmonic_term_is_the_closed_form() {
        let e = JointError {
            a1: 1e-3,
            phi1: 0.3,
            a2: -4e-4,
            phi2: 1.1,
            backlash: 0.0,
            revolute: true,
        };
        for q in [-2.0 as Real, -0.5, 0.0, 0.7, 3.0] {
            let want = 1e-3 * (q + 0.3).sin() - 4e-4 * (2.0 * q + 1.1).sin();
            assert!((e.actual(q, 0.0) - (q + want)).abs() < 1e-15, "{q}");
        }
        // The extremes of the first harmonic: q + φ1 = π/2 gives +A1.
        let e1 = JointError { a2: 0.0, ..e };
        let q = std::f64::consts::FRAC_PI_2 - 0.3;
        assert!((e1.harmonic(q) - 1e-3).abs() < 1e-15);
    }

    #[test]
    fn backlash_follows_the_direction_of_approach() {
        let e = JointError {
            a1: 0.0,
            phi1: 0.0,
            a2: 0.0,
            phi2: 0.0,
            backlash: 2e-3,
            revolute: true,
        };
        let u = Unmodelled {
            joints: vec![
                e,
                JointError {
                    revolute: false,
                    ..e
                },
            ],
        };
        let qs = vec![
            vec![0.5, 10.0],
            vec![0.2, 20.0],
            vec![0.2, 5.0],
            vec![0.9, 5.0],
        ];
        let a = u.actual(&qs);
        // Up from 0, down, not moving (counts as up), up; the prismatic joint untouched.
        let want = [0.501, 0.199, 0.201, 0.901];
        for (i, w) in want.iter().enumerate() {
            assert!((a[i][0] - w).abs() < 1e-15, "{i}: {:?}", a[i]);
            assert_eq!(a[i][1], qs[i][1]);
        }
    }

    #[test]
    fn zero_spreads_change_nothing_and_draws_are_seeded() {
        let robot = crate::robot::builtin::irb2600();
        let u = Unmodelled::draw(&settings(0.0, 0.0, 0.0), &robot, &mut stream(3, "u"));
        let qs = vec![vec![0.1, -0.2, 0.3, -0.4, 0.5, -0.6], vec![-0.0; 6]];
        let a = u.actual(&qs);
        for (x, y) in a.iter().flatten().zip(qs.iter().flatten()) {
            assert_eq!(x.to_bits(), y.to_bits());
        }
        let s = settings(1e-3, 5e-4, 2e-4);
        let d1 = Unmodelled::draw(&s, &robot, &mut stream(3, "u"));
        let d2 = Unmodelled::draw(&s, &robot, &mut stream(3, "u"));
        let d3 = Unmodelled::draw(&s, &robot, &mut stream(4, "u"));
        assert_eq!(d1, d2);
        assert_ne!(d1, d3);
        assert!(d1.joints.iter().all(|j| j.backlash >= 0.0));
        assert!(settings(0.2, 0.0, 0.0).check().is_err());
        assert!(settings(Real::NAN, 0.0, 0.0).check().is_err());
        assert!(settings(-1e-3, 0.0, 0.0).check().is_err());
        assert!(s.check().is_ok());
    }
}

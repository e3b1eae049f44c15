//! Joint-angle harmonics: a periodic error of each revolute joint's angle (encoder and gear
//! eccentricity, finer periodic errors of the drive at higher orders),
//! `Δq_j = Σ_n a_jn sin n q_j + b_jn cos n q_j` up to [`MAX_HARMONIC_ORDER`], added to
//! the joint's chain variable inside the forward kinematics ([`Param::Harmonic`];
//! docs/formats.md "Joint-angle harmonics").

use crate::numeric::Real;
use crate::robot::param::add_block_offsets;
use crate::robot::{ChainVars, Param, Robot, HARMONIC_TERMS, MAX_HARMONIC_ORDER};

/// Largest magnitude of a harmonic coefficient, rad (about 5.7°): far beyond any encoder or
/// gear eccentricity, small enough that the model stays a small correction.
pub const MAX_HARMONIC_RAD: Real = 0.1;

/// The factors of the harmonic terms at the chain variable with sine `s` and cosine `c`, up
/// to order `orders` (at least 2): `sin q`, `cos q`, `sin 2q`, `cos 2q`, … by the angle
/// addition `sin (n+1)q = sin nq cos q + cos nq sin q`, `cos (n+1)q = cos nq cos q − sin nq
/// sin q` (the second order is `2 s c` and `c² − s²` to the bit); the terms beyond `orders`
/// are zero.
#[inline(always)]
pub fn factors(s: Real, c: Real, orders: usize) -> [Real; HARMONIC_TERMS] {
    let mut f = [0.0; HARMONIC_TERMS];
    f[0] = s;
    f[1] = c;
    for n in 1..orders.clamp(2, MAX_HARMONIC_ORDER) {
        let (sn, cn) = (f[2 * n - 2], f[2 * n - 1]);
        f[2 * n] = sn * c + cn * s;
        f[2 * n + 1] = cn * c - sn * s;
    }
    f
}

/// The highest order (at least 2) among the non-zero entries of the harmonic coefficients
/// or columns `h` of one joint (`HARMONIC_TERMS` entries, `sin`/`cos` pairs).
#[inline]
pub fn orders_used(h: impl Iterator<Item = bool>) -> usize {
    h.enumerate()
        .filter(|(_, on)| *on)
        .map(|(k, _)| k / 2 + 1)
        .max()
        .unwrap_or(0)
        .max(2)
}

/// Whether any harmonic coefficient of `robot` is non-zero. A robot whose values do not
/// hold the harmonic block of its joint count (one being built) has none.
pub fn has_harmonics(robot: &Robot) -> bool {
    robot.any_term(HARMONIC_TERMS, Param::Harmonic)
}

/// Adds to `dv[j]` the harmonic offset of joint `j` at the (undeflected) chain variables
/// `vars`, from the flat parameter `values` of a robot with `dv.len()` joints.
/// Allocation-free.
#[inline]
pub fn add_offsets(values: &[Real], vars: &ChainVars, dv: &mut [Real]) {
    add_block_offsets(values, dv, (HARMONIC_TERMS, Param::Harmonic), |j, h| {
        let (s, c) = vars.1[j];
        let orders = orders_used(h.iter().map(|v| *v != 0.0));
        let f = factors(s, c, orders);
        h[..2 * orders]
            .iter()
            .zip(f)
            .map(|(a, b)| a * b)
            .sum::<Real>()
    });
}

/// Checks the harmonic coefficients of `robot` ([`Robot::check`]): each finite and within
/// ±[`MAX_HARMONIC_RAD`], and only on revolute joints.
pub(crate) fn check(robot: &Robot) -> std::result::Result<(), super::ModelIssue> {
    let terms = (HARMONIC_TERMS, Param::Harmonic as fn(usize, usize) -> Param);
    check_terms(
        robot,
        terms,
        ("harmonics", MAX_HARMONIC_RAD, "rad"),
        |j, _| {
            (robot.joints[j].kind != super::JointType::Revolute).then(|| {
                "only revolute joints have joint-angle harmonics in calbench's model".into()
            })
        },
    )
}

/// Checks a per-joint block of model terms of `robot` (`param(j, k)`, `k` below `terms`),
/// written under the robot file's `key`: each non-zero value finite and within ±`bound`
/// `unit`, and allowed where it stands (`refused(j, param)` says why it is not).
pub(crate) fn check_terms(
    robot: &Robot,
    (terms, param): (usize, fn(usize, usize) -> Param),
    (key, bound, unit): (&str, Real, &str),
    refused: impl Fn(usize, Param) -> Option<String>,
) -> std::result::Result<(), super::ModelIssue> {
    for j in 0..robot.dof() {
        for p in (0..terms).map(|k| param(j, k)) {
            let v = robot.get(p);
            if v == 0.0 {
                continue;
            }
            let msg = if !(v.is_finite() && v.abs() <= bound) {
                format!("must be finite numbers within ±{bound} {unit}, got {v:?}")
            } else if let Some(why) = refused(j, p) {
                why
            } else {
                continue;
            };
            let place = super::joint_place(j, key);
            return Err(super::ModelIssue { place, msg });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The recurrence gives `sin nq`, `cos nq` of the math library within rounding, and the
    /// second order bit for bit as `2 s c`, `c² − s²`.
    #[test]
    fn factors_are_the_multiple_angles() {
        for q in [0.3, -1.7, 2.9, 0.0] {
            let (s, c) = crate::numeric::sin_cos(q);
            let f = factors(s, c, MAX_HARMONIC_ORDER);
            for n in 1..=MAX_HARMONIC_ORDER {
                let x = n as Real * q;
                assert!((f[2 * n - 2] - x.sin()).abs() < 1e-12, "{q} {n}");
                assert!((f[2 * n - 1] - x.cos()).abs() < 1e-12, "{q} {n}");
            }
            assert_eq!(f[2].to_bits(), (2.0 * s * c).to_bits());
            assert_eq!(f[3].to_bits(), (c * c - s * s).to_bits());
            assert!(factors(s, c, 2)[4..].iter().all(|v| *v == 0.0));
        }
        assert_eq!(orders_used([false; 4].into_iter()), 2);
        assert_eq!(orders_used((0..HARMONIC_TERMS).map(|k| k == 23)), 12);
    }
}

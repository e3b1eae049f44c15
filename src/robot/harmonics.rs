//! Joint-angle harmonics: a periodic error of each revolute joint's angle (encoder and gear
//! eccentricity), `Δq_j = a_j sin q_j + b_j cos q_j + c_j sin 2q_j + d_j cos 2q_j`, added to
//! the joint's chain variable inside the forward kinematics ([`Param::Harmonic`];
//! docs/formats.md "Joint-angle harmonics").

use crate::numeric::Real;
use crate::robot::{ChainVars, Param, Robot, HARMONIC_TERMS};

/// Largest magnitude of a harmonic coefficient, rad (about 5.7°): far beyond any encoder or
/// gear eccentricity, small enough that the model stays a small correction.
pub const MAX_HARMONIC_RAD: Real = 0.1;

/// The factors of the harmonic terms at the chain variable with sine `s` and cosine `c`:
/// `sin q`, `cos q`, `sin 2q`, `cos 2q`.
#[inline(always)]
pub fn factors(s: Real, c: Real) -> [Real; HARMONIC_TERMS] {
    [s, c, 2.0 * s * c, c * c - s * s]
}

/// Whether any harmonic coefficient of `robot` is non-zero. A robot whose values do not
/// hold the harmonic block of its joint count (one being built) has none.
pub fn has_harmonics(robot: &Robot) -> bool {
    let dof = robot.dof();
    (0..dof).any(|j| {
        (0..HARMONIC_TERMS).any(|k| {
            robot
                .values
                .get(Param::Harmonic(j, k).index(dof))
                .is_some_and(|v| *v != 0.0)
        })
    })
}

/// Adds to `dv[j]` the harmonic offset of joint `j` at the (undeflected) chain variables
/// `vars`, from the flat parameter `values` of a robot with `dv.len()` joints.
/// Allocation-free.
#[inline]
pub fn add_offsets(values: &[Real], vars: &ChainVars, dv: &mut [Real]) {
    let dof = dv.len();
    for (j, d) in dv.iter_mut().enumerate() {
        let at = Param::Harmonic(j, 0).index(dof);
        let h = &values[at..at + HARMONIC_TERMS];
        if h.iter().all(|v| *v == 0.0) {
            continue;
        }
        let (s, c) = vars.1[j];
        let f = factors(s, c);
        *d += h.iter().zip(f).map(|(a, b)| a * b).sum::<Real>();
    }
}

/// Checks the harmonic coefficients of `robot` ([`Robot::check`]): each finite and within
/// ±[`MAX_HARMONIC_RAD`], and only on revolute joints.
pub(crate) fn check(robot: &Robot) -> std::result::Result<(), super::ModelIssue> {
    for j in 0..robot.dof() {
        for k in 0..HARMONIC_TERMS {
            let v = robot.get(Param::Harmonic(j, k));
            if v == 0.0 {
                continue;
            }
            let place = super::joint_place(j, "harmonics");
            if !(v.is_finite() && v.abs() <= MAX_HARMONIC_RAD) {
                return Err(super::ModelIssue {
                    place,
                    msg: format!(
                        "must be finite numbers within ±{MAX_HARMONIC_RAD} rad, got {v:?}"
                    ),
                });
            }
            if robot.joints[j].kind != super::JointType::Revolute {
                return Err(super::ModelIssue {
                    place,
                    msg: "only revolute joints have joint-angle harmonics in calbench's model"
                        .into(),
                });
            }
        }
    }
    Ok(())
}

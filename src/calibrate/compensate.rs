//! Joint-command compensation (Li 2018 §3): for a controller whose kinematic table is locked,
//! the identified model is used offline to correct the joint commands. A program computed with
//! the nominal model asks for the pose `T_nom(q)`; the corrected command `q'` is the solution of
//! `T_id(q') = T_nom(q)` (position and orientation), found by Gauss–Newton from `q' = q` on the
//! 6-vector error `[Δp (mm); k·log(R_targetR(q')ᵀ) (rad)]`, with a finite-difference joint
//! Jacobian (the error itself is exact, so the fixed point is exact).

use crate::calibrate::validation::rotation_angle_deg;
use crate::numeric::{Frame, Real};
use crate::robot::compliance::loaded_fk;
use crate::robot::Robot;

/// What a corrected row must reach to be flagged `ok`: residual_mm and residual_deg.
pub const ACCEPT_MM: Real = 1e-6;
/// See [`ACCEPT_MM`].
pub const ACCEPT_DEG: Real = 1e-6;

/// The corrected command of one program row.
#[derive(Clone, Debug, PartialEq)]
pub struct Corrected {
    /// Joint values (internal units: rad, mm).
    pub q: Vec<Real>,
    /// Position error of the identified robot at `q` against the nominal pose (mm).
    pub residual_mm: Real,
    /// Orientation error, rotation angle (deg).
    pub residual_deg: Real,
    /// `ok`, `limits` (the solution leaves the joint limits) or `failed` (the pose is not
    /// reached within [`ACCEPT_MM`] / [`ACCEPT_DEG`]: out of reach, or a singularity).
    pub flag: &'static str,
}

/// The joints (internal units) at which `identified` reaches `target` under a payload of
/// `payload_kg` (its gravity sag, when the robot has joint compliances), starting from `q0`
/// ([`crate::robot::ik::solve_pose`]). Fails when the robot has compliances but no link masses.
pub fn solve(
    identified: &Robot,
    target: &Frame,
    q0: &[Real],
    payload_kg: Real,
) -> crate::Result<Vec<Real>> {
    crate::robot::ik::solve_pose(identified, target, q0, payload_kg)
}

/// Corrects one program row `q_nominal` (internal units): the joints at which `identified`
/// reaches the pose `nominal` gives at `q_nominal`. `round` maps joint values to what is
/// written (the output's decimals), so the residuals are those of the written command. The
/// identified robot carries `payload_kg` at the tool (its sag, when it has compliances; the
/// nominal robot of a locked controller knows no sag).
pub fn compensate_row(
    nominal: &Robot,
    identified: &Robot,
    q_nominal: &[Real],
    payload_kg: Real,
    round: impl Fn(&[Real]) -> Vec<Real>,
) -> crate::Result<Corrected> {
    let target = nominal.fk(q_nominal);
    let q = round(&solve(identified, &target, q_nominal, payload_kg)?);
    let f = loaded_fk(identified, &identified.chain(), &q, payload_kg)?;
    let residual_mm = (f.pos - target.pos).norm();
    let residual_deg = rotation_angle_deg(&f, &target);
    let flag = if !(residual_mm <= ACCEPT_MM && residual_deg <= ACCEPT_DEG) {
        "failed"
    } else if !identified.within_limits(&q) {
        "limits"
    } else {
        "ok"
    };
    Ok(Corrected {
        q,
        residual_mm,
        residual_deg,
        flag,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;
    use crate::robot::Param;

    /// Simulation: a true robot (nominal + errors) identified exactly reaches, at the corrected
    /// joints, the poses the nominal model promised; the nominal joints miss them by the error.
    #[test]
    fn corrected_joints_reach_the_nominal_pose_on_the_true_robot() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let errors: Vec<(Param, Real)> = nominal
            .params()
            .into_iter()
            .enumerate()
            .map(|(i, p)| {
                let e = if matches!(p, Param::Theta(_) | Param::Alpha(_) | Param::Beta(_)) {
                    1e-3
                } else {
                    0.5
                };
                (p, if i % 2 == 0 { e } else { -e })
            })
            .collect();
        let truth = nominal.with_errors(&errors);
        let mut g = stream(7, "compensate-test");
        let qs = crate::robot::sampling::uniform_joint_poses(&nominal, 30, &mut g);
        let mut ok = 0;
        for q in &qs {
            let c = compensate_row(&nominal, &truth, q, 0.0, |q| q.to_vec()).unwrap();
            let target = nominal.fk(q);
            let before = (truth.fk(q).pos - target.pos).norm();
            assert!(before > 0.1, "the errors move the tool ({before} mm)");
            if c.flag == "failed" {
                continue;
            }
            let f = truth.fk(&c.q);
            assert!((f.pos - target.pos).norm() < 1e-8);
            assert!(rotation_angle_deg(&f, &target) < 1e-8);
            ok += 1;
        }
        assert!(ok >= 25, "only {ok} of 30 rows solved");
    }

    /// The residual is that of the written (rounded) command, and a bad solve is flagged.
    #[test]
    fn rounding_shows_in_the_residual_and_failures_are_flagged() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let q = vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        let coarse = compensate_row(&nominal, &nominal, &q, 0.0, |q| {
            q.iter().map(|v| v + 1e-3).collect()
        })
        .unwrap();
        assert!(coarse.residual_mm > 1e-3);
        assert_eq!(coarse.flag, "failed");
        let exact = compensate_row(&nominal, &nominal, &q, 0.0, |q| q.to_vec()).unwrap();
        assert_eq!(exact.flag, "ok");
        assert!(exact.residual_mm < 1e-12);
    }

    /// A robot with joint compliances: the corrected commands reach the nominal pose with the
    /// arm sagging under the payload (the elasto-geometric model's own forward kinematics), and
    /// the sag is what the uncorrected commands miss by.
    #[test]
    fn compliant_robot_commands_include_the_sag_at_the_payload() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let mut soft = nominal.clone();
        soft.set(Param::Compliance(1), 1.0 / 3.5e6);
        soft.set(Param::Compliance(2), 1.0 / 2.5e6);
        let chain = soft.chain();
        let q = vec![0.3, 0.4, -0.2, 0.5, 0.6, 0.1];
        let target = nominal.fk(&q);
        let sagged = loaded_fk(&soft, &chain, &q, 20.0).unwrap();
        let sag = (sagged.pos - target.pos).norm();
        assert!(sag > 0.05, "20 kg sag the arm by {sag} mm");
        let c = compensate_row(&nominal, &soft, &q, 20.0, |q| q.to_vec()).unwrap();
        assert_eq!(c.flag, "ok");
        let f = loaded_fk(&soft, &chain, &c.q, 20.0).unwrap();
        assert!((f.pos - target.pos).norm() < 1e-8);
        // Without a payload the rigid and the compliant arm differ by the links' own sag only.
        let light = compensate_row(&nominal, &soft, &q, 0.0, |q| q.to_vec()).unwrap();
        assert!(light.q != c.q);
    }
}

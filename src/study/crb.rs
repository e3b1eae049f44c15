//! The Cramér–Rao bound of a calibration under the tracker's noise model: the covariance
//! (JᵀWJ)⁻¹ an unbiased estimator of the identified parameters cannot beat (Kay, *Fundamentals
//! of Statistical Signal Processing*, vol. 1, § 3.7, Gaussian noise), its trace (the
//! `crb_ratio` of `summary.json`) and each parameter's standard deviation, which decides
//! whether a parameter's injected error is determinable at all (docs/formats.md
//! "summary.json", `eta_not_determinable`). Where JᵀWJ is singular, only the estimable
//! parameters have a bound ([`estimable_variances`]).

use nalgebra::DMatrix;

use crate::identify::solver::{inverse_diagonal, rank};
use crate::measurement::Measure;
use crate::numeric::Real;
use crate::robot::identifiability::gram_dependence;
use crate::robot::jacobian::{jacobian, Columns};
use crate::robot::{Param, Robot};
use crate::sim::tracker::Tracker;

/// How many Cramér–Rao standard deviations an injected error must exceed for its η to count
/// (k = 3, the identification's [`crate::identify::solver::DETERMINABLE_SIGMAS`], which says
/// why). Its η = 1 − |x̂ − x| / |x| at |x| ≤ 3σ measures the noise, not the method: the
/// expected |x̂ − x| = σ √(2/π) ≈ 0.8 σ, so the expected η at |x| = kσ is about
/// 100 (1 − 0.8 / k) % (73 % at k = 3) and without bound below as |x| / σ → 0.
pub use crate::identify::solver::DETERMINABLE_SIGMAS;

/// Each parameter's Cramér–Rao variance (mm², rad²) where it is estimable, `None` where it is
/// not: for `params` measured at the joint values `qs` (one row block per value, as the
/// measurement has them) on `robot`, with `measure`'s rows and the noise of `tracker`:
/// W = diag(1/σ²), σ the position noise at each point's range from the tracker and, for full
/// poses, its orientation noise. Of full rank, JᵀWJ gives the diagonal of its inverse; of
/// lower rank, [`estimable_variances`]. `None` where there is no bound at all: a noise-free
/// tracker, an elasto-geometric model (its bound would need each pose's payload and torques)
/// or a non-finite result.
pub fn variances(
    robot: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
    measure: Measure,
    tracker: &Tracker,
) -> Option<Vec<Option<Real>>> {
    if params.iter().any(|p| p.is_compliance()) {
        return None;
    }
    let cols = Columns::new(params, robot.dof());
    let mut j = jacobian(robot, &cols, qs, measure);
    let rows = measure.rows();
    let chain = robot.chain();
    let tracker_at = tracker.frame().pos;
    for (i, q) in qs.iter().enumerate() {
        let range = (chain.fk(q).pos - tracker_at).norm();
        let s = tracker.sigma_mm(range);
        if s <= 0.0 {
            return None;
        }
        let mut block = j.rows_mut(rows * i, 3);
        block /= s;
        if rows == 6 {
            let sa = tracker.angle_sigma_rad();
            if sa <= 0.0 {
                return None;
            }
            let mut b = j.rows_mut(rows * i + 3, 3);
            b /= sa;
        }
    }
    estimable_variances(&(j.transpose() * &j))
}

/// [`variances`] of a pose set that is the same in every trial, on a true robot that is too
/// (a fixed set under errors `paper`, `values` or `none`), computed once per study
/// ([`crate::study::plan::FixedSet::crb`]) instead of once per trial. The bound is a pure
/// function of the robot, the rows and the study's parameters, measure and tracker, so the
/// variances served here are the bits the trial would compute; [`Memo::variances`] serves
/// them only for the same robot values and rows, bit for bit, and computes them otherwise.
#[derive(Debug)]
pub struct Memo {
    /// The true robot's parameter values, as bits.
    values: Vec<u64>,
    /// The rows' joint values, as bits.
    qs: Vec<Vec<u64>>,
    /// [`variances`] at them.
    variances: Option<Vec<Option<Real>>>,
}

fn bits(v: &[Real]) -> impl Iterator<Item = u64> + '_ {
    v.iter().map(|x| x.to_bits())
}

impl Memo {
    /// [`variances`] of `robot` at the rows `qs`, kept with the values they belong to.
    pub fn new(
        robot: &Robot,
        params: &[Param],
        qs: &[Vec<Real>],
        measure: Measure,
        tracker: &Tracker,
    ) -> Memo {
        Memo {
            values: bits(&robot.values).collect(),
            qs: qs.iter().map(|q| bits(q).collect()).collect(),
            variances: variances(robot, params, qs, measure, tracker),
        }
    }

    /// Whether the memo was computed for `robot` at `qs` (the same bits).
    fn holds(&self, robot: &Robot, qs: &[Vec<Real>]) -> bool {
        bits(&robot.values).eq(self.values.iter().copied())
            && qs.len() == self.qs.len()
            && qs
                .iter()
                .zip(&self.qs)
                .all(|(q, b)| bits(q).eq(b.iter().copied()))
    }

    /// [`variances`] of `robot` at `qs` for the study's `params`, `measure` and `tracker`:
    /// from `memo` where it holds them, else computed.
    pub fn variances(
        memo: Option<&Memo>,
        robot: &Robot,
        params: &[Param],
        qs: &[Vec<Real>],
        measure: Measure,
        tracker: &Tracker,
    ) -> Option<Vec<Option<Real>>> {
        match memo {
            Some(m) if m.holds(robot, qs) => m.variances.clone(),
            _ => variances(robot, params, qs, measure, tracker),
        }
    }
}

/// Each parameter's Cramér–Rao variance from the weighted normal matrix `n = JᵀWJ`, `None` for
/// a parameter that is not estimable (docs/formats.md, **Determinable parameters**).
///
/// Parameter i is estimable when the unit vector eᵢ lies in the row space of J (Rao, *Linear
/// Statistical Inference*, § 4a; Searle, *Linear Models*, § 5.4): then and only then is
/// x̂ᵢ = eᵢᵀx̂ the same for every solution of the normal equations, and its variance
/// σᵢ² = eᵢᵀ n⁻ eᵢ the same for every generalised inverse n⁻ of `n`. A parameter of a dependent
/// group (Guo's d2 and d3, of which the poses see only the sum) is not: its part of the error
/// can be moved to the others without changing a residual, so no data determine it, whatever
/// its size.
///
/// `n` of full numerical rank ([`rank`], the identification's test) gives the diagonal of its
/// inverse, exactly as before ([`inverse_diagonal`]). Otherwise the columns are split by
/// pivoted Cholesky of the column-scaled `n` ([`gram_dependence`], the identifiability
/// analysis on the Gram matrix: a column is kept while its remaining scaled norm exceeds
/// [`crate::robot::identifiability::RANK_TOL`] = 1e-7, the relative singular value below which
/// the solver's [`crate::identify::solver::RANK_TOLERANCE`] calls a direction undetermined).
/// The kept columns B span the column space of J, and every dependent column d is J_B c_d,
/// so the null space of J is spanned by the vectors with −c_d on B and 1 at d: eᵢ is orthogonal
/// to it, i.e. in the row space, exactly when i is kept and no c_d weighs it
/// (above [`crate::robot::identifiability::DEPENDENCE_WEIGHT`] = 1e-6 on unit-norm columns).
/// For such an i, the generalised inverse that inverts n_BB and is zero elsewhere gives
/// σᵢ² = (n_BB⁻¹)ᵢᵢ. `None` overall where n_BB has no bound ([`inverse_diagonal`]).
pub fn estimable_variances(n: &DMatrix<Real>) -> Option<Vec<Option<Real>>> {
    let t = n.nrows();
    if rank(n) == t {
        return inverse_diagonal(n).map(|v| v.into_iter().map(Some).collect());
    }
    let d = gram_dependence(n);
    let kept = &d.identifiable;
    let inv = inverse_diagonal(&n.select_rows(kept).select_columns(kept))?;
    let mut out = vec![None; t];
    for (&c, v) in kept.iter().zip(inv) {
        if !d.in_group[c] {
            out[c] = Some(v);
        }
    }
    Some(out)
}

/// The study parameters (indices into `truth`) whose non-zero injected error is not
/// determinable: a parameter that is not estimable, or one within |x| ≤
/// [`DETERMINABLE_SIGMAS`] · σ, σ² from `variances` (none without a bound).
pub fn not_determinable(truth: &[Real], variances: Option<&[Option<Real>]>) -> Vec<usize> {
    let Some(v) = variances else {
        return Vec::new();
    };
    truth
        .iter()
        .zip(v)
        .enumerate()
        .filter(|(_, (x, v))| {
            **x != 0.0 && v.is_none_or(|v| x.abs() <= DETERMINABLE_SIGMAS * v.sqrt())
        })
        .map(|(k, _)| k)
        .collect()
}

#[cfg(test)]
mod estimable;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng;
    use crate::robot::builtin;
    use crate::robot::jacobian::jacobian_fd;
    use crate::robot::sampling::uniform_joint_poses;
    use crate::sim::settings::{MeasureSetting, TrackerSettings};
    use nalgebra::DMatrix;

    /// The same variances built independently: the Jacobian by central finite differences of
    /// forward kinematics, each row weighed by 1/σ² of its own point written out from the
    /// tracker's MPE (σ = (a + b·range) / coverage), the normal matrix summed row by row and
    /// inverted by LU.
    fn by_hand(
        robot: &Robot,
        params: &[Param],
        qs: &[Vec<Real>],
        measure: Measure,
        s: &TrackerSettings,
    ) -> Vec<Real> {
        let cols = Columns::new(params, robot.dof());
        let j = jacobian_fd(robot, &cols, qs, measure, 1e-6);
        let rows = measure.rows();
        let at = nalgebra::Vector3::new(s.pose[0], s.pose[1], s.pose[2]);
        let p = params.len();
        let mut n = DMatrix::<Real>::zeros(p, p);
        for (i, q) in qs.iter().enumerate() {
            let range = (robot.fk(q).pos - at).norm();
            let sigma = (s.mpe_a_um * 1e-3 + s.mpe_b_um_per_m * 1e-6 * range) / s.coverage;
            for r in 0..rows {
                let w = if r < 3 {
                    sigma.powi(-2)
                } else {
                    s.angle_noise_deg.to_radians().powi(-2)
                };
                let row = j.row(rows * i + r);
                n += row.transpose() * row * w;
            }
        }
        let inv = n.lu().try_inverse().expect("a regular normal matrix");
        (0..p).map(|c| inv[(c, c)]).collect()
    }

    fn check(measure: MeasureSetting) {
        let nominal = builtin::irb2600();
        // A true robot off the nominal one: the bound is taken where the data come from.
        let robot = nominal.with_errors(&[(Param::A(1), 0.4), (Param::Theta(2), 0.002)]);
        let params: Vec<Param> = [
            Param::A(0),
            Param::A(1),
            Param::D(0),
            Param::Theta(1),
            Param::Theta(2),
            Param::Alpha(1),
            Param::D(3),
        ]
        .to_vec();
        let qs = uniform_joint_poses(&nominal, 30, &mut rng::from_seed(5));
        let settings = TrackerSettings {
            measure,
            angle_noise_deg: 0.01,
            ..TrackerSettings::default()
        };
        let tracker = Tracker::new(&settings).expect("tracker");
        let m = tracker.measures();
        let got: Vec<Real> = variances(&robot, &params, &qs, m, &tracker)
            .expect("a bound")
            .into_iter()
            .map(|v| v.expect("full rank: every parameter estimable"))
            .collect();
        let want = by_hand(&robot, &params, &qs, m, &settings);
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            assert!((g - w).abs() <= 1e-5 * w, "{}: {g} against {w}", params[k]);
        }
    }

    #[test]
    fn each_parameters_variance_is_that_of_a_finite_difference_normal_matrix() {
        check(MeasureSetting::Position);
        check(MeasureSetting::Pose);
    }

    #[test]
    fn the_memo_serves_its_own_robot_and_rows_and_computes_the_others() {
        let nominal = builtin::irb2600();
        let robot = nominal.with_errors(&[(Param::A(1), 0.4)]);
        let params = [Param::A(0), Param::A(1), Param::Theta(2)];
        let tracker = Tracker::new(&TrackerSettings::default()).expect("tracker");
        let m = tracker.measures();
        let qs = uniform_joint_poses(&nominal, 20, &mut rng::from_seed(4));
        let memo = Memo::new(&robot, &params, &qs, m, &tracker);
        let direct = |r: &Robot, q: &[Vec<Real>]| variances(r, &params, q, m, &tracker);
        let served =
            |r: &Robot, q: &[Vec<Real>]| Memo::variances(Some(&memo), r, &params, q, m, &tracker);
        let bits = |v: Option<Vec<Option<Real>>>| -> Vec<Option<u64>> {
            v.expect("a bound")
                .into_iter()
                .map(|x| x.map(Real::to_bits))
                .collect()
        };
        assert!(memo.holds(&robot, &qs));
        assert_eq!(bits(served(&robot, &qs)), bits(direct(&robot, &qs)));
        // Another robot, other rows, fewer rows: not the memo's, so computed, and different.
        let other = nominal.with_errors(&[(Param::A(1), 0.5)]);
        assert!(!memo.holds(&other, &qs));
        assert_eq!(bits(served(&other, &qs)), bits(direct(&other, &qs)));
        let mut moved = qs.clone();
        moved[7][2] += 1e-3;
        assert!(!memo.holds(&robot, &moved) && !memo.holds(&robot, &qs[..19]));
        assert_eq!(bits(served(&robot, &moved)), bits(direct(&robot, &moved)));
        assert_ne!(bits(served(&robot, &moved)), bits(served(&robot, &qs)));
    }

    #[test]
    fn an_error_within_three_sigma_is_not_determinable() {
        let v = [Some(1.0), Some(4.0), Some(0.01), Some(1.0), None, None];
        // σ = 1, 2, 0.1, 1: 2.9 ≤ 3, 6.5 > 6, 0 is no error, −3 ≤ 3; the fifth is not
        // estimable whatever its error, the sixth has none.
        assert_eq!(
            not_determinable(&[2.9, 6.5, 0.0, -3.0, 1e6, 0.0], Some(&v)),
            vec![0, 3, 4]
        );
        assert!(not_determinable(&[1e-9, 1e-9, 0.0, 0.0], None).is_empty());
    }

    #[test]
    fn dependent_parameters_are_not_estimable_and_the_others_keep_their_bound() {
        // d2 and d3 of the IRB2600 move the wrist centre along the same joint axis: only
        // their sum is seen, so JᵀWJ is singular up to rounding; a1 stays estimable, with
        // the variance it has beside only one of the pair (the kept column spans the sum).
        let nominal = builtin::irb2600();
        let tracker = Tracker::new(&TrackerSettings::default()).expect("tracker");
        let qs = uniform_joint_poses(&nominal, 30, &mut rng::from_seed(2));
        let m = tracker.measures();
        let three = [Param::A(0), Param::D(1), Param::D(2)];
        let got = variances(&nominal, &three, &qs, m, &tracker).expect("a bound");
        assert!(got[1].is_none() && got[2].is_none(), "{got:?}");
        let two = variances(&nominal, &three[..2], &qs, m, &tracker).expect("a bound");
        let (a, b) = (got[0].expect("a1 estimable"), two[0].expect("a1"));
        assert!((a - b).abs() <= 1e-9 * b, "{a} against {b}");
        assert!(two.iter().all(Option::is_some));
    }

    #[test]
    fn no_bound_without_noise() {
        let nominal = builtin::irb2600();
        let settings = TrackerSettings {
            mpe_a_um: 0.0,
            mpe_b_um_per_m: 0.0,
            ..TrackerSettings::default()
        };
        let tracker = Tracker::new(&settings).expect("tracker");
        let qs = uniform_joint_poses(&nominal, 10, &mut rng::from_seed(1));
        let m = tracker.measures();
        assert!(variances(&nominal, &[Param::A(0)], &qs, m, &tracker).is_none());
    }
}

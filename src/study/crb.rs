//! The Cramér–Rao bound of a calibration under the tracker's noise model: the covariance
//! (JᵀWJ)⁻¹ an unbiased estimator of the identified parameters cannot beat (Kay, *Fundamentals
//! of Statistical Signal Processing*, vol. 1, § 3.7, Gaussian noise), its trace (the
//! `crb_ratio` of `summary.json`) and each parameter's standard deviation, which decides
//! whether a parameter's injected error is determinable at all (docs/formats.md
//! "summary.json", `eta_not_determinable`). Where JᵀWJ is singular, the bound is that of the
//! minimum-norm estimate, with the share of each parameter in the directions the data leave
//! undetermined ([`bounds`]).

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

/// What the calibration rows say about each parameter ([`Bounds`]): for `params` measured at
/// the joint values `qs` (one row block per value, as the measurement has them) on `robot`,
/// with `measure`'s rows and the noise of `tracker`: W = diag(1/σ²), σ the position noise at
/// each point's range from the tracker and, for full poses, its orientation noise ([`bounds`]
/// of JᵀWJ). `None` where there is no bound at all: a noise-free tracker, an
/// elasto-geometric model (its bound would need each pose's payload and torques) or a
/// non-finite result.
pub fn bounds_at(
    robot: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
    measure: Measure,
    tracker: &Tracker,
) -> Option<Bounds> {
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
    bounds(&(j.transpose() * &j))
}

/// [`bounds_at`] of a pose set that is the same in every trial, on a true robot that is too
/// (a fixed set under errors `paper`, `values` or `none`), computed once per study
/// ([`crate::study::plan::FixedSet::crb`]) instead of once per trial. The bound is a pure
/// function of the robot, the rows and the study's parameters, measure and tracker, so the
/// bounds served here are the bits the trial would compute; [`Memo::get`] serves them only
/// for the same robot values and rows, bit for bit.
#[derive(Debug)]
pub struct Memo {
    /// The true robot's parameter values, as bits.
    values: Vec<u64>,
    /// The rows' joint values, as bits.
    qs: Vec<Vec<u64>>,
    /// [`bounds_at`] them.
    bounds: Option<Bounds>,
}

fn bits(v: &[Real]) -> impl Iterator<Item = u64> + '_ {
    v.iter().map(|x| x.to_bits())
}

impl Memo {
    /// Keeps `bounds`, the [`bounds_at`] of `robot` at the rows `qs`, with the values they
    /// belong to.
    pub fn new(robot: &Robot, qs: &[Vec<Real>], bounds: Option<Bounds>) -> Memo {
        Memo {
            values: bits(&robot.values).collect(),
            qs: qs.iter().map(|q| bits(q).collect()).collect(),
            bounds,
        }
    }

    /// The kept bounds where the memo was computed for `robot` at `qs` (the same bits);
    /// `None` otherwise, where the caller computes them.
    pub fn get(&self, robot: &Robot, qs: &[Vec<Real>]) -> Option<Option<Bounds>> {
        let holds = bits(&robot.values).eq(self.values.iter().copied())
            && qs.len() == self.qs.len()
            && qs
                .iter()
                .zip(&self.qs)
                .all(|(q, b)| bits(q).eq(b.iter().copied()));
        holds.then(|| self.bounds.clone())
    }
}

/// What a weighted normal matrix `n = JᵀWJ` says about each parameter (docs/formats.md,
/// **Determinable parameters**).
#[derive(Clone, Debug, PartialEq)]
pub struct Bounds {
    /// Per parameter, the Cramér–Rao variance of its minimum-norm estimate (mm², rad²): the
    /// i-th diagonal element of (JᵀWJ)⁻¹ of full rank, of the pseudo-inverse of the
    /// column-scaled JᵀWJ (unscaled) otherwise.
    pub variances: Vec<Real>,
    /// Per parameter, how far a unit step along the undetermined directions can move it:
    /// ‖P ẽᵢ‖ / ‖Jᵢ‖, with P the projector onto the null space of the column-scaled J and ẽᵢ
    /// the i-th unit vector there (mm, rad per unit of scaled error). 0 for an estimable
    /// parameter, every one of a full-rank J; ∞ for a column without effect.
    pub undetermined: Vec<Real>,
    /// Per parameter, ‖Jᵢ‖ = √(JᵀWJ)ᵢᵢ: an error x moves the weighted residuals by up to
    /// |x| ‖Jᵢ‖, the parameter's scaled error.
    pub column_norms: Vec<Real>,
    /// Whether JᵀWJ has full numerical rank (the identification's test, [`rank`]).
    pub full_rank: bool,
}

impl Bounds {
    /// The Cramér–Rao trace, tr (JᵀWJ)⁻¹; `None` where JᵀWJ is singular (a parameter that
    /// is not estimable has no bound of its own).
    pub fn trace(&self) -> Option<Real> {
        self.full_rank.then(|| self.variances.iter().sum())
    }
}

/// [`Bounds`] of the weighted normal matrix `n = JᵀWJ`; `None` where there is none (a
/// singular kept block, a diagonal of the inverse that is not finite and non-negative).
///
/// `n` of full numerical rank ([`rank`], the identification's test) gives the diagonal of its
/// inverse ([`inverse_diagonal`]), every parameter estimable.
///
/// Otherwise the columns are split by pivoted Cholesky of the column-scaled `S = D⁻¹ n D⁻¹`
/// (D = diag of the column norms; [`gram_dependence`], the identifiability analysis on the
/// Gram matrix: a column is kept while its remaining scaled norm exceeds
/// [`crate::robot::identifiability::RANK_TOL`] = 1e-7, the relative singular value below which
/// the solver's [`crate::identify::solver::RANK_TOLERANCE`] calls a direction undetermined).
/// The kept columns B span the column space, every dependent column d is S_B c_d with
/// c_d = S_BB⁻¹ S_Bd, so the null space of the scaled J is spanned by the columns of N, −C on
/// B and the identity on the dependent columns, and P = N (NᵀN)⁻¹ Nᵀ projects onto it. A
/// parameter i is estimable when ẽᵢ lies in the row space (Rao, *Linear Statistical
/// Inference*, § 4a; Searle, *Linear Models*, § 5.4), that is when ‖P ẽᵢ‖ = 0: then every
/// solution of the normal equations gives it one value. Otherwise an estimate can move it by
/// ‖P ẽᵢ‖ per unit step along the null space without changing a residual ([`Bounds`]'s
/// `undetermined`). The variance is that of the minimum-norm estimate, the diagonal of
/// S⁺ = (I − P) G (I − P) for the generalised inverse G that inverts S_BB and is zero
/// elsewhere (A⁺ = A⁺AGAA⁺ for symmetric A), unscaled; for an estimable parameter it is
/// eᵢᵀ n⁻ eᵢ, the same for every generalised inverse.
pub fn bounds(n: &DMatrix<Real>) -> Option<Bounds> {
    let t = n.nrows();
    let column_norms: Vec<Real> = (0..t).map(|c| n[(c, c)].max(0.0).sqrt()).collect();
    if rank(n) == t {
        return Some(Bounds {
            variances: inverse_diagonal(n)?,
            undetermined: vec![0.0; t],
            column_norms,
            full_rank: true,
        });
    }
    let d = gram_dependence(n);
    let (kept, dep, scale) = (&d.identifiable, &d.dependent, &d.scale);
    let s = |i: usize, k: usize| n[(i, k)] * scale[i] * scale[k];
    let chol = DMatrix::from_fn(kept.len(), kept.len(), |i, k| s(kept[i], kept[k])).cholesky()?;
    let c = chol.solve(&DMatrix::from_fn(kept.len(), dep.len(), |i, k| {
        s(kept[i], dep[k])
    }));
    let mut null = DMatrix::<Real>::zeros(t, dep.len());
    for (k, &dk) in dep.iter().enumerate() {
        null[(dk, k)] = 1.0;
        for (i, &bi) in kept.iter().enumerate() {
            null[(bi, k)] = -c[(i, k)];
        }
    }
    let gram = (null.transpose() * &null).cholesky()?.inverse();
    let p = &null * gram * null.transpose();
    let off = DMatrix::<Real>::identity(t, t) - &p;
    let inv = chol.inverse();
    let g = DMatrix::from_fn(t, t, |i, k| {
        match (kept.binary_search(&i), kept.binary_search(&k)) {
            (Ok(a), Ok(b)) => inv[(a, b)],
            _ => 0.0,
        }
    });
    let pinv = &off * g * &off;
    let variances: Vec<Real> = (0..t).map(|i| pinv[(i, i)] * scale[i] * scale[i]).collect();
    if variances.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
        return None;
    }
    let undetermined = (0..t)
        .map(|i| {
            if scale[i] > 0.0 {
                p[(i, i)].max(0.0).sqrt() * scale[i]
            } else {
                Real::INFINITY
            }
        })
        .collect();
    Some(Bounds {
        variances,
        undetermined,
        column_norms,
        full_rank: false,
    })
}

/// The study parameters (indices into `truth`) whose non-zero injected error x is not
/// determinable (docs/formats.md, **Determinable parameters**): those with
/// |x| ≤ [`DETERMINABLE_SIGMAS`] · σ + u · ‖x̃‖, σ² and u the parameter's variance and
/// undetermined share in `bounds`, and ‖x̃‖ the size of the whole injected error in scaled
/// units, √Σ (xⱼ ‖Jⱼ‖)²: the most an estimate that leaves the undetermined directions where
/// it started (the minimum-norm one) can be off along them is u · ‖P x̃‖ ≤ u · ‖x̃‖, whatever
/// the injected errors' alignment with those directions. Of full rank, u = 0 and the rule is
/// |x| ≤ 3σ. None without a bound.
pub fn not_determinable(truth: &[Real], bounds: Option<&Bounds>) -> Vec<usize> {
    let Some(b) = bounds else {
        return Vec::new();
    };
    let size = truth
        .iter()
        .zip(&b.column_norms)
        .map(|(x, c)| (x * c) * (x * c))
        .sum::<Real>()
        .sqrt();
    truth
        .iter()
        .enumerate()
        .filter(|&(k, x)| {
            // Told from 0 beyond the noise and the undetermined share (false for a NaN).
            let told =
                x.abs() > DETERMINABLE_SIGMAS * b.variances[k].sqrt() + b.undetermined[k] * size;
            *x != 0.0 && !told
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
    /// inverted by LU. The rows are those of the settings' `measure`.
    fn by_hand(
        robot: &Robot,
        params: &[Param],
        qs: &[Vec<Real>],
        s: &TrackerSettings,
    ) -> Vec<Real> {
        let measure = s.measure.measure();
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
            angle_noise_deg: if measure == MeasureSetting::Pose {
                0.01
            } else {
                0.0
            },
            ..TrackerSettings::default()
        };
        let tracker = Tracker::new(&settings).expect("tracker");
        let m = tracker.measures();
        let b = bounds_at(&robot, &params, &qs, m, &tracker).expect("a bound");
        assert!(b.full_rank && b.undetermined.iter().all(|&u| u == 0.0));
        let got = b.variances;
        let want = by_hand(&robot, &params, &qs, &settings);
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
    fn the_memo_serves_its_own_robot_and_rows_only() {
        let nominal = builtin::irb2600();
        let robot = nominal.with_errors(&[(Param::A(1), 0.4)]);
        let params = [Param::A(0), Param::A(1), Param::Theta(2)];
        let tracker = Tracker::new(&TrackerSettings::default()).expect("tracker");
        let m = tracker.measures();
        let qs = uniform_joint_poses(&nominal, 20, &mut rng::from_seed(4));
        let direct = |r: &Robot, q: &[Vec<Real>]| bounds_at(r, &params, q, m, &tracker);
        let memo = Memo::new(&robot, &qs, direct(&robot, &qs));
        assert!(memo.get(&robot, &qs).expect("held").is_some());
        assert_eq!(memo.get(&robot, &qs), Some(direct(&robot, &qs)));
        // Another robot, other rows, fewer rows: not the memo's, and their bounds differ.
        let other = nominal.with_errors(&[(Param::A(1), 0.5)]);
        let mut moved = qs.clone();
        moved[7][2] += 1e-3;
        assert_eq!(memo.get(&other, &qs), None);
        assert_eq!(memo.get(&robot, &moved), None);
        assert_eq!(memo.get(&robot, &qs[..19]), None);
        assert_ne!(direct(&robot, &moved), direct(&robot, &qs));
    }

    #[test]
    fn an_error_within_three_sigma_is_not_determinable() {
        let full = Bounds {
            variances: vec![1.0, 4.0, 0.01, 1.0, 1.0],
            undetermined: vec![0.0; 5],
            column_norms: vec![1.0; 5],
            full_rank: true,
        };
        // σ = 1, 2, 0.1, 1, 1: 2.9 ≤ 3, 6.5 > 6, 0 is no error, −3 ≤ 3, 1e6 > 3.
        assert_eq!(
            not_determinable(&[2.9, 6.5, 0.0, -3.0, 1e6], Some(&full)),
            vec![0, 3]
        );
        assert!(not_determinable(&[1e-9, 1e-9, 0.0, 0.0], None).is_empty());
        // Undetermined shares 0.7 and 0.01 (per unit of scaled error) and a column without
        // effect: the scaled errors 3, 4 and 0 make ‖x̃‖ = 5, so the second must exceed
        // 3 · 0.1 + 0.05 and the first 0.3 + 3.5; the third is never determinable. With
        // errors 1 and 0.3, ‖x̃‖ = 1.044: 1 ≤ 0.3 + 0.73 and 0.3 ≤ 0.3 + 0.01.
        let deficient = Bounds {
            variances: vec![0.01, 0.01, 0.0],
            undetermined: vec![0.7, 0.01, Real::INFINITY],
            column_norms: vec![1.0, 1.0, 0.0],
            full_rank: false,
        };
        assert_eq!(
            not_determinable(&[3.0, 4.0, 1.0], Some(&deficient)),
            vec![0, 2]
        );
        assert_eq!(
            not_determinable(&[1.0, 0.3, 1.0], Some(&deficient)),
            vec![0, 1, 2]
        );
        assert_eq!(deficient.trace(), None);
        assert_eq!(full.trace(), Some(7.01));
    }

    #[test]
    fn dependent_parameters_are_undetermined_and_the_others_keep_their_bound() {
        // d2 and d3 of the IRB2600 move the wrist centre along the same joint axis: only
        // their sum is seen, so JᵀWJ is singular up to rounding; a1 stays estimable, with
        // the variance it has beside only one of the pair (the kept column spans the sum).
        let nominal = builtin::irb2600();
        let tracker = Tracker::new(&TrackerSettings::default()).expect("tracker");
        let qs = uniform_joint_poses(&nominal, 30, &mut rng::from_seed(2));
        let m = tracker.measures();
        let three = [Param::A(0), Param::D(1), Param::D(2)];
        let got = bounds_at(&nominal, &three, &qs, m, &tracker).expect("a bound");
        assert!(!got.full_rank && got.trace().is_none());
        // Equal columns: the null direction (1, −1)/√2 in scaled units, so each of the pair
        // moves by 1/√2 per unit step over its column norm, and a1 not at all.
        for k in [1, 2] {
            let want = std::f64::consts::FRAC_1_SQRT_2 / got.column_norms[k];
            let u = got.undetermined[k];
            assert!((u - want).abs() <= 1e-6 * want, "{u} against {want}");
        }
        assert!(got.undetermined[0] <= 1e-9 / got.column_norms[0], "{got:?}");
        let two = bounds_at(&nominal, &three[..2], &qs, m, &tracker).expect("a bound");
        let (a, b) = (got.variances[0], two.variances[0]);
        assert!((a - b).abs() <= 1e-9 * b, "{a} against {b}");
        assert!(two.full_rank);
    }

    /// Guo's arm with Guo's error set (every length +0.5 mm, every angle +0.05 rad on its
    /// 21 parameters), 60 random poses: at the true arm the injected α2 tilts joint 3's axis,
    /// and α2 and β2, estimable at the nominal arm, lean on the null direction of a1, θ2 and
    /// θ3 by a few per cent of their scaled columns (docs/formats.md "Determinable
    /// parameters"), while d2 and d3, of which the poses see the sum, lean on theirs by 1/√2;
    /// θ1 not at all.
    #[test]
    fn on_guos_true_arm_alpha2_and_beta2_lean_a_little_on_an_undetermined_direction() {
        let nominal = builtin::guo_3t2r();
        let mut params = Vec::new();
        for j in 0..5 {
            params.extend([Param::Theta(j), Param::D(j), Param::A(j), Param::Alpha(j)]);
        }
        params.push(Param::Beta(1));
        let errors: Vec<(Param, Real)> = params
            .iter()
            .map(|&p| match p {
                Param::D(_) | Param::A(_) => (p, 0.5),
                _ => (p, 0.05),
            })
            .collect();
        let truth = nominal.with_errors(&errors);
        let qs = uniform_joint_poses(&nominal, 60, &mut rng::from_seed(11));
        let tracker = Tracker::new(&TrackerSettings::default()).expect("tracker");
        let share = |robot: &Robot, p: Param| {
            let b = bounds_at(robot, &params, &qs, tracker.measures(), &tracker).expect("a bound");
            let k = params.iter().position(|&q| q == p).expect("a parameter");
            b.undetermined[k] * b.column_norms[k]
        };
        for p in [Param::Alpha(1), Param::Beta(1)] {
            assert!(share(&nominal, p) < 1e-9, "{p} at the nominal arm");
            let s = share(&truth, p);
            assert!((0.01..0.06).contains(&s), "{p}: {s}");
        }
        for p in [Param::D(1), Param::D(2)] {
            let s = share(&truth, p);
            assert!(
                (s - std::f64::consts::FRAC_1_SQRT_2).abs() < 0.01,
                "{p}: {s}"
            );
        }
        assert!(share(&truth, Param::Theta(0)) < 1e-9);
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
        assert!(bounds_at(&nominal, &[Param::A(0)], &qs, m, &tracker).is_none());
    }
}

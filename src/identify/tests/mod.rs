//! Tests of the identification methods against closed forms and simulated robots.

use nalgebra::{DMatrix, DVector};
use rand::Rng as _;
use rand_distr::{Distribution, Normal};

use super::*;
use crate::measurement::Measure;
use crate::numeric::rng::{self, Rng};
use crate::numeric::{Real, Vec3};
use crate::robot::builtin;
use crate::robot::identifiability::analyse;
use crate::robot::sampling::uniform_joint_poses;
use crate::robot::{Param, Robot};

/// Measured data in the base frame, for [`RobotProblem`].
#[derive(Clone, Debug, Default)]
struct RobotData {
    qs: Vec<Vec<Real>>,
    points: Vec<Vec3>,
    rotations: Option<Vec<crate::numeric::Mat3>>,
}

impl RobotData {
    fn problem<'a>(
        &'a self,
        nominal: &'a Robot,
        params: &[Param],
        measure: Measure,
    ) -> crate::Result<RobotProblem<'a>> {
        RobotProblem::new(
            nominal,
            params,
            &self.qs,
            &self.points,
            self.rotations.as_deref(),
            measure,
        )
    }
}

/// A [`RobotProblem`] evaluated whole, the path of every problem of at most
/// [`solver::STREAM_MIN_POINTS`] points, with its rounding floor or without it (`floor`
/// false: the step rule alone stops the solvers).
struct Whole<'a> {
    p: &'a RobotProblem<'a>,
    floor: bool,
}

impl LeastSquares for Whole<'_> {
    fn size(&self) -> solver::Size {
        self.p.size()
    }
    fn prior(&self) -> Option<&[Real]> {
        self.p.prior()
    }
    fn tikhonov(&self) -> Option<&[Real]> {
        self.p.tikhonov()
    }
    fn evaluate(&self, x: &DVector<Real>, r: &mut DVector<Real>, j: &mut DMatrix<Real>) {
        self.p.evaluate(x, r, j);
    }
    fn rounding_floor(&self) -> Real {
        if self.floor {
            self.p.rounding_floor()
        } else {
            0.0
        }
    }
}

/// A linear problem `model(x) = A x` with data `b`, 1 row per point.
struct Linear {
    a: DMatrix<Real>,
    b: DVector<Real>,
}

impl LeastSquares for Linear {
    fn size(&self) -> solver::Size {
        solver::Size {
            params: self.a.ncols(),
            points: self.a.nrows(),
            rows_per_point: 1,
        }
    }
    fn evaluate(&self, x: &DVector<Real>, r: &mut DVector<Real>, j: &mut DMatrix<Real>) {
        r.copy_from(&(&self.b - &self.a * x));
        j.copy_from(&self.a);
    }
}

fn linear() -> Linear {
    // Hand-sized, well-conditioned 6 × 3 system with inconsistent data.
    let a = DMatrix::from_row_slice(
        6,
        3,
        &[
            1.0, 0.0, 2.0, 0.5, 1.0, 0.0, 0.0, 3.0, 1.0, 2.0, -1.0, 0.0, 1.0, 1.0, 1.0, -1.0, 0.0,
            0.5,
        ],
    );
    let b = DVector::from_vec(vec![1.0, 2.0, -1.0, 0.5, 3.0, -2.0]);
    Linear { a, b }
}

#[test]
fn linear_problem_matches_the_normal_equations() {
    let p = linear();
    let x0 = DVector::zeros(3);
    let ata = p.a.transpose() * &p.a;
    let atb = p.a.transpose() * &p.b;
    let ls_truth = ata.clone().lu().solve(&atb).expect("regular");
    let r = &p.b - &p.a * &ls_truth;
    let s2 = r.norm_squared() / 3.0;
    let cov_truth = ata.clone().try_inverse().expect("regular") * s2;

    let out = solve(&LsOptions::default(), &p, &x0);
    assert_eq!(out.termination, Termination::Converged);
    assert!(out.iterations <= 2, "{} iterations", out.iterations);
    approx::assert_relative_eq!(out.x, ls_truth, epsilon = 1e-12);
    approx::assert_relative_eq!(out.covariance(), cov_truth, epsilon = 1e-12);
    approx::assert_relative_eq!(out.sigma0, s2.sqrt(), epsilon = 1e-12);
    // σmax/σmin of A with every column scaled to unit norm (FORMATS `condition_number`).
    let mut scaled = p.a.clone();
    for mut c in scaled.column_iter_mut() {
        let n = c.norm();
        c /= n;
    }
    let sv = scaled.svd(false, false).singular_values;
    let cond = sv.max() / sv.min();
    approx::assert_relative_eq!(out.condition_number(), cond, max_relative = 1e-10);
    assert_eq!(out.rank, Some(3));

    // Ridge with a fixed ξ and no scaling: the Tikhonov solution (AᵀA + ξI)⁻¹Aᵀb.
    let xi = 0.7;
    let ridge_truth = (ata.clone() + DMatrix::identity(3, 3) * xi)
        .lu()
        .solve(&atb)
        .expect("regular");
    let o = RidgeOptions {
        xi: XiRule::Fixed(xi),
        scale: false,
        ..Default::default()
    };
    let out = solve(&o, &p, &x0);
    assert_eq!(out.termination, Termination::Converged);
    approx::assert_relative_eq!(out.x, ridge_truth, epsilon = 1e-10);
    assert_eq!(out.ridge_xi, Some(xi));

    // With scaling D = diag(AᵀA): (AᵀA + ξD)⁻¹Aᵀb.
    let d = DMatrix::from_diagonal(&ata.diagonal());
    let scaled_truth = (ata.clone() + d * xi).lu().solve(&atb).expect("regular");
    let o = RidgeOptions {
        xi: XiRule::Fixed(xi),
        ..Default::default()
    };
    let out = solve(&o, &p, &x0);
    approx::assert_relative_eq!(out.x, scaled_truth, epsilon = 1e-10);

    // LM, fixed and adaptive, reach the least-squares answer.
    for adaptive in [false, true] {
        let o = LmOptions {
            adaptive,
            eps: 1e-12,
            max_iter: 200,
            ..Default::default()
        };
        let out = solve(&o, &p, &x0);
        assert_eq!(
            out.termination,
            Termination::Converged,
            "adaptive {adaptive}"
        );
        approx::assert_relative_eq!(out.x, ls_truth, epsilon = 1e-9);
    }
}

#[test]
fn a_damping_that_holds_every_step_small_is_not_convergence() {
    // μ = 1e12 against AᵀA of order 10: every step goes about 1e-12 of the way to the
    // least-squares answer, far below ε = 1e-5, while the answer is a unit away.
    let p = linear();
    let x0 = DVector::zeros(3);
    let ata = p.a.transpose() * &p.a;
    let ls_truth = ata.lu().solve(&(p.a.transpose() * &p.b)).expect("regular");
    let o = LmOptions {
        mu: 1e12,
        ..Default::default()
    };
    let out = solve(&o, &p, &x0);
    assert_eq!(out.termination, Termination::MaxIterations);
    assert_eq!(out.iterations, 50);
    assert!((&out.x - &ls_truth).amax() > 0.1, "{}", out.x);
    // The adaptive damping from λ0 = 1e12 falls after each step that lowers the cost, until
    // its steps reach the answer.
    let o = LmOptions {
        adaptive: true,
        lambda0: 1e12,
        eps: 1e-12,
        max_iter: 200,
        ..Default::default()
    };
    let out = solve(&o, &p, &x0);
    assert_eq!(out.termination, Termination::Converged);
    assert!(out.iterations > 10, "{} iterations", out.iterations);
    approx::assert_relative_eq!(out.x, ls_truth, epsilon = 1e-9);
}

#[test]
fn hoerl_kennard_baldwin_xi_by_hand() {
    // Orthonormal columns (scaling is then the identity): z_LS = Aᵀb, σ̂² = |b − A z|²/(n − t),
    // ξ = t σ̂² / |z|².
    let a = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0]);
    let b = DVector::from_vec(vec![3.0, 4.0, 1.0, 2.0]);
    let p = Linear { a, b };
    let o = RidgeOptions {
        max_iter: 1,
        ..Default::default()
    };
    let out = solve(&o, &p, &DVector::zeros(2));
    let xi = 2.0 * (5.0 / 2.0) / 25.0;
    approx::assert_relative_eq!(out.ridge_xi.expect("ridge"), xi, epsilon = 1e-12);
    approx::assert_relative_eq!(out.x[0], 3.0 / (1.0 + xi), epsilon = 1e-12);
}

#[test]
fn bad_input_is_reported_not_panicked() {
    let p = linear();
    let out = solve(&LsOptions::default(), &p, &DVector::zeros(2));
    assert_eq!(out.termination, Termination::InvalidInput);
    let nan = DVector::from_vec(vec![0.0, Real::NAN, 0.0]);
    let out = solve(&LsOptions::default(), &p, &nan);
    assert_eq!(out.termination, Termination::InvalidInput);
    let o = RobustOptions {
        robust: Robustness {
            k0: 3.0,
            k1: 2.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let out = solve(&o, &p, &DVector::zeros(3));
    assert_eq!(out.termination.as_str(), "invalid-input");
    // A rank-deficient problem: two equal columns.
    let mut q = linear();
    let c = q.a.column(0).into_owned();
    q.a.set_column(1, &c);
    let out = solve(&LsOptions::default(), &q, &DVector::zeros(3));
    assert_eq!(out.termination, Termination::Singular);
    // Two rows for three unknowns: rank-deficient, of rank at most two, at the start.
    let wide = Linear {
        a: p.a.rows(0, 2).into_owned(),
        b: p.b.rows(0, 2).into_owned(),
    };
    let out = solve(&LsOptions::default(), &wide, &DVector::zeros(3));
    assert_eq!(
        (out.termination, out.rank),
        (Termination::RankDeficient, Some(2))
    );
    assert_eq!((out.iterations, out.x), (0, DVector::zeros(3)));
}

#[test]
fn robot_problem_rejects_inconsistent_input() {
    let nominal = builtin::irb2600();
    let qs = vec![vec![0.0; 6]; 3];
    let data = RobotData {
        qs: qs.clone(),
        points: vec![Vec3::zeros(); 3],
        rotations: None,
    };
    let ok = [Param::D(1), Param::A(2)];
    assert!(data.problem(&nominal, &ok, Measure::Position).is_ok());
    // β does not exist in standard DH; a repeated parameter; no parameters.
    assert!(data
        .problem(&nominal, &[Param::Beta(1)], Measure::Position)
        .is_err());
    assert!(data
        .problem(&nominal, &[Param::A(1), Param::A(1)], Measure::Position)
        .is_err());
    assert!(data.problem(&nominal, &[], Measure::Position).is_err());
    // Full pose without orientations.
    assert!(data.problem(&nominal, &ok, Measure::Pose).is_err());
    // Lengths that disagree; a joint vector of the wrong length.
    let short = RobotData {
        qs: qs.clone(),
        points: vec![Vec3::zeros(); 2],
        rotations: None,
    };
    assert!(short.problem(&nominal, &ok, Measure::Position).is_err());
    let mut bad_q = data.clone();
    bad_q.qs[1].pop();
    assert!(bad_q.problem(&nominal, &ok, Measure::Position).is_err());
}

// ---------------------------------------------------------------------------------------
// Simulated robots.

struct Setup {
    nominal: Robot,
    truth: Robot,
    params: Vec<Param>,
    errors: Vec<Real>,
}

/// The identifiable parameters by [`analyse`], without those whose Jacobian column vanishes
/// at the nominal robot (`analyse` scales such a column of rounding noise to unit norm and may
/// keep it: θ6 of the irb2600 with a zero tool, for position data).
fn identifiable(nominal: &Robot, rich: &[Vec<Real>], measure: Measure) -> Vec<Param> {
    let params = analyse(nominal, &nominal.params(), rich, measure).identifiable;
    let cols = crate::robot::jacobian::Columns::new(&params, nominal.dof());
    let j = crate::robot::jacobian::jacobian(nominal, &cols, rich, measure);
    params
        .into_iter()
        .enumerate()
        .filter(|(c, _)| j.column(*c).norm() > 1e-6)
        .map(|(_, p)| p)
        .collect()
}

/// irb2600 with the paper set (every length +0.5 mm, every angle +0.05 rad) on the
/// parameters identifiable from positions.
fn paper_setup() -> Setup {
    let nominal = builtin::irb2600();
    let mut r = rng::from_seed(11);
    let rich = uniform_joint_poses(&nominal, 200, &mut r);
    let params = identifiable(&nominal, &rich, Measure::Position);
    let errors: Vec<Real> = params
        .iter()
        .map(|p| if p.is_length() { 0.5 } else { 0.05 })
        .collect();
    let pairs: Vec<(Param, Real)> = params.iter().copied().zip(errors.iter().copied()).collect();
    let truth = nominal.with_errors(&pairs);
    Setup {
        nominal,
        truth,
        params,
        errors,
    }
}

/// Measured points of `truth` at `qs` with Gaussian noise `sigma` per component.
fn measure(truth: &Robot, qs: Vec<Vec<Real>>, sigma: Real, rng: &mut Rng) -> RobotData {
    let chain = truth.chain();
    let normal = Normal::new(0.0, sigma.max(1e-300)).expect("sigma");
    let points = qs
        .iter()
        .map(|q| {
            let p = chain.fk(q).pos;
            if sigma > 0.0 {
                p + Vec3::new(normal.sample(rng), normal.sample(rng), normal.sample(rng))
            } else {
                p
            }
        })
        .collect();
    RobotData {
        qs,
        points,
        rotations: None,
    }
}

/// irb2600 with a tool offset and its identifiable kinematic parameters, tool first: the
/// robot to which the model extensions (harmonics, gravity basis) are added.
fn irb2600_with_tool() -> (Robot, Vec<Param>) {
    let mut nominal = builtin::irb2600();
    nominal.set(Param::Tool(0), 80.0);
    nominal.set(Param::Tool(2), 120.0);
    let params =
        crate::robot::param_sets::identified_params_tool_first(&nominal, Measure::Position, true);
    (nominal, params)
}

/// Parameter `i`'s (`p`'s) geometric error: 0.2 mm on a length, 1 mrad on an angle, the
/// sign alternating.
fn geometry_error(i: usize, p: &Param) -> Real {
    let sign = [1.0, -1.0][i % 2];
    if p.is_length() {
        0.2 * sign
    } else {
        1e-3 * sign
    }
}

/// `n` uniform poses of `nominal` (stream `seed`, `purpose`) and the tool points of `truth`
/// there, through the loaded forward kinematics (its model extensions applied).
fn loaded_points(nominal: &Robot, truth: &Robot, n: usize, stream: (u64, &str)) -> RobotData {
    let qs = uniform_joint_poses(nominal, n, &mut rng::stream(stream.0, stream.1));
    let chain = truth.chain();
    let points = qs
        .iter()
        .map(|q| {
            crate::robot::loaded::loaded_fk(truth, &chain, q, 0.0)
                .unwrap()
                .pos
        })
        .collect();
    RobotData {
        qs,
        points,
        rotations: None,
    }
}

/// The largest distance between the tool points of `a` and `b` at `qs`, through the loaded
/// forward kinematics (NaN when one is not a number).
fn largest_point_gap(a: &Robot, b: &Robot, qs: &[Vec<Real>]) -> Real {
    let (ca, cb) = (a.chain(), b.chain());
    let fk = |r: &Robot, c: &crate::robot::Chain, q: &[Real]| {
        crate::robot::loaded::loaded_fk(r, c, q, 0.0).unwrap().pos
    };
    qs.iter()
        .map(|q| (fk(a, &ca, q) - fk(b, &cb, q)).norm())
        .fold(0.0, |m: Real, g| if g > m || g.is_nan() { g } else { m })
}

/// `nominal` with the errors `want` on `params` identified back, noise-free, by `solver`
/// from zero on `n` loaded tool points of that truth (poses of `stream`): its residual under
/// `rms_tol` and every parameter recovered (to 1e-6 mm, 1e-9 rad). The truth, the data and
/// the identified robot.
fn recovered(
    (nominal, params): (&Robot, &[Param]),
    want: &DVector<Real>,
    (n, stream): (usize, (u64, &str)),
    solver: &dyn crate::identify::solver::Solver,
    rms_tol: Real,
) -> (Robot, RobotData, Robot) {
    let index: Vec<usize> = params.iter().map(|p| p.index(nominal.dof())).collect();
    let truth = nominal.with_added(&index, want.as_slice());
    let d = loaded_points(nominal, &truth, n, stream);
    let p = d.problem(nominal, params, Measure::Position).unwrap();
    let out = solve(solver, &p, &DVector::zeros(params.len()));
    assert!(out.rms_residual < rms_tol, "rms {:e}", out.rms_residual);
    for (c, q) in params.iter().enumerate() {
        let tol = if q.is_length() { 1e-6 } else { 1e-9 };
        let (got, want) = (out.x[c], want[c]);
        assert!((got - want).abs() < tol, "{q}: got {got:e}, want {want:e}");
    }
    let got = p.robot_with(&out.x);
    (truth, d, got)
}

/// How far `got` stands from `truth` at the first ten poses of `d` ([`largest_point_gap`]),
/// and the RMS residual left on `d` when `solver` identifies, from zero, the `params` of
/// `nominal` but those `dropped` picks: the size of what those explain.
fn gap_and_rms_without(
    d: &RobotData,
    (got, truth): (&Robot, &Robot),
    (nominal, params): (&Robot, &[Param]),
    dropped: fn(&Param) -> bool,
    solver: &dyn crate::identify::solver::Solver,
) -> (Real, Real) {
    let gap = largest_point_gap(got, truth, &d.qs[..10]);
    let kept: Vec<Param> = params.iter().copied().filter(|p| !dropped(p)).collect();
    let p = d.problem(nominal, &kept, Measure::Position).unwrap();
    (
        gap,
        solve(solver, &p, &DVector::zeros(kept.len())).rms_residual,
    )
}

/// Per parameter of `params`, how far the analytic Jacobian column of `p` (with `rows`
/// residuals) at `x0` stands from its central difference ([`central`]): the largest
/// difference over `1 +` the column's largest entry. A column `loaded` picks must move the
/// point (an entry above 1), or the test fails naming it.
fn column_errors(
    p: &RobotProblem,
    rows: usize,
    x0: &DVector<Real>,
    params: &[Param],
    loaded: fn(&Param) -> bool,
) -> Vec<Real> {
    let mut r = DVector::zeros(rows);
    let mut j = DMatrix::zeros(rows, params.len());
    p.evaluate(x0, &mut r, &mut j);
    let (mut rp, mut rm, mut jj) = (r.clone(), r.clone(), j.clone());
    let mut errs = Vec::with_capacity(params.len());
    for (c, param) in params.iter().enumerate() {
        let fd = central(p, x0, c, (&mut rp, &mut rm, &mut jj));
        assert!(!loaded(param) || fd.amax() > 1.0, "{param}: column ≈ 0");
        errs.push((&fd - j.column(c)).amax() / (1.0 + fd.amax()));
    }
    errs
}

/// The central difference (step 1e-6) of `p`'s point residual along parameter `c` at `x0`:
/// the Jacobian column its analytic one must match; `scratch` the residual and Jacobian
/// buffers it evaluates into.
fn central(
    p: &RobotProblem,
    x0: &DVector<Real>,
    c: usize,
    (rp, rm, jj): (&mut DVector<Real>, &mut DVector<Real>, &mut DMatrix<Real>),
) -> DVector<Real> {
    let h = 1e-6;
    let mut xp = x0.clone();
    xp[c] += h;
    let mut xm = x0.clone();
    xm[c] -= h;
    p.evaluate(&xp, rp, jj);
    p.evaluate(&xm, rm, jj);
    // r = measured − model, so the model's derivative is −∂r/∂x.
    (&*rm - &*rp) / (2.0 * h)
}

/// Displaces `count` points (the first ones) by 0.5–1 mm in random directions.
fn add_outliers(d: &mut RobotData, count: usize, rng: &mut Rng) {
    let normal = Normal::new(0.0, 1.0).expect("unit");
    for p in d.points.iter_mut().take(count) {
        let dir = Vec3::new(normal.sample(rng), normal.sample(rng), normal.sample(rng)).normalize();
        *p += dir * rng.random_range(0.5..1.0);
    }
}

/// RMS position error of `robot` against `truth` over 50 fresh poses.
fn validation_rms(truth: &Robot, robot: &Robot) -> Real {
    let mut r = rng::from_seed(999);
    let qs = uniform_joint_poses(truth, 50, &mut r);
    let (ct, cr) = (truth.chain(), robot.chain());
    let s: Real = qs
        .iter()
        .map(|q| (ct.fk(q).pos - cr.fk(q).pos).norm_squared())
        .sum();
    (s / qs.len() as Real).sqrt()
}

fn run(s: &Setup, data: &RobotData, m: &dyn Solver) -> (Identified, Real) {
    let p = data
        .problem(&s.nominal, &s.params, Measure::Position)
        .expect("problem");
    let out = solve(m, &p, &DVector::zeros(s.params.len()));
    let rms = validation_rms(&s.truth, &p.robot_with(&out.x));
    (out, rms)
}

fn all_methods() -> Vec<Box<dyn Solver>> {
    let ridge = |xi| -> Box<dyn Solver> {
        Box::new(RidgeOptions {
            xi,
            ..Default::default()
        })
    };
    vec![
        Box::new(LsOptions::default()),
        ridge(XiRule::Fixed(1e-12)),
        ridge(XiRule::DoubleH),
        ridge(XiRule::Gcv),
        ridge(XiRule::LCurve),
        Box::new(RobustOptions::default()),
        Box::new(RobustOptions {
            robust: Robustness {
                sigma0: Sigma0::Mad,
                ..Default::default()
            },
            ..Default::default()
        }),
        Box::new(LmOptions::default()),
        Box::new(LmOptions {
            adaptive: true,
            ..Default::default()
        }),
        Box::new(LmOptions {
            adaptive: true,
            marquardt: true,
            ..Default::default()
        }),
    ]
}

/// [`Linear`] with Tikhonov precisions: the MAP problem.
struct LinearMap {
    p: Linear,
    l: Vec<Real>,
}

impl LeastSquares for LinearMap {
    fn size(&self) -> solver::Size {
        self.p.size()
    }
    fn evaluate(&self, x: &DVector<Real>, r: &mut DVector<Real>, j: &mut DMatrix<Real>) {
        self.p.evaluate(x, r, j);
    }
    fn tikhonov(&self) -> Option<&[Real]> {
        Some(&self.l)
    }
}

/// The priors' Tikhonov terms give the closed-form MAP estimate `(AᵀA + Λ)⁻¹ Aᵀb` in every
/// Jacobian method (LM with a vanishing damping), and the reported normal matrix is the
/// posterior's `AᵀA + Λ`.
#[test]
fn priors_give_the_closed_form_map_estimate() {
    let l = vec![4.0, 0.0, 25.0];
    let p = LinearMap {
        p: linear(),
        l: l.clone(),
    };
    let n = p.p.a.transpose() * &p.p.a + DMatrix::from_diagonal(&DVector::from_vec(l));
    let want = n.clone().try_inverse().unwrap() * p.p.a.transpose() * &p.p.b;
    let x0 = DVector::zeros(3);
    let lm = LmOptions {
        adaptive: true,
        lambda0: 1e-12,
        eps: 1e-12,
        ..Default::default()
    };
    let methods: Vec<(&str, Box<dyn Solver>)> =
        vec![("ls", Box::new(LsOptions::default())), ("lm", Box::new(lm))];
    for (name, m) in methods {
        let r = solve(m.as_ref(), &p, &x0);
        assert!((&r.x - &want).amax() < 1e-9, "{name}: {} vs {want}", r.x);
        assert!((&r.normal - &n).amax() < 1e-9, "{name}");
    }
    // Without priors the estimate is the least-squares one, farther from 0 on x3.
    let free = solve(&LsOptions::default(), &linear(), &x0);
    assert!(free.x[2].abs() > want[2].abs());
}

mod floor;
mod gravity;
mod harmonics;
mod simulated;
mod streamed;

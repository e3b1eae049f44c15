//! Identification methods: every method behind one interface, [`Method`], over one
//! problem description, [`CalibrationProblem`], returning one result type, [`Identified`].
//!
//! | method (`name`) | type | what it solves | source |
//! |---|---|---|---|
//! | `ls` | [`LsOptions`] | `(JᵀPJ) δx = JᵀP E`, iterated (Gauss–Newton) | Li 2018 eq. 13 |
//! | `ridge` | [`RidgeOptions`] | `(JᵀPJ + ξD) δx = JᵀP E − ξD(x − x0)` | Li 2018 eq. 14 |
//! | `igg3` | [`RobustOptions`] | the ridge equations with IGG3 (Huber, Tukey) weights | Li 2018 §2.2, eqs. 15–18 |
//! | `lm` | [`LmOptions`] | `(JᵀJ + μI) Δx = JᵀΔP`, μ fixed or adaptive | Guo 2024 eq. 8; Ban (LM) |
//! | `ls` with `error_model` | [`PoseErrorLs`] | Gauss–Newton on one of Qiao's three pose-error models | Qiao 2021 §2.2–2.3, §4.2 |
//! | `bas`, `pso`, `bas-pso` | [`Metaheuristic`] | Qiao's fitness (eq. 14) by a derivative-free search | Qiao 2021 eqs. 12–14 |
//!
//! `E = measured − model(x)` is the residual and `J = ∂model/∂x`. Failing to converge is a
//! [`Termination`] in the result, never a panic, so a Monte-Carlo run can count failures; an
//! `Err` means the problem itself is inconsistent (sizes, non-finite values).
//!
//! ## Layout
//!
//! - this file: the interface ([`Method`], [`CalibrationProblem`], [`Identified`],
//!   [`Termination`]);
//! - [`external`]: a method supplied from outside (a function of the problem), as the
//!   Python module's methods are;
//! - [`registry`]: the method names, each with the function that reads its options from a
//!   scenario's `[[methods]]` entry ([`MethodSpec`]); [`options`]: how one table feeds two
//!   options structs, each declaring its own keys;
//! - one file per method: [`ls`], [`ridge`], [`robust`], [`lm`], and in [`qiao`] Qiao 2021's
//!   searches and pose-error models;
//! - the shared machinery of the Jacobian-based methods: [`solver`] (the least-squares
//!   engine), [`xi`] (ridge parameter rules), [`weights`] (robust weights), [`robot`] (the
//!   kinematic least-squares problem).
//!
//! Adding a method is one file with an options struct that implements [`Method`] and one
//! line in [`registry::METHODS`] (README, "Adding a method").

pub mod external;
pub mod kind;
pub mod lm;
pub mod ls;
pub use crate::numeric::options;
pub mod qiao;
pub mod registry;
pub mod ridge;
pub mod robot;
pub mod robust;
pub mod solver;
pub mod weights;
pub mod xi;

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};
use crate::measurement::Measure;
use crate::measurement::Measurements;
use crate::numeric::rng::Rng;
use crate::numeric::{Frame, Mat3, Real, Vec3};
use crate::robot::{Param, Robot};

pub use lm::LmOptions;
pub use ls::LsOptions;
pub use qiao::method::{Metaheuristic, Search};
pub use qiao::pose_error::PoseErrorLs;
pub use registry::{method_by_name, MethodEntry, MethodSpec, METHODS};
pub use ridge::RidgeOptions;
pub use robot::RobotProblem;
pub use robust::RobustOptions;
pub use solver::{solve, LeastSquares, Size, Solver};
pub use weights::{Per, Robustness, Sigma0, WeightFn};
pub use xi::XiRule;

/// An identification method with its options: the one interface through which `run` and
/// `identify` reach every method.
pub trait Method: std::fmt::Debug + Send + Sync {
    /// Checks the option values; an error names the offending key.
    fn check(&self) -> Result<()>;

    /// Identifies the errors of `problem.params` (in their order). `rng` is the method's own
    /// stream (used by the stochastic searches only). An `Err` means the problem is
    /// inconsistent; how a valid problem's iterations ended is [`Identified::termination`].
    fn identify(&self, problem: &CalibrationProblem, rng: &mut Rng) -> Result<Identified>;

    /// Whether the method gives an answer on parameters the data cannot all determine (a
    /// rank-deficient Jacobian): LM's damping (Guo 2024 eq. 8) and ridge's regularisation
    /// (Li 2018 eq. 14) keep such a problem solvable; plain least squares does not, and a
    /// study refuses to run it on a rank-deficient `identification.params`.
    fn tolerates_rank_deficiency(&self) -> bool {
        false
    }

    /// The method as a [`Solver`] of any least-squares problem (the Jacobian methods, which
    /// also solve the measurement kinds' [`kind::KindProblem`]); `None` for the others.
    fn solver(&self) -> Option<&dyn Solver> {
        None
    }

    /// For a search on Qiao's fitness (eq. 14), the pose-error model the fitness is built on:
    /// two searches with the same model and the same `k` minimise the same function of the
    /// same data, so their best fitnesses compare. `None` for the other methods.
    fn fitness_model(&self) -> Option<qiao::error_models::ErrorModel> {
        None
    }

    /// For a search, the box it explores around the nominal values; `None` for the others.
    fn search_box(&self) -> Option<&qiao::method::SearchBox> {
        None
    }
}

/// Why an identification stopped. The names (serde, kebab-case) are those of reports and
/// `trials.csv`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "kebab-case")]
pub enum Termination {
    /// The step fell below the tolerance (`max |dx| < ε`), or the fit reached the rounding
    /// floor of its data ([`solver::LeastSquares::rounding_floor`]).
    Converged,
    /// The iteration limit was reached first.
    MaxIterations,
    /// The evaluation budget was spent first.
    MaxEvaluations,
    /// A search reached its target fitness.
    TargetReached,
    /// The residual became non-finite or grew without bound.
    Diverged,
    /// The normal matrix could not be factorised (rank-deficient parameters).
    Singular,
    /// The data do not determine every parameter (the column-scaled Jacobian at the solution
    /// has a numerical rank below the number of parameters): the undetermined directions were
    /// filled in by the method's damping or regularisation, not by the data.
    RankDeficient,
    /// Levenberg–Marquardt could not find a step that lowers the cost.
    NoProgress,
    /// The problem or the settings are inconsistent (sizes, non-finite start, bad options);
    /// the default: no solve ran.
    #[default]
    InvalidInput,
}

impl Termination {
    /// The name used in reports: `converged`, `max-iterations`, `max-evaluations`,
    /// `target-reached`, `diverged`, `singular`, `rank-deficient`, `no-progress`,
    /// `invalid-input`.
    pub fn as_str(self) -> &'static str {
        self.into()
    }

    /// Whether an identification that ended so gave no result at all: it diverged, was
    /// singular or had invalid input (a rank-deficient one may still be used, where the
    /// deficiency was expected).
    pub fn gives_nothing(self) -> bool {
        matches!(
            self,
            Termination::Diverged | Termination::Singular | Termination::InvalidInput
        )
    }
}

/// The outcome of an identification, the same for every method.
#[derive(Clone, Debug)]
pub struct Identified {
    /// The estimate (for a [`CalibrationProblem`]: the parameter errors, mm / rad).
    pub x: DVector<Real>,
    /// Iterations carried out.
    pub iterations: usize,
    /// Evaluations of the model (residuals, with the Jacobian for the Jacobian methods; the
    /// fitness for the searches).
    pub evaluations: usize,
    /// Why the iterations stopped.
    pub termination: Termination,
    /// The objective per iteration, where the method records it (the searches' best
    /// fitness, Qiao 2021 fig. 4).
    pub trace: Option<Vec<Real>>,
    /// Final weight of each point: the prior weights (1 without standard deviations) for a
    /// solver that does not reweigh, times the robust weight for IGG3, Huber and Tukey; 1 for
    /// the searches and external methods. With IGG3's `per = "coordinate"`, each point's mean
    /// over its rows ([`Identified::row_weights`] holds the rows').
    pub weights: Vec<Real>,
    /// Final weight of each residual row, point after point, when the method weighed each row
    /// on its own (IGG3 with `per = "coordinate"`); `None` when every row has its point's
    /// weight ([`Identified::weights`]).
    pub row_weights: Option<Vec<Real>>,
    /// Whether [`Identified::weights`] are what the fit weighed its points by (the Jacobian
    /// methods: the prior weights, times the robust ones); false for a method that reports
    /// none (the searches and external methods: `weights` are then 1, and the points were
    /// weighed by the problem's prior weights, [`CalibrationProblem::weights`]).
    pub own_weights: bool,
    /// Numerical rank of the column-scaled, weighted Jacobian at the solution
    /// ([`solver::rank`], [`solver::RANK_TOLERANCE`]); `None` when not computed.
    pub rank: Option<usize>,
    /// The normal matrix `JᵀPJ` at the solution, from which [`Identified::covariance`] and
    /// [`Identified::condition_number`] come on demand; empty when not computed.
    pub normal: DMatrix<Real>,
    /// Unit-weight standard deviation `sqrt(vᵀPv / (n − t))` at the solution, n counting each
    /// row with its point's weight (for IGG3 with [`Sigma0::Mad`], the MAD-based value); NaN
    /// when `n ≤ t` or not computed.
    pub sigma0: Real,
    /// Root mean square over points of the residual norm per point, `sqrt(Σ|v_i|² / m)`,
    /// unweighted, at the solution; NaN when not computed.
    pub rms_residual: Real,
    /// The ridge parameter used in the last iteration (ridge and IGG3 only), in the units of
    /// the (scaled) normal matrix, see [`RidgeOptions`].
    pub ridge_xi: Option<Real>,
}

impl Identified {
    /// Condition number σ_max/σ_min of the column-scaled, weighted Jacobian at the solution
    /// ([`solver::conditioning`], docs/formats.md `condition_number`; computed here, as the
    /// Monte-Carlo runs do not need it); infinite below full rank, NaN when not computed.
    pub fn condition_number(&self) -> Real {
        if self.normal.is_empty() {
            Real::NAN
        } else if self.normal.iter().all(|v| v.is_finite()) {
            solver::conditioning(&self.normal).1
        } else {
            Real::NAN
        }
    }

    /// `σ0² (JᵀPJ)⁻¹` at the solution (computed here from [`Identified::normal`] and
    /// [`Identified::sigma0`], as the Monte-Carlo runs do not need it); NaN entries when
    /// `JᵀPJ` is below full rank or singular, or there is no redundancy, or the method does
    /// not estimate σ0 (the searches); empty when `JᵀPJ` was not computed.
    pub fn covariance(&self) -> DMatrix<Real> {
        let t = self.normal.nrows();
        let mut cov = DMatrix::from_element(t, t, Real::NAN);
        if t == 0 || self.rank != Some(t) {
            return cov;
        }
        let mut l = self.normal.clone();
        if !crate::numeric::linalg::cholesky_in_place(&mut l) {
            return cov;
        }
        let s2 = self.sigma0 * self.sigma0;
        let mut e = DVector::zeros(t);
        for c in 0..t {
            e.fill(0.0);
            e[c] = 1.0;
            crate::numeric::linalg::cholesky_solve(&l, &mut e);
            for k in 0..t {
                cov[(k, c)] = s2 * e[k];
            }
        }
        cov
    }

    /// The standard error of each parameter ([`standard_error`] of [`Self::covariance`]).
    pub fn standard_errors(&self) -> Vec<Real> {
        let cov = self.covariance();
        (0..cov.nrows()).map(|i| standard_error(&cov, i)).collect()
    }

    /// A result without the statistics of the Jacobian methods (no covariance, condition
    /// number or residual): for methods that do not form `JᵀPJ`.
    pub fn plain(
        x: Vec<Real>,
        iterations: usize,
        evaluations: usize,
        termination: Termination,
        points: usize,
    ) -> Identified {
        Identified {
            x: DVector::from_vec(x),
            iterations,
            evaluations,
            termination,
            trace: None,
            weights: vec![1.0; points],
            row_weights: None,
            own_weights: false,
            normal: DMatrix::zeros(0, 0),
            sigma0: Real::NAN,
            rms_residual: Real::NAN,
            ridge_xi: None,
            rank: None,
        }
    }
}

/// The problem every method solves: the nominal robot, the parameters whose errors are
/// identified, the measurements and the registration that brings them into the robot's base
/// frame, per-point weights and the orientation weight `k`.
#[derive(Clone, Debug)]
pub struct CalibrationProblem<'a> {
    /// The nominal robot.
    pub nominal: &'a Robot,
    /// The parameters identified, in the order of the estimate.
    pub params: &'a [Param],
    /// Position or full pose (full pose when the measurements carry orientations).
    pub measure: Measure,
    /// The measurements, as delivered (instrument frame).
    pub data: &'a Measurements,
    /// The registration: instrument coordinates → base frame.
    pub frame: Frame,
    /// Weight of orientation against position residuals of full-pose data, mm per rad (Qiao
    /// 2021 eq. 14's k).
    pub k: Real,
    /// The measured points in the base frame (mm).
    pub points: Vec<Vec3>,
    /// The measured orientations in the base frame (full-pose data).
    pub rotations: Option<Vec<Mat3>>,
    /// Per-point weights ([`Measurements::weights`]); `None`: every point weighs 1.
    pub weights: Option<Vec<Real>>,
    /// Tikhonov precision of each parameter's error towards 0 (the nominal value), in the
    /// units of the weighted cost ([`MethodSpec::precisions`]); empty: no priors. The
    /// Jacobian methods minimise `rᵀPr + Σ λ_k x_k²` (a MAP estimate); the searches ignore it.
    pub priors: Vec<Real>,
    /// Records the RMS point residual (mm) of each evaluation of the kinematic least squares
    /// ([`MethodSpec::trace`]); `None`: not recorded.
    pub trace: Option<TraceRecorder>,
    /// The errors of `params` the Jacobian methods start from; empty: 0, the nominal robot.
    /// The ridge's penalty and the priors stay towards 0 ([`solver::solve_from`]); the
    /// searches ignore it. A second fit with parameters re-admitted at the identified robot
    /// starts there ([`crate::calibrate::recheck`]).
    pub start: Vec<Real>,
}

/// A shared record of the RMS point residual per evaluation (`identify`'s convergence trace).
pub type TraceRecorder = std::sync::Arc<std::sync::Mutex<Vec<Real>>>;

impl<'a> CalibrationProblem<'a> {
    /// The problem of identifying the errors of `params` of `nominal` from `data`, brought
    /// into the base frame by `frame`, with orientation weight `k`.
    pub fn new(
        nominal: &'a Robot,
        params: &'a [Param],
        data: &'a Measurements,
        frame: Frame,
        k: Real,
    ) -> CalibrationProblem<'a> {
        let (points, rotations) = data.in_frame(&frame);
        CalibrationProblem {
            nominal,
            params,
            measure: data.measure(),
            data,
            frame,
            k,
            points,
            rotations,
            weights: data.weights(),
            priors: Vec::new(),
            trace: None,
            start: Vec::new(),
        }
    }

    /// The measured tool frames (in the problem's frame) of full-pose data, for the
    /// pose-error models (Qiao 2021 §2); `key` names the setting that needs them.
    pub fn measured_frames(&self, key: &str) -> Result<Vec<Frame>> {
        let rots = self
            .rotations
            .as_ref()
            .ok_or_else(|| Error::setting(key, "the pose-error models need full-pose data"))?;
        Ok(self
            .points
            .iter()
            .zip(rots)
            .map(|(p, r)| Frame { rot: *r, pos: *p })
            .collect())
    }

    /// The joint values of the measured poses.
    pub fn poses(&self) -> &[Vec<Real>] {
        &self.data.qs
    }

    /// The compensated robot: the nominal robot with the errors `x` added.
    pub fn robot_with(&self, x: &[Real]) -> Robot {
        let errors: Vec<(Param, Real)> =
            self.params.iter().copied().zip(x.iter().copied()).collect();
        self.nominal.with_errors(&errors)
    }
}

#[cfg(test)]
mod tests;

/// The standard error of parameter `i`: the square root of the covariance's diagonal; NaN
/// where the covariance is not given (its entries NaN: a method that forms no `JᵀPJ`, a
/// rank below full) or lacks the parameter, never 0, which would claim it known exactly.
pub fn standard_error(covariance: &DMatrix<Real>, i: usize) -> Real {
    covariance
        .get((i, i))
        .filter(|v| v.is_finite())
        .map_or(Real::NAN, |v| v.max(0.0).sqrt())
}

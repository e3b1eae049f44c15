//! Pose-error models for Jacobian-based identification and Qiao's accuracy figures (Qiao
//! 2021, §2.2–2.3, §4.1–4.2).
//!
//! Qiao compares three ways to relate a measured pose `T_m = [R_m P_m; 0 1]` to the model
//! pose `T = [R P; 0 1]` of the current parameters (columns of `R`: n, o, a):
//!
//! | model | residual `r` (measured − model) | `−∂r/∂η` | Qiao |
//! |---|---|---|---|
//! | [`ErrorModel::Differential`] | `[P_m − P; n_m − n; o_m − o; a_m − a]` (12 rows) | `[J_p; [ω]×n; [ω]×o; [ω]×a]`, `ω = J_ω` | §2.2, eq. 5 |
//! | [`ErrorModel::CoordinateTransfer`] | `[d; δ]` of `Δ = T_m T⁻¹ − I ≈ [[δ]× d; 0 0]`: `d = P_m − R_e P`, `δ = vee((R_e − R_eᵀ)/2)`, `R_e = R_m Rᵀ` (6 rows) | `[R_e(J_p + [P]×J_ω); ½(tr R_e·I − R_eᵀ)J_ω]`, at `R_e = I` eq. 11's `[J_p + [P]×J_ω; J_ω]` | §2.3, eqs. 6–11 |
//! | [`ErrorModel::DirectFk`] | `[P_m − P; φ]`, `φ = log(R_m Rᵀ)` (6 rows, exact rotation vector) | `[J_p; J_r⁻¹(φ)J_ω]` | §4.2 "model 3" |
//!
//! `J_p`, `J_ω` are the tool-point and tool-rotation columns of [`crate::robot::jacobian`]
//! (exact first derivatives of forward kinematics, `∂R = [J_ω ∂η]× R`), `J_r` the right
//! Jacobian of SO(3). The Jacobians are exact derivatives of the residuals at any
//! linearisation point (tested against finite differences), so Gauss–Newton converges to the
//! least-squares minimum of each model's residual, and on noise-free data all three reach the
//! true parameters. Each model is a least-squares problem ([`PoseErrorProblem`]) of the one
//! engine of the Jacobian-based methods ([`crate::identify::solver`]); [`identify`] runs its
//! Gauss–Newton iteration.
//!
//! At `T_m = T` the three Jacobians predict the same first-order change of the pose: the
//! models agree to first order and differ only in the coordinates in which they measure the
//! error. Those coordinates matter in two ways. Linearised once at the nominal parameters
//! (Qiao's models 1 and 2), each model keeps its own second-order error: the differential
//! model compares matrix entries (its rotation rows are not a rotation), the
//! coordinate-transfer model drops second-order parts of `R_m Rᵀ` in `δ` and through
//! `R_m Rᵀ P` in `d` (Qiao §4.2's "two neglects"); the direct model neglects nothing once
//! iterated. And with measurement noise, the coordinate-transfer position rows carry the
//! orientation noise times the lever arm `|P|` (about 1 m), which makes that model the
//! noisiest of the three: with tracker-like noise the order is coordinate transfer worst,
//! then differential, then direct identification on the forward kinematics, as Qiao reports
//! (see the tests).
//!
//! Residual rows are in mm for positions and rad (or dimensionless) for orientation; the
//! orientation rows are weighted by a factor `k` as in Qiao's fitness (eq. 14), see [`stack`].

use std::cell::RefCell;

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};
use crate::identify::solver::{solve, LeastSquares, Size};
use crate::identify::{Identified, LsOptions};
use crate::measurement::Measure;
use crate::numeric::{matrix_rpy, Frame, Mat3, Real, Vec3};
use crate::robot::jacobian::{log_orientation_rows, pose_rows, Columns};
use crate::robot::{Chain, Param, Robot};

/// The options key that picks a pose-error model (`ls`, `bas`, `pso`, `bas-pso`); errors
/// about the model name it.
pub const ERROR_MODEL: &str = "error_model";

/// The pose-error model of an identification (see the module docs for the formulas).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "snake_case")]
pub enum ErrorModel {
    /// Differential transformation of the pose matrix (Qiao §2.2, eq. 5): 12 rows per pose.
    Differential,
    /// Coordinate-error transfer through the link frames (Qiao §2.3, eqs. 6–11): 6 rows.
    CoordinateTransfer,
    /// Direct identification on forward kinematics (Qiao §4.2, error model 3): 6 rows.
    DirectFk,
}

impl ErrorModel {
    /// The three models.
    pub const ALL: [ErrorModel; 3] = [
        ErrorModel::Differential,
        ErrorModel::CoordinateTransfer,
        ErrorModel::DirectFk,
    ];

    /// Residual rows per pose.
    pub fn rows(self) -> usize {
        match self {
            ErrorModel::Differential => 12,
            ErrorModel::CoordinateTransfer | ErrorModel::DirectFk => 6,
        }
    }

    /// The setting's name: `differential`, `coordinate_transfer` or `direct_fk`.
    pub fn as_str(self) -> &'static str {
        self.into()
    }
}

impl std::fmt::Display for ErrorModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Writes one pose's residual (rows `row0..row0 + model.rows()` of `r`) and Jacobian (same
/// rows of `j`, one column per entry of `cols`) of `model` at joint values `q`, for the
/// robot compiled in `chain`, against the measured tool frame `measured` (world). Returns the
/// model frame. Allocation-free; `r` and `j` must have room for the rows.
#[allow(clippy::too_many_arguments)]
pub fn rows_into(
    model: ErrorModel,
    chain: &Chain,
    cols: &Columns,
    q: &[Real],
    measured: &Frame,
    r: &mut DVector<Real>,
    j: &mut DMatrix<Real>,
    row0: usize,
) -> Frame {
    let t = pose_rows(chain, cols, q, Measure::Pose, j, row0);
    let (rm, pm) = (&measured.rot, &measured.pos);
    match model {
        ErrorModel::Differential => {
            let dp = pm - t.pos;
            for k in 0..3 {
                r[row0 + k] = dp[k];
            }
            for c in 0..3 {
                let d = rm.column(c) - t.rot.column(c);
                for k in 0..3 {
                    r[row0 + 3 + 3 * c + k] = d[k];
                }
            }
            for col in 0..cols.len() {
                let w = Vec3::new(j[(row0 + 3, col)], j[(row0 + 4, col)], j[(row0 + 5, col)]);
                for c in 0..3 {
                    // ∂(column c) = ω × column c.
                    let d = w.cross(&t.rot.column(c).into_owned());
                    for k in 0..3 {
                        j[(row0 + 3 + 3 * c + k, col)] = d[k];
                    }
                }
            }
        }
        ErrorModel::CoordinateTransfer => {
            let re = rm * t.rot.transpose();
            let d = pm - re * t.pos;
            let s = (re - re.transpose()) * 0.5;
            let delta = Vec3::new(s[(2, 1)], s[(0, 2)], s[(1, 0)]);
            for k in 0..3 {
                r[row0 + k] = d[k];
                r[row0 + 3 + k] = delta[k];
            }
            // Exact derivatives at any R_e = R_m Rᵀ (with ∂R = [ω]×R): ∂d = −R_e(J_p + P × ω)
            // and ∂δ = −½(tr R_e·I − R_eᵀ)ω; both reduce to Qiao's eq. 11 at R_e = I.
            let g = (Mat3::identity() * re.trace() - re.transpose()) * 0.5;
            for col in 0..cols.len() {
                let w = Vec3::new(j[(row0 + 3, col)], j[(row0 + 4, col)], j[(row0 + 5, col)]);
                let v = Vec3::new(j[(row0, col)], j[(row0 + 1, col)], j[(row0 + 2, col)])
                    + t.pos.cross(&w);
                let (jp, jw) = (re * v, g * w);
                for k in 0..3 {
                    j[(row0 + k, col)] = jp[k];
                    j[(row0 + 3 + k, col)] = jw[k];
                }
            }
        }
        ErrorModel::DirectFk => {
            let dp = pm - t.pos;
            for k in 0..3 {
                r[row0 + k] = dp[k];
            }
            log_orientation_rows(rm, &t.rot, 1.0, r, j, row0 + 3);
        }
    }
    t
}

/// One pose's residual and Jacobian of `model` for `robot` (the linearisation point) and the
/// parameters `params`, against the measured tool frame (world). `out_r` must hold
/// `model.rows()` values and `out_j` be `model.rows()` × `params.len()`. Compiles the chain
/// per call: stacked identification should use [`rows_into`] or [`stack`].
pub fn residual_and_jacobian(
    model: ErrorModel,
    robot: &Robot,
    params: &[Param],
    q: &[Real],
    measured: &Frame,
    out_r: &mut [Real],
    out_j: &mut DMatrix<Real>,
) -> Result<()> {
    let rows = model.rows();
    if out_r.len() != rows || out_j.nrows() != rows || out_j.ncols() != params.len() {
        return Err(Error::setting(
            ERROR_MODEL,
            format!(
                "{model} needs a residual of {rows} and a Jacobian of {rows}×{}",
                params.len()
            ),
        ));
    }
    check_pose(robot, q, 0)?;
    let mut r = DVector::zeros(rows);
    let cols = Columns::new(params, robot.dof());
    rows_into(model, &robot.chain(), &cols, q, measured, &mut r, out_j, 0);
    out_r.copy_from_slice(r.as_slice());
    Ok(())
}

fn check_pose(robot: &Robot, q: &[Real], i: usize) -> Result<()> {
    if q.len() != robot.dof() || q.iter().any(|v| !v.is_finite()) {
        return Err(Error::setting(
            "poses",
            format!("pose {i}: expected {} finite joint values", robot.dof()),
        ));
    }
    Ok(())
}

/// The stacked residual and Jacobian of `model` over all poses, with the orientation rows
/// (all rows after the first three of each pose) multiplied by `k`: [`PoseErrorProblem`]
/// evaluated at `robot` (no errors added).
///
/// `k` plays the part of the weighting factor of Qiao's fitness (eq. 14), which balances
/// orientation errors (rad, or dimensionless matrix entries) against position errors (mm):
/// with `k = 1` one radian counts as one millimetre, which leaves the orientation data almost
/// unused; [`crate::identify::qiao::DEFAULT_K`] (100 mm) puts the two on a comparable footing
/// for a tracker measuring about 15 µm and 0.005°.
pub fn stack(
    model: ErrorModel,
    robot: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
    measured: &[Frame],
    k: Real,
) -> Result<(DVector<Real>, DMatrix<Real>)> {
    let problem = PoseErrorProblem::new(model, robot, params, qs, measured, k)?;
    let size = problem.size();
    let mut r = DVector::zeros(size.rows());
    let mut j = DMatrix::zeros(size.rows(), size.params);
    problem.evaluate(&DVector::zeros(size.params), &mut r, &mut j);
    Ok((r, j))
}

/// One of Qiao's pose-error models as a least-squares problem of the engine
/// ([`LeastSquares`], [`crate::identify::solver`]): the unknowns are errors `x` of `params`
/// added to the nominal robot; each pose's residual and Jacobian are those of [`rows_into`]
/// at the corrected robot, the orientation rows weighted by `k` (see [`stack`]), and each
/// pose may carry a prior weight (its rows weighed by `w_j` in `JᵀPJ`).
#[derive(Debug)]
pub struct PoseErrorProblem<'a> {
    model: ErrorModel,
    nominal: &'a Robot,
    /// Flat index of each parameter.
    index: Vec<usize>,
    cols: Columns,
    qs: &'a [Vec<Real>],
    measured: &'a [Frame],
    /// Weight of the orientation rows (mm per rad, or per unit of matrix entry).
    k: Real,
    prior: Option<&'a [Real]>,
    /// Working parameter values and the chain compiled from them, updated in place at each
    /// evaluation ([`Chain::set_values`]).
    work: RefCell<(Vec<Real>, Chain)>,
}

impl<'a> PoseErrorProblem<'a> {
    /// The problem of `model` over the errors of `params` of `nominal`, from the tool frames
    /// `measured` (world) at the joint values `qs`, orientation rows weighted by `k`. Fails
    /// when a parameter is not one of the robot's kinematic parameters, `k` is not finite and
    /// positive, the frames do not match the poses, or a pose has the wrong number of joint
    /// values or a non-finite one, or a non-finite measured frame.
    pub fn new(
        model: ErrorModel,
        nominal: &'a Robot,
        params: &[Param],
        qs: &'a [Vec<Real>],
        measured: &'a [Frame],
        k: Real,
    ) -> Result<Self> {
        super::check_k(k)?;
        let all = nominal.params();
        if let Some(p) = params.iter().find(|p| !all.contains(p)) {
            return Err(Error::setting(
                "params",
                format!("{p} is not a parameter of robot {}", nominal.name),
            ));
        }
        if qs.len() != measured.len() {
            return Err(Error::setting(
                "measurements",
                format!("{} poses but {} measured frames", qs.len(), measured.len()),
            ));
        }
        for (i, (q, m)) in qs.iter().zip(measured).enumerate() {
            check_pose(nominal, q, i)?;
            if m.pos.iter().chain(m.rot.iter()).any(|v| !v.is_finite()) {
                return Err(Error::setting(
                    "measurements",
                    format!("pose {i}: measured frame not finite"),
                ));
            }
        }
        let dof = nominal.dof();
        Ok(PoseErrorProblem {
            model,
            nominal,
            index: params.iter().map(|p| p.index(dof)).collect(),
            cols: Columns::new(params, dof),
            qs,
            measured,
            k,
            prior: None,
            work: RefCell::new((nominal.values.clone(), nominal.chain())),
        })
    }

    /// Gives pose `j` the prior weight `w[j]` (`None`: every pose weighs 1). Fails unless
    /// there is one finite, positive weight per pose.
    pub fn with_weights(mut self, w: Option<&'a [Real]>) -> Result<Self> {
        if w.is_some_and(|w| {
            w.len() != self.qs.len() || w.iter().any(|v| !(v.is_finite() && *v > 0.0))
        }) {
            return Err(Error::setting(
                "weights",
                "need one finite positive weight per pose",
            ));
        }
        self.prior = w;
        Ok(self)
    }
}

impl LeastSquares for PoseErrorProblem<'_> {
    /// The model's rows of every pose ([`rows_into`]) at `nominal + x`, orientation rows
    /// times `k`. The chain is updated in place.
    fn evaluate(&self, x: &DVector<Real>, r: &mut DVector<Real>, j: &mut DMatrix<Real>) {
        let mut guard = self.work.borrow_mut();
        let (values, chain) = &mut *guard;
        self.nominal
            .set_chain_with_added(&self.index, x.as_slice(), values, chain);
        let rows = self.model.rows();
        for (i, (q, m)) in self.qs.iter().zip(self.measured).enumerate() {
            rows_into(self.model, chain, &self.cols, q, m, r, j, rows * i);
        }
        if self.k != 1.0 {
            for row in (0..r.len()).filter(|row| row % rows >= 3) {
                r[row] *= self.k;
                j.row_mut(row).scale_mut(self.k);
            }
        }
    }

    fn size(&self) -> Size {
        Size::new(self.index.len(), self.qs.len(), self.model.rows())
    }

    fn prior(&self) -> Option<&[Real]> {
        self.prior
    }
}

/// The step below which the Gauss–Newton iteration of [`identify`] counts as converged:
/// `max |δx| < 1e-9` (mm or rad), the `eps` of `ls`.
pub const STEP_TOLERANCE: Real = 1e-9;

/// The result of [`identify`].
#[derive(Clone, Debug)]
pub struct ModelFit {
    /// Identified errors of the parameters, in their order (mm, rad).
    pub x: Vec<Real>,
    /// The robot with the errors applied.
    pub robot: Robot,
    /// The engine's result: how the iteration ended ([`Identified::termination`]), the
    /// iterations and evaluations, and the statistics of the model's least squares.
    pub identified: Identified,
}

/// Gauss–Newton identification with `model`: at most `iterations` steps of
/// `(JᵀPJ) δx = JᵀP r` (orientation rows weighted by `k`, see [`stack`]; `P` the prior
/// weights `w_j` per pose, or 1), re-linearised at the corrected robot each step, until
/// `max |δx| <` [`STEP_TOLERANCE`]: the [`PoseErrorProblem`] solved by the engine of `ls`
/// ([`LsOptions`], [`crate::identify::solver`]).
///
/// One step from the nominal robot is the linear identification of Qiao's error models 1
/// and 2 (their Jacobians carry the nominal parameters, §2.2–2.3); iterated to convergence,
/// [`ErrorModel::DirectFk`] is the identification on the forward kinematics without
/// neglected terms of §4.2 (model 3). The Jacobians are exact derivatives of the residuals
/// everywhere, so each model's iteration converges to the least-squares minimum of its own
/// residual.
///
/// How the iteration ended is the engine's [`Identified::termination`]: a residual that
/// becomes non-finite or grows without bound ends it as
/// [`crate::identify::Termination::Diverged`], a singular `JᵀPJ` as `Singular`. An `Err`
/// means the inputs are inconsistent (see [`PoseErrorProblem::new`], `iterations` 0, bad
/// weights).
#[allow(clippy::too_many_arguments)]
pub fn identify(
    model: ErrorModel,
    nominal: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
    measured: &[Frame],
    iterations: usize,
    k: Real,
    weights: Option<&[Real]>,
) -> Result<ModelFit> {
    crate::identify::qiao::search::check_iterations(iterations)?;
    let problem =
        PoseErrorProblem::new(model, nominal, params, qs, measured, k)?.with_weights(weights)?;
    let options = LsOptions {
        eps: STEP_TOLERANCE,
        max_iter: iterations,
    };
    let identified = solve(&options, &problem, &DVector::zeros(params.len()));
    Ok(ModelFit {
        x: identified.x.iter().copied().collect(),
        robot: problem
            .nominal
            .with_added(&problem.index, identified.x.as_slice()),
        identified,
    })
}

/// Qiao 2021's accuracy figures (§4.1–4.2).
#[derive(Clone, Debug, PartialEq)]
pub struct PoseErrorStats {
    /// ACPE of each run, mm: `(1/M) Σ_j √(Δx² + Δy² + Δz²)` over the M points (§4.1).
    pub acpe_mm: Vec<Real>,
    /// ACAE of each run, degrees: `(1/M) Σ_j √(Δα² + Δβ² + Δγ²)` (§4.1), with Δα, Δβ, Δγ the
    /// differences of the fixed X-Y-Z angles (wrapped to ±180°).
    pub acae_deg: Vec<Real>,
    /// APE, mm: `(1/(NM)) Σ_i Σ_j √(Δx² + Δy² + Δz²)` over N runs and M points (§4.2).
    pub ape: Real,
    /// AAE, degrees: `(1/(NM)) Σ_i Σ_j √(Δα² + Δβ² + Δγ²)` (§4.2).
    pub aae: Real,
}

fn wrap(a: Real) -> Real {
    use std::f64::consts::PI;
    let mut w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI {
        w += 2.0 * PI;
    }
    w
}

/// ACPE (mm) and ACAE (deg) of model frames against true frames (Qiao §4.1).
pub fn acpe_acae(truth: &[Frame], model: &[Frame]) -> Result<(Real, Real)> {
    if truth.is_empty() || truth.len() != model.len() {
        return Err(Error::setting(
            "frames",
            format!(
                "need as many model frames as true ones (at least one), got {} and {}",
                model.len(),
                truth.len()
            ),
        ));
    }
    let (mut p, mut a) = (0.0, 0.0);
    for (t, m) in truth.iter().zip(model) {
        p += (t.pos - m.pos).norm();
        a += attitude_error_deg(t, m);
    }
    let m = truth.len() as Real;
    Ok((p / m, a / m))
}

/// One pose's attitude error as Qiao's ACAE counts it (§4.1), degrees:
/// `√(Δα² + Δβ² + Δγ²)` of the differences of the fixed X-Y-Z angles (wrapped to ±180°).
/// Unlike the angle of `R_m R_tᵀ` it depends on the frames' orientation, and grows near the
/// angles' singularity (β = ±90°).
pub fn attitude_error_deg(truth: &Frame, model: &Frame) -> Real {
    let (rt, rm) = (matrix_rpy(&truth.rot), matrix_rpy(&model.rot));
    let d: Real = (0..3).map(|i| wrap(rt[i] - rm[i]).powi(2)).sum();
    d.sqrt().to_degrees()
}

/// ACPE/ACAE of each run and APE/AAE over all runs (Qiao §4.1–4.2) of model frames
/// (`runs[i][j]`: run i, point j) against the true frames.
pub fn pose_errors(truth: &[Frame], runs: &[Vec<Frame>]) -> Result<PoseErrorStats> {
    if runs.is_empty() {
        return Err(Error::setting("runs", "need at least one run"));
    }
    let mut acpe_mm = Vec::with_capacity(runs.len());
    let mut acae_deg = Vec::with_capacity(runs.len());
    for run in runs {
        let (p, a) = acpe_acae(truth, run)?;
        acpe_mm.push(p);
        acae_deg.push(a);
    }
    let n = runs.len() as Real;
    Ok(PoseErrorStats {
        ape: acpe_mm.iter().sum::<Real>() / n,
        aae: acae_deg.iter().sum::<Real>() / n,
        acpe_mm,
        acae_deg,
    })
}

//! Measurement-pose selection (Guo 2024).
//!
//! - [`indices`]: observability indices O1–O6, the entropy-weighted composite (eqs. 9–15), GCN
//!   (eq. 14);
//! - [`separation`]: ill-conditioned parameter separation by branch and bound / backward
//!   elimination over the θ/α/a/d/β blocks (§3.1, tables 1–3);
//! - [`detmax`]: the DETMAX exchange algorithm (§3.2 steps 1–3);
//! - [`ide`]: the improved differential evolution (eqs. 19–26).
//!
//! [`select`] runs one [`Strategy`] over a candidate pool; [`objective_curve`] is Guo's fig. 7
//! (objective against pose count). A [`PoseModel`] gives the Jacobian rows of one pose; the
//! caller chooses its parameters (the identifiable ones, or those kept by [`separate`]) and
//! any column scaling (the indices depend on the units of the columns).

pub mod detmax;
pub mod ide;
pub mod indices;
pub mod separation;
mod spectra;

use std::cell::RefCell;

use nalgebra::{DMatrix, DMatrixViewMut};
use rand::seq::index::sample;

pub use ide::IdeOptions;
pub use indices::{score, Scores};
pub use separation::{separate, BlockGcn, GcnRow, Separation};
pub(crate) use spectra::{add_outer_lower, objective_of_lower, Evaluator, KnownBlocks, Spectra};

use crate::robot::jacobian::{pose_rows, Columns};

use crate::measurement::Measure;
use crate::numeric::rng::Rng;
use crate::numeric::Real;
use crate::robot::{Chain, Param, Robot};
use crate::Error;

/// The Jacobian rows of one measurement pose: what pose selection optimises over.
pub trait PoseModel: Sync {
    /// Number of joint values per pose.
    fn dof(&self) -> usize;
    /// Number of parameters (Jacobian columns), k.
    fn n_params(&self) -> usize;
    /// Jacobian rows per pose (3 for positions, 6 for full poses).
    fn rows_per_pose(&self) -> usize;
    /// Joint limits (lower, upper) per joint, in the units of the poses.
    fn limits(&self) -> &[(Real, Real)];
    /// Writes the `rows_per_pose × n_params` Jacobian block of pose `q` into `out`.
    fn jacobian_block(&self, q: &[Real], out: &mut DMatrixViewMut<Real>);
    /// [`PoseModel::jacobian_block`] into a whole matrix of that shape (the same values; a
    /// model may skip the intermediate view).
    fn jacobian_block_into(&self, q: &[Real], out: &mut DMatrix<Real>) {
        self.jacobian_block(q, &mut out.as_view_mut());
    }
}

/// A [`PoseModel`] over a robot's identification Jacobian ([`crate::robot::jacobian::pose_rows`],
/// Guo 2024 eq. 7).
#[derive(Clone, Debug)]
pub struct RobotPoseModel {
    chain: Chain,
    cols: Columns,
    measure: Measure,
    limits: Vec<(Real, Real)>,
    /// An orthonormal basis (k × r) of the row space of the parameters' Jacobian: the model's
    /// columns are J·basis ([`RobotPoseModel::on_row_space`]).
    basis: Option<DMatrix<Real>>,
}

thread_local! {
    static SCRATCH: RefCell<DMatrix<Real>> = RefCell::new(DMatrix::zeros(0, 0));
    static RAW: RefCell<DMatrix<Real>> = RefCell::new(DMatrix::zeros(0, 0));
}

impl RobotPoseModel {
    /// The model of `robot` for the parameters `params` (in that order) and `measure`; poses
    /// are joint values in internal units (rad, mm) within the robot's joint limits. The
    /// coupled-axis constraint of Guo's 3T2R arm (eq. 16, last line) is not modelled: only
    /// the per-joint limits bound the search.
    pub fn new(robot: &Robot, params: &[Param], measure: Measure) -> Self {
        RobotPoseModel {
            chain: robot.chain(),
            cols: Columns::new(params, robot.dof()),
            measure,
            limits: robot.joints.iter().map(|j| j.limits).collect(),
            basis: None,
        }
    }

    /// The same model scored on its nonzero spectrum: the Jacobian J of the parameters
    /// is replaced by J·V, V an orthonormal basis of J's row space over the
    /// poses `qs` (the right singular vectors whose singular values exceed 1e-9 of the
    /// largest). A structurally rank-deficient model (Guo 2024's full model, eq. 7, and its
    /// reconstructed model J_p, eq. 27) has singular values that are zero at every pose set,
    /// which make every observability index zero (eqs. 9–15); J·V has exactly J's nonzero
    /// singular values at any pose set whose Jacobian has the same null space as over `qs`
    /// (generic poses), so the indices compare pose sets on the model as it is, with no
    /// parameter left out. `qs` should be generic (e.g. the candidate pool). A model of
    /// full rank keeps its singular values (V is then square).
    pub fn on_row_space(mut self, qs: &[Vec<Real>]) -> Self {
        self.basis = None;
        let (r, k) = (self.measure.rows(), self.cols.len());
        let mut j = DMatrix::zeros(r * qs.len(), k);
        let mut block = DMatrix::zeros(r, k);
        for (i, q) in qs.iter().enumerate() {
            self.jacobian_block_into(q, &mut block);
            j.rows_mut(r * i, r).copy_from(&block);
        }
        // A Jacobian the SVD cannot take (not finite) keeps the model on its own columns.
        let Some(svd) = crate::numeric::linalg::svd(j, false, true) else {
            return self;
        };
        let v_t = svd.v_t.expect("v_t was requested");
        let max = svd
            .singular_values
            .iter()
            .fold(0.0 as Real, |a, &b| a.max(b));
        let keep: Vec<usize> = (0..svd.singular_values.len())
            .filter(|&i| svd.singular_values[i] > 1e-9 * max)
            .collect();
        let mut basis = DMatrix::zeros(k, keep.len());
        for (c, &i) in keep.iter().enumerate() {
            basis.column_mut(c).copy_from(&v_t.row(i).transpose());
        }
        self.basis = Some(basis);
        self
    }

    /// The Jacobian block of the parameters (no basis).
    fn raw_block(&self, q: &[Real], out: &mut DMatrix<Real>) {
        out.fill(0.0);
        pose_rows(&self.chain, &self.cols, q, self.measure, out, 0);
    }
}

impl PoseModel for RobotPoseModel {
    fn dof(&self) -> usize {
        self.limits.len()
    }
    fn n_params(&self) -> usize {
        self.basis.as_ref().map_or(self.cols.len(), |b| b.ncols())
    }
    fn rows_per_pose(&self) -> usize {
        self.measure.rows()
    }
    fn limits(&self) -> &[(Real, Real)] {
        &self.limits
    }
    fn jacobian_block(&self, q: &[Real], out: &mut DMatrixViewMut<Real>) {
        let (r, k) = (self.measure.rows(), self.n_params());
        SCRATCH.with(|s| {
            let mut s = s.borrow_mut();
            if s.shape() != (r, k) {
                *s = DMatrix::zeros(r, k);
            }
            self.jacobian_block_into(q, &mut s);
            out.copy_from(&*s);
        });
    }
    fn jacobian_block_into(&self, q: &[Real], out: &mut DMatrix<Real>) {
        let Some(basis) = &self.basis else {
            self.raw_block(q, out);
            return;
        };
        RAW.with(|s| {
            let mut s = s.borrow_mut();
            let shape = (self.measure.rows(), self.cols.len());
            if s.shape() != shape {
                *s = DMatrix::zeros(shape.0, shape.1);
            }
            self.raw_block(q, &mut s);
            out.gemm(1.0, &*s, basis, 0.0);
        });
    }
}

/// The objective maximised by DETMAX and IDE (Guo 2024 eq. 15, or a single index).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "lowercase")]
pub enum Objective {
    /// The entropy-weighted composite index (eqs. 12–15); `"composite"`.
    Composite,
    /// O1 (eq. 9, D-optimal); `"o1"`.
    O1,
    /// O6 (eq. 11, A-optimal); `"o6"`.
    O6,
}

impl Objective {
    /// The name used in scenario files.
    pub fn as_str(self) -> &'static str {
        self.into()
    }
}

/// How poses are chosen from the candidates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "kebab-case")]
pub enum Strategy {
    /// A uniformly random subset of the candidates; `"random"`.
    Random,
    /// DETMAX exchange from the first `count` candidates (Guo 2024 §3.2); `"detmax"`.
    Detmax,
    /// IDE (eqs. 19–26) from a random subset of the candidates; `"ide"`.
    Ide,
    /// DETMAX, then IDE from the DETMAX set; `"detmax-ide"`.
    DetmaxIde,
}

impl Strategy {
    /// The name used in scenario files and on the command line.
    pub fn as_str(self) -> &'static str {
        self.into()
    }
}

/// Settings of [`select`].
#[derive(Clone, Debug, PartialEq)]
pub struct SelectOptions {
    /// Number of poses to choose, M.
    pub count: usize,
    /// The objective to maximise.
    pub objective: Objective,
    /// Settings of the IDE stage.
    pub ide: IdeOptions,
    /// Upper bound on DETMAX exchanges (each is one add and one remove).
    pub detmax_max_exchanges: usize,
}

impl Default for SelectOptions {
    /// 60 poses (Guo 2024 §4.2), composite objective, default IDE, at most 500 exchanges.
    fn default() -> Self {
        SelectOptions {
            count: 60,
            objective: Objective::Composite,
            ide: IdeOptions::default(),
            detmax_max_exchanges: 500,
        }
    }
}

impl SelectOptions {
    /// The defaults with `count` poses.
    pub fn new(count: usize) -> Self {
        SelectOptions {
            count,
            ..Default::default()
        }
    }
}

/// The chosen poses and how they were found.
#[derive(Clone, Debug, PartialEq)]
pub struct Selection {
    /// The chosen poses (joint values in the model's units).
    pub poses: Vec<Vec<Real>>,
    /// For each pose, its index among the candidates; `None` for a pose created by IDE.
    pub indices: Vec<Option<usize>>,
    /// The indices of the chosen set ([`score`]).
    pub scores: Scores,
    /// The objective after each iteration: the start, then each DETMAX exchange, then each
    /// IDE generation.
    pub trace: Vec<Real>,
    /// Why the search stopped.
    pub termination: String,
}

/// Checks the candidates: right length, finite, within the limits.
fn check_candidates(model: &dyn PoseModel, candidates: &[Vec<Real>]) -> crate::Result<()> {
    let lim = model.limits();
    for (i, q) in candidates.iter().enumerate() {
        if q.len() != model.dof() {
            let what = format_args!("pose {i}");
            return Err(Error::joint_count("candidates", what, q.len(), model.dof()));
        }
        for (j, (&v, &(lo, hi))) in q.iter().zip(lim).enumerate() {
            if !v.is_finite() || v < lo - 1e-9 || v > hi + 1e-9 {
                return Err(Error::setting(
                    "candidates",
                    format!("pose {i}, joint {}: {v} is outside [{lo}, {hi}]", j + 1),
                ));
            }
        }
    }
    Ok(())
}

fn check_count(model: &dyn PoseModel, n_candidates: usize, count: usize) -> crate::Result<()> {
    let r = model.rows_per_pose();
    let k = model.n_params();
    if k == 0 {
        return Err(Error::setting("params", "no parameters to observe"));
    }
    let need = k.div_ceil(r.max(1));
    if count < need {
        return Err(Error::setting(
            "calibration.count",
            format!(
                "{count} poses give fewer rows than the {k} parameters: at least {need} needed"
            ),
        ));
    }
    if count > n_candidates {
        return Err(Error::setting(
            "calibration.count",
            format!("{count} poses requested from {n_candidates} candidates"),
        ));
    }
    Ok(())
}

/// Chooses `opts.count` measurement poses from `candidates` (joint values in the model's
/// units, within its limits) by `strategy`, maximising `opts.objective` (Guo 2024 §3.2).
///
/// - `Random`: a uniformly random subset;
/// - `Detmax`: [`detmax::detmax`] from the first `count` candidates (the paper's start);
/// - `Ide`: [`ide::ide`] from a random subset;
/// - `DetmaxIde`: DETMAX, then IDE from the DETMAX set.
///
/// Randomness comes only from `rng`; the result is the same for any number of rayon threads.
/// Errors: bad candidates, too few poses for the parameter count, more poses than
/// candidates, bad IDE settings.
pub fn select(
    model: &dyn PoseModel,
    candidates: &[Vec<Real>],
    strategy: Strategy,
    opts: &SelectOptions,
    rng: &mut Rng,
) -> crate::Result<Selection> {
    check_candidates(model, candidates)?;
    check_count(model, candidates.len(), opts.count)?;
    if matches!(strategy, Strategy::Ide | Strategy::DetmaxIde) {
        opts.ide.check()?;
    }
    let m = opts.count;
    let (idx, mut trace, mut termination) = match strategy {
        Strategy::Random | Strategy::Ide => {
            let idx: Vec<usize> = sample(rng, candidates.len(), m).into_vec();
            (idx, Vec::new(), String::new())
        }
        Strategy::Detmax | Strategy::DetmaxIde => {
            let res = detmax::detmax(
                model,
                candidates,
                (0..m).collect(),
                opts.objective,
                opts.detmax_max_exchanges,
            );
            (res.set, res.trace, res.termination)
        }
    };
    let mut poses: Vec<Vec<Real>> = idx.iter().map(|&i| candidates[i].clone()).collect();
    let mut indices: Vec<Option<usize>> = idx.iter().map(|&i| Some(i)).collect();
    if matches!(strategy, Strategy::Ide | Strategy::DetmaxIde) {
        let res = ide::ide(model, &poses, &indices, opts.objective, &opts.ide, rng);
        if trace.is_empty() {
            trace.push(res.start_value);
        }
        trace.extend_from_slice(&res.trace);
        termination = if termination.is_empty() {
            res.termination
        } else {
            format!("{termination}; {}", res.termination)
        };
        poses = res.poses;
        indices = res.indices;
    }
    if strategy == Strategy::Random {
        let mut ev = Evaluator::new(model);
        let flat: Vec<Real> = poses.iter().flatten().copied().collect();
        trace.push(ev.value(model, &flat, opts.objective));
        termination = "random subset".to_string();
    }
    let scores = score(model, &poses);
    Ok(Selection {
        poses,
        indices,
        scores,
        trace,
        termination,
    })
}

/// The objective against the pose count (Guo 2024 fig. 7): one random ordering of the
/// candidates is drawn from `rng`, and for each `c` in `counts` the first `c` poses of it are
/// scored with `opts.objective`. A count with fewer rows than parameters scores 0.
/// Errors: a count of 0 or above the number of candidates, bad candidates.
pub fn objective_curve(
    model: &dyn PoseModel,
    candidates: &[Vec<Real>],
    counts: &[usize],
    opts: &SelectOptions,
    rng: &mut Rng,
) -> crate::Result<Vec<(usize, Real)>> {
    check_candidates(model, candidates)?;
    for &c in counts {
        if c == 0 || c > candidates.len() {
            return Err(Error::setting(
                "counts",
                format!("{c} poses: allowed 1..={}", candidates.len()),
            ));
        }
    }
    let order = sample(rng, candidates.len(), candidates.len()).into_vec();
    let mut ev = Evaluator::new(model);
    let mut flat = Vec::with_capacity(candidates.len() * model.dof());
    Ok(counts
        .iter()
        .map(|&c| {
            flat.clear();
            for &i in &order[..c] {
                flat.extend_from_slice(&candidates[i]);
            }
            let v = ev.value(model, &flat, opts.objective).max(0.0);
            (c, v)
        })
        .collect())
}

#[cfg(test)]
pub(crate) mod test_models {
    use super::*;

    /// A model whose pose `[i]` has the fixed Jacobian block `blocks[i]` (for hand-built
    /// tests); limits `[0, n − 1]`.
    pub struct TableModel {
        pub blocks: Vec<DMatrix<Real>>,
        pub limits: Vec<(Real, Real)>,
    }

    impl TableModel {
        pub fn new(blocks: Vec<DMatrix<Real>>) -> Self {
            let n = blocks.len() as Real;
            TableModel {
                blocks,
                limits: vec![(0.0, n - 1.0)],
            }
        }
        pub fn candidates(&self) -> Vec<Vec<Real>> {
            (0..self.blocks.len()).map(|i| vec![i as Real]).collect()
        }
    }

    impl PoseModel for TableModel {
        fn dof(&self) -> usize {
            1
        }
        fn n_params(&self) -> usize {
            self.blocks[0].ncols()
        }
        fn rows_per_pose(&self) -> usize {
            self.blocks[0].nrows()
        }
        fn limits(&self) -> &[(Real, Real)] {
            &self.limits
        }
        fn jacobian_block(&self, q: &[Real], out: &mut DMatrixViewMut<Real>) {
            let i = (q[0].round().max(0.0) as usize).min(self.blocks.len() - 1);
            out.copy_from(&self.blocks[i]);
        }
    }
}

#[cfg(test)]
mod tests;

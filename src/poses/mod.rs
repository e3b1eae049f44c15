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

use std::cell::RefCell;

use nalgebra::{DMatrix, DMatrixViewMut};
use rand::seq::index::sample;

pub use ide::IdeOptions;
pub use indices::{score, Scores};
pub use separation::{separate, BlockGcn, GcnRow, Separation};

use crate::robot::jacobian::{pose_rows, Columns};

use crate::measurement::Measure;
use crate::numeric::rng::Rng;
use crate::numeric::symeig::{symmetric_eigenvalues, symmetric_eigenvalues_lanes};
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
/// Guo 2024 eq. 7), with optional column scaling.
#[derive(Clone, Debug)]
pub struct RobotPoseModel {
    chain: Chain,
    cols: Columns,
    measure: Measure,
    limits: Vec<(Real, Real)>,
    scale: Option<Vec<Real>>,
}

thread_local! {
    static SCRATCH: RefCell<DMatrix<Real>> = RefCell::new(DMatrix::zeros(0, 0));
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
            scale: None,
        }
    }

    /// The same model with column `c` multiplied by `scale[c]` (e.g. the inverse column norms
    /// of [`crate::robot::identifiability::scale_columns`] over a reference pose set, so that mm and
    /// rad columns compare). Fails when the length differs from the parameter count or a
    /// factor is not finite and positive.
    pub fn with_column_scale(mut self, scale: Vec<Real>) -> crate::Result<Self> {
        if scale.len() != self.cols.len() {
            return Err(Error::setting(
                "column_scale",
                format!("{} factors for {} parameters", scale.len(), self.cols.len()),
            ));
        }
        if scale.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(Error::setting(
                "column_scale",
                "every factor must be finite and positive",
            ));
        }
        self.scale = Some(scale);
        Ok(self)
    }

    /// The parameters, one per column.
    pub fn params(&self) -> &[Param] {
        self.cols.params()
    }
}

impl PoseModel for RobotPoseModel {
    fn dof(&self) -> usize {
        self.limits.len()
    }
    fn n_params(&self) -> usize {
        self.cols.len()
    }
    fn rows_per_pose(&self) -> usize {
        self.measure.rows()
    }
    fn limits(&self) -> &[(Real, Real)] {
        &self.limits
    }
    fn jacobian_block(&self, q: &[Real], out: &mut DMatrixViewMut<Real>) {
        let (r, k) = (self.measure.rows(), self.cols.len());
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
        out.fill(0.0);
        pose_rows(&self.chain, &self.cols, q, self.measure, out, 0);
        if let Some(sc) = &self.scale {
            for (mut c, f) in out.column_iter_mut().zip(sc) {
                c *= *f;
            }
        }
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

/// The objective of the Gram matrix JᵀJ over `m` poses whose lower triangle is stored
/// row-major in `g` (k × k): singular values of J are sqrt(eig(JᵀJ)) (symmetric eigenvalues of
/// the small k × k matrix, by [`crate::numeric::symeig`]). A set with cond(J) above about 3e6 counts as
/// rank-deficient (objective 0).
pub(crate) fn objective_of_lower(g: &[Real], k: usize, objective: Objective, m: usize) -> Real {
    let mut lower = g.to_vec();
    let (mut ev, mut scratch) = (vec![0.0; k], vec![0.0; k]);
    if !symmetric_eigenvalues(&mut lower, k, &mut ev, &mut scratch) {
        return Real::NEG_INFINITY;
    }
    objective_of_eigenvalues(&mut ev, objective, m)
}

/// The objective from the eigenvalues `ev` of JᵀJ over `m` poses (overwritten by the
/// singular values): the second half of [`objective_of_lower`].
pub(crate) fn objective_of_eigenvalues(ev: &mut [Real], objective: Objective, m: usize) -> Real {
    // Eigenvalues of JᵀJ carry an absolute error of a few ε·λmax: below 1e-13·λmax (σ below
    // about 3e-7·σmax) they are noise, and the set counts as rank-deficient.
    let floor = 1e-13 * ev.iter().fold(0.0 as Real, |a, &b| a.max(b));
    for e in ev.iter_mut() {
        *e = if *e > floor { e.sqrt() } else { 0.0 };
    }
    let v = indices::objective_value(objective, ev, m);
    if v.is_nan() {
        Real::NEG_INFINITY
    } else {
        v
    }
}

/// Adds `sign · bbᵀ` to the lower triangle of the row-major k × k matrix `g` (k = `b.len()`).
#[inline]
pub(crate) fn add_outer_lower(g: &mut [Real], b: &[Real], sign: Real) {
    let k = b.len();
    for i in 0..k {
        let f = sign * b[i];
        for (x, bj) in g[i * k..i * k + i + 1].iter_mut().zip(&b[..=i]) {
            *x += f * bj;
        }
    }
}

/// Gram matrices whose objectives are found together: the eigenvalue problems of up to
/// [`Spectra::LANES`] matrices share their instructions
/// ([`crate::numeric::symeig::symmetric_eigenvalues_lanes`]; eight lanes are two AVX2 registers, whose
/// independent chains hide the latency of the QL sweeps better than one). Each matrix's
/// objective is the same bits as [`objective_of_lower`] of the same entries. Only the lower
/// triangles are stored (the rest stays zero: [`symmetric_eigenvalues_lanes`] neither reads nor
/// writes it), and they are built in the lanes too ([`Spectra::set_plus_rows`],
/// [`Spectra::accumulate`]).
pub(crate) struct Spectra {
    k: usize,
    a: Vec<[Real; Spectra::LANES]>,
    d: Vec<[Real; Spectra::LANES]>,
    e: Vec<[Real; Spectra::LANES]>,
    ev: Vec<Real>,
    /// Rows of pose blocks, row after row (k values each), lane t holding matrix t's.
    rows: Vec<[Real; Spectra::LANES]>,
}

impl Spectra {
    /// Matrices per call of [`Spectra::objectives`].
    pub(crate) const LANES: usize = 8;

    /// `f` with this thread's buffers for k × k matrices, made once per thread and k: a scan
    /// asks for buffers per rayon task (about 1200 per DETMAX selection), and fresh ones cost
    /// an allocation and the zeroing of k² lanes each time. A buffer's earlier contents never
    /// reach a result (each use overwrites the lanes it reads).
    pub(crate) fn with<R>(k: usize, f: impl FnOnce(&mut Spectra) -> R) -> R {
        thread_local! {
            static BUF: RefCell<Option<Spectra>> = const { RefCell::new(None) };
        }
        BUF.with(|cell| match cell.try_borrow_mut() {
            Ok(mut slot) => {
                if slot.as_ref().is_none_or(|s| s.k != k) {
                    *slot = Some(Spectra::new(k));
                }
                f(slot.as_mut().expect("just set"))
            }
            // Already in use further up this thread's stack: a buffer of its own.
            Err(_) => f(&mut Spectra::new(k)),
        })
    }

    pub(crate) fn new(k: usize) -> Self {
        Spectra {
            k,
            a: vec![[0.0; Self::LANES]; k * k],
            d: vec![[0.0; Self::LANES]; k],
            e: vec![[0.0; Self::LANES]; k],
            ev: vec![0.0; k],
            rows: Vec::new(),
        }
    }

    /// Puts into lanes `0..used` the lower triangles of `g` + `sign`·Σ_r b_r b_rᵀ, `g` row-major
    /// k × k and the rows b_r of lane t's pose block stored one after another in `rows(t)`
    /// (k values each): the lanes computed together, each entry the same bits as
    /// [`add_outer_lower`] of the rows one after another on a copy of `g`. Lanes from `used`
    /// on get unspecified matrices.
    pub(crate) fn set_plus_rows<'a>(
        &mut self,
        used: usize,
        g: &[Real],
        rows: impl Fn(usize) -> &'a [Real],
        sign: Real,
    ) {
        let n = rows(0).len();
        self.rows.resize(n, [0.0; Self::LANES]);
        for t in 0..used {
            for (x, &v) in self.rows.iter_mut().zip(rows(t)) {
                x[t] = v;
            }
        }
        self.accumulate(Some(g), sign);
    }

    /// Zeroes the lower triangles of every lane.
    fn clear(&mut self) {
        let k = self.k;
        for i in 0..k {
            self.a[i * k..i * k + i + 1].fill([0.0; Self::LANES]);
        }
    }

    /// Puts the rows of the `r` × k pose block `block` into lane `t`, for
    /// [`Spectra::accumulate`].
    fn put_rows(&mut self, t: usize, block: &DMatrix<Real>) {
        let (r, k) = block.shape();
        self.rows.resize(r * k, [0.0; Self::LANES]);
        for row in 0..r {
            for i in 0..k {
                self.rows[row * k + i][t] = block[(row, i)];
            }
        }
    }

    /// Each lane's lower triangle becomes `g` (or, without `g`, stays as it is) plus
    /// `sign`·Σ_r b_r b_rᵀ of that lane's rows b_r, added one row after another as
    /// [`add_outer_lower`] adds them.
    fn accumulate(&mut self, g: Option<&[Real]>, sign: Real) {
        let k = self.k;
        let (a, b) = (&mut self.a, &self.rows);
        crate::numeric::simd::dispatch(
            #[inline(always)]
            |_| {
                for i in 0..k {
                    let row = i * k..i * k + i + 1;
                    for (j, x) in a[row.clone()].iter_mut().enumerate() {
                        let mut v = match g {
                            Some(g) => [g[i * k + j]; Self::LANES],
                            None => *x,
                        };
                        for r in b.chunks_exact(k) {
                            for t in 0..Self::LANES {
                                v[t] += sign * r[i][t] * r[j][t];
                            }
                        }
                        *x = v;
                    }
                }
            },
        );
    }

    /// The objectives over `m` poses of the matrices in lanes `0..used` (entries from `used`
    /// on are −∞); lanes `used..` are overwritten.
    pub(crate) fn objectives(
        &mut self,
        used: usize,
        objective: Objective,
        m: usize,
    ) -> [Real; Self::LANES] {
        let k = self.k;
        for i in 0..k {
            for x in &mut self.a[i * k..i * k + i + 1] {
                for t in used..Self::LANES {
                    x[t] = x[0];
                }
            }
        }
        let ok = symmetric_eigenvalues_lanes(&mut self.a, self.k, &mut self.d, &mut self.e);
        std::array::from_fn(|t| {
            if t >= used || !ok[t] {
                return Real::NEG_INFINITY;
            }
            for (x, d) in self.ev.iter_mut().zip(&self.d) {
                *x = d[t];
            }
            objective_of_eigenvalues(&mut self.ev, objective, m)
        })
    }
}

/// Reusable buffers for evaluating pose sets.
pub(crate) struct Evaluator {
    block: DMatrix<Real>,
    row: Vec<Real>,
    gram: Vec<Real>,
}

impl Evaluator {
    pub(crate) fn new(model: &dyn PoseModel) -> Self {
        let (r, k) = (model.rows_per_pose(), model.n_params());
        Evaluator {
            block: DMatrix::zeros(r, k),
            row: vec![0.0; k],
            gram: vec![0.0; k * k],
        }
    }

    /// The lower triangle of JᵀJ of the poses stored flat in `poses` (`dof` values each) into
    /// `self.gram`; returns the pose count.
    fn gram(&mut self, model: &dyn PoseModel, poses: &[Real]) -> usize {
        let dof = model.dof();
        self.gram.fill(0.0);
        for q in poses.chunks_exact(dof) {
            model.jacobian_block_into(q, &mut self.block);
            for i in 0..self.block.nrows() {
                for (x, b) in self.row.iter_mut().zip(self.block.row(i).iter()) {
                    *x = *b;
                }
                add_outer_lower(&mut self.gram, &self.row, 1.0);
            }
        }
        poses.len() / dof.max(1)
    }

    /// The objective of the poses stored flat in `poses` (`dof` values each).
    pub(crate) fn value(
        &mut self,
        model: &dyn PoseModel,
        poses: &[Real],
        objective: Objective,
    ) -> Real {
        let m = self.gram(model, poses);
        objective_of_lower(&self.gram, self.row.len(), objective, m)
    }

    /// The objectives of up to [`Spectra::LANES`] pose sets stored one after another in
    /// `sets`, `len` values each (entries past the sets are −∞): the same bits as
    /// [`Evaluator::value`] of each. A pose equal (to the bit) to the same pose of `known`
    /// takes its block from there.
    pub(crate) fn values(
        &mut self,
        model: &dyn PoseModel,
        sets: &[Real],
        len: usize,
        objective: Objective,
        known: &KnownBlocks,
    ) -> [Real; Spectra::LANES] {
        // The sets' Gram matrices built together, pose after pose.
        let dof = model.dof().max(1);
        let used = sets.len() / len.max(1);
        let m = len / dof;
        Spectra::with(self.block.ncols(), |spectra| {
            spectra.clear();
            for p in 0..m {
                let at = p * dof..(p + 1) * dof;
                for (t, set) in sets.chunks_exact(len.max(1)).enumerate() {
                    let q = &set[at.clone()];
                    match known.block(p, q) {
                        Some(block) => spectra.put_rows(t, block),
                        None => {
                            model.jacobian_block_into(q, &mut self.block);
                            spectra.put_rows(t, &self.block);
                        }
                    }
                }
                spectra.accumulate(None, 1.0);
            }
            spectra.objectives(used, objective, m)
        })
    }
}

/// The Jacobian blocks of one pose set (IDE's current best), for the trial sets that keep
/// some of its poses: a block depends only on its pose, so a pose met again need not be
/// differentiated again.
pub(crate) struct KnownBlocks {
    dof: usize,
    poses: Vec<Real>,
    blocks: Vec<DMatrix<Real>>,
}

impl KnownBlocks {
    /// The blocks of the poses stored flat in `poses` (`model.dof()` values each).
    pub(crate) fn new(model: &dyn PoseModel, poses: &[Real]) -> Self {
        let (r, k, dof) = (model.rows_per_pose(), model.n_params(), model.dof().max(1));
        let blocks = poses
            .chunks_exact(dof)
            .map(|q| {
                let mut b = DMatrix::zeros(r, k);
                model.jacobian_block_into(q, &mut b);
                b
            })
            .collect();
        KnownBlocks {
            dof,
            poses: poses.to_vec(),
            blocks,
        }
    }

    /// The block of pose `p` when it is `q` (bit for bit).
    fn block(&self, p: usize, q: &[Real]) -> Option<&DMatrix<Real>> {
        let own = self.poses.get(p * self.dof..(p + 1) * self.dof)?;
        let same = own.iter().zip(q).all(|(a, b)| a.to_bits() == b.to_bits());
        same.then(|| &self.blocks[p])
    }
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

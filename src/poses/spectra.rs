//! The objective of a pose set from its Gram matrix JᵀJ (Guo 2024 eqs. 9–15 on the singular
//! values of J): one set ([`objective_of_lower`]), up to eight sets in vector lanes
//! ([`Spectra`]), and the reusable buffers of the searches ([`Evaluator`], [`KnownBlocks`]).

use std::cell::RefCell;

use nalgebra::DMatrix;

use super::{indices, Objective, PoseModel};
use crate::numeric::symeig::{symmetric_eigenvalues, symmetric_eigenvalues_lanes};
use crate::numeric::Real;

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

//! The buffers the Jacobian-based solvers share ([`Work`]): residual, Jacobian, weighted
//! Jacobian and normal equations, whole or a block at a time for a problem that streams.

use nalgebra::{DMatrix, DVector};

use super::{weighted_cost, LeastSquares};
use crate::numeric::gram;
use crate::numeric::normal::NormalEquations;
use crate::numeric::Real;

/// Buffers shared by the solvers: residual, Jacobian, weighted Jacobian, normal equations.
///
/// A problem that streams ([`LeastSquares::block_points`]) keeps its whole residual but only
/// one block of Jacobian rows: each evaluation accumulates the normal equations with the
/// weights it was given ([`Stream`]), and [`Work::normal`] takes them, or makes a second pass
/// when the weights changed in between (the robust rounds).
pub(crate) struct Work {
    pub rows: usize,
    pub r: DVector<Real>,
    /// The Jacobian: whole, or one block of a streamed problem.
    pub j: DMatrix<Real>,
    /// `P J` (rows scaled by their point's weight); allocated on the first use, as most
    /// problems weigh every point 1.
    pub pj: DMatrix<Real>,
    /// `JᵀPJ`.
    pub n: DMatrix<Real>,
    /// `JᵀP r`.
    pub g: DVector<Real>,
    /// Factorisation buffer.
    pub a: DMatrix<Real>,
    /// Step.
    pub dx: DVector<Real>,
    /// Evaluations of the problem so far.
    pub evaluations: usize,
    /// The problem's Tikhonov precisions ([`LeastSquares::tikhonov`]); empty: none.
    pub tikhonov: Vec<Real>,
    /// The `x` last evaluated (kept only with priors, whose gradient needs it).
    pub x: DVector<Real>,
    /// The block buffers and sums of a streamed problem.
    stream: Option<Stream>,
}

/// What [`Work`] keeps for a streamed problem.
struct Stream {
    /// Points per block.
    points: usize,
    /// One block's residual.
    r: DVector<Real>,
    /// The last, shorter block's residual and Jacobian.
    r_tail: DVector<Real>,
    j_tail: DMatrix<Real>,
    /// Where the problem was last evaluated.
    x: DVector<Real>,
    /// The normal equations of that evaluation, with the weights `w`; `fresh` until
    /// [`Work::normal`] takes them.
    sums: NormalEquations,
    w: Vec<Real>,
    fresh: bool,
}

impl Work {
    pub fn new(p: &dyn LeastSquares) -> Work {
        let size = p.size();
        let (m, t) = (size.rows(), size.params);
        let rows = size.rows_per_point;
        let block = p.block_points().filter(|&b| b > 0 && b < size.points);
        let stream = block.map(|b| {
            let tail = size.points % b;
            Stream {
                points: b,
                r: DVector::zeros(b * rows),
                r_tail: DVector::zeros(tail * rows),
                j_tail: DMatrix::zeros(tail * rows, t),
                x: DVector::zeros(t),
                sums: NormalEquations::new(t, b * rows),
                w: Vec::with_capacity(size.points),
                fresh: false,
            }
        });
        Work {
            rows,
            r: DVector::zeros(m),
            j: DMatrix::zeros(block.map_or(m, |b| b * rows), t),
            pj: DMatrix::zeros(0, 0),
            n: DMatrix::zeros(t, t),
            g: DVector::zeros(t),
            a: DMatrix::zeros(t, t),
            dx: DVector::zeros(t),
            evaluations: 0,
            tikhonov: p.tikhonov().map_or_else(Vec::new, <[Real]>::to_vec),
            x: DVector::zeros(t),
            stream,
        }
    }

    /// Evaluates the problem at `x` and returns the weighted cost `rᵀPr`, plus the priors'
    /// `Σ λ_k x_k²` (non-finite when the model is). A streamed problem also sums its normal
    /// equations with the weights `w`, for [`Work::normal`].
    pub fn evaluate(&mut self, p: &dyn LeastSquares, x: &DVector<Real>, w: &[Real]) -> Real {
        self.evaluations += 1;
        let cost = if self.stream.is_none() {
            p.evaluate(x, &mut self.r, &mut self.j);
            weighted_cost(&self.r, self.rows, w)
        } else {
            if let Some(s) = &mut self.stream {
                s.x.copy_from(x);
                s.w.clear();
                s.w.extend_from_slice(w);
                s.fresh = true;
            }
            self.pass(p, w, Pass::Evaluate);
            weighted_cost(&self.r, self.rows, w)
        };
        if self.tikhonov.is_empty() {
            return cost;
        }
        self.x.copy_from(x);
        cost + self
            .tikhonov
            .iter()
            .zip(x.iter())
            .map(|(l, v)| l * v * v)
            .sum::<Real>()
    }

    /// One pass over the blocks of a streamed problem at the point of its last evaluation.
    fn pass(&mut self, p: &dyn LeastSquares, w: &[Real], what: Pass) {
        let Some(s) = &mut self.stream else {
            return;
        };
        let rows = self.rows;
        let points = w.len();
        if what != Pass::Step {
            s.sums.clear();
        }
        for first in (0..points).step_by(s.points) {
            let k = s.points.min(points - first);
            let (r, j) = if k == s.points {
                (&mut s.r, &mut self.j)
            } else {
                (&mut s.r_tail, &mut s.j_tail)
            };
            p.evaluate_points(&s.x, first, r, j);
            let mut seg = self.r.rows_mut(first * rows, k * rows);
            match what {
                Pass::Evaluate => seg.copy_from(r),
                Pass::Normal => {}
                Pass::Step => {
                    seg.copy_from(r);
                    seg.gemv(-1.0, j, &self.dx, 1.0);
                    continue;
                }
            }
            s.sums.add(j, r.as_slice(), &w[first..first + k]);
        }
    }

    /// Moves the residual to the point after the step `dx` just solved, to first order:
    /// `r ← r − J dx`. Used once the step is below the stopping tolerance `ε`, so that the
    /// statistics of the estimate need no further evaluation: the neglected term is of the
    /// order of `|dx|²` times the model's curvature (below 1e-9 mm for `|dx| < 1e-6` on a
    /// 2 m arm), and the normal equations kept are those one step (< ε) before. A streamed
    /// problem forms its Jacobian blocks at that point again.
    pub fn take_step_in_residual(&mut self, p: &dyn LeastSquares) {
        if self.stream.is_some() {
            let w = std::mem::take(&mut self.stream.as_mut().expect("streamed").w);
            self.pass(p, &w, Pass::Step);
            self.stream.as_mut().expect("streamed").w = w;
        } else {
            self.r.gemv(-1.0, &self.j, &self.dx, 1.0);
        }
        if !self.tikhonov.is_empty() {
            self.x += &self.dx;
        }
    }

    /// Forms `N = JᵀPJ` and `g = JᵀP r` with per-point weights `w`. Allocation-free: the
    /// lower triangle of `N` by dot products of `J`'s contiguous columns
    /// ([`gram::normal_equations`]), mirrored so that `N` is exactly symmetric; with all
    /// weights 1 `P J` is not formed. A streamed problem takes the sums of its last
    /// evaluation, or sums them again at its point when the weights have changed since.
    pub fn normal(&mut self, p: &dyn LeastSquares, w: &[Real]) {
        if let Some(s) = &self.stream {
            let taken = s.fresh && s.w == w;
            if !taken {
                self.pass(p, w, Pass::Normal);
            }
            let s = self.stream.as_mut().expect("streamed");
            s.sums.swap_into(&mut self.n, &mut self.g);
            s.fresh = false;
        } else {
            self.whole_normal(w);
        }
        // The priors' Tikhonov terms (Gauss–Newton of `rᵀPr + Σ λ_k x_k²`): `λ` on the
        // diagonal, `−λ x` in the gradient, added after the last block of a streamed problem.
        for (k, &l) in self.tikhonov.iter().enumerate() {
            self.n[(k, k)] += l;
            self.g[k] -= l * self.x[k];
        }
    }

    /// [`Work::normal`] of a problem held whole.
    fn whole_normal(&mut self, w: &[Real]) {
        let rows = self.rows;
        let unit = w.iter().all(|&wi| wi == 1.0);
        if !unit {
            if self.pj.shape() != self.j.shape() {
                self.pj = self.j.clone();
            } else {
                self.pj.copy_from(&self.j);
            }
            for (i, &wi) in w.iter().enumerate() {
                if wi != 1.0 {
                    self.pj.rows_mut(i * rows, rows).scale_mut(wi);
                }
            }
        }
        let pj = if unit { &self.j } else { &self.pj };
        let (js, pjs) = (self.j.as_slice(), pj.as_slice());
        let (n, g, r) = (
            self.n.as_mut_slice(),
            self.g.as_mut_slice(),
            self.r.as_slice(),
        );
        gram::normal_equations(js, pjs, r, n, g);
    }
}

/// What a pass over a streamed problem's blocks does besides evaluating them.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Pass {
    /// Writes the residual and sums the normal equations.
    Evaluate,
    /// Sums the normal equations only (new weights, the same point).
    Normal,
    /// Writes the residual moved by the step `dx` ([`Work::take_step_in_residual`]).
    Step,
}

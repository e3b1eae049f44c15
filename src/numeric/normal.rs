//! The normal equations `N = JᵀPJ`, `g = JᵀP r` accumulated block by block, so that a
//! problem of millions of measured points never holds its whole Jacobian (Li 2018 eq. 13 is
//! a sum over points: each block of points adds its own Gram product).
//!
//! [`NormalEquations`] is the accumulator: [`NormalEquations::clear`], then
//! [`NormalEquations::add`] for each block of rows (its Jacobian rows, residual and point
//! weights), then read [`NormalEquations::n`] and [`NormalEquations::g`]. Each block's
//! product is the Gram kernel of the whole-Jacobian path (`gram::normal_equations`); only
//! the order of the sum over blocks differs from that path, so the two agree to rounding
//! (docs/performance.md, "Streaming identification"). Terms that do not come from the rows,
//! a ridge or a prior, are added to `n` and `g` after the last block by the caller.

use nalgebra::{DMatrix, DVector};

use super::gram;
use super::Real;

/// `JᵀPJ` and `JᵀP r` summed over blocks of rows. Allocation-free after [`NormalEquations::new`]
/// for blocks of at most the size it was made for.
#[derive(Clone, Debug)]
pub struct NormalEquations {
    n: DMatrix<Real>,
    g: DVector<Real>,
    /// One block's `N` and `g`.
    block_n: Vec<Real>,
    block_g: Vec<Real>,
    /// One block's `PJ` (column-major), when some weight differs from 1.
    pj: Vec<Real>,
    /// With [`NormalEquations::both_ways`]: the sums with `J` and `PJ` swapped, their block
    /// sums and a block's unused `g`.
    swapped: Option<(DMatrix<Real>, Vec<Real>, Vec<Real>)>,
}

impl NormalEquations {
    /// Empty (zero) normal equations of `params` unknowns, for blocks of up to `block_rows`
    /// residual rows.
    pub fn new(params: usize, block_rows: usize) -> NormalEquations {
        NormalEquations {
            n: DMatrix::zeros(params, params),
            g: DVector::zeros(params),
            block_n: vec![0.0; params * params],
            block_g: vec![0.0; params],
            pj: Vec::with_capacity(block_rows * params),
            swapped: None,
        }
    }

    /// As [`NormalEquations::new`], keeping also the products [`NormalEquations::n`] leaves
    /// out: [`NormalEquations::cross`] gives `(PJ)_a · J_b` for every `a` and `b`. `n` holds
    /// at both `(a, b)` and `(b, a)` the one with `PJ` of the later column, the same bits as
    /// the normal equations of any subset of the columns in the same order give; with weights
    /// other than 1 the earlier column's differs in the last bit. A subset in another order
    /// takes its entries from [`NormalEquations::cross`] and has the bits its own sums would.
    pub fn both_ways(params: usize, block_rows: usize) -> NormalEquations {
        let mut sums = NormalEquations::new(params, block_rows);
        sums.swapped = Some((
            DMatrix::zeros(params, params),
            vec![0.0; params * params],
            vec![0.0; params],
        ));
        sums
    }

    /// Back to zero, for the next pass over the rows.
    pub fn clear(&mut self) {
        self.n.fill(0.0);
        self.g.fill(0.0);
        if let Some((n, ..)) = &mut self.swapped {
            n.fill(0.0);
        }
    }

    /// Adds one block of rows: `j` its Jacobian rows (m × t), `r` its residual (length m)
    /// and `w` the weight of each of its points, `m / w.len()` rows per point.
    pub fn add(&mut self, j: &DMatrix<Real>, r: &[Real], w: &[Real]) {
        let (m, t) = j.shape();
        assert!(r.len() == m && t == self.g.len() && !w.is_empty() && m % w.len() == 0);
        let rows = m / w.len();
        let js = j.as_slice();
        let pjs: &[Real] = if w.iter().all(|&wi| wi == 1.0) {
            js
        } else {
            self.pj.clear();
            self.pj.extend_from_slice(js);
            for c in 0..t {
                let col = &mut self.pj[c * m..(c + 1) * m];
                for (i, &wi) in w.iter().enumerate() {
                    for v in &mut col[i * rows..(i + 1) * rows] {
                        *v *= wi;
                    }
                }
            }
            &self.pj
        };
        gram::normal_equations(js, pjs, r, &mut self.block_n, &mut self.block_g);
        for (a, b) in self.n.as_mut_slice().iter_mut().zip(&self.block_n) {
            *a += b;
        }
        if let Some((n, block_n, block_g)) = &mut self.swapped {
            gram::normal_equations(pjs, js, r, block_n, block_g);
            for (a, b) in n.as_mut_slice().iter_mut().zip(&*block_n) {
                *a += b;
            }
        }
        for (a, b) in self.g.as_mut_slice().iter_mut().zip(&self.block_g) {
            *a += b;
        }
    }

    /// `JᵀPJ` so far (exactly symmetric).
    pub fn n(&self) -> &DMatrix<Real> {
        &self.n
    }

    /// `(PJ)_a · J_b` summed so far, for sums made by [`NormalEquations::both_ways`] (else
    /// the entry of [`NormalEquations::n`]).
    pub fn cross(&self, a: usize, b: usize) -> Real {
        match &self.swapped {
            // The swapped sums hold `J_a · (PJ)_b` at (a, b) for a ≥ b, mirrored.
            Some((n, ..)) if a < b => n[(b, a)],
            _ => self.n[(a, b)],
        }
    }

    /// `JᵀP r` so far.
    pub fn g(&self) -> &DVector<Real> {
        &self.g
    }

    /// Moves the sums into `n` and `g` (swapping buffers: no copy).
    pub fn swap_into(&mut self, n: &mut DMatrix<Real>, g: &mut DVector<Real>) {
        std::mem::swap(&mut self.n, n);
        std::mem::swap(&mut self.g, g);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random problem of `points` points of `rows` rows and `t` columns (seed `seed`): its
    /// Jacobian and residual.
    fn problem(
        seed: u64,
        (points, rows, t): (usize, usize, usize),
    ) -> (DMatrix<Real>, DVector<Real>) {
        let mut rng = crate::numeric::rng::from_seed(seed);
        let m = points * rows;
        let j = DMatrix::from_fn(m, t, |_, _| rand::Rng::random_range(&mut rng, -1.0..1.0));
        let r = DVector::from_fn(m, |_, _| rand::Rng::random_range(&mut rng, -1.0..1.0));
        (j, r)
    }

    /// `acc` after the columns `cols` of `(j, r)` are added `block` points at a time, the
    /// points weighed `w` (`rows` rows each).
    fn summed(
        mut acc: NormalEquations,
        (j, r): (&DMatrix<Real>, &DVector<Real>),
        (w, rows, block): (&[Real], usize, usize),
        cols: &[usize],
    ) -> NormalEquations {
        for first in (0..w.len()).step_by(block) {
            let k = block.min(w.len() - first);
            let jb = DMatrix::from_fn(k * rows, cols.len(), |i, c| j[(first * rows + i, cols[c])]);
            let rb = &r.as_slice()[first * rows..(first + k) * rows];
            acc.add(&jb, rb, &w[first..first + k]);
        }
        acc
    }

    /// Block sums against the normal equations of the whole weighted Jacobian, formed by
    /// nalgebra, for blocks that do not divide the rows evenly; cleared, the same again.
    #[test]
    fn blocks_sum_to_the_whole_normal_equations() {
        let (points, rows, t) = (23, 3, 5);
        let (j, r) = problem(3, (points, rows, t));
        let w: Vec<Real> = (0..points).map(|i| [1.0, 0.5, 0.0][i % 3]).collect();
        let p = DMatrix::from_diagonal(&DVector::from_fn(points * rows, |i, _| w[i / rows]));
        let want_n = j.transpose() * &p * &j;
        let want_g = j.transpose() * &p * &r;
        let all: Vec<usize> = (0..t).collect();
        let mut acc = NormalEquations::new(t, 7 * rows);
        for _ in 0..2 {
            acc.clear();
            acc = summed(acc, (&j, &r), (&w, rows, 7), &all);
            assert!((acc.n() - &want_n).amax() <= 1e-12 * want_n.amax());
            assert!((acc.g() - &want_g).amax() <= 1e-12 * want_g.amax());
            assert_eq!(acc.n(), &acc.n().transpose());
        }
    }

    /// The normal equations of any subset of the columns, in any order, read off sums made
    /// both ways have every bit of the subset's own sums: with unequal weights, where the
    /// entries of the two triangles differ.
    #[test]
    fn sums_both_ways_give_every_subset_in_any_order_to_the_bit() {
        let (points, rows, t) = (29, 3, 7);
        let (j, r) = problem(5, (points, rows, t));
        let mut rng = crate::numeric::rng::from_seed(6);
        let w: Vec<Real> = (0..points)
            .map(|_| rand::Rng::random_range(&mut rng, 0.1..3.0))
            .collect();
        let all: Vec<usize> = (0..t).collect();
        let both = summed(
            NormalEquations::both_ways(t, 8 * rows),
            (&j, &r),
            (&w, rows, 8),
            &all,
        );
        let mut lopsided = false;
        for cols in [vec![6, 0, 3], vec![2, 5, 1, 4, 0], vec![1, 0], all.clone()] {
            let own = NormalEquations::new(cols.len(), 8 * rows);
            let own = summed(own, (&j, &r), (&w, rows, 8), &cols);
            let n = DMatrix::from_fn(cols.len(), cols.len(), |k, l| {
                both.cross(cols[k.max(l)], cols[k.min(l)])
            });
            assert_eq!(&n, own.n(), "columns {cols:?}");
            for (k, &c) in cols.iter().enumerate() {
                assert_eq!(own.g()[k], both.g()[c]);
            }
            lopsided |= (0..t).any(|a| (0..a).any(|b| both.cross(a, b) != both.cross(b, a)));
        }
        assert!(
            lopsided,
            "the weights should make the triangles differ somewhere"
        );
    }
}

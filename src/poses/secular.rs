//! Eigenvalues of a symmetric low-rank update Λ ± WWᵀ in O(k²) per rank, for the DETMAX
//! candidate scans (Guo 2024 §3.2: every scan evaluates the objective of JᵀJ ± BᵀB for each
//! candidate block B).
//!
//! With JᵀJ = QΛQᵀ computed once per scan, the spectrum of JᵀJ ± BᵀB is that of Λ ± WWᵀ with
//! W = QᵀBᵀ (k × r). It is obtained by r successive rank-1 updates D + ρzzᵀ (Golub 1973,
//! "Some modified matrix eigenvalue problems"; Bunch, Nielsen & Sorensen 1978):
//!
//! - **deflation** (as LAPACK `dlaed2`): a component with |z_i|·‖z‖ below a tolerance keeps its
//!   eigenvalue d_i; two poles closer than the tolerance allows are merged by a Givens rotation
//!   that zeroes one z component;
//! - **roots** of the secular equation f(λ) = 1 + ρ Σ z_i²/(d_i − λ) = 0, one in each interval
//!   between consecutive poles (and one above the last), each found in coordinates shifted to
//!   the nearer pole, by the two-pole rational model of Bunch–Nielsen–Sorensen safeguarded by
//!   bisection on a sign bracket (O(k) per iteration);
//! - **eigenvectors** (needed only to express the next column of W in the new basis) by the
//!   Löwner formula with the recomputed ẑ of Gu & Eisenstat (1994), which keeps them
//!   orthogonal: v_j ∝ (ẑ_i/(d_i − λ_j))_i.
//!
//! A downdate (ρ = −1) is the update of the negated problem: eig(Λ − WWᵀ) = −eig(−Λ + WWᵀ).
//! The absolute error of each eigenvalue is a few ε·max(‖Λ‖, ‖W‖²), as for a dense symmetric
//! eigen-solver.

use crate::math::Real;

/// Reusable buffers for [`SpectrumUpdate::eigenvalues`]; nothing is allocated after the
/// first call with a given size.
#[derive(Clone, Debug, Default)]
pub struct SpectrumUpdate {
    d: Vec<Real>,
    w: Vec<Real>,
    kept: Vec<usize>,
    dk: Vec<Real>,
    zk: Vec<Real>,
    org: Vec<usize>,
    tau: Vec<Real>,
    delta: Vec<Real>,
    zhat: Vec<Real>,
    tmp: Vec<Real>,
    newd: Vec<Real>,
    perm: Vec<usize>,
    neww: Vec<Real>,
}

impl SpectrumUpdate {
    /// Empty buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// The eigenvalues (ascending) of diag(`lambda`) + `sign`·WWᵀ into `out`, where
    /// `lambda` holds the k eigenvalues of the base matrix in ascending order, W is k × r
    /// stored column by column in `w` (`w.len() = k·r`), and `sign` is +1 (update) or −1
    /// (downdate). Golub's secular equation, one rank-1 step per column of W (module docs).
    pub fn eigenvalues(&mut self, lambda: &[Real], w: &[Real], sign: Real, out: &mut [Real]) {
        let k = lambda.len();
        let r = w.len().checked_div(k).unwrap_or(0);
        self.d.clear();
        self.w.clear();
        if sign >= 0.0 {
            self.d.extend_from_slice(lambda);
            self.w.extend_from_slice(&w[..k * r]);
        } else {
            // −Λ ascending is Λ reversed and negated; rows of W follow.
            self.d.extend(lambda.iter().rev().map(|&x| -x));
            for c in 0..r {
                self.w.extend(w[c * k..(c + 1) * k].iter().rev());
            }
        }
        for c in 0..r {
            self.rank1(k, r, c, c + 1 < r);
        }
        if sign >= 0.0 {
            out[..k].copy_from_slice(&self.d);
        } else {
            for (o, &x) in out[..k].iter_mut().zip(self.d.iter().rev()) {
                *o = -x;
            }
        }
    }

    /// One rank-1 update D + zzᵀ with z column `c` of `self.w`; when `more`, the columns after
    /// `c` are re-expressed in the new eigenbasis and everything is re-sorted ascending.
    fn rank1(&mut self, k: usize, r: usize, c: usize, more: bool) {
        let eps = Real::EPSILON;
        let z = &self.w[c * k..(c + 1) * k];
        let nz2: Real = z.iter().map(|x| x * x).sum();
        if nz2 == 0.0 {
            return;
        }
        let nz = nz2.sqrt();
        let dmax = self.d.iter().fold(0.0 as Real, |a, &b| a.max(b.abs()));
        let tol = 8.0 * eps * dmax.max(nz2);
        // Deflation (dlaed2): small z components, then close poles by Givens rotations.
        self.kept.clear();
        for i in 0..k {
            if nz * self.w[c * k + i].abs() <= tol {
                continue;
            }
            if let Some(&p) = self.kept.last() {
                let (zp, zi) = (self.w[c * k + p], self.w[c * k + i]);
                let t = zp.hypot(zi);
                let (cs, sn) = (zi / t, -zp / t);
                if ((self.d[i] - self.d[p]) * cs * sn).abs() <= tol {
                    // Rotate coordinates p, i of every column from c on.
                    for cc in c..r {
                        let (wp, wi) = (self.w[cc * k + p], self.w[cc * k + i]);
                        self.w[cc * k + p] = cs * wp + sn * wi;
                        self.w[cc * k + i] = cs * wi - sn * wp;
                    }
                    self.w[c * k + p] = 0.0;
                    self.w[c * k + i] = t;
                    let (dp, di) = (self.d[p], self.d[i]);
                    self.d[p] = dp * cs * cs + di * sn * sn;
                    self.d[i] = dp * sn * sn + di * cs * cs;
                    self.kept.pop();
                }
            }
            self.kept.push(i);
        }
        let n = self.kept.len();
        if n == 0 {
            return;
        }
        self.dk.clear();
        self.zk.clear();
        for &i in &self.kept {
            self.dk.push(self.d[i]);
            self.zk.push(self.w[c * k + i]);
        }
        let zz: Real = self.zk.iter().map(|x| x * x).sum();
        // Roots: λ_j = dk[org_j] + tau_j.
        self.org.clear();
        self.tau.clear();
        for j in 0..n {
            let (o, t) = secular_root(&self.dk, &self.zk, zz, j);
            self.org.push(o);
            self.tau.push(t);
        }
        if !more {
            for (jj, &i) in self.kept.iter().enumerate() {
                self.d[i] = self.dk[self.org[jj]] + self.tau[jj];
            }
            self.d.sort_unstable_by(|a, b| a.total_cmp(b));
            return;
        }
        // delta[i·n + j] = dk_i − λ_j, accurate through the shifted roots.
        self.delta.clear();
        for i in 0..n {
            for j in 0..n {
                self.delta
                    .push((self.dk[i] - self.dk[self.org[j]]) - self.tau[j]);
            }
        }
        // Gu–Eisenstat ẑ: ẑ_i² = Π_j (λ_j − d_i) / Π_{j≠i} (d_j − d_i).
        self.zhat.clear();
        for i in 0..n {
            let mut p = -self.delta[i * n + i];
            for j in 0..n {
                if j != i {
                    p *= -self.delta[i * n + j] / (self.dk[j] - self.dk[i]);
                }
            }
            self.zhat.push(p.abs().sqrt().copysign(self.zk[i]));
        }
        // New coordinates of the later columns: w'_j = v_jᵀ w over the kept indices.
        for cc in (c + 1)..r {
            self.tmp.clear();
            for j in 0..n {
                let (mut s, mut nv) = (0.0, 0.0);
                for i in 0..n {
                    let v = self.zhat[i] / self.delta[i * n + j];
                    nv += v * v;
                    s += v * self.w[cc * k + self.kept[i]];
                }
                self.tmp.push(s / nv.sqrt());
            }
            for (j, &i) in self.kept.iter().enumerate() {
                self.w[cc * k + i] = self.tmp[j];
            }
        }
        for (jj, &i) in self.kept.iter().enumerate() {
            self.d[i] = self.dk[self.org[jj]] + self.tau[jj];
        }
        // Re-sort eigenvalues ascending, rows of the later columns with them.
        self.perm.clear();
        self.perm.extend(0..k);
        let d = &self.d;
        self.perm.sort_unstable_by(|&a, &b| d[a].total_cmp(&d[b]));
        self.newd.clear();
        self.newd.extend(self.perm.iter().map(|&i| d[i]));
        std::mem::swap(&mut self.d, &mut self.newd);
        self.neww.clear();
        self.neww.resize(k * r, 0.0);
        for cc in (c + 1)..r {
            for (dst, &src) in self.perm.iter().enumerate() {
                self.neww[cc * k + dst] = self.w[cc * k + src];
            }
        }
        for cc in (c + 1)..r {
            self.w[cc * k..(cc + 1) * k].copy_from_slice(&self.neww[cc * k..(cc + 1) * k]);
        }
    }
}

/// Secular function parts at λ = d[o] + t: (f, ψ, ψ', φ, φ'), with ψ the poles 0..=split and
/// φ the poles after `split`.
fn secular_parts(d: &[Real], z: &[Real], o: usize, t: Real, split: usize) -> [Real; 5] {
    let (mut psi, mut dpsi, mut phi, mut dphi) = (0.0, 0.0, 0.0, 0.0);
    let base = d[o];
    for (i, (&di, &zi)) in d.iter().zip(z).enumerate() {
        let del = (di - base) - t;
        let q = zi / del;
        if i <= split {
            psi += zi * q;
            dpsi += q * q;
        } else {
            phi += zi * q;
            dphi += q * q;
        }
    }
    [1.0 + psi + phi, psi, dpsi, phi, dphi]
}

/// The j-th root (ascending) of 1 + Σ z_i²/(d_i − λ) = 0, d strictly ascending, z nonzero,
/// zz = Σ z_i²; returned as (origin pole index, offset) with λ = d[origin] + offset.
fn secular_root(d: &[Real], z: &[Real], zz: Real, j: usize) -> (usize, Real) {
    let n = d.len();
    let eps = Real::EPSILON;
    if j + 1 == n {
        // Last root in (d_{n−1}, d_{n−1} + zz]; origin at the last pole, model
        // f ≈ C + b/(0 − t) from value and slope.
        let o = n - 1;
        let (mut lo, mut hi) = (0.0, zz);
        let mut t = zz * 0.5;
        for _ in 0..200 {
            let [f, psi, dpsi, phi, dphi] = secular_parts(d, z, o, t, n.saturating_sub(2));
            let _ = (psi, phi);
            let err = 8.0 * eps * n as Real * (1.0 + psi.abs() + phi.abs());
            if f.abs() <= err {
                return (o, t);
            }
            if f < 0.0 {
                lo = t;
            } else {
                hi = t;
            }
            // Whole-function pole-at-origin model: C − b/t, b = f'·t².
            let df = dpsi + dphi;
            let b = df * t * t;
            let cc = f + b / t;
            let mut tn = if cc > 0.0 { b / cc } else { Real::NAN };
            if !(tn > lo && tn < hi) {
                tn = 0.5 * (lo + hi);
            }
            if (tn - t).abs() <= 2.0 * eps * t.abs() || hi - lo <= 2.0 * eps * hi.abs() {
                return (o, tn);
            }
            t = tn;
        }
        return (o, t);
    }
    // Root in (d_j, d_{j+1}); pick the nearer pole as origin from f at the midpoint.
    let gap = d[j + 1] - d[j];
    let [fmid, ..] = secular_parts(d, z, j, 0.5 * gap, j);
    let (o, mut lo, mut hi) = if fmid >= 0.0 {
        (j, 0.0, 0.5 * gap)
    } else {
        (j + 1, -0.5 * gap, 0.0)
    };
    let (plo, phi_pole) = if o == j { (0.0, gap) } else { (-gap, 0.0) };
    let mut t = 0.5 * (lo + hi);
    for _ in 0..200 {
        let [f, psi, dpsi, phi, dphi] = secular_parts(d, z, o, t, j);
        let err = 8.0 * eps * n as Real * (1.0 + psi.abs() + phi.abs());
        if f.abs() <= err {
            return (o, t);
        }
        if f < 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        // Two-pole model (Bunch–Nielsen–Sorensen): ψ ≈ a + b/(plo − τ), φ ≈ c + e/(phi − τ).
        let dl = plo - t;
        let dh = phi_pole - t;
        let b = dpsi * dl * dl;
        let e = dphi * dh * dh;
        let cc = 1.0 + (psi - b / dl) + (phi - e / dh);
        // cc (plo − τ)(phi − τ) + b (phi − τ) + e (plo − τ) = 0.
        let qa = cc;
        let qb = -(cc * (plo + phi_pole) + b + e);
        let qc = cc * plo * phi_pole + b * phi_pole + e * plo;
        let mut tn = Real::NAN;
        if qa.abs() <= eps * (qb.abs() + qc.abs()) {
            if qb != 0.0 {
                tn = -qc / qb;
            }
        } else {
            let disc = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
            let q = -0.5 * (qb + disc.copysign(qb));
            let r1 = q / qa;
            let r2 = if q != 0.0 { qc / q } else { Real::NAN };
            if r1 > lo && r1 < hi {
                tn = r1;
            } else if r2 > lo && r2 < hi {
                tn = r2;
            }
        }
        if !(tn > lo && tn < hi) {
            tn = 0.5 * (lo + hi);
        }
        let scale = t.abs().max(tn.abs());
        if (tn - t).abs() <= 2.0 * eps * scale || (hi - lo) <= 2.0 * eps * lo.abs().max(hi.abs())
        {
            return (o, tn);
        }
        t = tn;
    }
    (o, t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::from_seed;
    use nalgebra::DMatrix;
    use rand::Rng as _;
    use rand_distr::StandardNormal;

    /// Fast path against nalgebra's dense symmetric eigenvalues of diag(λ) ± WWᵀ.
    fn check(lambda: &[Real], w: &DMatrix<Real>, sign: Real) -> Real {
        let k = lambda.len();
        let mut a = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(lambda));
        a.gemm(sign, w, &w.transpose(), 1.0);
        let mut want: Vec<Real> = a.symmetric_eigenvalues().iter().copied().collect();
        want.sort_unstable_by(|a, b| a.total_cmp(b));
        let mut got = vec![0.0; k];
        SpectrumUpdate::new().eigenvalues(lambda, w.as_slice(), sign, &mut got);
        let scale = want.iter().fold(0.0 as Real, |a, &b| a.max(b.abs()));
        got.iter()
            .zip(&want)
            .map(|(g, w)| (g - w).abs() / scale)
            .fold(0.0, Real::max)
    }

    fn randn(rng: &mut crate::rng::Rng, r: usize, c: usize) -> DMatrix<Real> {
        DMatrix::from_fn(r, c, |_, _| rng.sample::<Real, _>(StandardNormal))
    }

    #[test]
    fn rank1_closed_form_two_by_two() {
        // diag(1, 3) + zzᵀ, z = (1, 1): [[2, 1], [1, 4]] → 3 ± √2.
        let mut out = [0.0; 2];
        SpectrumUpdate::new().eigenvalues(&[1.0, 3.0], &[1.0, 1.0], 1.0, &mut out);
        assert!((out[0] - (3.0 - 2.0f64.sqrt())).abs() < 1e-14, "{out:?}");
        assert!((out[1] - (3.0 + 2.0f64.sqrt())).abs() < 1e-14, "{out:?}");
    }

    #[test]
    fn rank3_updates_and_downdates_match_dense_eigen() {
        let mut rng = from_seed(5);
        for trial in 0..200 {
            let k = 26;
            let r = if trial % 2 == 0 { 3 } else { 6 };
            // Base: eigenvalues of a random Gram matrix over a wide range.
            let j = randn(&mut rng, 3 * 40, k);
            let g = j.transpose() * &j;
            let mut lam: Vec<Real> = g.symmetric_eigenvalues().iter().copied().collect();
            lam.sort_unstable_by(|a, b| a.total_cmp(b));
            let w = randn(&mut rng, k, r) * 3.0;
            assert!(check(&lam, &w, 1.0) < 1e-13, "update {trial}");
            // Downdate of a matrix that contains WWᵀ (so the result stays PSD).
            let mut a = g.clone();
            a.gemm(1.0, &w, &w.transpose(), 1.0);
            let e = a.symmetric_eigen();
            let mut idx: Vec<usize> = (0..k).collect();
            idx.sort_unstable_by(|&x, &y| e.eigenvalues[x].total_cmp(&e.eigenvalues[y]));
            let lam2: Vec<Real> = idx.iter().map(|&i| e.eigenvalues[i]).collect();
            let q = DMatrix::from_fn(k, k, |row, col| e.eigenvectors[(row, idx[col])]);
            let wq = q.transpose() * &w;
            assert!(check(&lam2, &wq, -1.0) < 1e-13, "downdate {trial}");
        }
    }

    #[test]
    fn clustered_and_degenerate_spectra() {
        let mut rng = from_seed(9);
        for trial in 0..200 {
            let k = 26;
            // Clusters of equal or nearly equal eigenvalues, some zero, spread scales.
            let mut lam: Vec<Real> = (0..k)
                .map(|i| {
                    let base = [0.0, 1.0, 1.0, 1e3, 1e-6][(i + trial) % 5];
                    base * (1.0 + 1e-15 * rng.gen::<Real>() * (trial % 3) as Real)
                })
                .collect();
            lam.sort_unstable_by(|a, b| a.total_cmp(b));
            let mut w = randn(&mut rng, k, 3);
            // Some W rows zero or tiny (deflation by small z).
            for i in (0..k).step_by(4 + trial % 3) {
                for c in 0..3 {
                    w[(i, c)] *= if trial % 2 == 0 { 0.0 } else { 1e-17 };
                }
            }
            assert!(check(&lam, &w, 1.0) < 1e-13, "update {trial}");
            let e = check(&lam, &(w.clone() * 1e-3), -1.0);
            assert!(e < 1e-13, "downdate {trial}: {e}");
            // A W that removes a whole direction: λ + wwᵀ − wwᵀ with repeated columns.
            let mut w2 = w.clone();
            w2.set_column(1, &w.column(0));
            assert!(check(&lam, &w2, 1.0) < 1e-13, "repeated columns {trial}");
        }
    }
}

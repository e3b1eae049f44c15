//! Gaussian-process regression with an ARD squared-exponential kernel, several outputs
//! sharing one kernel (Rasmussen & Williams, *Gaussian Processes for Machine Learning*, 2006,
//! alg. 2.1 and eqs. 2.30, 5.8, 5.9).
//!
//! The kernel of inputs `x`, `x'` (dimension d) is
//! `k(x, x') = σ_f² exp(−½ Σ_k (x_k − x'_k)² / ℓ_k²)`, and the covariance of the training
//! outputs `K = [k(x_i, x_j)] + (σ_n² + ε) I`: σ_n² the noise variance, ε a fixed jitter
//! ([`JITTER`] times the mean square of the outputs) that keeps the Cholesky factor defined.
//! The hyperparameters are taken in logs, `θ = (ln ℓ_1, …, ln ℓ_d, ln σ_f, ln σ_n)`. Each of
//! the m outputs is an independent GP with that kernel, so the log marginal likelihood is
//! the sum over the outputs of eq. 2.30,
//! `L(θ) = −½ Σ_o y_oᵀ K⁻¹ y_o − (m/2) ln|K| − (m n/2) ln 2π`, and its gradient (eq. 5.9)
//! `∂L/∂θ_k = ½ tr((A − m K⁻¹) ∂K/∂θ_k)`, `A = Σ_o α_o α_oᵀ`, `α_o = K⁻¹ y_o`.
//!
//! [`maximise`] finds θ by L-BFGS on −L in the logs, bounded to a box, from each of the
//! given starting points (the best end kept; deterministic). One evaluation costs a Cholesky
//! factorisation (the library's one factor, solve and inverse, `numeric::linalg`), the
//! inverse from it (for the gradient) and an O(n² d) pass: O(n³) in all.
//! The factor, the inverse and the kernel matrix live in a [`Workspace`] allocated once per
//! fit; an evaluation allocates nothing.

use super::linalg;
use super::Real;

/// The jitter added to the diagonal of `K`, relative to the mean square of the outputs.
pub const JITTER: Real = 1e-10;

/// Training data: `n` inputs of dimension `d` and `n` outputs of dimension `m`, row-major.
#[derive(Clone, Copy, Debug)]
pub struct GpData<'a> {
    /// Inputs, `n × d`.
    pub x: &'a [Real],
    /// Outputs, `n × m`.
    pub y: &'a [Real],
    /// Rows.
    pub n: usize,
    /// Input dimension.
    pub d: usize,
    /// Output dimension.
    pub m: usize,
}

impl GpData<'_> {
    /// The jitter ε: [`JITTER`] times the mean square of the outputs (at least `JITTER`).
    pub fn jitter(&self) -> Real {
        let ms = self.y.iter().map(|v| v * v).sum::<Real>() / self.y.len().max(1) as Real;
        JITTER * ms.max(1.0)
    }
}

/// Scratch space of one fit: the scaled inputs, the kernel matrix, its factor and inverse,
/// the weights α.
pub struct Workspace {
    xs: Vec<Real>,
    kf: Vec<Real>,
    l: Vec<Real>,
    w: Vec<Real>,
    /// `α = K⁻¹ Y` of the last evaluation, `n × m`.
    pub alpha: Vec<Real>,
}

impl Workspace {
    /// Space for `n` rows of dimension `d`, `m` outputs.
    pub fn new(n: usize, d: usize, m: usize) -> Workspace {
        Workspace {
            xs: vec![0.0; n * d],
            kf: vec![0.0; n * n],
            l: vec![0.0; n * n],
            w: vec![0.0; n * n],
            alpha: vec![0.0; n * m],
        }
    }
}

/// `Σ a_k b_k`, in eight partial sums (the same bits on every machine).
#[inline]
fn dot(a: &[Real], b: &[Real]) -> Real {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut s = [0.0; 8];
    let chunks = n / 8;
    for c in 0..chunks {
        let (x, y) = (&a[8 * c..8 * c + 8], &b[8 * c..8 * c + 8]);
        for t in 0..8 {
            s[t] += x[t] * y[t];
        }
    }
    let mut r = ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]));
    for k in 8 * chunks..n {
        r += a[k] * b[k];
    }
    r
}

/// Fills the kernel matrix (`kf`, lower triangle row-major, without noise) and `K` (`l`,
/// lower triangle column-major, as [`linalg::factor`] reads it) at `θ`.
fn fill(data: &GpData, theta: &[Real], jitter: Real, ws: &mut Workspace) {
    let (n, d) = (data.n, data.d);
    for i in 0..n {
        for (k, t) in theta[..d].iter().enumerate() {
            ws.xs[i * d + k] = data.x[i * d + k] * (-t).exp();
        }
    }
    let sf2 = (2.0 * theta[d]).exp();
    let sn2 = (2.0 * theta[d + 1]).exp();
    for i in 0..n {
        let xi = &ws.xs[i * d..i * d + d];
        for j in 0..=i {
            let xj = &ws.xs[j * d..j * d + d];
            let r2: Real = xi.iter().zip(xj).map(|(a, b)| (a - b) * (a - b)).sum();
            let k = sf2 * (-0.5 * r2).exp();
            ws.kf[i * n + j] = k;
            ws.l[j * n + i] = k;
        }
        ws.l[i * n + i] += sn2 + jitter;
    }
}

/// The log marginal likelihood `L(θ)` of `data` (module docs) and, with `grad`, its gradient
/// in θ; `None` when `K` is not positive definite. Leaves α in `ws.alpha`.
pub fn log_marginal_likelihood(
    data: &GpData,
    theta: &[Real],
    jitter: Real,
    ws: &mut Workspace,
    grad: Option<&mut [Real]>,
) -> Option<Real> {
    let (n, d, m) = (data.n, data.d, data.m);
    fill(data, theta, jitter, ws);
    // Positive definiteness (pivot tolerance 0) is all the likelihood needs: the jitter keeps
    // `K` away from singular.
    if !linalg::factor(&mut ws.l, n, 0.0) {
        return None;
    }
    let mut fit = 0.0;
    for o in 0..m {
        // One output's column through the first row of `w` (scratch until the inverse).
        let col = &mut ws.w[..n];
        for (i, c) in col.iter_mut().enumerate() {
            *c = data.y[i * m + o];
        }
        linalg::solve(&ws.l, n, col);
        for (i, c) in col.iter().enumerate() {
            ws.alpha[i * m + o] = *c;
            fit += data.y[i * m + o] * c;
        }
    }
    let logdet: Real = 2.0 * (0..n).map(|i| ws.l[i * n + i].ln()).sum::<Real>();
    let nm = (n * m) as Real;
    let value =
        -0.5 * fit - 0.5 * m as Real * logdet - 0.5 * nm * (2.0 * std::f64::consts::PI).ln();
    if let Some(g) = grad {
        linalg::inverse(&mut ws.l, &mut ws.w, n);
        g.iter_mut().for_each(|v| *v = 0.0);
        let sn2 = (2.0 * theta[d + 1]).exp();
        for i in 0..n {
            let ai = &ws.alpha[i * m..i * m + m];
            let xi = &ws.xs[i * d..i * d + d];
            for j in 0..=i {
                let aa = dot(ai, &ws.alpha[j * m..j * m + m]);
                let both = if i == j { 1.0 } else { 2.0 };
                let wij = both * (aa - m as Real * ws.l[i * n + j]);
                let wk = wij * ws.kf[i * n + j];
                let xj = &ws.xs[j * d..j * d + d];
                for k in 0..d {
                    let dx = xi[k] - xj[k];
                    g[k] += wk * dx * dx;
                }
                g[d] += 2.0 * wk;
                if i == j {
                    g[d + 1] += 2.0 * sn2 * wij;
                }
            }
        }
        g.iter_mut().for_each(|v| *v *= 0.5);
    }
    Some(value)
}

/// The posterior mean at `x` (dimension d) of each of the m outputs:
/// `Σ_i k(x, x_i) α_i` (eq. 2.27), added into `out`.
pub fn posterior_mean(
    (x_train, alpha): (&[Real], &[Real]),
    (d, m): (usize, usize),
    theta: &[Real],
    x: &[Real],
    out: &mut [Real],
) {
    let sf2 = (2.0 * theta[d]).exp();
    let n = x_train.len() / d.max(1);
    for i in 0..n {
        let xi = &x_train[i * d..i * d + d];
        let mut r2 = 0.0;
        for k in 0..d {
            let t = (x[k] - xi[k]) * (-theta[k]).exp();
            r2 += t * t;
        }
        let kx = sf2 * (-0.5 * r2).exp();
        for o in 0..m {
            out[o] += kx * alpha[i * m + o];
        }
    }
}

/// The result of [`maximise`].
#[derive(Clone, Debug, PartialEq)]
pub struct Maximum {
    /// θ at the maximum.
    pub theta: Vec<Real>,
    /// `L(θ)`.
    pub lml: Real,
    /// Evaluations of `L` and its gradient, over every start.
    pub evaluations: usize,
    /// Which start ended best (0-based).
    pub start: usize,
}

/// The L-BFGS memory.
const MEMORY: usize = 7;

/// Maximises `L(θ)` from each of `starts` within the box `[lo, hi]` (L-BFGS with
/// backtracking, projected on the box: a hyperparameter held at a bound by the gradient takes
/// no part in the step; at most `iterations` steps per start; it stops when a step gains less
/// than `1e-9 (1 + |L|)` or the projected gradient is below `1e-6 (1 + |L|)`), and keeps the
/// best end (the first of equals). `None` when no start
/// has a positive definite `K`.
pub fn maximise(
    data: &GpData,
    starts: &[Vec<Real>],
    (lo, hi): (&[Real], &[Real]),
    iterations: usize,
    ws: &mut Workspace,
) -> Option<Maximum> {
    let p = data.d + 2;
    let jitter = data.jitter();
    let mut best: Option<Maximum> = None;
    let mut evaluations = 0;
    let (mut g, mut g_new, mut x_new, mut dir) =
        (vec![0.0; p], vec![0.0; p], vec![0.0; p], vec![0.0; p]);
    let (mut pg, mut active) = (vec![0.0; p], vec![false; p]);
    let mut s_hist = vec![vec![0.0; p]; MEMORY];
    let mut y_hist = vec![vec![0.0; p]; MEMORY];
    let mut rho = [0.0; MEMORY];
    let mut a_coef = [0.0; MEMORY];
    for (start_index, start) in starts.iter().enumerate() {
        let mut x: Vec<Real> = (0..p).map(|k| start[k].clamp(lo[k], hi[k])).collect();
        evaluations += 1;
        let Some(mut f) = log_marginal_likelihood(data, &x, jitter, ws, Some(&mut g)) else {
            continue;
        };
        // Minimise −L: work with its gradient −g.
        g.iter_mut().for_each(|v| *v = -*v);
        f = -f;
        let mut stored = 0usize;
        let mut newest = 0usize;
        for _ in 0..iterations {
            // The bounds that hold a hyperparameter (the descent would leave the box) take
            // no part in the step: the projected gradient `pg`.
            for k in 0..p {
                active[k] = (x[k] <= lo[k] && g[k] > 0.0) || (x[k] >= hi[k] && g[k] < 0.0);
                pg[k] = if active[k] { 0.0 } else { g[k] };
            }
            if pg.iter().fold(0.0 as Real, |a, v| a.max(v.abs())) < 1e-6 * (1.0 + f.abs()) {
                break;
            }
            // Two-loop recursion: dir = −H pg.
            dir.copy_from_slice(&pg);
            for t in 0..stored {
                let h = (newest + MEMORY - t) % MEMORY;
                a_coef[h] = rho[h] * dot(&s_hist[h], &dir);
                for k in 0..p {
                    dir[k] -= a_coef[h] * y_hist[h][k];
                }
            }
            if stored > 0 {
                let h = newest;
                let gamma = dot(&s_hist[h], &y_hist[h]) / dot(&y_hist[h], &y_hist[h]);
                dir.iter_mut().for_each(|v| *v *= gamma);
            }
            for t in (0..stored).rev() {
                let h = (newest + MEMORY - t) % MEMORY;
                let b = rho[h] * dot(&y_hist[h], &dir);
                for k in 0..p {
                    dir[k] += (a_coef[h] - b) * s_hist[h][k];
                }
            }
            for k in 0..p {
                dir[k] = if active[k] { 0.0 } else { -dir[k] };
            }
            if dot(&dir, &pg) >= 0.0 {
                // Not a descent direction: restart from the projected steepest descent.
                stored = 0;
                for k in 0..p {
                    dir[k] = -pg[k];
                }
            }
            // At most one unit in any log-hyperparameter per step.
            let longest = dir.iter().fold(0.0 as Real, |a, v| a.max(v.abs()));
            if longest > 1.0 {
                dir.iter_mut().for_each(|v| *v /= longest);
            }
            let mut step = 1.0;
            let mut accepted = None;
            for _ in 0..30 {
                for k in 0..p {
                    x_new[k] = (x[k] + step * dir[k]).clamp(lo[k], hi[k]);
                }
                evaluations += 1;
                if let Some(v) = log_marginal_likelihood(data, &x_new, jitter, ws, Some(&mut g_new))
                {
                    let gain: Real = (0..p).map(|k| g[k] * (x_new[k] - x[k])).sum();
                    if -v <= f + 1e-4 * gain.min(0.0) {
                        accepted = Some(-v);
                        break;
                    }
                }
                step *= 0.5;
            }
            let Some(f_new) = accepted else { break };
            g_new.iter_mut().for_each(|v| *v = -*v);
            let next = if stored == 0 {
                newest
            } else {
                (newest + 1) % MEMORY
            };
            let sy: Real = (0..p).map(|k| (x_new[k] - x[k]) * (g_new[k] - g[k])).sum();
            if sy > 1e-12 {
                for k in 0..p {
                    s_hist[next][k] = x_new[k] - x[k];
                    y_hist[next][k] = g_new[k] - g[k];
                }
                rho[next] = 1.0 / sy;
                newest = next;
                stored = (stored + 1).min(MEMORY);
            }
            let gained = f - f_new;
            x.copy_from_slice(&x_new);
            g.copy_from_slice(&g_new);
            f = f_new;
            if gained < 1e-9 * (1.0 + f.abs()) {
                break;
            }
        }
        if best.as_ref().is_none_or(|b| -f > b.lml) {
            best = Some(Maximum {
                theta: x.clone(),
                lml: -f,
                evaluations: 0,
                start: start_index,
            });
        }
    }
    best.map(|b| Maximum { evaluations, ..b })
}

#[cfg(test)]
#[path = "tests/gp.rs"]
mod tests;

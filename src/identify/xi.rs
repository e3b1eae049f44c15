//! The choice of the ridge parameter ξ of ridge and the robust ridge (Li 2018 eq. 14).
//!
//! Iteration k solves `(JᵀPJ + ξ_k D) δx = JᵀP E − ξ_k D (x − x0)` (the Gauss–Newton step of
//! the ridge objective `EᵀPE + ξ (x − x0)ᵀ D (x − x0)`; from `x0` it is Li's eq. 14). With
//! [`crate::identify::RidgeOptions::scale`] `D = diag(JᵀPJ)` at `x0`, i.e. ξ acts on the column-scaled problem
//! `A = P^½ J D^-½` whose columns have unit norm, so one ξ means the same for mm and rad
//! columns; without it `D = I` (Li's literal form, ξ in the units of `JᵀPJ`).
//!
//! ξ is fixed or chosen anew at every iteration from the linearised, scaled problem
//! `min |A z − b|² + ξ|z|²` with `z = D^½ (x + δx − x0)` and `b = P^½ (E + J (x − x0))`,
//! through the eigen-decomposition `AᵀA = V diag(s²) Vᵀ` (`β = (Vᵀ Aᵀ b) / s`):
//!
//! - [`XiRule::DoubleH`]: Li 2018 chooses ξ by the "双h" (double-h) method of its ref. 10
//!   (Huang & Niu, *Science of Surveying and Mapping* 36(4), 2011), whose formula is not in the
//!   paper and could not be recovered. calbench uses in its place the published
//!   Hoerl–Kennard–Baldwin rule (Hoerl, Kennard & Baldwin 1975, *Comm. Statist.* 4:105–123),
//!   `ξ = t σ̂² / |ẑ|²` with the least-squares solution `ẑ` and `σ̂² = |A ẑ − b|² / (n − t)`
//!   of the scaled problem.
//! - [`XiRule::Gcv`]: generalised cross-validation (Golub, Heath & Wahba 1979): the minimiser
//!   of `|A z_ξ − b|² / (n − tr H_ξ)²` over a log grid.
//! - [`XiRule::LCurve`]: the corner of the L-curve (Hansen 1992): the point of largest
//!   curvature of `(log |A z_ξ − b|, log |z_ξ|)` over the log grid. With consistent data (the
//!   least-squares residual at the rounding level, `< 1e-10 |b|`) the L-curve has no corner
//!   and the smallest ξ of the grid is taken.
//!
//! The grid holds 141 values of ξ from `1e-14 s²_max` to `s²_max`, evenly spaced in log.

use nalgebra::{DMatrix, DVector};

use crate::numeric::Real;

/// How the ridge parameter ξ is chosen.
#[derive(Clone, Debug, PartialEq)]
pub enum XiRule {
    /// A fixed ξ (relative to the scaled normal matrix when scaling is on).
    Fixed(Real),
    /// Li 2018's double-h choice, here the Hoerl–Kennard–Baldwin rule (see the module docs).
    DoubleH,
    /// Generalised cross-validation.
    Gcv,
    /// Maximum curvature of the L-curve.
    LCurve,
}

impl XiRule {
    /// The rule's name in scenarios: `double-h`, `gcv`, `l-curve`, or the number.
    pub fn name(&self) -> String {
        match self {
            XiRule::Fixed(v) => format!("{v}"),
            XiRule::DoubleH => "double-h".into(),
            XiRule::Gcv => "gcv".into(),
            XiRule::LCurve => "l-curve".into(),
        }
    }
}

impl<'de> serde::Deserialize<'de> for XiRule {
    /// `xi = "double-h" | "gcv" | "l-curve"` or a number ξ ≥ 0 (docs/formats.md `[[methods]]`).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(rename_all = "kebab-case")]
        enum Named {
            DoubleH,
            Gcv,
            LCurve,
        }
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Named(Named),
            Fixed(Real),
        }
        match Raw::deserialize(d).map_err(|_| {
            serde::de::Error::custom("expected \"double-h\", \"gcv\", \"l-curve\" or a number ≥ 0")
        })? {
            Raw::Named(Named::DoubleH) => Ok(XiRule::DoubleH),
            Raw::Named(Named::Gcv) => Ok(XiRule::Gcv),
            Raw::Named(Named::LCurve) => Ok(XiRule::LCurve),
            Raw::Fixed(v) => Ok(XiRule::Fixed(v)),
        }
    }
}

impl serde::Serialize for XiRule {
    /// The number, or the rule's name.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            XiRule::Fixed(v) => s.serialize_f64(*v),
            named => s.serialize_str(&named.name()),
        }
    }
}

impl XiRule {
    /// Checks a fixed ξ (finite, ≥ 0); errors name `key`.
    pub fn check(&self, key: &str) -> crate::Result<()> {
        match self {
            XiRule::Fixed(v) if !(v.is_finite() && *v >= 0.0) => Err(crate::Error::setting(
                key,
                format!("must be a number ≥ 0 or a rule, got {v}"),
            )),
            _ => Ok(()),
        }
    }
}

const GRID: usize = 141;
const GRID_DECADES: Real = 14.0;

/// What the ridge parameter of one iteration is chosen from: `n = JᵀPJ`, `g = JᵀP E`,
/// `cost = EᵀPE`, `dev = x − x0`, `d` the scaling and `n_rows` the rows with non-zero weight.
pub(crate) struct RidgeStep<'a> {
    pub n: &'a DMatrix<Real>,
    pub g: &'a DVector<Real>,
    pub cost: Real,
    pub dev: &'a DVector<Real>,
    pub d: &'a DVector<Real>,
    pub n_rows: usize,
}

/// The ridge parameter for one iteration of `s`; `a` and `y` are scratch buffers of `n`'s and
/// `g`'s sizes.
///
/// [`XiRule::DoubleH`] needs only the least-squares solution of the scaled problem and its
/// residual, which a Cholesky solve of `n` gives without the eigen-decomposition (and without
/// allocating): with `δ = n⁻¹ g`, `ẑ = D^½ (δ + dev)`, `|ẑ|² = Σ d_k (δ_k + dev_k)²` and the
/// explained part `βᵀβ = (g + n dev)ᵀ (δ + dev)`. When `n` is too close to singular for the
/// factorisation ([`crate::numeric::linalg::PIVOT_TOL`]) the eigen-decomposition below decides which
/// components carry information, as for the other rules.
pub(crate) fn choose_xi(
    rule: &XiRule,
    s: &RidgeStep,
    a: &mut DMatrix<Real>,
    y: &mut DVector<Real>,
) -> Real {
    if let XiRule::Fixed(v) = rule {
        return *v;
    }
    if let XiRule::DoubleH = rule {
        if let Some(xi) = double_h_cholesky(s, a, y) {
            return xi;
        }
    }
    let (n, g, cost, dev, d, n_rows) = (s.n, s.g, s.cost, s.dev, s.d, s.n_rows);
    let t = n.nrows();
    let nd = n * dev;
    let b2 = (cost + 2.0 * dev.dot(g) + dev.dot(&nd)).max(0.0);
    let mut ns = n.clone();
    let mut gs = g + nd;
    for i in 0..t {
        let si = d[i].sqrt();
        gs[i] /= si;
        for k in 0..t {
            ns[(i, k)] /= si * d[k].sqrt();
        }
    }
    let eig = ns.symmetric_eigen();
    let lmax = eig.eigenvalues.iter().fold(0.0 as Real, |a, &b| a.max(b));
    if lmax.is_nan() || lmax <= 0.0 || !lmax.is_finite() {
        return 0.0;
    }
    let h = eig.eigenvectors.tr_mul(&gs);
    // (λ_i, β_i²) of the components that carry information.
    let comps: Vec<(Real, Real)> = eig
        .eigenvalues
        .iter()
        .zip(h.iter())
        .filter(|(l, _)| **l > 1e-14 * lmax)
        .map(|(&l, &hi)| (l, hi * hi / l))
        .collect();
    let beta2: Real = comps.iter().map(|c| c.1).sum();
    let rho0 = (b2 - beta2).max(0.0);
    let dof = n_rows as Real - t as Real;
    match rule {
        XiRule::DoubleH => {
            let z2: Real = comps.iter().map(|(l, b)| b / l).sum();
            if dof <= 0.0 || z2 <= 0.0 {
                0.0
            } else {
                t as Real * (rho0 / dof) / z2
            }
        }
        XiRule::Gcv => {
            let mut best = (Real::INFINITY, grid(lmax, 0));
            for k in 0..GRID {
                let xi = grid(lmax, k);
                let (rho2, _, tr) = curve(&comps, rho0, xi);
                let den = n_rows as Real - tr;
                if den <= 0.0 {
                    continue;
                }
                let v = rho2 / (den * den);
                if v < best.0 {
                    best = (v, xi);
                }
            }
            best.1
        }
        XiRule::LCurve => {
            if rho0 <= 1e-20 * b2 {
                return grid(lmax, 0);
            }
            let pts: Vec<(Real, Real)> = (0..GRID)
                .map(|k| {
                    let (rho2, eta2, _) = curve(&comps, rho0, grid(lmax, k));
                    (
                        0.5 * rho2.max(Real::MIN_POSITIVE).ln(),
                        0.5 * eta2.max(Real::MIN_POSITIVE).ln(),
                    )
                })
                .collect();
            let mut best = (0.0, grid(lmax, 0));
            for k in 1..GRID - 1 {
                let (u1, v1) = (
                    0.5 * (pts[k + 1].0 - pts[k - 1].0),
                    0.5 * (pts[k + 1].1 - pts[k - 1].1),
                );
                let (u2, v2) = (
                    pts[k + 1].0 - 2.0 * pts[k].0 + pts[k - 1].0,
                    pts[k + 1].1 - 2.0 * pts[k].1 + pts[k - 1].1,
                );
                let den = (u1 * u1 + v1 * v1).powf(1.5);
                if den <= 0.0 {
                    continue;
                }
                let kappa = (u1 * v2 - v1 * u2) / den;
                if kappa > best.0 {
                    best = (kappa, grid(lmax, k));
                }
            }
            best.1
        }
        XiRule::Fixed(_) => unreachable!("handled above"),
    }
}

/// [`XiRule::DoubleH`] through a Cholesky solve of `n` (see [`choose_xi`]); `None` when `n`
/// does not factorise or the result is not finite.
fn double_h_cholesky(s: &RidgeStep, a: &mut DMatrix<Real>, y: &mut DVector<Real>) -> Option<Real> {
    let (n, g, cost, dev, d, n_rows) = (s.n, s.g, s.cost, s.dev, s.d, s.n_rows);
    let t = n.nrows();
    a.copy_from(n);
    if !crate::numeric::linalg::cholesky_in_place(a) {
        return None;
    }
    y.copy_from(g);
    crate::numeric::linalg::cholesky_solve(a, y);
    let (mut b2, mut beta2, mut z2) = (cost, 0.0, 0.0);
    for i in 0..t {
        let nd: Real = n.column(i).dot(dev);
        b2 += 2.0 * dev[i] * g[i] + dev[i] * nd;
        let zi = y[i] + dev[i];
        beta2 += (g[i] + nd) * zi;
        z2 += d[i] * zi * zi;
    }
    if !(b2.is_finite() && beta2.is_finite() && z2.is_finite()) {
        return None;
    }
    let rho0 = (b2.max(0.0) - beta2).max(0.0);
    let dof = n_rows as Real - t as Real;
    Some(if dof <= 0.0 || z2 <= 0.0 {
        0.0
    } else {
        t as Real * (rho0 / dof) / z2
    })
}

fn grid(lmax: Real, k: usize) -> Real {
    lmax * (10.0 as Real).powf(-GRID_DECADES + GRID_DECADES * k as Real / (GRID - 1) as Real)
}

/// `(|A z_ξ − b|², |z_ξ|², tr H_ξ)` of the scaled problem.
fn curve(comps: &[(Real, Real)], rho0: Real, xi: Real) -> (Real, Real, Real) {
    let (mut rho2, mut eta2, mut tr) = (rho0, 0.0, 0.0);
    for &(l, b2) in comps {
        let f = l / (l + xi);
        rho2 += (1.0 - f) * (1.0 - f) * b2;
        eta2 += f * f * b2 / l;
        tr += f;
    }
    (rho2, eta2, tr)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Cholesky form of the double-h rule against its definition on the
    /// eigen-decomposition of the scaled normal matrix (`ξ = t σ̂² / |ẑ|²`).
    #[test]
    fn double_h_by_cholesky_matches_the_eigen_decomposition() {
        let t = 6;
        let jac = DMatrix::from_fn(40, t, |i, k| {
            (((i * 37 + k * 101 + i * k * 7) % 97) as Real / 97.0 - 0.5) * (k + 1) as Real
        });
        let e = DVector::from_fn(40, |i, _| ((i * 3) as Real * 0.91).cos() * 0.1);
        let n = jac.tr_mul(&jac);
        let g = jac.tr_mul(&e);
        let cost = e.norm_squared();
        let dev = DVector::from_fn(t, |k, _| 0.01 * k as Real - 0.02);
        let d = DVector::from_fn(t, |k, _| n[(k, k)]);
        let (mut a, mut y) = (DMatrix::zeros(t, t), DVector::zeros(t));
        let step = RidgeStep {
            n: &n,
            g: &g,
            cost,
            dev: &dev,
            d: &d,
            n_rows: 40,
        };
        let xi = choose_xi(&XiRule::DoubleH, &step, &mut a, &mut y);
        // Reference: b = E + J dev, A = J D^-½; ẑ = argmin |A z − b|, σ̂² = |A ẑ − b|² / (m − t).
        let b = &e + &jac * &dev;
        let dinv = DMatrix::from_diagonal(&d.map(|v| 1.0 / v.sqrt()));
        let am = &jac * &dinv;
        let eig = am.tr_mul(&am).symmetric_eigen();
        let h = eig.eigenvectors.tr_mul(&am.tr_mul(&b));
        let z = &eig.eigenvectors * DVector::from_fn(t, |k, _| h[k] / eig.eigenvalues[k]);
        let s2 = (&am * &z - &b).norm_squared() / (40 - t) as Real;
        let want = t as Real * s2 / z.norm_squared();
        approx::assert_relative_eq!(xi, want, max_relative = 1e-9);
        assert!(xi > 0.0);
    }
}

//! Tests of [`super`] against independent truth (the Cholesky factor, solve and inverse it
//! uses are `numeric::linalg`'s, tested there): the gradient against central differences, a two-point case in closed form, and the
//! noise-free recovery of a known smooth function (with an irrelevant input found so by ARD).

use super::*;
use crate::numeric::rng::stream;
use rand::Rng;

fn random_data(n: usize, d: usize, m: usize, seed: u64) -> (Vec<Real>, Vec<Real>) {
    let mut g = stream(seed, "gp-test");
    let x: Vec<Real> = (0..n * d).map(|_| g.random_range(-1.0..1.0)).collect();
    let y: Vec<Real> = (0..n * m).map(|_| g.random_range(-1.0..1.0)).collect();
    (x, y)
}

#[test]
fn gradient_matches_central_differences() {
    let (n, d, m) = (37, 3, 2);
    let (x, y) = random_data(n, d, m, 2);
    let data = GpData {
        x: &x,
        y: &y,
        n,
        d,
        m,
    };
    let mut ws = Workspace::new(n, d, m);
    let theta = vec![-0.3, 0.2, 0.5, 0.1, -1.2];
    let mut g = vec![0.0; d + 2];
    let jitter = data.jitter();
    log_marginal_likelihood(&data, &theta, jitter, &mut ws, Some(&mut g)).unwrap();
    for k in 0..d + 2 {
        let h = 1e-5;
        let (mut up, mut down) = (theta.clone(), theta.clone());
        up[k] += h;
        down[k] -= h;
        let fu = log_marginal_likelihood(&data, &up, jitter, &mut ws, None).unwrap();
        let fd = log_marginal_likelihood(&data, &down, jitter, &mut ws, None).unwrap();
        let numeric = (fu - fd) / (2.0 * h);
        crate::assert_fd(g[k], numeric, 1e-6, &format!("θ{k}"));
    }
}

#[test]
fn two_points_in_closed_form() {
    // x = 0 and 1 (d = 1), y = 1 and −2; ℓ = 0.5, σ_f = 2, σ_n = 0.1.
    let (x, y) = (vec![0.0, 1.0], vec![1.0, -2.0]);
    let data = GpData {
        x: &x,
        y: &y,
        n: 2,
        d: 1,
        m: 1,
    };
    let theta = vec![0.5f64.ln(), 2.0f64.ln(), 0.1f64.ln()];
    let eps = data.jitter();
    let (a, b) = (4.0 + 0.01 + eps, 4.0 * (-0.5f64 * 4.0).exp());
    let det = a * a - b * b;
    // K⁻¹ = [[a, −b], [−b, a]] / det.
    let quad = (a * 1.0 + a * 4.0 - 2.0 * b * (1.0 * -2.0)) / det;
    let truth = -0.5 * quad - 0.5 * det.ln() - (2.0 * std::f64::consts::PI).ln();
    let mut ws = Workspace::new(2, 1, 1);
    let v = log_marginal_likelihood(&data, &theta, eps, &mut ws, None).unwrap();
    assert!((v - truth).abs() < 1e-12, "{v} vs {truth}");
    // Posterior mean at x = 0.5: k*ᵀ K⁻¹ y, k* = 4 e^{−½}(1, 1).
    let alpha = [(a * 1.0 + b * 2.0) / det, (-b * 1.0 - a * 2.0) / det];
    let ks = 4.0 * (-0.5f64).exp();
    let mut out = [0.0];
    posterior_mean((&x, &ws.alpha), (1, 1), &theta, &[0.5], &mut out);
    assert!((out[0] - ks * (alpha[0] + alpha[1])).abs() < 1e-12);
}

#[test]
fn noise_free_recovery_of_a_smooth_function() {
    let f = |x: &[Real]| (2.0 * x[0]).sin() + 0.5 * (1.5 * x[1]).cos();
    let (n, d) = (80, 3);
    let (x, _) = random_data(n, d, 1, 3);
    let y: Vec<Real> = (0..n).map(|i| f(&x[i * d..i * d + d])).collect();
    let data = GpData {
        x: &x,
        y: &y,
        n,
        d,
        m: 1,
    };
    let mut ws = Workspace::new(n, d, 1);
    let starts = vec![vec![0.0, 0.0, 0.0, 0.0, -1.0]];
    let lo = vec![-4.0, -4.0, -4.0, -5.0, -12.0];
    let hi = vec![4.0, 4.0, 4.0, 3.0, 1.0];
    let best = maximise(&data, &starts, (&lo, &hi), 200, &mut ws).unwrap();
    let t = &best.theta;
    assert!(
        t[2] > t[0] + 1.0 && t[2] > t[1] + 1.0,
        "the third input is irrelevant: {t:?}"
    );
    assert!(t[4] < -5.0, "noise-free data: σ_n small, {t:?}");
    log_marginal_likelihood(&data, t, data.jitter(), &mut ws, None).unwrap();
    let (probe, _) = random_data(50, d, 1, 4);
    let mut sq = 0.0;
    for p in probe.chunks(d) {
        let p = [p[0] * 0.9, p[1] * 0.9, p[2]];
        let mut out = [0.0];
        posterior_mean((&x, &ws.alpha), (d, 1), t, &p, &mut out);
        sq += (out[0] - f(&p)).powi(2);
    }
    let rms = (sq / 50.0).sqrt();
    assert!(rms < 1e-3, "RMS error {rms} at new points");
}

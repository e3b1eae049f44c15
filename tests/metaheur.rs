//! Derivative-free identification of the TX60 on noise-free full-pose data (Qiao 2021 §4).

use calbench::errmodel::acpe_acae;
use calbench::kinematics::{Param, Robot};
use calbench::math::{Frame, Real};
use calbench::metaheur::{
    bas, bas_pso, poses_in_cube, pso, BasOptions, BasPsoOptions, MetaProblem, PsoOptions,
    DEFAULT_K,
};
use calbench::rng::stream;

/// The parameters searched in these tests: the joint offsets θ2–θ6, the link lengths a2, a3,
/// the offsets d3, d4, d6 and the twists α2, α3, α4 plus β2 (Qiao's parallel-axis angle) — 14
/// of Qiao's 24, all identifiable from full-pose data with the base known, chosen to keep the
/// test under a few seconds while mixing mm and rad and every parameter kind.
fn subset() -> Vec<Param> {
    let mut v: Vec<Param> = (1..6).map(Param::Theta).collect();
    v.extend([Param::A(1), Param::A(2), Param::D(2), Param::D(3), Param::D(5)]);
    v.extend([Param::Alpha(1), Param::Alpha(2), Param::Alpha(3), Param::Beta(1)]);
    v
}

/// Errors of ±0.1 mm / ±0.001 rad, signs alternating, on the subset.
fn injected(params: &[Param]) -> Vec<Real> {
    params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let s = if i % 2 == 0 { 1.0 } else { -1.0 };
            let m = 0.5 + 0.5 * ((i % 3) as Real) / 2.0;
            s * m * if p.is_length() { 0.1 } else { 0.001 }
        })
        .collect()
}

struct Case {
    nominal: Robot,
    params: Vec<Param>,
    truth: Vec<Real>,
    qs: Vec<Vec<Real>>,
    measured: Vec<Frame>,
}

fn case() -> Case {
    let nominal = calbench::robots::load("tx60").unwrap();
    let params = subset();
    let truth = injected(&params);
    let errs: Vec<(Param, Real)> = params.iter().copied().zip(truth.iter().copied()).collect();
    let real = nominal.with_errors(&errs);
    let mut rng = stream(2021, "poses");
    let qs = poses_in_cube(&nominal, 50, [550.0, 0.0, 550.0], 1000.0, 200_000, &mut rng).unwrap();
    let chain = real.chain();
    let measured = qs.iter().map(|q| chain.fk(q)).collect();
    Case {
        nominal,
        params,
        truth,
        qs,
        measured,
    }
}

fn acpe(c: &Case, x: &[Real]) -> (Real, Real) {
    let p = MetaProblem::from_frames(&c.nominal, c.params.clone(), c.qs.clone(), &c.measured, DEFAULT_K)
        .unwrap();
    let model = p.frames(x).unwrap();
    acpe_acae(&c.measured, &model).unwrap()
}

#[test]
fn bas_pso_cuts_tx60_acpe_by_90_percent() {
    let c = case();
    let p = MetaProblem::from_frames(&c.nominal, c.params.clone(), c.qs.clone(), &c.measured, DEFAULT_K)
        .unwrap();
    let b = p.bounds(0.5, 0.005);
    let f = |x: &[Real]| p.fitness(x);
    let zero = vec![0.0; c.params.len()];
    let before = acpe(&c, &zero);
    let t = std::time::Instant::now();
    let o = BasPsoOptions { iterations: 300, ..Default::default() };
    let r = bas_pso(&f, &b, &o, &mut stream(1, "bas_pso")).unwrap();
    let after = acpe(&c, &r.x);
    eprintln!("bas_pso {:?} {:?} -> {:?} fit {} evals {}", t.elapsed(), before, after, r.fitness, r.evaluations);
    let t = std::time::Instant::now();
    let o = PsoOptions { iterations: 300, ..Default::default() };
    let r = pso(&f, &b, &o, &mut stream(1, "pso")).unwrap();
    eprintln!("pso {:?} {:?} fit {} evals {}", t.elapsed(), acpe(&c, &r.x), r.fitness, r.evaluations);
    let t = std::time::Instant::now();
    let o = BasOptions { iterations: 3000, ..Default::default() };
    let r = bas(&f, &b, &o, &mut stream(1, "bas")).unwrap();
    eprintln!("bas {:?} {:?} fit {} evals {}", t.elapsed(), acpe(&c, &r.x), r.fitness, r.evaluations);
    assert!(after.0 < 0.1 * before.0, "{before:?} -> {after:?}");
}

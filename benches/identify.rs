//! Identification on the irb2600: 50 random poses, noise-free measurements of the paper set
//! (every length +0.5 mm, every angle +0.05 rad on the position-identifiable parameters).

use calbench::identify::{
    solve, LmOptions, LsOptions, RidgeOptions, RobotProblem, RobustOptions, Solver, XiRule,
};
use calbench::measurement::Measure;
use calbench::numeric::rng;
use calbench::numeric::Real;
use calbench::robot::builtin;
use calbench::robot::identifiability::analyse;
use calbench::robot::jacobian::{jacobian, Columns};
use calbench::robot::sampling::uniform_joint_poses;
use calbench::robot::Param;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::DVector;

fn bench(c: &mut Criterion) {
    let nominal = builtin::irb2600();
    let mut r = rng::from_seed(11);
    let rich = uniform_joint_poses(&nominal, 200, &mut r);
    let cand = analyse(&nominal, &nominal.params(), &rich, Measure::Position).identifiable;
    // Drop columns that vanish at the nominal robot (θ6 with a zero tool).
    let j = jacobian(&nominal, &Columns::new(&cand, 6), &rich, Measure::Position);
    let params: Vec<Param> = cand
        .iter()
        .enumerate()
        .filter(|(k, _)| j.column(*k).norm() > 1e-6)
        .map(|(_, p)| *p)
        .collect();
    let pairs: Vec<(Param, Real)> = params
        .iter()
        .map(|&p| (p, if p.is_length() { 0.5 } else { 0.05 }))
        .collect();
    let truth = nominal.with_errors(&pairs);
    let qs = uniform_joint_poses(&nominal, 50, &mut r);
    let chain = truth.chain();
    let points: Vec<_> = qs.iter().map(|q| chain.fk(q).pos).collect();
    let problem = RobotProblem::new(&nominal, &params, &qs, &points, None, Measure::Position)
        .expect("problem");
    let x0 = DVector::zeros(params.len());
    let methods: [(&str, Box<dyn Solver>); 7] = [
        ("ls", Box::new(LsOptions::default())),
        ("ridge-double-h", Box::new(RidgeOptions::default())),
        (
            "ridge-gcv",
            Box::new(RidgeOptions {
                xi: XiRule::Gcv,
                ..Default::default()
            }),
        ),
        (
            "ridge-l-curve",
            Box::new(RidgeOptions {
                xi: XiRule::LCurve,
                ..Default::default()
            }),
        ),
        ("igg3", Box::new(RobustOptions::default())),
        ("lm", Box::new(LmOptions::default())),
        (
            "lm-adaptive",
            Box::new(LmOptions {
                adaptive: true,
                ..Default::default()
            }),
        ),
    ];
    let mut g = c.benchmark_group("identify-irb2600-50");
    for (name, m) in &methods {
        let out = solve(m.as_ref(), &problem, &x0);
        eprintln!(
            "{name}: {} after {} iterations",
            out.termination.as_str(),
            out.iterations
        );
        g.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter(|| solve(m.as_ref(), &problem, &x0))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

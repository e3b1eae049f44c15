//! BAS, PSO and BAS-PSO on the TX60 with 50 noise-free full-pose measurements (Qiao 2021 §4):
//! one fitness evaluation, and each search with a fixed budget; and the three pose-error
//! models (Qiao §2.2–2.3, §4.2), one linear step and Gauss–Newton to convergence.

use calbench::identify::qiao::error_models::{identify, ErrorModel};
use calbench::identify::qiao::{
    bas, bas_pso, poses_in_cube, pso, BasOptions, BasPsoOptions, MetaProblem, PsoOptions, DEFAULT_K,
};
use calbench::numeric::rng::stream;
use calbench::numeric::{Frame, Real};
use calbench::robot::builtin::tx60_qiao_params;
use calbench::robot::Param;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

fn bench(c: &mut Criterion) {
    let nominal = calbench::robot::builtin::load("tx60").expect("tx60");
    let params = tx60_qiao_params();
    let errs: Vec<(Param, Real)> = params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let s = [1.0, -0.6, 0.8, -1.0, 0.4][i % 5];
            (*p, s * if p.is_length() { 0.1 } else { 0.001 })
        })
        .collect();
    let real = nominal.with_errors(&errs);
    let mut rng = stream(2021, "poses");
    let qs =
        poses_in_cube(&nominal, 50, [550.0, 0.0, 550.0], 1000.0, 200_000, &mut rng).expect("poses");
    let measured: Vec<Frame> = qs.iter().map(|q| real.fk(q)).collect();
    let mut g = c.benchmark_group("errmodel_tx60_50_poses");
    for model in ErrorModel::ALL {
        for steps in [1, 5] {
            let id = BenchmarkId::new(model.as_str(), steps);
            g.bench_with_input(id, &steps, |bch, &steps| {
                bch.iter(|| {
                    identify(
                        model, &nominal, &params, &qs, &measured, steps, DEFAULT_K, None,
                    )
                    .expect("identify")
                })
            });
        }
    }
    g.finish();

    let p = MetaProblem::from_frames(&nominal, params, qs, &measured, DEFAULT_K).expect("problem");
    let b = p.bounds(0.5, 0.005, 1e-5);
    let f = |x: &[Real]| p.fitness(x);
    let x0 = vec![0.0; b.dim()];

    let mut g = c.benchmark_group("metaheur_tx60_50_poses");
    g.sample_size(10);
    g.bench_function("fitness", |bch| {
        bch.iter(|| p.fitness(std::hint::black_box(&x0)))
    });
    // Budgets of about 36 000 evaluations each.
    let it = 300;
    g.bench_with_input(BenchmarkId::new("bas_pso", it), &it, |bch, &it| {
        let o = BasPsoOptions {
            swarm: PsoOptions {
                iterations: it,
                ..Default::default()
            },
            ..Default::default()
        };
        bch.iter(|| bas_pso(&f, &b, &o, &mut stream(1, "m")).expect("bas_pso"))
    });
    g.bench_with_input(BenchmarkId::new("pso", 3 * it), &(3 * it), |bch, &it| {
        let o = PsoOptions {
            iterations: it,
            ..Default::default()
        };
        bch.iter(|| pso(&f, &b, &o, &mut stream(1, "m")).expect("pso"))
    });
    g.bench_with_input(BenchmarkId::new("bas", 12_000), &12_000, |bch, &it| {
        let o = BasOptions {
            iterations: it,
            ..Default::default()
        };
        bch.iter(|| bas(&f, &b, &o, &mut stream(1, "m")).expect("bas"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

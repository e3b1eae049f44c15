//! The default study as `cargo run --release` runs it (the built-in scenario, 1000 trials, its
//! eight method × strategy pairs, rapier sag, two threads), outputs written to a scratch
//! folder: the speed table's wall-time line (target ≤ 4 s).

use calbench::runner::run::run_study;
use calbench::study::reporter::Silent;
use calbench::study::scenario::Scenario;
use calbench::study::RunOptions;
use criterion::{criterion_group, criterion_main, Criterion};

fn bench(c: &mut Criterion) {
    let out = std::env::temp_dir().join(format!("calbench-bench-study-{}", std::process::id()));
    let opts = RunOptions {
        threads: Some(2),
        out: Some(out.clone()),
        progress: false,
        shard: None,
        precision: None,
    };
    let mut g = c.benchmark_group("study");
    g.sample_size(10);
    g.bench_function("default-1000-trials-2-threads", |b| {
        b.iter(|| {
            run_study(
                Scenario::default_study().expect("default scenario"),
                &opts,
                &Silent,
            )
        })
    });
    g.finish();
    std::fs::remove_dir_all(&out).ok();
}

criterion_group!(benches, bench);
criterion_main!(benches);

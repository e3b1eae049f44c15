//! The default study as `cargo run --release` runs it (the built-in scenario, 1000 trials, its
//! eight method × strategy pairs, rapier sag, two threads), outputs written to a scratch
//! folder: the speed table's wall-time line (target ≤ 4 s).
//!
//! Beside it, in the same sitting, what the study's statistics cost: the trials of one run
//! kept in memory and aggregated again (the running sums and order statistics of every
//! figure, the per-trial headline values, then `summary.json`'s intervals, paired
//! comparisons, Wilcoxon tests and claims). That is an upper bound of the statistics' share
//! of the run (the means and maxima that reports had before are in it too); the budget is
//! at most 5 % (docs/performance.md).

use calbench::analysis::analyse::analyse;
use calbench::runner::run::{run, run_study};
use calbench::study::reporter::Silent;
use calbench::study::scenario::Scenario;
use calbench::study::trial::TrialResult;
use calbench::study::{BlockInfo, Collector, RunOptions, RunResult, TrialSink};
use criterion::{criterion_group, criterion_main, Criterion};

/// Keeps every trial of a run with its block.
struct Keep(Vec<(BlockInfo, TrialResult)>);

impl TrialSink for Keep {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> calbench::Result<()> {
        self.0.push((info.clone(), t.clone()));
        Ok(())
    }
}

/// The aggregation of a finished run's trials into `summary.json`'s text.
fn aggregate(kept: &[(BlockInfo, TrialResult)], like: &RunResult) -> String {
    let mut c = Collector::new();
    c.begin(kept[0].0.clone(), None);
    for (_, t) in kept {
        c.trial(t, &mut ()).expect("trial");
    }
    let r = RunResult {
        scenario: like.scenario.clone(),
        blocks: c.finish(None).expect("finish"),
        out: like.out.clone(),
        seconds: 0.0,
        shard: None,
        stopping: None,
    };
    analyse(&r).expect("analysis").to_json().expect("summary")
}

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
    let mut kept = Keep(Vec::new());
    let whole = run(
        Scenario::default_study().expect("default scenario"),
        &opts,
        &mut kept,
        &Silent,
    )
    .expect("default study");
    // The same bytes as the run's own summary: the bench times what the run does.
    assert_eq!(
        aggregate(&kept.0, &whole),
        analyse(&whole)
            .expect("analysis")
            .to_json()
            .expect("summary")
    );
    g.bench_function("default-1000-trials-statistics", |b| {
        b.iter(|| aggregate(&kept.0, &whole))
    });
    g.finish();
    std::fs::remove_dir_all(&out).ok();
}

criterion_group!(benches, bench);
criterion_main!(benches);

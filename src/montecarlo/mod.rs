//! The Monte-Carlo harness (FORMATS.md `run`): a scenario's trials in parallel with rayon,
//! each from its own seed, aggregated per method and pose strategy. It returns values; the
//! files (`summary.json`, `trials.csv`, `report.md`, plots) are written by
//! [`crate::report::write_all`].
//!
//! - [`study`]: what a scenario needs once (nominal robot, parameters, tracker, fixed pose
//!   sets);
//! - [`trial`]: one trial (true robot, measurements, every method's calibration, validation);
//! - [`stats`]: the aggregation into [`Entry`] values.
//!
//! Determinism: trial i draws everything from `rng::trial_seed(seed, i)` and results are
//! collected in trial order, so the output is the same whatever the thread count (timing
//! fields excepted).

pub mod stats;
pub mod study;
pub mod trial;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::scenario::Scenario;
pub use stats::{aggregate, Entry};
pub use study::Study;
pub use trial::{run_trial, TrialResult};

/// Options of a run from the command line.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Worker threads (`None`: rayon's default, one per core).
    pub threads: Option<usize>,
    /// Output folder (`None`: `results/<name>/`).
    pub out: Option<PathBuf>,
    /// Show a progress bar (only drawn when stderr is a terminal).
    pub progress: bool,
}

/// The study of one swept value (or the whole study without a sweep).
pub struct Block {
    /// The swept value, if any.
    pub sweep_value: Option<toml::Value>,
    /// The prepared study.
    pub study: Study,
    /// Its trials, in order.
    pub trials: Vec<TrialResult>,
    /// One entry per strategy × method.
    pub entries: Vec<Entry>,
}

/// Everything a run produced.
pub struct RunResult {
    /// The scenario as run.
    pub scenario: Scenario,
    /// One block per swept value.
    pub blocks: Vec<Block>,
    /// The output folder.
    pub out: PathBuf,
    /// Wall time of the whole run (s).
    pub seconds: f64,
}

/// Converts a TOML value to JSON (sweep values in `summary.json`).
pub fn toml_to_json(v: &toml::Value) -> serde_json::Value {
    serde_json::to_value(v).unwrap_or(serde_json::Value::Null)
}

/// Runs the trials of a prepared study on the current rayon pool.
pub fn run_trials(study: &Study, bar: &ProgressBar) -> Result<Vec<TrialResult>> {
    (0..study.scenario.trials)
        .into_par_iter()
        .map(|i| {
            let r = run_trial(study, i);
            bar.inc(1);
            r
        })
        .collect()
}

/// Runs `scenario` (every sweep value, every trial) and returns the results; nothing is
/// written.
pub fn run(scenario: Scenario, opts: &RunOptions) -> Result<RunResult> {
    let t0 = std::time::Instant::now();
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| Path::new("results").join(&scenario.name));
    let plans = scenario.sweep_plans()?;
    let total = (plans.len() * scenario.trials) as u64;
    let bar = if opts.progress && std::io::stderr().is_terminal() {
        let b = ProgressBar::new(total);
        if let Ok(style) = ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} trials ({per_sec}, {eta} left) {msg}",
        ) {
            b.set_style(style);
        }
        b
    } else {
        ProgressBar::hidden()
    };
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = opts.threads {
        builder = builder.num_threads(t);
    }
    let pool = builder
        .build()
        .map_err(|e| Error::Compute(format!("cannot start the worker threads: {e}")))?;
    let mut blocks = Vec::new();
    for (value, plan) in plans {
        if let Some(v) = &value {
            bar.set_message(format!(
                "{} = {v}",
                scenario.sweep.as_ref().map_or("", |s| &s.key)
            ));
        }
        let study = pool.install(|| Study::new(plan))?;
        let trials = pool.install(|| run_trials(&study, &bar))?;
        let names: Vec<String> = study.params.iter().map(|p| p.to_string()).collect();
        let mut entries = Vec::new();
        for (si, s) in study.scenario.calibration.strategies.iter().enumerate() {
            for (mi, m) in study.scenario.methods.iter().enumerate() {
                entries.push(aggregate(
                    &trials,
                    si,
                    mi,
                    &names,
                    (&m.label, s.name()),
                    value.as_ref().map(toml_to_json),
                ));
            }
        }
        blocks.push(Block {
            sweep_value: value,
            study,
            trials,
            entries,
        });
    }
    bar.finish_and_clear();
    Ok(RunResult {
        scenario,
        blocks,
        out,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

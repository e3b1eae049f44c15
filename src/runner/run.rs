//! Running a study (docs/formats.md `run`, `run --resume`): its trials in chunks on rayon,
//! handed in order to the aggregation and to sinks; its output folder written as a whole
//! through the report's outputs ([`crate::report::write_run`], [`crate::report::TrialsCsv`]);
//! the checkpoint beside it that lets a killed run continue ([`super::checkpoint`]); a share
//! of it ([`super::shard`]); and a run held in memory ([`InMemoryRun`]). Progress and
//! warnings go to the [`Reporter`] the caller supplies.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use super::checkpoint::Checkpoint;
use super::shard::{self, Both};
use crate::analysis::{idle::analyse_warning, summary::Summary};
use crate::error::{Error, Opt, Result, Said};
use crate::report::output::{write_all, Bytes, Outputs};
use crate::report::{atomically, run as files, run_outputs, write_run};
use crate::study::kind::AnyScenario;
use crate::study::reporter::{NoProgress, Progress, Reporter, Silent, Terminal};
use crate::study::scenario::Scenario;
use crate::study::stats::precision::{widest_and_needed, Stopping, BLOCK};
use crate::study::{run_trial, BlockInfo, Collector, Replay, RunOptions, RunResult, Study};
use crate::study::{TrialResult, TrialSink, CHUNK};

/// Runs `scenario` and writes its output folder as a whole ([`atomically`]):
/// `trials.csv` as trials finish, then `summary.json`, `timing.json`, `report.md` and the
/// plots; with `opts.shard`, the shard's partial result instead ([`shard`]). A checkpoint
/// beside the output folder lets `calbench run --resume` continue the run if it is killed
/// ([`super::checkpoint`]). Progress and warnings go to `reporter`.
pub fn run_study(
    scenario: Scenario,
    opts: &RunOptions,
    reporter: &dyn Reporter,
) -> Result<RunResult> {
    let out = opts.out_or(&scenario.name);
    crate::report::guard::guard_folder(&out, "out")?;
    let cp = Checkpoint::start(
        &AnyScenario::MonteCarlo(scenario.clone()),
        opts.shard,
        opts.precision.as_ref(),
        &out,
        reporter,
    )?;
    study_into(scenario, opts, &out, cp, None, reporter)
}

/// Runs (or continues) a study into `out` with its checkpoint `cp`, written whole or not at
/// all; the checkpoint is removed once the run ends, with its output or with an error.
pub(super) fn study_into(
    scenario: Scenario,
    opts: &RunOptions,
    out: &Path,
    mut cp: Checkpoint,
    replay: Option<&mut dyn Replay>,
    reporter: &dyn Reporter,
) -> Result<RunResult> {
    let mut result = None;
    let done = atomically(out, |dir| {
        let mut csv = files::TrialsCsv::create(dir, scenario.sweep.as_ref())?;
        let r = match opts.shard {
            None => {
                let r = {
                    let mut both = Both(&mut csv, &mut cp);
                    run_resumed(scenario, opts, &mut both, replay, reporter)?
                };
                let summary = analyse_warning(&r, reporter)?;
                write_run(&r, &summary, csv.finish()?, dir)?;
                r
            }
            Some(_) => {
                let any = AnyScenario::MonteCarlo(scenario.clone());
                let mut records = shard::Records::create(dir, &any)?;
                let r = {
                    let mut sinks = Both(&mut csv, &mut records);
                    let mut all = Both(&mut sinks, &mut cp);
                    run_resumed(scenario, opts, &mut all, replay, reporter)?
                };
                let mut outputs = vec![csv.finish()?];
                outputs.extend(records.finish(&r)?);
                write_all(dir, &outputs)?;
                r
            }
        };
        result = Some(r);
        Ok(())
    });
    // A run that ends, with its output or with an error, leaves no checkpoint: only a run
    // killed from outside does.
    cp.finish()?;
    done?;
    result.ok_or_else(|| Error::Compute("the run produced no result".into()))
}

/// A complete run held in memory (the Python module's `run`): its result and the bytes of
/// its `trials.csv`, written as a folder on demand with the same files and bytes as
/// [`run_study`] writes.
pub struct InMemoryRun {
    /// The run's results.
    pub result: RunResult,
    /// `trials.csv`.
    pub trials_csv: Vec<u8>,
    /// Its summary.
    pub summary: Summary,
}

impl InMemoryRun {
    /// Runs `scenario` (whole: `opts.shard` and `opts.out` are not used) and keeps its
    /// results; with `opts.progress`, progress goes to the [`Terminal`] (as `calbench run`
    /// shows it), otherwise nowhere. [`InMemoryRun::run_with`] takes any reporter.
    pub fn run(scenario: Scenario, opts: &RunOptions) -> Result<InMemoryRun> {
        if opts.progress {
            InMemoryRun::run_with(scenario, opts, &Terminal)
        } else {
            InMemoryRun::run_with(scenario, opts, &Silent)
        }
    }

    /// [`InMemoryRun::run`] with progress and warnings going to `reporter`.
    pub fn run_with(
        scenario: Scenario,
        opts: &RunOptions,
        reporter: &dyn Reporter,
    ) -> Result<InMemoryRun> {
        InMemoryRun::run_until(scenario, opts, reporter, &AtomicBool::new(false))
    }

    /// [`InMemoryRun::run_with`] that ends with an error once `stop` is set (Ctrl-C in the
    /// Python front end). The flag is read as each trial's result is taken, in order, so the
    /// trials already running finish first: two chunks of [`CHUNK`] trials at most.
    pub fn run_until(
        scenario: Scenario,
        opts: &RunOptions,
        reporter: &dyn Reporter,
        stop: &AtomicBool,
    ) -> Result<InMemoryRun> {
        let mut csv = files::TrialsCsv::in_memory(scenario.sweep.as_ref());
        let opts = RunOptions {
            shard: None,
            ..opts.clone()
        };
        let mut until = Until {
            sink: &mut csv,
            stop,
        };
        let result = run(scenario, &opts, &mut until, reporter)?;
        let summary = analyse_warning(&result, reporter)?;
        Ok(InMemoryRun {
            summary,
            result,
            trials_csv: csv.into_bytes()?,
        })
    }

    /// `summary.json`'s text.
    pub fn summary_json(&self) -> Result<String> {
        self.summary.to_json()
    }

    /// Writes the run's folder `out` as a whole ([`atomically`]), the files of
    /// `calbench run --out`: `trials.csv`, then [`write_run`], as [`run_study`] does.
    pub fn write(&self, out: &Path) -> Result<()> {
        atomically(out, |dir| {
            let csv = Bytes {
                name: files::trials_csv::NAME,
                bytes: &self.trials_csv,
            };
            let mut outputs: Outputs<'_> = vec![Box::new(csv)];
            outputs.extend(run_outputs(&self.result, &self.summary)?);
            write_all(dir, &outputs)
        })
    }
}

/// A sink that refuses the next trial once `stop` is set ([`InMemoryRun::run_until`]).
struct Until<'a> {
    sink: &'a mut dyn TrialSink,
    stop: &'a AtomicBool,
}

impl TrialSink for Until<'_> {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        if self.stop.load(Ordering::SeqCst) {
            return Err(Error::Compute("the run was interrupted".into()));
        }
        self.sink.trial(info, t)
    }
}

/// Runs trials `range` of a prepared study on `pool`, a chunk at a time, handing each
/// chunk's results in order to `each`.
///
/// While this thread hands a finished chunk to `each` (the statistics, `trials.csv`, the
/// checkpoint's records: work done one trial after the other), the next chunk already runs
/// on the pool, so the pool does not wait for it. `each` sees the same trials in the same
/// order as without the overlap, so the outputs are the same bytes; at most two chunks are
/// held at once. An error of `each` is returned once the chunk running beside it is done.
pub fn run_trials(
    study: &Study,
    range: std::ops::Range<usize>,
    pool: &rayon::ThreadPool,
    bar: &dyn Progress,
    each: &mut dyn FnMut(TrialResult) -> Result<()>,
) -> Result<()> {
    let end = range.end;
    let chunk = |start: usize| -> Result<Vec<TrialResult>> {
        pool.install(|| {
            (start..(start + CHUNK).min(end))
                .into_par_iter()
                .map(|i| {
                    let r = run_trial(study, i);
                    bar.inc(1);
                    r
                })
                .collect::<Result<_>>()
        })
    };
    let mut start = range.start;
    if start >= end {
        return Ok(());
    }
    let mut done = chunk(start)?;
    while start + CHUNK < end {
        let next = start + CHUNK;
        let (ahead, handed) = std::thread::scope(|s| {
            let ahead = s.spawn(|| chunk(next));
            let handed = done.into_iter().try_for_each(&mut *each);
            (ahead.join(), handed)
        });
        handed?;
        done = ahead.unwrap_or_else(|panic| std::panic::resume_unwind(panic))?;
        start = next;
    }
    done.into_iter().try_for_each(each)
}

/// Runs `scenario` (every sweep point, every trial; with `opts.shard` only its share) and
/// returns the aggregated results; every trial goes to `sink` in order as it finishes, and
/// the progress (with `opts.progress`) to `reporter`.
pub fn run(
    scenario: Scenario,
    opts: &RunOptions,
    sink: &mut dyn TrialSink,
    reporter: &dyn Reporter,
) -> Result<RunResult> {
    run_resumed(scenario, opts, sink, None, reporter)
}

/// Gives the replayed trial 0 `t` what a record does not keep and the summary and the
/// plots show (the searches' fitness traces, the per-point errors): trial 0 is run again,
/// and its seed gives the same numbers.
fn restore_trial0(study: &Study, pool: &rayon::ThreadPool, t: &mut TrialResult) -> Result<()> {
    let fresh = pool.install(|| run_trial(study, 0))?;
    for (o, f) in t.outcomes.iter_mut().zip(fresh.outcomes) {
        o.trace = f.trace;
        o.per_point = f.per_point;
        o.per_point_attitude_deg = f.per_point_attitude_deg;
    }
    Ok(())
}

/// [`run`] continuing a killed run: the first `replay.done()` trials of the share come from
/// `replay` instead of being run again (and go to `sink` like the others).
pub fn run_resumed(
    scenario: Scenario,
    opts: &RunOptions,
    sink: &mut dyn TrialSink,
    mut replay: Option<&mut dyn Replay>,
    reporter: &dyn Reporter,
) -> Result<RunResult> {
    let t0 = std::time::Instant::now();
    let out = opts.out_or(&scenario.name);
    let plans = scenario.sweep_plans()?;
    let trials = scenario.trials as u64;
    let total = plans.len() as u64 * trials;
    let (first, last) = opts.shard.map_or((0, total), |s| s.range(total));
    let bar: Box<dyn Progress + '_> = if opts.progress {
        reporter.progress(last - first)
    } else {
        Box::new(NoProgress)
    };
    let pool = super::threads::pool(opts.threads, last - first, reporter)?;
    for w in scenario.warnings() {
        reporter.warning(&w);
    }
    if opts.precision.is_some() {
        refuse_precision(&scenario, opts)?;
    }
    let mut collector = Collector::new();
    // With --precision, the trials run so far, and the count the rule stopped at.
    let mut seen = 0usize;
    let mut stop = None;
    for (b, (point, plan)) in plans.into_iter().enumerate() {
        let (lo, hi) = (b as u64 * trials, (b as u64 + 1) * trials);
        let (from, to) = (first.max(lo), last.min(hi));
        if from >= to {
            continue;
        }
        if let (Some(p), Some(sw)) = (&point, &scenario.sweep) {
            let shown: Vec<String> = sw
                .axes
                .iter()
                .zip(p)
                .map(|(a, v)| format!("{} = {v}", a.key))
                .collect();
            bar.message(&shown.join(", "));
        }
        let study = pool.install(|| Study::new(plan))?;
        let info = BlockInfo::of(&study, b, point);
        collector.begin(info.clone(), None);
        let mut range = (from - lo) as usize..(to - lo) as usize;
        if let Some(r) = replay.as_mut() {
            let done = (first + r.done()).clamp(from, to);
            for _ in from..done {
                let (rb, mut t) = r.next()?;
                if let Some(why) = info.misfit(&t) {
                    return Err(r.unfit(&why));
                }
                if rb != b {
                    return Err(Error::Compute(format!(
                        "the checkpoint holds a trial of sweep point {rb} where one of point {b} \
                         was expected"
                    )));
                }
                if t.index == 0 {
                    restore_trial0(&study, &pool, &mut t)?;
                }
                collector.trial(&t, sink)?;
                bar.inc(1);
                seen += 1;
                if look(opts, &collector, seen) {
                    stop = Some(seen);
                    break;
                }
            }
            range.start = (done - lo) as usize;
        }
        match &opts.precision {
            None => run_trials(&study, range, &pool, bar.as_ref(), &mut |t| {
                collector.trial(&t, sink)
            })?,
            Some(_) => {
                // Whole blocks of BLOCK trials, a look after each: where the run stops
                // does not depend on how the trials were spread over the threads.
                while stop.is_none() && range.start < range.end {
                    let end = ((range.start / BLOCK + 1) * BLOCK).min(range.end);
                    run_trials(&study, range.start..end, &pool, bar.as_ref(), &mut |t| {
                        collector.trial(&t, sink)
                    })?;
                    seen = end;
                    range.start = end;
                    if look(opts, &collector, seen) {
                        stop = Some(seen);
                    }
                }
            }
        }
    }
    bar.finish();
    let (scenario, mut stopping, widest) = match &opts.precision {
        None => (scenario, None, None),
        Some(p) => {
            let headlines = collector
                .current()
                .map_or(Vec::new(), |a| a.headlines(p.metric));
            let n = stop.unwrap_or(seen);
            let reached = p.reached(&headlines);
            let (i, needed) = widest_and_needed(p, &headlines, n);
            let stopping = Stopping {
                rule: "precision".into(),
                target: p.text.clone(),
                reached,
                trials: n,
                max_trials: scenario.trials,
                block: BLOCK,
                widest: p.widest(&headlines),
                widest_entry: None,
                trials_needed: needed.filter(|_| !reached),
            };
            let scenario = scenario.with_run_overrides(Some(n), None)?;
            (scenario, Some(stopping), i.filter(|_| !reached))
        }
    };
    let blocks = collector.finish(scenario.sweep.as_ref())?;
    if let (Some(st), Some(i)) = (stopping.as_mut(), widest) {
        // Entries are in the headlines' order (strategy × method).
        let entry = blocks.first().and_then(|b| b.entries.get(i));
        st.widest_entry = entry.map(|e| format!("{} / {}", e.method, e.poses));
    }
    // A run that stopped at its cap short of the target says so, to the terminal and to Python.
    if let Some(w) = stopping.as_ref().and_then(Stopping::shortfall) {
        reporter.warning(&w);
    }
    Ok(RunResult {
        scenario,
        blocks,
        out,
        seconds: t0.elapsed().as_secs_f64(),
        shard: opts.shard,
        stopping,
    })
}

/// With `--precision`, whether the run stops after `seen` trials: at a whole block of
/// [`BLOCK`] trials where every entry's headline interval is narrow enough.
fn look(opts: &RunOptions, collector: &Collector, seen: usize) -> bool {
    match (&opts.precision, collector.current()) {
        (Some(p), Some(acc)) => seen.is_multiple_of(BLOCK) && p.reached(&acc.headlines(p.metric)),
        _ => false,
    }
}

/// Refuses `--precision` where it makes no sense: with a sweep (every point runs the same
/// trials, one point after the other) and with `--shard` (a share's trials are fixed before
/// it starts).
pub fn refuse_precision(scenario: &Scenario, opts: &RunOptions) -> Result<()> {
    if scenario.sweep.is_some() {
        let msg = Said::from(
            "a sweep runs the same trials at every point, one point after the other; give ",
        )
        .name(Opt::Trials)
        .text(" instead (a run of one point with ")
        .name(Opt::Precision)
        .text(" tells how many are needed)");
        return Err(Error::option(Opt::Precision, msg));
    }
    if opts.shard.is_some() {
        let msg = Said::from("a shard's trials are fixed before it starts; find the trial count with a whole run with ")
            .name(Opt::Precision)
            .text(", then shard the run with ")
            .name(Opt::Trials)
            .text(" N");
        return Err(Error::option(Opt::Precision, msg));
    }
    Ok(())
}

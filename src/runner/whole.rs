//! The studies that run cells rather than calibration trials — Ban fig. 3's registration
//! study and an instruments study — on the runner of every study: their work units (cell ×
//! trial, in run order) in chunks on rayon, in order, into the checkpoint beside the output
//! folder and, with `--shard I/N`, into the shard's `records.txt`; `run --resume` replays a
//! killed run's records and `merge` the shards', so each gives the bytes of one run.

use std::path::Path;

use rayon::prelude::*;

use super::cells::{Cells, Instruments};
use super::checkpoint::{Checkpoint, Records as Replayed};
use super::resume::Resumable;
use super::shard;
use crate::error::{Error, Result};
use crate::report::output::write_all;
use crate::study::kind::AnyScenario;
use crate::study::reporter::{NoProgress, Progress, Reporter};
use crate::study::{Replay, RunOptions, RunResult, CHUNK};

/// Runs `cells`, the study `sc` (or its share `opts.shard`), into the folder `out` as a
/// whole, with its checkpoint `cp` (removed once the run ends) and, when resumed, the records
/// `replay` of the killed run first; returns the table the terminal shows (nothing for a
/// shard).
pub fn run_cells<C: Cells>(
    cells: &C,
    sc: &AnyScenario,
    opts: &RunOptions,
    out: &Path,
    mut cp: Checkpoint,
    mut replay: Option<&mut Replayed>,
    reporter: &dyn Reporter,
) -> Result<String> {
    let t0 = std::time::Instant::now();
    let (blocks, trials) = (sc.blocks().0, sc.trials() as u64);
    let total = blocks as u64 * trials;
    let (first, last) = opts.shard.map_or((0, total), |s| s.range(total));
    let pool = super::threads::pool(opts.threads, last - first, reporter)?;
    let bar: Box<dyn Progress + '_> = match opts.progress {
        true => reporter.progress(last - first),
        false => Box::new(NoProgress),
    };
    let mut table = String::new();
    let done = crate::report::atomically(out, |dir| {
        let mut records = match opts.shard {
            Some(_) => Some(shard::Records::create(dir, sc)?),
            None => None,
        };
        let mut done: Vec<(C::Block, Vec<C::Trial>)> = Vec::new();
        for b in 0..blocks {
            let (lo, hi) = (b as u64 * trials, (b as u64 + 1) * trials);
            let (from, to) = (first.max(lo), last.min(hi));
            if from >= to {
                continue;
            }
            let prev = done.last().map(|d| &d.0);
            let block = pool.install(|| cells.block(b, prev))?;
            let mut results = Vec::with_capacity((to - from) as usize);
            let mut keep = |i: u64, t: C::Trial| -> Result<()> {
                let i = (i - lo) as usize;
                cp.record(b, i, &t)?;
                if let Some(r) = records.as_mut() {
                    r.record(b, i, &t)?;
                }
                results.push(t);
                Ok(())
            };
            let mut next = from;
            if let Some(r) = replay.as_mut() {
                let upto = (first + r.done()).clamp(from, to);
                while next < upto {
                    let (rb, i, t) = r.next_record::<C::Trial>()?;
                    if let Some(why) = cells.misfit(&block, &t) {
                        return Err(r.unfit(&why));
                    }
                    if (rb, i as u64) != (b, next - lo) {
                        return Err(Error::Compute(format!(
                            "the checkpoint holds trial {i} of block {rb} where trial {} of \
                             block {b} was expected",
                            next - lo
                        )));
                    }
                    keep(next, t)?;
                    bar.inc(1);
                    next += 1;
                }
            }
            while next < to {
                let end = (next + CHUNK as u64).min(to);
                let chunk: Vec<C::Trial> = pool.install(|| {
                    (next..end)
                        .into_par_iter()
                        .map(|u| {
                            let t = cells.trial(&block, (u - lo) as usize);
                            bar.inc(1);
                            t
                        })
                        .collect::<Result<_>>()
                })?;
                for (u, t) in (next..end).zip(chunk) {
                    keep(u, t)?;
                }
                next = end;
            }
            cp.sync()?;
            done.push((block, results));
        }
        bar.finish();
        let outputs = match (records, opts.shard) {
            (Some(r), Some(s)) => r.finish_with(sc, s, t0.elapsed().as_secs_f64(), Vec::new())?,
            _ => {
                let (outputs, text) = super::cells::study_files(cells, sc, done)?;
                table = text;
                outputs
            }
        };
        write_all(dir, &outputs)
    });
    cp.finish()?;
    done?;
    Ok(table)
}

/// Runs `sc`, a registration or instruments study (or its share `opts.shard`), into
/// `opts.out` (default `results/<name>/`) as a whole, with a checkpoint beside it that
/// `calbench run --resume` continues from if it is killed; returns the table the terminal
/// shows.
pub fn run_cells_study(
    sc: &AnyScenario,
    opts: &RunOptions,
    reporter: &dyn Reporter,
) -> Result<String> {
    let out = opts.out_or(sc.name());
    let cp = Checkpoint::start(sc, opts.shard, None, &out, reporter)?;
    dispatch(sc, opts, &out, cp, None, reporter)
}

/// A continued run's result: a Monte-Carlo study's, or the table of a study of cells.
pub enum Resumed {
    /// A Monte-Carlo study.
    Study(Box<RunResult>),
    /// A registration or instruments study: the table the terminal shows.
    Cells(String),
}

/// Continues a killed run of any kind from its checked checkpoint ([`Resumable::open`]) with
/// `threads` worker threads: writes the same files as an uninterrupted run.
pub fn resume(run: Resumable, threads: Option<usize>, reporter: &dyn Reporter) -> Result<Resumed> {
    let mut c = run.continued(threads)?;
    let (opts, out, cp) = (&c.opts, &c.out, c.checkpoint);
    match c.scenario {
        AnyScenario::MonteCarlo(s) => {
            let replay: &mut dyn Replay = &mut c.records;
            let r = super::run::study_into(s, opts, out, cp, Some(replay), reporter)?;
            Ok(Resumed::Study(Box::new(r)))
        }
        sc => dispatch(&sc, opts, out, cp, Some(&mut c.records), reporter).map(Resumed::Cells),
    }
}

/// [`run_cells`] with the study of `sc`'s kind.
fn dispatch(
    sc: &AnyScenario,
    opts: &RunOptions,
    out: &Path,
    cp: Checkpoint,
    replay: Option<&mut Replayed>,
    reporter: &dyn Reporter,
) -> Result<String> {
    match sc {
        AnyScenario::Registration(s) => run_cells(s, sc, opts, out, cp, replay, reporter),
        AnyScenario::Instruments(s) => {
            run_cells(&Instruments::new(s)?, sc, opts, out, cp, replay, reporter)
        }
        AnyScenario::MonteCarlo(_) => Err(Error::Compute(
            "a Monte-Carlo study runs through runner::run::run_study".into(),
        )),
    }
}

//! The Monte-Carlo harness (docs/formats.md `run`): a scenario's trials, each from its own
//! seed, aggregated per method and pose strategy. Running a study (in parallel with rayon, its
//! output folder written whole, the checkpoint, the shards and their merge) is
//! [`crate::runner`], above this module and the report.
//!
//! - [`plan`]: what a scenario needs once (nominal robot, parameters, tracker, fixed pose
//!   sets);
//! - [`scenario`]: the scenario file, parsed and checked (sweeps included);
//! - [`trial`]: one trial (true robot, measurements, every method's calibration, validation);
//! - [`stats`]: the aggregation into [`Entry`] values;
//! - [`records`]: the checked record lines that a shard and a checkpoint keep;
//! - [`reporter`]: where progress and warnings go (the caller supplies it; nothing here
//!   prints).
//!
//! Determinism: trial i draws everything from `rng::trial_seed(seed, i)` and results are
//! consumed in trial order, so the output is the same whatever the thread count (timing
//! fields excepted) and whatever the split into shards ([`Shard`]).
//!
//! Memory: trials run in chunks of [`CHUNK`]; each chunk's results go to a [`TrialSink`]
//! (the `trials.csv` writer, a shard's record file) and into a streaming
//! [`stats::Accumulator`], then are dropped, so a run holds a chunk of trials plus the
//! accumulators' running sums; the per-trial numbers of the exact medians go to a scratch
//! file ([`spill`]), so memory does not grow with the trials.

pub mod claims;
pub mod crb;
pub mod inputs;
pub mod instruments;
pub mod instruments_table;
pub mod kind;
pub mod margin;
pub mod metric;
pub mod outcome;
pub mod plan;
pub mod records;
pub mod registration_study;
pub mod reporter;
pub mod scenario;
pub mod spill;
pub mod stats;
pub mod trial;
pub mod verdict;
pub mod whole;

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::study::scenario::Scenario;
pub use plan::Study;
pub use stats::{Accumulator, Entry};
pub use trial::{run_trial, TrialResult};

/// The refusal of a list of a study's points (a sweep's values, a study's grid: its outlier
/// counts, magnitudes, pose counts or strategies) that holds one value twice: each value is a
/// point of its own, and a repeated one would run one point twice under one name. `same`
/// says whether two values are one point (`==`, or the same strategy however spelled);
/// the later value's index and a message naming it as `shown` gives it and what the points
/// are (`sweep points`, `cells`). `None` when every value is distinct.
pub fn given_twice<T>(
    values: &[T],
    same: impl Fn(&T, &T) -> bool,
    shown: impl Fn(&T) -> String,
    points: &str,
) -> Option<(usize, String)> {
    let j = (1..values.len()).find(|&j| values[..j].iter().any(|v| same(v, &values[j])))?;
    let msg = format!(
        "{} is given twice: two {points} would be one",
        shown(&values[j])
    );
    Some((j, msg))
}

/// Trials run in parallel at a time: their results are handed on, in order, and dropped.
pub const CHUNK: usize = 256;

/// A share of a run's work (`calbench run --shard I/N`): the work units (sweep point ×
/// trial, in run order) from ⌊I·W/N⌋ to ⌊(I+1)·W/N⌋ of the W in all, so the N shards cover
/// every unit once, in contiguous runs. Read from a file (`shard.json`, `checkpoint.json`),
/// it is checked as `--shard` is: a share with I ≥ N or N = 0 is refused, naming it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "ShardFields")]
pub struct Shard {
    /// I, from 0.
    pub index: usize,
    /// N.
    pub count: usize,
}

/// The fields of a [`Shard`] as a file holds them, before they are checked.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShardFields {
    index: usize,
    count: usize,
}

impl TryFrom<ShardFields> for Shard {
    type Error = String;
    fn try_from(s: ShardFields) -> std::result::Result<Shard, String> {
        Shard::new(s.index, s.count).ok_or_else(|| {
            format!(
                "shard {}/{} is not I/N with 0 ≤ I < N: the file was altered",
                s.index, s.count
            )
        })
    }
}

impl Shard {
    /// Share `index` of `count`, if 0 ≤ `index` < `count`.
    pub fn new(index: usize, count: usize) -> Option<Shard> {
        (index < count).then_some(Shard { index, count })
    }

    /// Parses `I/N` (0 ≤ I < N).
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = || {
            Error::option(
                crate::error::Opt::Shard,
                format!("\"{text}\" is not I/N with 0 ≤ I < N (e.g. 0/8)"),
            )
        };
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        Shard::new(index, count).ok_or_else(bad)
    }

    /// Refuses a split of a run of `total` work units into more shares than it has units (a
    /// share would hold none): why, for the caller to place.
    pub fn fits(&self, total: u64) -> std::result::Result<(), String> {
        if self.count as u64 <= total.max(1) {
            return Ok(());
        }
        Err(format!(
            "{}/{} splits a run of {total} work units (sweep points × trials) into more \
             shares than it has units, so some would run nothing: give at most {total} shards",
            self.index, self.count
        ))
    }

    /// The work units `[start, end)` of this shard out of `total`.
    pub fn range(&self, total: u64) -> (u64, u64) {
        let at = |i: usize| (total as u128 * i as u128 / self.count as u128) as u64;
        (at(self.index), at(self.index + 1))
    }
}

/// Options of a run from the command line.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Worker threads (`None`: rayon's default, one per core).
    pub threads: Option<usize>,
    /// Output folder (`None`: `results/<name>/`).
    pub out: Option<PathBuf>,
    /// Show a progress bar (only drawn when stderr is a terminal).
    pub progress: bool,
    /// Run only this share of the work.
    pub shard: Option<Shard>,
    /// Stop once every entry's headline interval is this narrow (`--precision`; the
    /// scenario's `trials` is then the cap).
    pub precision: Option<stats::precision::Precision>,
}

impl RunOptions {
    /// The output folder of the run of the scenario `name`: `out`, else `results/<name>/`.
    pub fn out_or(&self, name: &str) -> PathBuf {
        let default = || std::path::Path::new("results").join(name);
        self.out.clone().unwrap_or_else(default)
    }
}

/// A fixed calibration pose set as the reports show it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FixedInfo {
    /// Poses in the set.
    pub poses: usize,
    /// The optimiser's objective per iteration.
    pub trace: Vec<Real>,
    /// The optimiser's scores of the set.
    pub scores: Option<serde_json::Value>,
}

/// What the reports need of a block's prepared study (kept once the study is dropped, and
/// carried by shards to the merge).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlockInfo {
    /// The block's place in the run (sweep point index; 0 without a sweep).
    pub index: usize,
    /// The sweep point: one value per axis.
    pub point: Option<Vec<toml::Value>>,
    /// The robot's name.
    pub robot: String,
    /// Full-pose (rather than position) measurement.
    pub full_pose: bool,
    /// The identified parameters.
    pub params: Vec<String>,
    /// The parameters carrying injected errors.
    pub error_params: Vec<String>,
    /// Method labels.
    pub methods: Vec<String>,
    /// Strategy names.
    pub strategies: Vec<String>,
    /// Per strategy: the fixed pose set, if any.
    pub fixed: Vec<Option<FixedInfo>>,
    /// Guo's separation report (`calibration.separate`), if any.
    pub separation: Option<serde_json::Value>,
    /// The simulated arm's joint compliances (name → rad/(N·m)), when it sags.
    pub true_compliance: Option<serde_json::Value>,
    /// Whether a method was supplied from outside the scenario file
    /// ([`crate::identify::external`]): `trials.csv` then records each failure's message.
    pub external: bool,
    /// Whether a method is a search (BAS, PSO, BAS-PSO): `trials.csv` then has the column
    /// `final_fitness`.
    pub searches: bool,
}

impl BlockInfo {
    /// The reports' view of `study`, block `index` at sweep `point`.
    pub fn of(study: &Study, index: usize, point: Option<Vec<toml::Value>>) -> BlockInfo {
        let sc = &study.scenario;
        BlockInfo {
            index,
            point,
            robot: study.nominal.name.clone(),
            full_pose: study.measure == crate::measurement::Measure::Pose,
            params: study.params.iter().map(|p| p.to_string()).collect(),
            error_params: study.error_params.iter().map(|p| p.to_string()).collect(),
            methods: sc.methods.iter().map(|m| m.label.clone()).collect(),
            strategies: sc
                .calibration
                .strategies
                .iter()
                .map(|s| s.name().to_string())
                .collect(),
            fixed: study
                .fixed
                .iter()
                .map(|f| {
                    f.as_ref().map(|f| FixedInfo {
                        poses: f.poses.len(),
                        trace: f.trace.clone(),
                        scores: f.scores.clone(),
                    })
                })
                .collect(),
            separation: study.separation.as_ref().map(|s| s.to_json()),
            true_compliance: study.true_compliance_json(),
            external: sc.methods.iter().any(|m| m.is_external()),
            searches: sc
                .methods
                .iter()
                .any(|m| m.method.fitness_model().is_some()),
        }
    }

    /// Why the trial `t` cannot be one of this block's, if it cannot: its injected errors,
    /// identified values, strategies and methods are not those the block lists (a block read
    /// from an altered file; [`Collector::trial`] would index past them).
    pub fn misfit(&self, t: &TrialResult) -> Option<String> {
        let (p, m, s) = (self.params.len(), self.methods.len(), self.strategies.len());
        if self.fixed.len() != s {
            return Some(format!(
                "{} fixed pose sets for {s} strategies",
                self.fixed.len()
            ));
        }
        if t.truth.len() != p {
            return Some(format!(
                "{} injected errors for {p} parameters",
                t.truth.len()
            ));
        }
        if t.crb_trace.len() != s || t.not_determinable.len() > s {
            return Some(format!(
                "{} Cramér–Rao traces for {s} strategies",
                t.crb_trace.len()
            ));
        }
        if t.not_determinable.iter().flatten().any(|&k| k >= p) {
            return Some(format!("a parameter index beyond its {p} parameters"));
        }
        t.outcomes.iter().find_map(|o| {
            (o.method >= m || o.strategy >= s || o.identified.len() != p).then(|| {
                format!(
                    "an outcome of method {} and strategy {} with {} identified values, for \
                     {m} methods, {s} strategies and {p} parameters",
                    o.method,
                    o.strategy,
                    o.identified.len()
                )
            })
        })
    }
}

/// What trial 0 of a block keeps for the plots and `summary.json`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Trial0 {
    /// The first outcome's validation errors per point, before and after, with its
    /// (strategy, method).
    pub per_point: Option<(usize, usize, Vec<Real>, Vec<Real>)>,
    /// The same outcome's attitude errors per point (Qiao's, deg), before and after, for
    /// full-pose data.
    pub per_point_attitude_deg: Option<(Vec<Real>, Vec<Real>)>,
    /// The metaheuristics' best fitness per iteration: (strategy, method, trace).
    pub traces: Vec<(usize, usize, Vec<Real>)>,
}

impl Trial0 {
    fn of(t: &TrialResult) -> Trial0 {
        Trial0 {
            per_point: t.outcomes.first().and_then(|o| {
                o.per_point
                    .as_ref()
                    .map(|(b, a)| (o.strategy, o.method, b.clone(), a.clone()))
            }),
            per_point_attitude_deg: t
                .outcomes
                .first()
                .and_then(|o| o.per_point_attitude_deg.clone()),
            traces: t
                .outcomes
                .iter()
                .filter_map(|o| {
                    o.trace
                        .as_ref()
                        .map(|tr| (o.strategy, o.method, tr.clone()))
                })
                .collect(),
        }
    }
}

/// The results of one sweep point (or of the whole study without a sweep).
pub struct Block {
    /// The reports' view of the block's study.
    pub info: BlockInfo,
    /// One entry per strategy × method.
    pub entries: Vec<Entry>,
    /// Trial 0's per-point errors and traces, when this run had trial 0.
    pub trial0: Option<Trial0>,
    /// Block 0 only: each trial's validation RMS after compensation, per strategy × method
    /// (the box plot).
    pub after_rms: Vec<Vec<Real>>,
}

impl Block {
    /// The metaheuristics' best fitness per iteration in trial 0 (Qiao 2021 fig. 4), labelled
    /// `method / poses`.
    pub fn fitness_traces(&self) -> Vec<(String, Vec<Real>)> {
        let label = |si: usize, mi: usize| {
            format!("{} / {}", self.info.methods[mi], self.info.strategies[si])
        };
        let traces = self.trial0.as_ref().map(|t| t.traces.as_slice());
        let traces = traces.unwrap_or_default().iter();
        traces
            .map(|(si, mi, tr)| (label(*si, *mi), tr.clone()))
            .collect()
    }
}

/// Everything a run produced.
pub struct RunResult {
    /// The scenario as run.
    pub scenario: Scenario,
    /// One block per sweep point this run covered, in order.
    pub blocks: Vec<Block>,
    /// The output folder.
    pub out: PathBuf,
    /// Wall time of the whole run (s).
    pub seconds: f64,
    /// The share of the work run, if not all.
    pub shard: Option<Shard>,
    /// Why a run with `--precision` stopped (`summary.json`'s `stopping`).
    pub stopping: Option<stats::precision::Stopping>,
}

/// The trials a killed run had finished, read back in order when it is resumed
/// (`calbench run --resume`): they go through the same aggregation and sinks as the trials
/// run now, so the result is the same bytes as an uninterrupted run.
pub trait Replay {
    /// Work units (trials) already done, from the start of this run's share.
    fn done(&self) -> u64;
    /// The next finished trial and its block.
    fn next(&mut self) -> Result<(usize, TrialResult)>;
    /// The refusal of the trial last read, which does not fit its block for the reason `why`
    /// ([`BlockInfo::misfit`]): naming where it was read.
    fn unfit(&self, why: &str) -> Error;
}

/// Where each trial goes once it has run, in trial order (per block, blocks in order).
pub trait TrialSink {
    /// Takes trial `t` of the block described by `info`.
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()>;
}

/// A sink that keeps nothing.
impl TrialSink for () {
    fn trial(&mut self, _: &BlockInfo, _: &TrialResult) -> Result<()> {
        Ok(())
    }
}

/// Gathers trials, in order, into blocks: the streaming aggregation shared by `run` and
/// `merge`, so a merged result is the same bytes as an unsharded one.
pub struct Collector {
    blocks: Vec<Collecting>,
}

/// One block being collected: its view, its statistics, trial 0's details and the per-trial
/// CRB traces.
type Collecting = (BlockInfo, Accumulator, Option<Trial0>, Vec<Vec<Real>>);

impl Collector {
    /// An empty collector.
    pub fn new() -> Collector {
        Collector { blocks: Vec::new() }
    }

    /// Starts the block `info` (blocks come in order).
    pub fn begin(&mut self, info: BlockInfo, trial0: Option<Trial0>) {
        let acc = Accumulator::new(&info.params, info.strategies.len(), info.methods.len());
        let cells = if info.index == 0 {
            vec![Vec::new(); info.strategies.len() * info.methods.len()]
        } else {
            Vec::new()
        };
        self.blocks.push((info, acc, trial0, cells));
    }

    /// The statistics of the block being collected.
    pub fn current(&self) -> Option<&Accumulator> {
        self.blocks.last().map(|b| &b.1)
    }

    /// Adds trial `t` to the current block and hands it to `sink`.
    pub fn trial(&mut self, t: &TrialResult, sink: &mut dyn TrialSink) -> Result<()> {
        let (info, acc, trial0, rms) = self
            .blocks
            .last_mut()
            .ok_or_else(|| Error::Compute("a trial before its block".into()))?;
        acc.push(t)?;
        if t.index == 0 && trial0.is_none() {
            *trial0 = Some(Trial0::of(t));
        }
        if !rms.is_empty() {
            for o in &t.outcomes {
                rms[o.strategy * info.methods.len() + o.method].push(o.after_mm.rms);
            }
        }
        sink.trial(info, t)
    }

    /// The blocks, with their entries. Fails only when the scratch file of the statistics
    /// cannot be read.
    pub fn finish(self, sweep: Option<&crate::study::scenario::Sweep>) -> Result<Vec<Block>> {
        self.blocks
            .into_iter()
            .map(|(info, acc, trial0, after_rms)| {
                let (value, map) = match (sweep, &info.point) {
                    (Some(sw), Some(p)) => {
                        let map: BTreeMap<String, serde_json::Value> = sw
                            .axes
                            .iter()
                            .map(|a| a.key.clone())
                            .zip(p.iter().map(toml_to_json))
                            .collect();
                        let value = crate::study::scenario::Sweep::point_value(p);
                        (Some(value), Some(map))
                    }
                    _ => (None, None),
                };
                let mut entries = Vec::new();
                for (si, s) in info.strategies.iter().enumerate() {
                    for (mi, m) in info.methods.iter().enumerate() {
                        entries.push(acc.entry(si, mi, (m, s), value.clone(), map.clone())?);
                    }
                }
                Ok(Block {
                    info,
                    entries,
                    trial0,
                    after_rms,
                })
            })
            .collect()
    }
}

impl Default for Collector {
    fn default() -> Self {
        Collector::new()
    }
}

/// Converts a TOML value to JSON (sweep values in `summary.json`).
pub fn toml_to_json(v: &toml::Value) -> serde_json::Value {
    serde_json::to_value(v).unwrap_or(serde_json::Value::Null)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_unit_once_in_order() {
        for total in [0u64, 1, 7, 20, 1001] {
            for n in [1usize, 3, 7, 40] {
                let mut next = 0;
                for i in 0..n {
                    let (a, b) = Shard { index: i, count: n }.range(total);
                    assert_eq!(a, next);
                    assert!(b >= a);
                    next = b;
                }
                assert_eq!(next, total);
            }
        }
    }

    #[test]
    fn shard_text_is_checked() {
        assert_eq!(Shard::parse("2/7").unwrap(), Shard { index: 2, count: 7 });
        for bad in ["7/7", "1/0", "a/3", "3", "-1/3"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }
}

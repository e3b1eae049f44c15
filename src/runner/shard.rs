//! Sharded runs (docs/formats.md `run --shard`, `merge`): a shard's partial result and the merge
//! of all shards into the output of the unsharded run.
//!
//! A shard folder holds `trials.csv` (its own rows), `shard.json` (the scenario as run, the
//! share, the machine that ran it, and what the reports need of each block's study and of
//! trial 0) and `records.txt`:
//! one line per trial with every number the aggregation reads, each line with its checksum
//! ([`crate::study::records`]), so the merge checks every record and replays the trials in order
//! through the same streaming aggregation ([`crate::study::Collector`]) and writes the same
//! bytes as one machine.

use std::io::BufRead;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::as_run::{one_effect, scenario_as_run, settings_difference, trials_as_run};
use super::cells::{Cells, Instruments};
use crate::analysis::idle::analyse_warning;
use crate::error::{Error, Result};
use crate::report::output::{write_all, Outputs, Stream, Text};
use crate::report::{write_run, TrialsCsv};
use crate::results::provenance::Machine;
use crate::study::inputs::{self, Input};
use crate::study::kind::AnyScenario;
use crate::study::records::{encode, RunId, Verifier};
use crate::study::reporter::Reporter;
use crate::study::{BlockInfo, Collector, RunResult, Shard, Trial0, TrialResult, TrialSink};

/// The `format` of `shard.json`, and so of its `records.txt` (docs/formats.md § 7.3): a new one
/// whenever what a record or `shard.json` holds changes, so that `merge` refuses a shard of an
/// earlier calbench instead of reading it with a field missing (tests/cli/record_formats.rs
/// fixes each format's keys).
pub const FORMAT: &str = "calbench-shard-10";

/// One block of a shard: what the reports need of a sweep point's study and of its trial 0,
/// and the checksum that binds it to the run as the records' checksums bind them.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ShardBlock {
    info: BlockInfo,
    trial0: Option<Trial0>,
    sum: String,
}

impl ShardBlock {
    fn new(id: &RunId, info: BlockInfo, trial0: Option<Trial0>) -> Result<ShardBlock> {
        let sum = id.block_checksum(info.index, &ShardBlock::body(&info, &trial0)?);
        Ok(ShardBlock { info, trial0, sum })
    }

    /// The text the checksum covers: the block's `[info, trial0]` as compact JSON with its
    /// keys sorted, so that it is the same text however `shard.json` is laid out.
    fn body(info: &BlockInfo, trial0: &Option<Trial0>) -> Result<String> {
        serde_json::to_value((info, trial0))
            .map(|v| v.to_string())
            .map_err(|e| Error::Compute(format!("cannot write a shard's block: {e}")))
    }

    /// Refuses, naming `holder` (the `shard.json` of the run `id`) and the block's place
    /// `k` in `blocks`, a block whose checksum its content does not give.
    fn check(&self, id: &RunId, holder: &Path, k: usize) -> Result<()> {
        if self.sum
            == id.block_checksum(
                self.info.index,
                &ShardBlock::body(&self.info, &self.trial0)?,
            )
        {
            return Ok(());
        }
        Err(Error::file(
            holder,
            format!("blocks[{k}]"),
            format!(
                "the block of sweep point {} does not match its checksum: it was altered, or \
                 belongs to another run (another scenario, seed or sweep point)",
                self.info.index
            ),
        ))
    }
}

/// Refuses, naming `holder` (its `shard.json`), a shard `m` whose `blocks` lack a sweep
/// point its units run trials of: the reports' view of that point (trial 0's plots) would be
/// lost without a word.
fn every_block(m: &ShardMeta, holder: &Path) -> Result<()> {
    let per = m.trials.max(1) as u64;
    let (start, end) = m.units;
    let points = match start < end {
        true => start / per..(end - 1) / per + 1,
        false => 0..0,
    };
    for p in points {
        if !m.blocks.iter().any(|b| b.info.index as u64 == p) {
            let msg = format!(
                "holds no block of sweep point {p}, whose trials the shard ran (its \
                 records.txt holds them): the file was altered"
            );
            return Err(Error::file(holder, "blocks", msg));
        }
    }
    Ok(())
}

/// `shard.json`.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ShardMeta {
    format: String,
    scenario: String,
    scenario_file: Option<PathBuf>,
    settings: String,
    /// The files the scenario reads, as they were when the shard started.
    inputs: Vec<Input>,
    seed: u64,
    trials: usize,
    shard: Shard,
    units: (u64, u64),
    /// The records in `records.txt`: `units.1 - units.0`.
    records: u64,
    seconds: f64,
    /// The machine that ran the shard; `merge` does not compare it: shards of one run are
    /// meant to run on different machines.
    machine: Machine,
    blocks: Vec<ShardBlock>,
}

impl ShardMeta {
    /// What its records' checksums bind.
    fn id(&self) -> RunId {
        RunId::new(&self.settings, &self.inputs, self.seed)
    }
}

/// Two sinks in one.
pub struct Both<'a, A: TrialSink, B: TrialSink>(pub &'a mut A, pub &'a mut B);

impl<A: TrialSink, B: TrialSink> TrialSink for Both<'_, A, B> {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        self.0.trial(info, t)?;
        self.1.trial(info, t)
    }
}

/// The writer of a shard's `records.txt` (streamed as the trials finish, like `trials.csv`)
/// and `shard.json`.
pub struct Records {
    out: Stream,
    /// The scenario as run (TOML) and the files it reads, and what the records' checksums
    /// bind.
    settings: String,
    inputs: Vec<Input>,
    id: RunId,
    count: u64,
}

impl Records {
    /// Starts `records.txt` in the output folder `dir` for the records of a run of `scenario`.
    pub fn create(dir: &Path, scenario: &AnyScenario) -> Result<Records> {
        let settings = scenario.settings()?;
        let inputs = inputs::of(scenario)?;
        Ok(Records {
            out: Stream::create(dir, "records.txt")?,
            id: RunId::new(&settings, &inputs, scenario.seed()),
            settings,
            inputs,
            count: 0,
        })
    }

    /// The finished `records.txt` and `shard.json` of the run `r`.
    pub fn finish(self, r: &RunResult) -> Result<Outputs<'static>> {
        let shard = r.shard.unwrap_or(Shard { index: 0, count: 1 });
        let blocks = r
            .blocks
            .iter()
            .map(|b| ShardBlock::new(&self.id, b.info.clone(), b.trial0.clone()))
            .collect::<Result<_>>()?;
        let sc = AnyScenario::MonteCarlo(r.scenario.clone());
        self.finish_with(&sc, shard, r.seconds, blocks)
    }

    /// The finished `records.txt` and `shard.json` of share `shard` of `sc`, run in
    /// `seconds`, with what the reports need of each block it touched (`blocks`).
    pub(crate) fn finish_with(
        self,
        sc: &AnyScenario,
        shard: Shard,
        seconds: f64,
        blocks: Vec<ShardBlock>,
    ) -> Result<Outputs<'static>> {
        let records = self.out.finish()?;
        let meta = ShardMeta {
            format: FORMAT.into(),
            scenario: sc.name().to_string(),
            scenario_file: sc.path().map(Path::to_path_buf),
            settings: self.settings,
            inputs: self.inputs,
            seed: sc.seed(),
            trials: sc.trials(),
            shard,
            units: shard.range(sc.units()),
            records: self.count,
            seconds,
            machine: Machine::here(),
            blocks,
        };
        let meta = Text {
            name: "shard.json",
            text: crate::error::json_text(&meta)?,
        };
        Ok(vec![Box::new(records), Box::new(meta)])
    }
}

impl Records {
    /// Appends trial `trial` of block `point`, which gave `t`.
    pub fn record<T: Serialize>(&mut self, point: usize, trial: usize, t: &T) -> Result<()> {
        let line = encode(&self.id, point, trial, t)?;
        self.count += 1;
        self.out.append(line.as_bytes())
    }
}

impl TrialSink for Records {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        self.record(info.index, t.index, t)
    }
}

/// The `format` of a document, read first: a file of another format is refused by its format,
/// not by the first field it lacks.
#[derive(Deserialize)]
pub(crate) struct FormatOnly {
    pub(crate) format: String,
}

fn read_meta(dir: &Path) -> Result<ShardMeta> {
    let path = dir.join("shard.json");
    // A shard.json that is there but cannot be read is refused as every text file is (one
    // that is not UTF-8 at its line and byte).
    let text = match path.is_file() {
        true => crate::error::read_text(&path),
        false => crate::error::read_bounded_text(&path).map_err(|e| {
            // A shard whose run was killed has no folder yet, only its checkpoint beside it.
            let msg = if crate::report::checkpoint_folder(dir).is_dir() {
                format!(
                    "this shard's run did not finish: its checkpoint is there, and \
                     `calbench run --resume {}` finishes it",
                    dir.display()
                )
            } else {
                format!("not a shard folder of `calbench run --shard` ({e})")
            };
            Error::file(dir, "shard.json", msg)
        }),
    }?;
    let v = crate::error::json_value(&path, &text)?;
    let head: FormatOnly = crate::error::json_typed(&v, &path, &text, "shard.json")?;
    if head.format != FORMAT {
        return Err(Error::file(
            &path,
            "format",
            format!(
                "\"{}\", expected \"{FORMAT}\": the shard was written by another calbench, \
                 whose records this one does not read; run the shard again with this calbench \
                 (the same `calbench run … --shard I/N`)",
                head.format
            ),
        ));
    }
    let meta: ShardMeta = crate::error::json_typed(&v, &path, &text, "shard.json")?;
    if !(meta.seconds.is_finite() && meta.seconds >= 0.0) {
        let msg = format!("{} is not a run's wall time (finite, ≥ 0 s)", meta.seconds);
        return Err(Error::file(&path, "seconds", msg));
    }
    Ok(meta)
}

/// The commands that run the shards missing from `by_index` (one line each): the scenario
/// file, trial count and seed of the given shards, and an output folder beside theirs when
/// they are named by their index (`shards/NAME/I`).
fn missing_commands(
    metas: &[(PathBuf, ShardMeta)],
    n: usize,
    by_index: &[Option<&Path>],
) -> String {
    let (d0, m0) = &metas[0];
    let scenario = m0.scenario_file.as_ref().map_or_else(
        || format!("{}.toml", m0.scenario),
        |p| p.display().to_string(),
    );
    // A relative path is the one the shards were started with, from their folder.
    let from = match &m0.scenario_file {
        Some(p) if p.is_relative() && !p.exists() => format!(
            "\n(from the folder the shards were run in: {} is relative to it)",
            p.display()
        ),
        _ => String::new(),
    };
    let by_index_names = d0
        .file_name()
        .is_some_and(|f| f.to_string_lossy() == m0.shard.index.to_string());
    (0..n)
        .filter(|&i| by_index[i].is_none())
        .map(|i| {
            let out = match d0.parent() {
                Some(p) if by_index_names => p.join(i.to_string()).display().to_string(),
                _ => format!("SHARD_{i}_DIR"),
            };
            format!(
                "  calbench run {scenario} --trials {} --seed {} --shard {i}/{n} --out {out}",
                m0.trials, m0.seed
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
        + &from
}

/// What a merge wrote: a Monte-Carlo run, or the study of cells whose table it gives.
pub enum Merged {
    /// A Monte-Carlo run's results.
    Run(Box<RunResult>),
    /// A registration or instruments study: the table the terminal shows.
    Cells(String),
}

/// `calbench merge DIR… --out DIR`: checks that `dirs` are all the shards of one run (same
/// scenario, settings and seed, each shard once, none missing) and writes the run's output to
/// `out`, the same bytes (`summary.json`, `trials.csv`) as the unsharded run. The checkpoint
/// of an unfinished run into `out`, whose `--resume` would overwrite the merge, is then
/// removed with a warning to `reporter`.
pub fn merge(dirs: &[PathBuf], out: &Path, reporter: &dyn Reporter) -> Result<Merged> {
    let merged = merge_into(dirs, out, reporter)?;
    let now = "the merged run replaces it";
    discard_unfinished(out, now, reporter)?;
    Ok(merged)
}

fn merge_into(dirs: &[PathBuf], out: &Path, reporter: &dyn Reporter) -> Result<Merged> {
    if dirs.is_empty() {
        return Err(Error::setting("DIR", "give the shard folders to merge"));
    }
    let mut metas: Vec<(PathBuf, ShardMeta)> = Vec::new();
    for d in dirs {
        let meta = read_meta(d)?;
        inputs::unchanged(&d.join("shard.json"), &meta.inputs)?;
        metas.push((d.clone(), meta));
    }
    let (d0, m0) = &metas[0];
    for (d, m) in &metas[1..] {
        let differ = |what: &str, a: String, b: String| {
            Err(Error::setting(
                "DIR",
                format!(
                    "{} and {} are shards of different runs: {what} {a} against {b}",
                    d0.display(),
                    d.display()
                ),
            ))
        };
        if m.scenario != m0.scenario {
            return differ("scenario", m0.scenario.clone(), m.scenario.clone());
        }
        if m.seed != m0.seed {
            return differ("seed", m0.seed.to_string(), m.seed.to_string());
        }
        if m.trials != m0.trials {
            return differ("trials", m0.trials.to_string(), m.trials.to_string());
        }
        if m.shard.count != m0.shard.count {
            return differ(
                "shard count",
                m0.shard.count.to_string(),
                m.shard.count.to_string(),
            );
        }
        if m.settings != m0.settings {
            // Settings that are not a scenario are that file's fault, not a second run's.
            for (d, m) in [(d0, m0), (d, m)] {
                let file = m.scenario_file.as_deref();
                scenario_as_run(&d.join("shard.json"), &m.settings, file)?;
            }
            let Some((key, a, b)) = settings_difference(&m0.settings, &m.settings) else {
                let name = format!("\"{}\"", m0.scenario);
                return differ("settings of scenario", name, "others".into());
            };
            if one_effect(&m0.settings, &m.settings) {
                return Err(Error::setting(
                    "DIR",
                    format!(
                        "{} and {} ran scenario texts that write `{key}` otherwise ({a} against \
                         {b}): they set the same, but the shards of one run come from one text, \
                         which its scenario.toml holds; run {} again from the scenario {} ran",
                        d0.display(),
                        d.display(),
                        d.display(),
                        d0.display()
                    ),
                ));
            }
            return differ(&format!("`{key}`"), a, b);
        }
        // One file may be named by other paths (the scenario started from another folder, or
        // a copy of it): its bytes, which the records' checksums bind, are what must agree.
        let bytes = |m: &ShardMeta| {
            m.inputs
                .iter()
                .map(|i| i.sha256.clone())
                .collect::<Vec<_>>()
        };
        if bytes(m) != bytes(m0) {
            let names = |m: &ShardMeta| {
                let each: Vec<String> = (m.inputs.iter())
                    .map(|i| format!("{} (SHA-256 {})", i.path.display(), i.sha256))
                    .collect();
                format!("[{}]", each.join(", "))
            };
            return differ("files read", names(m0), names(m));
        }
    }
    let any = scenario_as_run(
        &d0.join("shard.json"),
        &m0.settings,
        m0.scenario_file.as_deref(),
    )?;
    let total = any.units();
    let n = m0.shard.count;
    if let Err(m) = m0.shard.fits(total) {
        let msg = format!("{m} (the file was altered)");
        return Err(Error::file(d0.join("shard.json"), "shard", msg));
    }
    let mut by_index: Vec<Option<&Path>> = vec![None; n];
    for (d, m) in &metas {
        if let Some(other) = by_index[m.shard.index] {
            return Err(Error::setting(
                "DIR",
                format!(
                    "shard {}/{n} is given twice: {} and {}",
                    m.shard.index,
                    other.display(),
                    d.display()
                ),
            ));
        }
        by_index[m.shard.index] = Some(d);
    }
    let missing: Vec<String> = (0..n)
        .filter(|&i| by_index[i].is_none())
        .map(|i| format!("{i}/{n}"))
        .collect();
    if !missing.is_empty() {
        return Err(Error::setting(
            "DIR",
            format!(
                "shards missing: {}; run them with\n{}",
                missing.join(", "),
                missing_commands(&metas, n, &by_index)
            ),
        ));
    }
    let any_file = m0.scenario_file.clone();
    metas.sort_by_key(|(_, m)| m.shard.index);
    let files = inputs::files(&any)?;
    for (d, m) in &metas {
        let holder = d.join("shard.json");
        trials_as_run(&holder, m.trials, &any)?;
        // Its files as its own scenario file names them.
        if m.scenario_file == any_file {
            inputs::as_run(&holder, &m.inputs, &files)?;
        } else {
            let own = scenario_as_run(&holder, &m.settings, m.scenario_file.as_deref())?;
            inputs::as_run(&holder, &m.inputs, &inputs::files(&own)?)?;
        }
        let units = m.shard.range(total);
        if m.units != units || m.records != units.1 - units.0 {
            return Err(Error::file(
                d.join("shard.json"),
                "units",
                format!(
                    "shard {}/{n} of {total} work units holds units {}..{} in {} records; it \
                     should hold {}..{}, one record each (the file was altered)",
                    m.shard.index, m.units.0, m.units.1, m.records, units.0, units.1
                ),
            ));
        }
    }
    let scenario = match &any {
        AnyScenario::MonteCarlo(s) => s.clone(),
        AnyScenario::Registration(s) => {
            return merge_cells(s, &any, &metas, out).map(Merged::Cells)
        }
        AnyScenario::Instruments(s) => {
            let c = Instruments::new(s)?;
            return merge_cells(&c, &any, &metas, out).map(Merged::Cells);
        }
    };
    // The reports' view of every block, and trial 0's extras, from the shard that ran it.
    let mut infos: Vec<Option<(BlockInfo, Option<Trial0>)>> = Vec::new();
    for (d, m) in &metas {
        let id = m.id();
        every_block(m, &d.join("shard.json"))?;
        for (k, b) in m.blocks.iter().enumerate() {
            b.check(&id, &d.join("shard.json"), k)?;
            let i = b.info.index;
            if infos.len() <= i {
                infos.resize_with(i + 1, || None);
            }
            match &mut infos[i] {
                slot @ None => *slot = Some((b.info.clone(), b.trial0.clone())),
                Some((_, t0)) if t0.is_none() => t0.clone_from(&b.trial0),
                Some(_) => {}
            }
        }
    }
    let seconds: f64 = metas.iter().map(|(_, m)| m.seconds).sum();
    if !seconds.is_finite() {
        let msg = "the shards' wall times add up beyond any number: a `seconds` was altered";
        return Err(Error::file(metas[0].0.join("shard.json"), "seconds", msg));
    }
    let mut result = None;
    crate::report::atomically(out, |dir| {
        let mut csv = TrialsCsv::create(dir, scenario.sweep.as_ref())?;
        let mut collector = Collector::new();
        let mut current: Option<usize> = None;
        let mut aggregated = 0u64;
        for (d, m) in &metas {
            let path = d.join("records.txt");
            let sweep = scenario.sweep.is_some().then_some("sweep point");
            let id = m.id();
            let records = Verifier::new(&path, id, m.trials, sweep, m.units);
            each_record(records, |records, line| {
                let (b, index, t) = records.record(line)?;
                let t = TrialResult { index, ..t };
                if current != Some(b) {
                    let (info, t0) = infos.get(b).cloned().flatten().ok_or_else(|| {
                        Error::file(
                            &path,
                            format!("line {}", records.lines()),
                            format!("sweep point {b} is not in any shard.json"),
                        )
                    })?;
                    collector.begin(info, t0);
                    current = Some(b);
                }
                let info = infos.get(b).and_then(Option::as_ref);
                if let Some(why) = info.and_then(|(i, _)| i.misfit(&t)) {
                    return Err(Error::file(
                        d.join("shard.json"),
                        "blocks",
                        format!(
                            "the record of trial {index} (records.txt, line {}) does not fit \
                             its block: {why} (the file was altered)",
                            records.lines()
                        ),
                    ));
                }
                collector.trial(&t, &mut csv)?;
                aggregated += 1;
                Ok(())
            })?;
        }
        // Every shard's units checked and every record read once: the run's trials.
        if aggregated != total {
            return Err(Error::Compute(format!(
                "the merge aggregated {aggregated} records of a run of {total} trials"
            )));
        }
        let r = RunResult {
            blocks: collector.finish(scenario.sweep.as_ref())?,
            scenario: scenario.clone(),
            out: out.to_path_buf(),
            seconds,
            shard: None,
            stopping: None,
        };
        let summary = analyse_warning(&r, reporter)?;
        write_run(&r, &summary, csv.finish()?, dir)?;
        result = Some(r);
        Ok(())
    })?;
    let r = result.ok_or_else(|| Error::Compute("the merge produced no result".into()))?;
    Ok(Merged::Run(Box::new(r)))
}

/// The merge of a study of cells: every shard's records, checked, into their blocks in
/// order, then the study's files into `out`, as a whole; the table the terminal shows.
fn merge_cells<C: Cells>(
    cells: &C,
    sc: &AnyScenario,
    metas: &[(PathBuf, ShardMeta)],
    out: &Path,
) -> Result<String> {
    let mut table = String::new();
    crate::report::atomically(out, |dir| {
        let mut done: Vec<(C::Block, Vec<C::Trial>)> = Vec::new();
        for (d, m) in metas {
            let path = d.join("records.txt");
            let id = m.id();
            let records = Verifier::new(&path, id, m.trials, sc.blocks().1, m.units);
            each_record(records, |records, line| {
                let (b, _, t) = records.record::<C::Trial>(line)?;
                while done.len() <= b {
                    let block = cells.block(done.len(), done.last().map(|d| &d.0))?;
                    done.push((block, Vec::new()));
                }
                if let Some(why) = cells.misfit(&done[b].0, &t) {
                    return Err(records.unfit(&why));
                }
                done[b].1.push(t);
                Ok(())
            })?;
        }
        let (outputs, text) = super::cells::study_files(cells, sc, done)?;
        table = text;
        write_all(dir, &outputs)
    })?;
    Ok(table)
}

/// Hands each line of the shard's `records.txt` that `records` checks to `f` (which reads it
/// with `records`), without its line end (LF, or CR LF where a copy converted them), then
/// checks that none is missing. Blank lines at the end (an editor's) are passed over; one
/// before a record, or a line that is not UTF-8, is refused at its line.
fn each_record(
    mut records: Verifier,
    mut f: impl FnMut(&mut Verifier, &str) -> Result<()>,
) -> Result<()> {
    let path = records.path().to_path_buf();
    let file = std::fs::File::open(&path).map_err(|e| Error::io(&path, e))?;
    let mut blank = 0;
    for line in std::io::BufReader::new(file).split(b'\n') {
        let mut line = line.map_err(|e| Error::io(&path, e))?;
        if line.last() == Some(&b'\r') {
            line.pop();
        }
        if line.iter().all(u8::is_ascii_whitespace) {
            blank += 1;
            continue;
        }
        let at = format!("line {}", records.lines() + 1);
        if blank > 0 {
            let why = "a blank line between records, where every line holds one: the file \
                       was altered";
            return Err(Error::file(&path, at, why));
        }
        let Ok(text) = String::from_utf8(line) else {
            let why = "the record is not UTF-8 text: the file was altered";
            return Err(Error::file(&path, at, why));
        };
        f(&mut records, &text)?;
    }
    records.finish()
}

/// Removes the checkpoint of an unfinished run into `out` (and, when its process has ended on
/// this host, its temporary output folder), if there is one, with a warning to `reporter`
/// saying what replaces that run (`now`): a new run into `out`, or a merge, whose output a
/// later `run --resume` would otherwise overwrite.
pub fn discard_unfinished(out: &Path, now: &str, reporter: &dyn Reporter) -> Result<()> {
    let dir = crate::report::checkpoint_folder(out);
    if !dir.exists() {
        return Ok(());
    }
    reporter.warning(&format!(
        "{} held the checkpoint of an unfinished run into {}; {now}, it is removed \
         (`calbench run --resume {}` would have continued that run)",
        dir.display(),
        out.display(),
        out.display()
    ));
    if let Some((pid, true)) = crate::report::guard::writer(out) {
        if !crate::report::guard::alive(pid) {
            let _ = std::fs::remove_dir_all(crate::report::partial_path(out, pid));
        }
    }
    std::fs::remove_dir_all(&dir).map_err(|e| Error::io(&dir, e))
}

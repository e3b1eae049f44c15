//! Sharded runs (docs/formats.md `run --shard`, `merge`): a shard's partial result and the merge
//! of all shards into the output of the unsharded run.
//!
//! A shard folder holds `trials.csv` (its own rows), `shard.json` (the scenario as run, the
//! share, and what the reports need of each block's study and of trial 0) and `records.txt`:
//! one line per trial with every number the aggregation reads, floats in shortest
//! round-trip form, so the merge replays the trials in order through the same streaming
//! aggregation ([`crate::study::Collector`]) and writes the same bytes as one machine.

use std::io::{BufRead, Write as _};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::run::TrialsCsv;
use super::write_run;
use crate::calibrate::ErrorStats;
use crate::error::{Error, Result};
use crate::identify::Termination;
use crate::numeric::Real;
use crate::study::scenario::Scenario;
use crate::study::trial::OptionalStats;
use crate::study::trial::Outcome;
use crate::study::{BlockInfo, Collector, RunResult, Shard, Trial0, TrialResult, TrialSink};

/// The `format` of `shard.json`.
const FORMAT: &str = "calbench-shard-4";

/// One block of a shard.
#[derive(Serialize, Deserialize)]
struct ShardBlock {
    info: BlockInfo,
    trial0: Option<Trial0>,
}

/// `shard.json`.
#[derive(Serialize, Deserialize)]
struct ShardMeta {
    format: String,
    scenario: String,
    scenario_file: Option<PathBuf>,
    settings: String,
    seed: u64,
    trials: usize,
    shard: Shard,
    units: (u64, u64),
    seconds: f64,
    blocks: Vec<ShardBlock>,
}

/// Two sinks in one.
pub struct Both<'a, A: TrialSink, B: TrialSink>(pub &'a mut A, pub &'a mut B);

impl<A: TrialSink, B: TrialSink> TrialSink for Both<'_, A, B> {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        self.0.trial(info, t)?;
        self.1.trial(info, t)
    }
}

/// The writer of a shard's `records.txt` and `shard.json`.
pub struct Records {
    dir: PathBuf,
    out: std::io::BufWriter<std::fs::File>,
}

impl Records {
    /// Creates `records.txt` in `dir`.
    pub fn create(dir: &Path) -> Result<Records> {
        let path = dir.join("records.txt");
        let file = std::fs::File::create(&path).map_err(|e| Error::io(&path, e))?;
        Ok(Records {
            dir: dir.to_path_buf(),
            out: std::io::BufWriter::new(file),
        })
    }

    /// Flushes the records and writes `shard.json` for the run `r`.
    pub fn finish(mut self, r: &RunResult) -> Result<()> {
        let path = self.dir.join("records.txt");
        self.out.flush().map_err(|e| Error::io(&path, e))?;
        let shard = r.shard.unwrap_or(Shard { index: 0, count: 1 });
        let total = r.scenario.trials as u64
            * r.scenario.sweep.as_ref().map_or(1, |s| s.points().len()) as u64;
        let settings = toml::to_string(r.scenario.table())
            .map_err(|e| Error::Compute(format!("cannot write the scenario: {e}")))?;
        let meta = ShardMeta {
            format: FORMAT.into(),
            scenario: r.scenario.name.clone(),
            scenario_file: r.scenario.path.clone(),
            settings,
            seed: r.scenario.seed,
            trials: r.scenario.trials,
            shard,
            units: shard.range(total),
            seconds: r.seconds,
            blocks: r
                .blocks
                .iter()
                .map(|b| ShardBlock {
                    info: b.info.clone(),
                    trial0: b.trial0.clone(),
                })
                .collect(),
        };
        let path = self.dir.join("shard.json");
        let text =
            serde_json::to_string_pretty(&meta).map_err(|e| Error::Compute(e.to_string()))?;
        std::fs::write(&path, text + "\n").map_err(|e| Error::io(&path, e))
    }
}

impl TrialSink for Records {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        let line = encode(info.index, t);
        self.out
            .write_all(line.as_bytes())
            .map_err(|e| Error::io(self.dir.join("records.txt"), e))
    }
}

fn push_stats(s: &mut String, e: &ErrorStats) {
    for v in [e.mean, e.rms, e.max, e.std] {
        s.push(' ');
        s.push_str(&format!("{v:e}"));
    }
}

/// One trial as a line of `records.txt`: `block trial n truth… crb… outcomes`, each
/// outcome `strategy method termination rank-deficient-expected iterations evaluations seconds before×4 after×4`, four optional
/// orientation statistics (`-` or `+` and four numbers) and the n identified values.
pub(crate) fn encode(block: usize, t: &TrialResult) -> String {
    let mut s = format!("{block} {} {}", t.index, t.truth.len());
    for v in &t.truth {
        s.push_str(&format!(" {v:e}"));
    }
    s.push_str(&format!(" {}", t.crb_trace.len()));
    for c in &t.crb_trace {
        match c {
            Some(v) => s.push_str(&format!(" {v:e}")),
            None => s.push_str(" -"),
        }
    }
    s.push_str(&format!(" {}", t.outcomes.len()));
    for o in &t.outcomes {
        s.push_str(&format!(
            " {} {} {} {} {} {} {:e}",
            o.strategy,
            o.method,
            o.termination.as_str(),
            u8::from(o.rank_deficient_expected),
            o.iterations,
            o.evaluations,
            o.seconds
        ));
        push_stats(&mut s, &o.before_mm);
        push_stats(&mut s, &o.after_mm);
        push_stats(&mut s, &o.calibration_before_mm);
        push_stats(&mut s, &o.calibration_after_mm);
        for d in o.optional.values() {
            match d {
                Some(d) => {
                    s.push_str(" +");
                    push_stats(&mut s, &d);
                }
                None => s.push_str(" -"),
            }
        }
        for v in &o.identified {
            s.push_str(&format!(" {v:e}"));
        }
    }
    s.push('\n');
    s
}

/// Reads the tokens of one record line.
struct Tokens<'a> {
    it: std::str::SplitAsciiWhitespace<'a>,
    path: &'a Path,
    line: usize,
}

impl<'a> Tokens<'a> {
    fn err(&self, what: &str) -> Error {
        Error::file(
            self.path,
            format!("line {}", self.line),
            format!("{what} (the file is not a calbench shard record, or is cut short)"),
        )
    }
    fn word(&mut self) -> Result<&'a str> {
        self.it.next().ok_or_else(|| self.err("missing field"))
    }
    fn usize(&mut self) -> Result<usize> {
        let w = self.word()?;
        w.parse()
            .map_err(|_| self.err(&format!("\"{w}\" is not a count")))
    }
    fn real(&mut self) -> Result<Real> {
        let w = self.word()?;
        w.parse()
            .map_err(|_| self.err(&format!("\"{w}\" is not a number")))
    }
    fn reals(&mut self, n: usize) -> Result<Vec<Real>> {
        (0..n).map(|_| self.real()).collect()
    }
    fn stats(&mut self) -> Result<ErrorStats> {
        Ok(ErrorStats {
            mean: self.real()?,
            rms: self.real()?,
            max: self.real()?,
            std: self.real()?,
        })
    }
    fn optional_stats(&mut self) -> Result<Option<ErrorStats>> {
        match self.word()? {
            "-" => Ok(None),
            "+" => self.stats().map(Some),
            w => Err(self.err(&format!("\"{w}\" is neither - nor +"))),
        }
    }
}

/// Parses line `line` of `path` (see [`encode`]): the block index and the trial.
pub(crate) fn decode(text: &str, path: &Path, line: usize) -> Result<(usize, TrialResult)> {
    let mut t = Tokens {
        it: text.split_ascii_whitespace(),
        path,
        line,
    };
    let block = t.usize()?;
    let index = t.usize()?;
    let n = t.usize()?;
    let truth = t.reals(n)?;
    let ns = t.usize()?;
    let mut crb_trace = Vec::with_capacity(ns);
    for _ in 0..ns {
        crb_trace.push(match t.word()? {
            "-" => None,
            w => Some(
                w.parse()
                    .map_err(|_| t.err(&format!("\"{w}\" is not a number")))?,
            ),
        });
    }
    let no = t.usize()?;
    let mut outcomes = Vec::with_capacity(no);
    for _ in 0..no {
        let strategy = t.usize()?;
        let method = t.usize()?;
        let name = t.word()?.to_string();
        let termination: Termination = crate::robot::names::parse("termination", &name)
            .map_err(|_| t.err(&format!("unknown termination \"{name}\"")))?;
        let rank_deficient_expected = match t.usize()? {
            0 => false,
            1 => true,
            v => return Err(t.err(&format!("{v} is not a flag (0 or 1)"))),
        };
        let iterations = t.usize()?;
        let evaluations = t.usize()?;
        let seconds = t.real()?;
        let before_mm = t.stats()?;
        let after_mm = t.stats()?;
        let calibration_before_mm = t.stats()?;
        let calibration_after_mm = t.stats()?;
        let mut optional = OptionalStats::default();
        for o in optional.values_mut() {
            *o = t.optional_stats()?;
        }
        let identified = t.reals(n)?;
        outcomes.push(Outcome {
            method,
            strategy,
            identified,
            before_mm,
            after_mm,
            calibration_before_mm,
            calibration_after_mm,
            optional,
            per_point: None,
            per_point_attitude_deg: None,
            trace: None,
            iterations,
            evaluations,
            termination,
            rank_deficient_expected,
            seconds,
            // Shards run scenario files, whose methods are all registered ones.
            error: None,
        });
    }
    if t.it.next().is_some() {
        return Err(t.err("extra fields at the end of the line"));
    }
    Ok((
        block,
        TrialResult {
            index,
            truth,
            crb_trace,
            outcomes,
        },
    ))
}

fn read_meta(dir: &Path) -> Result<ShardMeta> {
    let path = dir.join("shard.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Error::file(
            dir,
            "shard.json",
            format!("not a shard folder of `calbench run --shard` ({e})"),
        )
    })?;
    let meta: ShardMeta =
        serde_json::from_str(&text).map_err(|e| Error::file(&path, "shard.json", e.to_string()))?;
    if meta.format != FORMAT {
        return Err(Error::file(
            &path,
            "format",
            format!("\"{}\", expected \"{FORMAT}\"", meta.format),
        ));
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
}

/// `calbench merge DIR… --out DIR`: checks that `dirs` are all the shards of one run (same
/// scenario, settings and seed, each shard once, none missing) and writes the run's output to
/// `out`, the same bytes (`summary.json`, `trials.csv`) as the unsharded run.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<RunResult> {
    if dirs.is_empty() {
        return Err(Error::setting("DIR", "give the shard folders to merge"));
    }
    let mut metas: Vec<(PathBuf, ShardMeta)> = Vec::new();
    for d in dirs {
        metas.push((d.clone(), read_meta(d)?));
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
            return differ(
                "settings of scenario",
                format!("\"{}\"", m0.scenario),
                "others".into(),
            );
        }
    }
    let n = m0.shard.count;
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
    metas.sort_by_key(|(_, m)| m.shard.index);
    let scenario = Scenario::parse(&metas[0].1.settings, metas[0].1.scenario_file.as_deref())?;
    // The reports' view of every block, and trial 0's extras, from the shard that ran it.
    let mut infos: Vec<Option<(BlockInfo, Option<Trial0>)>> = Vec::new();
    for (_, m) in &metas {
        for b in &m.blocks {
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
    let seconds = metas.iter().map(|(_, m)| m.seconds).sum();
    let mut result = None;
    super::atomically(out, |dir| {
        let mut csv = TrialsCsv::create(&dir.join("trials.csv"), scenario.sweep.as_ref())?;
        let mut collector = Collector::new();
        let mut current: Option<usize> = None;
        for (d, _) in &metas {
            let path = d.join("records.txt");
            let file = std::fs::File::open(&path).map_err(|e| Error::io(&path, e))?;
            for (k, line) in std::io::BufReader::new(file).lines().enumerate() {
                let line = line.map_err(|e| Error::io(&path, e))?;
                let (b, t) = decode(&line, &path, k + 1)?;
                if current != Some(b) {
                    let (info, t0) = infos.get(b).cloned().flatten().ok_or_else(|| {
                        Error::file(
                            &path,
                            format!("line {}", k + 1),
                            format!("block {b} is not in any shard.json"),
                        )
                    })?;
                    collector.begin(info, t0);
                    current = Some(b);
                }
                collector.trial(&t, &mut csv)?;
            }
        }
        csv.finish()?;
        let r = RunResult {
            blocks: collector.finish(scenario.sweep.as_ref())?,
            scenario: scenario.clone(),
            out: out.to_path_buf(),
            seconds,
            shard: None,
        };
        write_run(&r, dir)?;
        result = Some(r);
        Ok(())
    })?;
    result.ok_or_else(|| Error::Compute("the merge produced no result".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_record_reads_back_bit_for_bit() {
        let stats = |x: Real| ErrorStats {
            mean: x,
            rms: x * 1.1,
            max: 1e-300,
            std: Real::NAN,
        };
        let t = TrialResult {
            index: 17,
            truth: vec![0.1, -0.0, 1.0 / 3.0],
            crb_trace: vec![Some(2.5e-7), None],
            outcomes: vec![Outcome {
                method: 1,
                strategy: 0,
                identified: vec![Real::INFINITY, Real::NAN, -1e300],
                before_mm: stats(0.7),
                after_mm: stats(0.1),
                calibration_before_mm: stats(0.6),
                calibration_after_mm: stats(0.05),
                optional: crate::study::trial::OptionalStats {
                    validation_after_deg: Some(stats(0.3)),
                    validation_before_axis_mm: Some(stats(-0.2)),
                    validation_after_axis_abs_mm: Some(stats(0.01)),
                    calibration_after_attitude_deg: Some(stats(0.02)),
                    ..Default::default()
                },
                per_point: None,
                per_point_attitude_deg: None,
                trace: None,
                iterations: 12,
                evaluations: 40,
                termination: Termination::MaxIterations,
                rank_deficient_expected: true,
                seconds: 0.00123,
                error: None,
            }],
        };
        let line = encode(3, &t);
        let (b, u) = decode(&line, Path::new("r.txt"), 1).unwrap();
        assert_eq!(b, 3);
        assert_eq!(encode(3, &u), line);
        assert_eq!(u.truth[2].to_bits(), t.truth[2].to_bits());
        assert_eq!(u.truth[1].to_bits(), (-0.0f64).to_bits());
        assert!(u.outcomes[0].identified[1].is_nan());
        assert!(decode("3 17 2 0.1", Path::new("r.txt"), 4)
            .unwrap_err()
            .to_string()
            .contains("line 4"));
    }
}

//! Checkpoints of a run (docs/formats.md `run --resume`): what a run killed at any moment
//! needs to continue.
//!
//! While `calbench run … --out DIR` runs, the folder `.NAME.checkpoint` beside `DIR` holds
//! `records.txt`, one line per finished trial in the record format ([`crate::study::records`],
//! each line with its checksum), and `checkpoint.json`: the scenario as run, the binary's
//! version, the share, the writer's process and host, and how many trials (and bytes of
//! `records.txt`) are complete. `checkpoint.json` is rewritten (temporary file and rename)
//! after every [`CHUNK`] trials, once the records before it are flushed, so whatever moment
//! the run is killed, it names a prefix of `records.txt` made of whole lines.
//!
//! `calbench run --resume DIR` first checks the whole checkpoint without changing it: its
//! format, version and scenario, that its writer is no longer running, and every record of
//! the prefix (checksum, and the share's trials in order, each once). A refusal leaves the
//! checkpoint as it was. Then it cuts `records.txt` back to that prefix, replays it through
//! the same aggregation as a live run ([`super::run::run_resumed`]) and runs the rest; the
//! folder is removed when the run ends, with its output or with an error (only a run killed
//! from outside leaves one).
//!
//! The checkpoint is not an output of the run, so it is written here and not through
//! [`crate::report::output`]: it lives beside the output folder, and it must be on disk at
//! every moment for a killed run to resume, so its records are appended and flushed as the
//! trials finish and `checkpoint.json` is replaced by a rename, where an output is written
//! once the run is complete.

use std::io::{BufRead, Read as _, Write as _};
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::cells::{Cells, Instruments};
use crate::error::{Error, Result};
use crate::report::guard::{alive, host, writing, Writing};
use crate::report::MadeFolders;
use crate::runner::as_run::{one_effect, scenario_as_run, settings_difference, trials_as_run};
use crate::runner::shard::FormatOnly;
use crate::study::inputs::{self, Input};
use crate::study::kind::AnyScenario;
use crate::study::records::{encode, RunId, Verifier};
use crate::study::registration_study::RegistrationScenario;
use crate::study::reporter::Reporter;
use crate::study::stats::precision::Precision;
use crate::study::{BlockInfo, Replay, Shard, TrialResult, TrialSink, CHUNK};

/// The `format` of `checkpoint.json`, and so of its `records.txt`: the records of
/// [`crate::runner::shard::FORMAT`] (docs/formats.md § 7.3.1), a new one with each of its.
pub const FORMAT: &str = "calbench-checkpoint-7";

/// `checkpoint.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Meta {
    format: String,
    /// The version of the calbench that wrote it.
    version: String,
    scenario: String,
    scenario_file: Option<PathBuf>,
    /// The scenario as run (overrides applied), TOML.
    settings: String,
    /// The files the scenario reads, as they were when the run started.
    inputs: Vec<Input>,
    seed: u64,
    trials: usize,
    shard: Option<Shard>,
    /// `--precision`, as given: a resumed run stops where the uninterrupted one would.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    precision: Option<String>,
    /// The process that wrote it (its temporary output folder is removed on resume), and
    /// the host it ran on: a resume on that host refuses a checkpoint whose writer runs.
    pid: u32,
    host: String,
    /// Trials complete, and the bytes of `records.txt` that hold them.
    done: u64,
    bytes: u64,
}

impl Meta {
    /// What its records' checksums bind.
    fn id(&self) -> RunId {
        RunId::new(&self.settings, &self.inputs, self.seed)
    }
}

/// The checkpoint of a running study: a [`TrialSink`] that records every trial past those
/// already recorded, and rewrites `checkpoint.json` every [`CHUNK`] trials.
pub struct Checkpoint {
    dir: PathBuf,
    /// The output folder held for this thread while the run writes it.
    _writing: Writing,
    /// The folders made for it (the checkpoint's and those holding it): the ones still empty
    /// are removed again when it is.
    _made: MadeFolders,
    meta: Meta,
    /// What the records' checksums bind.
    id: RunId,
    records: std::io::BufWriter<std::fs::File>,
    /// Trials handed to the sink so far (replayed ones included).
    seen: u64,
    /// Trials already in `records.txt` when this process started.
    skip: u64,
}

/// The `--precision` the checkpoint `path` records, a malformed one refused naming the file
/// and its key `precision` (checked before a resume touches the checkpoint).
fn precision_in(path: &Path, meta: &Meta) -> Result<Option<Precision>> {
    let parse = |p: &str| {
        Precision::parse(p).map_err(|e| match e {
            Error::Setting { msg, .. } | Error::Option { msg, .. } => {
                Error::file(path, "precision", msg)
            }
            e => e,
        })
    };
    meta.precision.as_deref().map(parse).transpose()
}

/// Removes the temporary output folder a killed process `pid` left beside `out`
/// ([`crate::report::partial_path`]), if any.
fn remove_partial(out: &Path, pid: u32) {
    let _ = std::fs::remove_dir_all(crate::report::partial_path(out, pid));
}

fn write_meta(dir: &Path, meta: &Meta) -> Result<()> {
    let path = dir.join("checkpoint.json");
    let tmp = dir.join("checkpoint.json.tmp");
    let text = crate::error::json_text(meta)?;
    std::fs::write(&tmp, text).map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, &path).map_err(|e| Error::io(&path, e))
}

impl Checkpoint {
    /// Starts the checkpoint of a new run of `scenario` into `out` (replacing the checkpoint
    /// of an earlier run into the same folder, with a warning to `reporter`).
    pub fn start(
        scenario: &AnyScenario,
        shard: Option<Shard>,
        precision: Option<&Precision>,
        out: &Path,
        reporter: &dyn Reporter,
    ) -> Result<Checkpoint> {
        if let Some(s) = shard {
            let why = s.fits(scenario.units());
            why.map_err(|m| Error::option(crate::error::Opt::Shard, m))?;
        }
        let held = Writing::hold(out)?;
        crate::runner::shard::discard_unfinished(out, "starting anew", reporter)?;
        let dir = crate::report::checkpoint_folder(out);
        let made = MadeFolders::create(&dir)?;
        let settings = scenario.settings()?;
        let meta = Meta {
            format: FORMAT.into(),
            version: env!("CARGO_PKG_VERSION").into(),
            scenario: scenario.name().to_string(),
            scenario_file: scenario.path().map(Path::to_path_buf),
            settings,
            inputs: inputs::of(scenario)?,
            seed: scenario.seed(),
            trials: scenario.trials(),
            shard,
            precision: precision.map(|p| p.text.clone()),
            pid: std::process::id(),
            host: host(),
            done: 0,
            bytes: 0,
        };
        let path = dir.join("records.txt");
        let file = std::fs::File::create(&path).map_err(|e| Error::io(&path, e))?;
        write_meta(&dir, &meta)?;
        Ok(Checkpoint {
            _made: made,
            _writing: held,
            dir,
            id: meta.id(),
            meta,
            records: std::io::BufWriter::new(file),
            seen: 0,
            skip: 0,
        })
    }

    /// Opens the checkpoint of the killed run into `out`: checks it against this binary and,
    /// when given, the scenario the user names (its name, seed, trials and settings; an
    /// error names what differs), that the process that wrote it is not running on this
    /// host (unless `force`) and every record it counts (its `Verifier`), all before changing
    /// anything; then cuts `records.txt` back to its complete prefix and returns the
    /// checkpoint, the scenario as run, its share and the replay of its trials.
    pub fn resume(
        out: &Path,
        given: Option<&AnyScenario>,
        force: bool,
    ) -> Result<(Checkpoint, AnyScenario, Option<Shard>, Records)> {
        let held = Writing::hold(out)?;
        let dir = crate::report::checkpoint_folder(out);
        let path = dir.join("checkpoint.json");
        let text = crate::error::read_bounded_text(&path).map_err(|e| {
            Error::file(
                out,
                "--resume",
                format!(
                    "no checkpoint of a run into this folder ({}: {e}); a run leaves one while \
                     it runs and removes it when it has finished",
                    path.display()
                ),
            )
        })?;
        let v = crate::error::json_value(&path, &text)?;
        let head: FormatOnly = crate::error::json_typed(&v, &path, &text, "checkpoint.json")?;
        let refuse = |what: &str, had: String, now: String| {
            Error::file(
                &path,
                what,
                format!(
                    "the checkpoint was written with {what} {had}, this run has {now}: it cannot \
                     continue (start the run anew without --resume)"
                ),
            )
        };
        if head.format != FORMAT {
            return Err(refuse("format", head.format, FORMAT.into()));
        }
        let mut meta: Meta = crate::error::json_typed(&v, &path, &text, "checkpoint.json")?;
        let version = env!("CARGO_PKG_VERSION");
        if meta.version != version {
            return Err(refuse(
                "calbench version",
                meta.version,
                version.to_string(),
            ));
        }
        inputs::unchanged(&path, &meta.inputs)?;
        let scenario = scenario_as_run(&path, &meta.settings, meta.scenario_file.as_deref())?;
        inputs::as_run(&path, &meta.inputs, &inputs::files(&scenario)?)?;
        if let Some(Err(m)) = meta.shard.map(|s| s.fits(scenario.units())) {
            return Err(Error::file(
                &path,
                "shard",
                format!("{m} (the file was altered)"),
            ));
        }
        if let Some(g) = given {
            if g.name() != meta.scenario {
                return Err(refuse(
                    "scenario",
                    format!("\"{}\"", meta.scenario),
                    format!("\"{}\"", g.name()),
                ));
            }
            if g.seed() != meta.seed {
                return Err(refuse("seed", meta.seed.to_string(), g.seed().to_string()));
            }
            if g.trials() != meta.trials {
                return Err(refuse(
                    "trials",
                    meta.trials.to_string(),
                    g.trials().to_string(),
                ));
            }
            // Settings written otherwise (`2500` for `2500.0`, a default written out) set the
            // same: the run goes on as its checkpoint's text wrote them.
            let given = g.settings()?;
            if let Some((key, had, now)) = settings_difference(&meta.settings, &given)
                .filter(|_| !one_effect(&meta.settings, &given))
            {
                return Err(refuse(&format!("`{key}`"), had, now));
            }
        }
        precision_in(&path, &meta)?;
        if meta.host == host() && alive(meta.pid) {
            // Forcing passes a number another program took, never the run that is writing.
            let pid = meta.pid;
            let why = match (force, writing(pid, &dir)) {
                (_, true) => Some(format!(
                    "process {pid} holds its records.txt open: stop it first (--force passes \
                     only a number another program took)"
                )),
                (false, false) => Some(format!(
                    "process {pid} on this host: stop it first, or give --force if that \
                     process is not calbench"
                )),
                (true, false) => None,
            };
            if let Some(why) = why {
                let msg = format!("the run that writes this checkpoint is still running ({why})");
                return Err(Error::file(&path, "pid", msg));
            }
        }
        let records = dir.join("records.txt");
        let units = units(&path, &scenario, &meta)?;
        let sweep = scenario.blocks().1;
        let id = meta.id();
        let verifier = || Verifier::new(&records, id, meta.trials, sweep, units);
        match &scenario {
            AnyScenario::MonteCarlo(_) => {
                check_records::<TrialResult>(&records, &meta, verifier())?;
            }
            AnyScenario::Registration(_) => {
                check_records::<<RegistrationScenario as Cells>::Trial>(
                    &records,
                    &meta,
                    verifier(),
                )?;
            }
            AnyScenario::Instruments(_) => {
                check_records::<<Instruments as Cells>::Trial>(&records, &meta, verifier())?;
            }
        }
        // Checked: from here on the checkpoint is the resumed run's.
        remove_partial(out, meta.pid);
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&records)
            .map_err(|e| Error::io(&records, e))?;
        file.set_len(meta.bytes)
            .map_err(|e| Error::io(&records, e))?;
        let reader = std::fs::File::open(&records).map_err(|e| Error::io(&records, e))?;
        let mut append = file;
        std::io::Seek::seek(&mut append, std::io::SeekFrom::End(0))
            .map_err(|e| Error::io(&records, e))?;
        let (shard, done) = (meta.shard, meta.done);
        let check = verifier();
        meta.pid = std::process::id();
        meta.host = host();
        write_meta(&dir, &meta)?;
        Ok((
            Checkpoint {
                _made: MadeFolders::create(&dir)?,
                _writing: held,
                dir,
                meta,
                id,
                records: std::io::BufWriter::new(append),
                seen: 0,
                skip: done,
            },
            scenario,
            shard,
            Records {
                path: records.clone(),
                lines: std::io::BufReader::new(reader),
                done,
                check,
            },
        ))
    }

    /// The `--precision` of the run it checkpoints.
    pub fn precision(&self) -> Result<Option<Precision>> {
        precision_in(&self.dir.join("checkpoint.json"), &self.meta)
    }

    /// Removes the checkpoint once the run's output is written (or refused), and the folders
    /// made to hold it that are left empty.
    pub fn finish(self) -> Result<()> {
        drop(self.records);
        std::fs::remove_dir_all(&self.dir).map_err(|e| Error::io(&self.dir, e))
    }
}

impl Checkpoint {
    /// Records trial `trial` of block `point`, which gave `t` (unless it was already recorded
    /// when this process started), and rewrites `checkpoint.json` every [`CHUNK`] trials.
    pub fn record<T: serde::Serialize>(&mut self, point: usize, trial: usize, t: &T) -> Result<()> {
        self.seen += 1;
        if self.seen <= self.skip {
            return Ok(());
        }
        let line = encode(&self.id, point, trial, t)?;
        let path = self.dir.join("records.txt");
        self.records
            .write_all(line.as_bytes())
            .map_err(|e| Error::io(&path, e))?;
        self.meta.bytes += line.len() as u64;
        if self.seen.is_multiple_of(CHUNK as u64) {
            self.sync()?;
        }
        Ok(())
    }

    /// Flushes the records and counts them in `checkpoint.json` (at the end of a block too).
    pub fn sync(&mut self) -> Result<()> {
        let path = self.dir.join("records.txt");
        self.records.flush().map_err(|e| Error::io(&path, e))?;
        if self.seen > self.meta.done && self.seen >= self.skip {
            self.meta.done = self.seen;
            write_meta(&self.dir, &self.meta)?;
        }
        Ok(())
    }
}

impl TrialSink for Checkpoint {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        self.record(info.index, t.index, t)
    }
}

/// The work units `[start, start + done)` that the checkpoint `meta` (at `path`) of a run of
/// `scenario` counts as done: its trial count must be the scenario's, and `done` no more than
/// its share holds.
fn units(path: &Path, scenario: &AnyScenario, meta: &Meta) -> Result<(u64, u64)> {
    trials_as_run(path, meta.trials, scenario)?;
    let total = scenario.units();
    let (start, end) = meta.shard.map_or((0, total), |s| s.range(total));
    if meta.done > end - start {
        return Err(Error::file(
            path,
            "done",
            format!(
                "{} trials complete, where the run's share holds {}: the file was altered",
                meta.done,
                end - start
            ),
        ));
    }
    Ok((start, start + meta.done))
}

/// Checks, reading only, that `records.txt` at `path` holds at least the `bytes` of `meta`
/// and that they are its `done` records, whole lines, each verified by `check` and read as
/// the `T` that the replay reads: a record the replay could not read is refused here, before
/// anything changes.
fn check_records<T: DeserializeOwned>(path: &Path, meta: &Meta, mut check: Verifier) -> Result<()> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    // A file shorter than its count is read too: the first record missing or changed is
    // named by its line and trial.
    let cut = len < meta.bytes;
    let mut lines = std::io::BufReader::new(file.take(meta.bytes));
    let mut text = Vec::new();
    loop {
        text.clear();
        let n = lines
            .read_until(b'\n', &mut text)
            .map_err(|e| Error::io(path, e))?;
        let at = format!("line {}", check.lines() + 1);
        if n == 0 {
            check.finish()?;
            if !cut {
                return Ok(());
            }
            let why = format!(
                "the file ends before the {} bytes that checkpoint.json counts for its {} \
                 trials: checkpoint.json was altered",
                meta.bytes, meta.done
            );
            return Err(Error::file(path, at, why));
        }
        let whole = text.last() == Some(&b'\n');
        if whole {
            text.pop();
        }
        // A record cut at its CR is refused, by the check below, as a CR LF line.
        if !whole && text.last() != Some(&b'\r') {
            let why = match cut {
                true => format!(
                    "the file ends inside the record {}: it was cut short",
                    check.expected()
                ),
                false => format!(
                    "the {} bytes that checkpoint.json counts end inside the record {}: it \
                     was altered",
                    meta.bytes,
                    check.expected()
                ),
            };
            return Err(Error::file(path, at, why));
        }
        check.record::<T>(&String::from_utf8_lossy(&text))?;
    }
}

/// The trials of a checkpoint's `records.txt`, read back in order ([`Replay`]), each
/// checked again as it is read.
pub struct Records {
    path: PathBuf,
    lines: std::io::BufReader<std::fs::File>,
    done: u64,
    check: Verifier,
}

impl Replay for Records {
    fn done(&self) -> u64 {
        self.done
    }

    fn next(&mut self) -> Result<(usize, TrialResult)> {
        let (point, index, t) = self.next_record::<TrialResult>()?;
        Ok((point, TrialResult { index, ..t }))
    }

    fn unfit(&self, why: &str) -> Error {
        self.check.unfit(why)
    }
}

impl Records {
    /// The next finished trial: its block, its index and what it gave.
    pub fn next_record<T: serde::de::DeserializeOwned>(&mut self) -> Result<(usize, usize, T)> {
        let mut text = String::new();
        let n = self
            .lines
            .read_line(&mut text)
            .map_err(|e| Error::io(&self.path, e))?;
        if n == 0 {
            self.check.finish()?;
        }
        self.check.record(text.trim_end_matches('\n'))
    }
}

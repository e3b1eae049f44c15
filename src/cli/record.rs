//! `calbench record DIR… [--db PATH] [--scenario FILE] [--label L] [--machine NAME]`: the
//! results of run, merge, identify and task folders stored in the results database; and the
//! `--record` flags of `run`, `identify` and `merge`, which do it as they finish.

use std::path::{Path, PathBuf};

use anyhow::Result;

use calbench::error::counted;
use calbench::results::{db_path, Db, Kind, Provenance, Record, Recorded};

/// Arguments of `calbench record`.
#[derive(clap::Args)]
pub struct RecordArgs {
    /// The folders to record: run or merge (summary.json), identify (identified.json) or
    /// task (task.json) outputs.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    #[command(flatten)]
    pub db: DbArg,
    /// The scenario file of the run folders (default: scenarios/<name>.toml, the name their
    /// summary.json gives); its trials and seed are those of the run.
    #[arg(long, value_name = "FILE")]
    pub scenario: Option<PathBuf>,
    /// The task file of the task folders (default: tasks/<task>.toml, the task their
    /// task.json names): the files their task.toml names are read beside it, and with them it
    /// must have the task_hash the entry states.
    #[arg(long, value_name = "FILE")]
    pub task: Option<PathBuf>,
    /// The version label history orders and compares by (default: VERSION+COMMIT).
    #[arg(long, value_name = "L", value_parser = not_blank)]
    pub label: Option<String>,
    /// The machine's name (default: the host name).
    #[arg(long, value_name = "NAME", value_parser = not_blank)]
    pub machine: Option<String>,
}

/// `--db` of `record`, `history` and `leaderboard`.
#[derive(clap::Args)]
pub struct DbArg {
    /// The results database (default: $CALBENCH_DB, else results/calbench.sqlite).
    #[arg(long, value_name = "PATH")]
    pub db: Option<PathBuf>,
}

impl DbArg {
    /// The database's path: `--db`, else $CALBENCH_DB, else results/calbench.sqlite.
    pub fn path(&self) -> PathBuf {
        db_path(self.db.as_deref())
    }

    /// The database, opened for writing (created and migrated) or for reading.
    pub fn open(&self, write: bool) -> Result<Db> {
        Ok(Db::open(&self.path(), write)?)
    }
}

/// `--record`, `--db` and `--label` of `run`, `identify` and `merge`.
#[derive(clap::Args, Clone, Default)]
pub struct RecordFlags {
    /// Record the results in the results database when the command finishes (`calbench
    /// record`).
    #[arg(long)]
    pub record: bool,
    /// With --record: the results database (default: $CALBENCH_DB, else
    /// results/calbench.sqlite).
    #[arg(long, value_name = "PATH", requires = "record")]
    pub db: Option<PathBuf>,
    /// With --record: the version label (default: VERSION+COMMIT).
    #[arg(long, value_name = "L", requires = "record", value_parser = not_blank)]
    pub label: Option<String>,
}

/// The database a command records its result in ([`RecordFlags::open`]).
pub enum Target {
    /// An existing database, opened.
    Open(Db),
    /// A database to create once there is a result.
    New(PathBuf),
}

impl RecordFlags {
    /// The database of `--record` before any work: one that exists is opened (and migrated)
    /// so that one calbench cannot use is refused first; one that does not is created only
    /// when there is a result to record, so that a refused command leaves nothing behind.
    /// `None` without `--record`.
    pub fn open(&self) -> Result<Option<Target>> {
        if !self.record {
            return Ok(None);
        }
        let path = db_path(self.db.as_deref());
        if path.exists() {
            return Ok(Some(Target::Open(Db::open(&path, true)?)));
        }
        // The folders to create for it must not meet a file on the way.
        Db::creatable(&path)?;
        Ok(Some(Target::New(path)))
    }

    /// Records `record` in `db` (from [`RecordFlags::open`]) and says so.
    pub fn finish(
        &self,
        db: Option<Target>,
        record: impl FnOnce() -> Result<Record>,
    ) -> Result<()> {
        let Some(db) = db else {
            return Ok(());
        };
        let record = record()?;
        let mut db = match db {
            Target::Open(db) => db,
            Target::New(path) => Db::open(&path, true)?,
        };
        let p = Provenance::here(self.label.as_deref(), None);
        report(&record, db.record(&record, &p)?, &db);
        Ok(())
    }
}

fn report(record: &Record, done: Recorded, db: &Db) {
    match done {
        Recorded::Added(id) => out!(
            "recorded {} as {} #{id} of {} ({}, {}) in {}",
            record.output.source_and_document.0,
            record.kind.as_str(),
            record.scenario.name,
            counted(record.results.entries.len(), "entry", "entries"),
            counted(record.results.figures.len(), "figure", "figures"),
            db.path().display()
        ),
        Recorded::AlreadyThere(id) => out!(
            "{}: already recorded as #{id} in {}; nothing added",
            record.output.source_and_document.0,
            db.path().display()
        ),
    }
}

/// `--label`, `--machine`: a name that is not empty or blank (history orders and groups by
/// it) and holds no control character ([`calbench::error::is_hidden`]).
fn not_blank(text: &str) -> std::result::Result<String, String> {
    if text.trim().is_empty() {
        return Err("must not be empty: history orders and groups the records by it".into());
    }
    if text.chars().any(calbench::error::is_hidden) {
        let msg = "must be a name without control characters (bidirectional overrides \
                   included): history shows it on the terminal and in its pages and CSV";
        return Err(msg.into());
    }
    Ok(text.to_string())
}

/// Reads every folder first (a bad one is refused before anything is stored), then records
/// each.
pub fn run(args: &RecordArgs) -> Result<()> {
    if let Some(d) = args.dirs.iter().find(|d| !d.exists()) {
        let why = format!("{} does not exist", d.display());
        return Err(calbench::Error::setting("DIR", why).into());
    }
    let records = args
        .dirs
        .iter()
        .map(|d| Record::of_folder(d, args.scenario.as_deref(), args.task.as_deref()))
        .collect::<calbench::Result<Vec<Record>>>()?;
    let mut db = args.db.open(true)?;
    let p = Provenance::here(args.label.as_deref(), args.machine.as_deref());
    for r in &records {
        let done = db.record(r, &p)?;
        report(r, done, &db);
    }
    Ok(())
}

/// The record of a finished registration or instruments study (or its merge, `kind`) in
/// `out`, read from the folder as `calbench record` reads it.
pub fn of_study(out: &Path, kind: Kind) -> Result<Record> {
    let mut r = Record::of_folder(out, None, None)?;
    r.kind = kind;
    Ok(r)
}

/// The record of a finished run or merge into `out` of the scenario `sc`.
pub fn of_run(out: &Path, sc: &calbench::study::scenario::Scenario, kind: Kind) -> Result<Record> {
    Ok(Record::of_run(out, sc, kind)?)
}

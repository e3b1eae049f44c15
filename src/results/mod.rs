//! The results database (docs/formats.md, "The results database"): runs, merges,
//! identifications and task entries recorded in one SQLite file, each with its scenario,
//! provenance ([`provenance`]) and every figure with its interval; the history of a metric
//! across versions ([`history`]) and the leaderboard of the tasks ([`board`]) read it back.
//!
//! The schema is versioned by SQLite's `PRAGMA user_version` and migrated forward when a
//! database is opened; a database of a newer schema is refused. A record is identified by a
//! content hash ([`Record`]'s kind, scenario hash and document, the version label and the
//! machine), so recording the same output twice adds nothing.
//!
//! This layer sits above `report` (whose noise rule the history applies) and `study`; nothing
//! below it imports it.

pub mod board;
pub mod folder;
pub mod history;
pub mod provenance;

use std::path::{Path, PathBuf};

use rusqlite::{params, Connection, OptionalExtension};

pub use folder::{Kind, Record};
pub use provenance::Provenance;

use crate::error::{Error, Result};

/// The database's default path, under the current folder.
pub const DEFAULT_PATH: &str = "results/calbench.sqlite";

/// The schema version this calbench writes (`PRAGMA user_version`).
pub const SCHEMA_VERSION: i64 = 1;

/// The migrations, in order: `MIGRATIONS[i]` takes a database from version `i` to `i + 1`.
const MIGRATIONS: [&str; 1] = [r"
CREATE TABLE runs (
  id INTEGER PRIMARY KEY,
  content_hash TEXT NOT NULL UNIQUE,
  kind TEXT NOT NULL,
  scenario TEXT NOT NULL,
  scenario_hash TEXT NOT NULL,
  scenario_text TEXT NOT NULL,
  seed INTEGER,
  trials TEXT,
  label TEXT NOT NULL,
  calbench_version TEXT NOT NULL,
  git_commit TEXT NOT NULL,
  cargo_lock_hash TEXT NOT NULL,
  machine TEXT NOT NULL,
  cpu TEXT NOT NULL,
  cores INTEGER NOT NULL,
  os TEXT NOT NULL,
  recorded_at TEXT NOT NULL,
  source TEXT NOT NULL,
  document TEXT NOT NULL
);
CREATE TABLE entries (
  run INTEGER NOT NULL REFERENCES runs(id),
  entry TEXT NOT NULL,
  method TEXT NOT NULL,
  PRIMARY KEY (run, entry)
);
CREATE TABLE figures (
  run INTEGER NOT NULL REFERENCES runs(id),
  entry TEXT NOT NULL,
  metric TEXT NOT NULL,
  value REAL NOT NULL,
  ci_lo REAL,
  ci_hi REAL,
  PRIMARY KEY (run, entry, metric)
);
CREATE TABLE tasks (
  run INTEGER PRIMARY KEY REFERENCES runs(id),
  task TEXT NOT NULL,
  task_hash TEXT NOT NULL,
  metric TEXT NOT NULL,
  value REAL NOT NULL,
  ci_lo REAL,
  ci_hi REAL,
  division TEXT NOT NULL,
  method TEXT NOT NULL,
  models TEXT NOT NULL,
  chosen_by TEXT NOT NULL,
  entrant TEXT NOT NULL
);
CREATE TABLE published (
  run INTEGER NOT NULL REFERENCES runs(id),
  task TEXT NOT NULL,
  label TEXT NOT NULL,
  value REAL NOT NULL,
  source TEXT NOT NULL,
  division TEXT NOT NULL
);
CREATE INDEX figures_metric ON figures (metric);
CREATE INDEX runs_scenario ON runs (scenario, machine);
"];

/// An open results database.
pub struct Db {
    conn: Connection,
    path: PathBuf,
}

/// What recording did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Recorded {
    /// A new record, with its id.
    Added(i64),
    /// The same record was there already, with its id: nothing was added.
    AlreadyThere(i64),
}

/// The database path: `given` (`--db`), else `CALBENCH_DB`, else [`DEFAULT_PATH`].
pub fn db_path(given: Option<&Path>) -> PathBuf {
    given
        .map(Path::to_path_buf)
        .or_else(|| {
            std::env::var_os("CALBENCH_DB")
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
        })
        .unwrap_or_else(|| PathBuf::from(DEFAULT_PATH))
}

impl Db {
    /// Opens (`create`: or creates, with its folder) the database at `path` and migrates it
    /// to [`SCHEMA_VERSION`]; refuses a database of a newer schema, or a file that is not one.
    pub fn open(path: &Path, create: bool) -> Result<Db> {
        let bad = |e: rusqlite::Error| {
            Error::file(
                path,
                "database",
                format!("not a usable SQLite database ({e})"),
            )
        };
        if !path.exists() {
            if !create {
                return Err(Error::file(
                    path,
                    "database",
                    "does not exist; record results first (`calbench record DIR`)",
                ));
            }
            if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
                std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
            }
        }
        let conn = Connection::open(path).map_err(bad)?;
        conn.busy_timeout(std::time::Duration::from_secs(30))
            .map_err(bad)?;
        let version: i64 = conn
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .map_err(bad)?;
        if version > SCHEMA_VERSION {
            return Err(Error::file(
                path,
                "user_version",
                format!(
                    "the database has schema version {version}, newer than this calbench's \
                     {SCHEMA_VERSION}; use a newer calbench (nothing was changed)"
                ),
            ));
        }
        if version < 0 {
            return Err(Error::file(
                path,
                "user_version",
                format!("{version} is not a schema version"),
            ));
        }
        for (i, sql) in MIGRATIONS.iter().enumerate().skip(version as usize) {
            let tx = conn.unchecked_transaction().map_err(bad)?;
            tx.execute_batch(sql).map_err(bad)?;
            tx.pragma_update(None, "user_version", (i + 1) as i64)
                .map_err(bad)?;
            tx.commit().map_err(bad)?;
        }
        Ok(Db {
            conn,
            path: path.to_path_buf(),
        })
    }

    /// The connection, for the queries of [`history`] and [`board`].
    pub fn conn(&self) -> &Connection {
        &self.conn
    }

    fn sql_error(&self, e: rusqlite::Error) -> Error {
        Error::file(&self.path, "database", e.to_string())
    }

    /// Stores `record` with its provenance `p`, in one transaction; nothing when a record of
    /// the same content hash is there.
    pub fn record(&mut self, record: &Record, p: &Provenance) -> Result<Recorded> {
        let (version, commit) = match &record.results.ran_with {
            Some((v, c)) => (v.as_str(), c.as_str()),
            None => (p.version.as_str(), p.git_commit.as_str()),
        };
        let hash = provenance::sha256_hex(
            [
                record.kind.as_str(),
                &record.scenario.hash,
                &record.output.source_and_document.1,
                &p.label,
                &p.machine,
            ]
            .join("\u{0}")
            .as_bytes(),
        );
        let path = self.path.clone();
        let err = move |e: rusqlite::Error| Error::file(&path, "database", e.to_string());
        let tx = self.conn.transaction().map_err(&err)?;
        let had: Option<i64> = tx
            .query_row(
                "SELECT id FROM runs WHERE content_hash = ?1",
                [&hash],
                |r| r.get(0),
            )
            .optional()
            .map_err(&err)?;
        if let Some(id) = had {
            return Ok(Recorded::AlreadyThere(id));
        }
        tx.execute(
            "INSERT INTO runs (content_hash, kind, scenario, scenario_hash, scenario_text, seed, \
             trials, label, calbench_version, git_commit, cargo_lock_hash, machine, cpu, cores, \
             os, recorded_at, source, document) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, \
             ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18)",
            params![
                hash,
                record.kind.as_str(),
                record.scenario.name,
                record.scenario.hash,
                record.scenario.text,
                record.output.seed.map(|s| s as i64),
                record.output.trials,
                p.label,
                version,
                commit,
                p.cargo_lock_hash,
                p.machine,
                p.cpu,
                p.cores,
                p.os,
                p.recorded_at,
                record.output.source_and_document.0,
                record.output.source_and_document.1
            ],
        )
        .map_err(&err)?;
        let id = tx.last_insert_rowid();
        for e in &record.results.entries {
            tx.execute(
                "INSERT INTO entries (run, entry, method) VALUES (?1, ?2, ?3)",
                params![id, e.name, e.method],
            )
            .map_err(&err)?;
        }
        {
            let mut ins = tx
                .prepare(
                    "INSERT INTO figures (run, entry, metric, value, ci_lo, ci_hi) \
                     VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
                )
                .map_err(&err)?;
            for f in &record.results.figures {
                ins.execute(params![
                    id,
                    f.entry,
                    f.metric,
                    f.value,
                    f.ci.map(|c| c[0]),
                    f.ci.map(|c| c[1])
                ])
                .map_err(&err)?;
            }
        }
        if let Some(t) = &record.results.task {
            tx.execute(
                "INSERT INTO tasks (run, task, task_hash, metric, value, ci_lo, ci_hi, division, \
                 method, models, chosen_by, entrant) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, \
                 ?9, ?10, ?11, ?12)",
                params![
                    id,
                    t.task,
                    record.scenario.hash,
                    t.metric,
                    t.value,
                    t.ci.map(|c| c[0]),
                    t.ci.map(|c| c[1]),
                    t.division,
                    t.method,
                    t.models,
                    t.chosen_by,
                    t.entrant
                ],
            )
            .map_err(&err)?;
            for (label, value, source, division) in &t.published {
                tx.execute(
                    "INSERT INTO published (run, task, label, value, source, division) \
                     VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
                    params![id, t.task, label, value, source, division],
                )
                .map_err(&err)?;
            }
        }
        tx.commit().map_err(&err)?;
        Ok(Recorded::Added(id))
    }

    /// The path of the database.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Runs a query, mapping an SQL error to one naming the database.
    pub fn query<T>(
        &self,
        sql: &str,
        params: impl rusqlite::Params,
        row: impl FnMut(&rusqlite::Row<'_>) -> rusqlite::Result<T>,
    ) -> Result<Vec<T>> {
        let mut st = self.conn.prepare(sql).map_err(|e| self.sql_error(e))?;
        let rows = st
            .query_map(params, row)
            .map_err(|e| self.sql_error(e))?
            .collect::<rusqlite::Result<Vec<T>>>()
            .map_err(|e| self.sql_error(e));
        rows
    }
}

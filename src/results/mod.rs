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
mod identified;
pub mod provenance;
mod reader;
pub use crate::analysis::regression::a_shard;
mod whole;

use std::path::{Path, PathBuf};

use rusqlite::types::ValueRef;
use rusqlite::{params, Connection, OpenFlags, OptionalExtension, TransactionBehavior};

pub use folder::{Kind, Record};
pub use provenance::Provenance;

use crate::error::{Error, Result};

/// The database's default path, under the current folder.
pub const DEFAULT_PATH: &str = "results/calbench.sqlite";

/// How long a connection waits for another process's write before it gives up.
pub const BUSY_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(60);

/// The schema version this calbench writes (`PRAGMA user_version`).
pub const SCHEMA_VERSION: i64 = 2;

/// The migrations, in order: `MIGRATIONS[i]` takes a database from version `i` to `i + 1`.
/// Version 2 adds the time of calbench's commit, which orders versions of equal number.
const MIGRATIONS: [&str; 2] = [
    r"
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
",
    "ALTER TABLE runs ADD COLUMN commit_time INTEGER;",
];

/// The tables of the database `conn` (SQLite's own left out), by name, as `(table, columns)`
/// with each column as `name type`.
fn tables_of(conn: &Connection) -> rusqlite::Result<Vec<(String, Vec<String>)>> {
    let names: Vec<String> = conn
        .prepare(
            "SELECT name FROM sqlite_schema WHERE type = 'table' AND name NOT LIKE 'sqlite_%' \
             ORDER BY name",
        )?
        .query_map([], |r| r.get(0))?
        .collect::<rusqlite::Result<_>>()?;
    names
        .into_iter()
        .map(|t| {
            let cols = conn
                .prepare("SELECT name, type FROM pragma_table_info(?1) ORDER BY cid")?
                .query_map([&t], |r| {
                    Ok(format!(
                        "{} {}",
                        r.get::<_, String>(0)?,
                        r.get::<_, String>(1)?
                    ))
                })?
                .collect::<rusqlite::Result<Vec<String>>>()?;
            Ok((t, cols))
        })
        .collect()
}

/// Why the database `conn`, of schema version `v` (`0..=SCHEMA_VERSION`), is not a calbench
/// results database, or `None` when it is one (or is empty: a new database). Reads only: the
/// tables and their columns must be those of calbench's schema `v` (a database of version 0
/// has no table); tables beside them are allowed in a database of calbench's.
fn not_calbench(conn: &Connection, v: i64) -> rusqlite::Result<Option<String>> {
    let have = tables_of(conn)?;
    let schema = |v: i64| -> rusqlite::Result<Vec<(String, Vec<String>)>> {
        let mem = Connection::open_in_memory()?;
        for sql in &MIGRATIONS[..v as usize] {
            mem.execute_batch(sql)?;
        }
        tables_of(&mem)
    };
    if v == 0 {
        if have.is_empty() {
            return Ok(None);
        }
        let ours = schema(SCHEMA_VERSION)?;
        if let Some((t, _)) = have.iter().find(|(t, _)| ours.iter().any(|(o, _)| o == t)) {
            return Ok(Some(format!("table `{t}` has another schema")));
        }
        let list = have
            .iter()
            .map(|(t, _)| format!("`{t}`"))
            .collect::<Vec<_>>()
            .join(", ");
        return Ok(Some(format!(
            "no calbench schema: user_version 0, and it holds table {list}"
        )));
    }
    for (t, cols) in schema(v)? {
        match have.iter().find(|(h, _)| *h == t) {
            None => {
                return Ok(Some(format!(
                    "user_version {v}, but no table `{t}` of calbench's schema {v}"
                )))
            }
            Some((_, h)) if *h != cols => {
                return Ok(Some(format!("table `{t}` has another schema")));
            }
            Some(_) => {}
        }
    }
    Ok(None)
}

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

/// Whether a reader failed because SQLite could not open or create the write-ahead log's
/// shared-memory file (`PATH-shm`) beside the database: its folder cannot be written.
fn cannot_share(e: &rusqlite::Error) -> bool {
    use rusqlite::ErrorCode::{CannotOpen, ReadOnly};
    matches!(e, rusqlite::Error::SqliteFailure(f, _) if matches!(f.code, ReadOnly | CannotOpen))
}

/// The database at `path` opened to read as a file that does not change (SQLite's
/// `immutable`), for a reader in a folder it cannot write: safe when every commit is in the
/// file, that is when its write-ahead log (`PATH-wal`) is absent or empty, since no writer can
/// create one there either. Refused, naming the log, when it holds commits.
fn unchanging(path: &Path, bad: impl Fn(rusqlite::Error) -> Error) -> Result<Connection> {
    let mut wal = path.as_os_str().to_owned();
    wal.push("-wal");
    let wal = PathBuf::from(wal);
    if std::fs::metadata(&wal).is_ok_and(|m| m.len() > 0) {
        return Err(Error::file(
            &wal,
            "database",
            format!(
                "holds commits not yet written into {}, and its folder cannot be written, so \
                 SQLite cannot read them (it needs the file -shm beside it); open the database \
                 once where its folder can be written (nothing was changed)",
                path.display()
            ),
        ));
    }
    // A URI: the path's bytes beyond the unreserved ones percent-encoded, an absolute path
    // after an empty authority (`file:///…`).
    let mut uri = String::from(if path.is_absolute() {
        "file://"
    } else {
        "file:"
    });
    for &b in path.as_os_str().as_encoded_bytes() {
        match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' | b'/' => {
                uri.push(b as char)
            }
            _ => uri.push_str(&format!("%{b:02X}")),
        }
    }
    uri.push_str("?immutable=1");
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY
        | OpenFlags::SQLITE_OPEN_NO_MUTEX
        | OpenFlags::SQLITE_OPEN_URI;
    Connection::open_with_flags(uri, flags).map_err(bad)
}

impl Db {
    /// Refuses, naming `path` and its key `database`, a database that cannot be created
    /// because a folder to hold it is a file.
    pub fn creatable(path: &Path) -> Result<()> {
        let mut up = path.parent();
        while let Some(p) = up.filter(|p| !p.as_os_str().is_empty()) {
            if p.exists() {
                if !p.is_dir() {
                    let why = format!("cannot be created: {} is not a folder", p.display());
                    return Err(Error::file(path, "database", why));
                }
                break;
            }
            up = p.parent();
        }
        Ok(())
    }

    /// Opens the database at `path`. With `create` (the commands that record) it is opened
    /// for writing, created with its folder when absent, put in write-ahead-log mode (readers
    /// never block the writer) and migrated to [`SCHEMA_VERSION`] in one immediate
    /// transaction that reads the version again once it holds the lock, so that two processes
    /// creating or migrating the same database at once do it once; without `create` (the
    /// commands that only read) it is opened read-only and nothing is written to it (in a
    /// folder it cannot write, as a file that does not change: `unchanging`), and a
    /// database of an older schema is refused until a recording command migrates it. Every
    /// connection waits up to [`BUSY_TIMEOUT`] for another writer. Refuses a file that is not
    /// an SQLite database, one whose integrity check fails (damaged pages: it would answer
    /// wrongly), and a database of a newer schema.
    pub fn open(path: &Path, create: bool) -> Result<Db> {
        let bad = |e: rusqlite::Error| {
            Error::file(
                path,
                "database",
                format!("not a usable SQLite database ({e})"),
            )
        };
        if path.is_dir() {
            return Err(Error::file(
                path,
                "database",
                "is a folder: give the database's file (results/calbench.sqlite by default)",
            ));
        }
        if !crate::error::exists(path)? {
            if !create {
                return Err(Error::file(
                    path,
                    "database",
                    "does not exist; record results first (`calbench record DIR`)",
                ));
            }
            Db::creatable(path)?;
            if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
                std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
            }
        }
        let flags = if create {
            OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_CREATE
        } else {
            OpenFlags::SQLITE_OPEN_READ_ONLY
        } | OpenFlags::SQLITE_OPEN_NO_MUTEX
            | OpenFlags::SQLITE_OPEN_URI;
        let quick_check = |c: &Connection| c.query_row("PRAGMA quick_check", [], |r| r.get(0));
        let mut conn = Connection::open_with_flags(path, flags).map_err(bad)?;
        conn.busy_timeout(BUSY_TIMEOUT).map_err(bad)?;
        let check: String = match quick_check(&conn) {
            Err(e) if !create && cannot_share(&e) => {
                conn = unchanging(path, bad)?;
                quick_check(&conn).map_err(bad)?
            }
            r => r.map_err(bad)?,
        };
        if check != "ok" {
            return Err(Error::file(
                path,
                "database",
                format!(
                    "fails SQLite's integrity check ({check}): the file is damaged, and its \
                     answers could be wrong; restore it from a copy (nothing was changed)"
                ),
            ));
        }
        // The schema version, refused when newer than this calbench's.
        let version = |c: &Connection| -> Result<i64> {
            let v: i64 = c
                .query_row("PRAGMA user_version", [], |r| r.get(0))
                .map_err(bad)?;
            if v > SCHEMA_VERSION {
                return Err(Error::file(
                    path,
                    "user_version",
                    format!(
                        "the database has schema version {v}, newer than this calbench's \
                         {SCHEMA_VERSION}; use a newer calbench (nothing was changed)"
                    ),
                ));
            }
            Ok(v)
        };
        // The version and the tables are read in one read transaction, so that they are of
        // one state of the file: read apart, another process creating the database could
        // commit its tables in between, and they would be judged against version 0.
        let snapshot = conn
            .transaction_with_behavior(TransactionBehavior::Deferred)
            .map_err(bad)?;
        let v = version(&snapshot)?;
        if v < 0 {
            return Err(Error::file(
                path,
                "user_version",
                format!("{v} is not a schema version"),
            ));
        }
        // Before anything that writes (the journal mode, a migration): another program's
        // database, or one whose tables are not calbench's, is refused and left unchanged.
        let foreign = not_calbench(&snapshot, v).map_err(bad)?;
        snapshot.finish().map_err(bad)?;
        if let Some(why) = foreign {
            return Err(Error::file(
                path,
                "database",
                format!("not a calbench results database ({why}); nothing was changed"),
            ));
        }
        if !create {
            if v == 0 {
                // No table (another program's would have been refused above): an empty file,
                // such as `/dev/null`, which holds no results to read.
                return Err(Error::file(
                    path,
                    "database",
                    "holds no recorded results (an empty file, not yet a calbench results \
                     database); record results first (`calbench record DIR --db FILE`)",
                ));
            }
            if v < SCHEMA_VERSION {
                return Err(Error::file(
                    path,
                    "user_version",
                    format!(
                        "the database has schema version {v}, older than this calbench's \
                         {SCHEMA_VERSION}; `calbench record` migrates it (nothing was changed)"
                    ),
                ));
            }
            return Ok(Db {
                conn,
                path: path.to_path_buf(),
            });
        }
        // WAL: a writer and readers at once; the mode is kept in the file. Setting it takes a
        // lock, which the busy handler does not wait for: retried until the timeout.
        let start = std::time::Instant::now();
        loop {
            match conn.query_row("PRAGMA journal_mode = WAL", [], |r| r.get::<_, String>(0)) {
                Ok(_) => break,
                Err(_) if start.elapsed() < BUSY_TIMEOUT => {
                    std::thread::sleep(std::time::Duration::from_millis(20));
                }
                Err(e) => return Err(bad(e)),
            }
        }
        if v < SCHEMA_VERSION {
            let tx = conn
                .transaction_with_behavior(TransactionBehavior::Immediate)
                .map_err(bad)?;
            // Another process may have migrated it while this one waited for the lock.
            let now = version(&tx)?;
            for (i, sql) in MIGRATIONS.iter().enumerate().skip(now.max(0) as usize) {
                tx.execute_batch(sql).map_err(bad)?;
                tx.pragma_update(None, "user_version", (i + 1) as i64)
                    .map_err(bad)?;
            }
            tx.commit().map_err(bad)?;
        }
        Ok(Db {
            conn,
            path: path.to_path_buf(),
        })
    }

    fn sql_error(&self, e: rusqlite::Error) -> Error {
        Error::file(&self.path, "database", e.to_string())
    }

    /// Stores `record` with its provenance `p`, in one transaction; nothing when a record of
    /// the same content hash is there.
    pub fn record(&mut self, record: &Record, p: &Provenance) -> Result<Recorded> {
        let (version, commit, commit_time) = match &record.results.ran_with {
            Some((v, c)) => (v.as_str(), c.as_str(), None),
            None => (p.version.as_str(), p.git_commit.as_str(), p.commit_time),
        };
        let hash_as = |kind: Kind| {
            provenance::sha256_hex(
                [
                    kind.as_str(),
                    &record.scenario.hash,
                    &record.output.source_and_document.1,
                    &p.label,
                    &p.machine,
                ]
                .join("\u{0}")
                .as_bytes(),
            )
        };
        let hash = hash_as(record.kind);
        // A merged folder holds the bytes of the run it merges, and `record` of it reads it
        // as a run: the same results, whichever of the two recorded them first.
        let twin = match record.kind {
            Kind::Run => hash_as(Kind::Merge),
            Kind::Merge => hash_as(Kind::Run),
            _ => hash.clone(),
        };
        let path = self.path.clone();
        let err = move |e: rusqlite::Error| Error::file(&path, "database", e.to_string());
        // Immediate: the write lock is taken (waiting for another writer) before the
        // content hash is looked up, so two processes recording the same folder add it once.
        let tx = self
            .conn
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(&err)?;
        let had: Option<i64> = tx
            .query_row(
                "SELECT id FROM runs WHERE content_hash IN (?1, ?2)",
                [&hash, &twin],
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
             os, recorded_at, source, document, commit_time) VALUES (?1, ?2, ?3, ?4, ?5, ?6, \
             ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19)",
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
                record.output.source_and_document.1,
                commit_time
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

    /// Runs a query whose rows deserialise to `T` by column name (integers, reals, text and
    /// NULLs as serde_json reads them), mapping an error to one naming the database.
    pub fn query_as<T: serde::de::DeserializeOwned>(
        &self,
        sql: &str,
        params: impl rusqlite::Params,
    ) -> Result<Vec<T>> {
        let rows = self.query(sql, params, |r| {
            let names = AsRef::<rusqlite::Statement>::as_ref(r).column_names();
            let mut row = serde_json::Map::new();
            for (i, name) in names.into_iter().enumerate() {
                let v = match r.get_ref(i)? {
                    ValueRef::Null => serde_json::Value::Null,
                    ValueRef::Integer(n) => n.into(),
                    ValueRef::Real(x) => x.into(),
                    _ => serde_json::Value::String(r.get(i)?),
                };
                row.insert(name.to_string(), v);
            }
            Ok(serde_json::Value::Object(row))
        })?;
        rows.into_iter()
            .map(|v| {
                serde_json::from_value(v)
                    .map_err(|e| Error::file(&self.path, "database", e.to_string()))
            })
            .collect()
    }
}

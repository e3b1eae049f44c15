//! Another program's SQLite file given as the results database (docs/formats.md § 7.11.1):
//! `record`, `history` and `leaderboard` refuse it in one line naming the file, before
//! anything writes to it (the journal mode included), and leave it byte for byte as it was;
//! an empty file is a new database, as an absent one is.

use std::path::Path;

use crate::common::{calbench, calbench_ok, one_line_naming, path_arg, refused, tmp_dir};

/// A task folder as `calbench task` writes it (the `task.json` contract): something
/// `record` reads without a run.
fn task_folder(dir: &Path) -> std::path::PathBuf {
    let out = dir.join("t");
    std::fs::create_dir_all(&out).unwrap();
    let json = r#"{
  "format": "calbench-task-1",
  "task": "barrett-wam",
  "task_hash": "0f3c",
  "metric": "validation_mean_mm",
  "value": 3.0,
  "ci95": [2.8, 3.2],
  "division": "closed",
  "method": "lm",
  "models": ["kinematic"],
  "chosen_by": "cv",
  "entrant": "calbench",
  "calbench_version": "0.1.0", "git_commit": "0123456789abcdef0123456789abcdef01234567",
  "published": []
}
"#;
    std::fs::write(out.join("task.json"), json).unwrap();
    out
}

/// An SQLite file at `path` made by another program: the statements `sql`, committed.
fn foreign(path: &Path, sql: &str) {
    let c = rusqlite::Connection::open(path).unwrap();
    c.execute_batch(sql).unwrap();
}

/// `calbench ARGS --db DB` refuses `db` (exit 1) in one line naming it and `want`, and leaves
/// its bytes as they were, with no write-ahead log beside it.
fn refuses_unchanged(args: &[&str], db: &Path, want: &[&str]) {
    let before = std::fs::read(db).unwrap();
    let mut a = args.to_vec();
    a.extend(["--db", path_arg(db)]);
    let o = calbench(&a);
    let err = refused(&o, &["not a calbench results database"]);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    one_line_naming(err.trim_start_matches("error: "), db, want);
    assert!(
        std::fs::read(db).unwrap() == before,
        "{args:?} changed {db:?}"
    );
    let wal = db.with_extension("sqlite-wal");
    assert!(!wal.exists() || std::fs::metadata(&wal).unwrap().len() == 0);
}

#[test]
fn another_programs_database_is_refused_and_left_unchanged() {
    let dir = tmp_dir("cli-foreign-db");
    let t = task_folder(&dir);
    let (board, hist) = (dir.join("board"), dir.join("hist"));
    // Tables of another program, user_version 0: not calbench's.
    let db = dir.join("db.sqlite");
    foreign(&db, "CREATE TABLE foo(x); INSERT INTO foo VALUES (1);");
    let want = ["no calbench schema", "user_version 0", "`foo`"];
    refuses_unchanged(&["record", path_arg(&t)], &db, &want);
    refuses_unchanged(&["history", "--out", path_arg(&hist)], &db, &want);
    refuses_unchanged(&["leaderboard", "--out", path_arg(&board)], &db, &want);
    assert!(!board.exists() && !hist.exists());
    // A table of calbench's name but not its schema: refused in one line, the journal mode
    // (header bytes 18-19) untouched.
    let runs = dir.join("runs.sqlite");
    foreign(
        &runs,
        "CREATE TABLE runs(x text); INSERT INTO runs VALUES ('a');",
    );
    let want = ["table `runs` has another schema"];
    refuses_unchanged(&["record", path_arg(&t)], &runs, &want);
    refuses_unchanged(&["history", "--out", path_arg(&hist)], &runs, &want);
    // An empty file is a new database, as an absent one is.
    let empty = dir.join("empty.sqlite");
    std::fs::write(&empty, b"").unwrap();
    calbench_ok(&["record", path_arg(&t), "--db", path_arg(&empty)]);
    calbench_ok(&[
        "leaderboard",
        "--db",
        path_arg(&empty),
        "--out",
        path_arg(&board),
    ]);
    let absent = dir.join("new/calbench.sqlite");
    calbench_ok(&["record", path_arg(&t), "--db", path_arg(&absent)]);
    // Calbench's database with a table of its own beside calbench's: still calbench's.
    foreign(&absent, "CREATE TABLE notes(x);");
    let again = dir.join("board2");
    calbench_ok(&[
        "leaderboard",
        "--db",
        path_arg(&absent),
        "--out",
        path_arg(&again),
    ]);
}

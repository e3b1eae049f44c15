//! The results database end to end (docs/formats.md, "The results database"): `run
//! --record` and `record` of ci-guard runs, idempotent recording, the refusal of a newer
//! schema, `history` and its regressions (a planted one: the validation error 60 % larger
//! under a newer label), and `leaderboard` from task folders written to the `task.json`
//! contract; both pages opened in Chromium.

use std::path::Path;

use crate::common::{calbench, calbench_ok, path_arg, read, root, tmp_dir};
use crate::html::{browse, chromium, ci, self_contained};

fn ci_guard() -> String {
    root().join("scenarios/ci-guard.toml").display().to_string()
}

fn count(db: &Path, sql: &str) -> i64 {
    let c = rusqlite::Connection::open(db).unwrap();
    c.query_row(sql, [], |r| r.get(0)).unwrap()
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn recorded_ci_guard_runs_give_a_history_that_catches_a_planted_regression() {
    let dir = tmp_dir("cli-results-history");
    let db = dir.join("db/calbench.sqlite");
    let sc = ci_guard();
    let run = |seed: &str, out: &str, extra: &[&str]| {
        let mut args = vec!["run", &sc, "--trials", "12", "--seed", seed, "--out"];
        let out = dir.join(out);
        args.push(path_arg(&out));
        args.extend_from_slice(extra);
        calbench_ok(&args)
    };
    // One run recorded as it finishes, one recorded afterwards.
    let o = run(
        "1",
        "a",
        &["--record", "--db", path_arg(&db), "--label", "v1"],
    );
    assert!(stdout(&o).contains("recorded"), "{}", stdout(&o));
    run("2", "b", &[]);
    let rec = |what: &str, label: &str| {
        calbench_ok(&[
            "record",
            path_arg(&dir.join(what)),
            "--db",
            path_arg(&db),
            "--scenario",
            &sc,
            "--label",
            label,
        ])
    };
    rec("b", "v1");
    assert_eq!(count(&db, "SELECT COUNT(*) FROM runs"), 2);
    assert_eq!(count(&db, "SELECT COUNT(*) FROM entries"), 6);
    let figures = count(&db, "SELECT COUNT(*) FROM figures");
    // The first again: nothing added.
    let again = rec("a", "v1");
    assert!(
        stdout(&again).contains("nothing added"),
        "{}",
        stdout(&again)
    );
    assert_eq!(count(&db, "SELECT COUNT(*) FROM runs"), 2);
    assert_eq!(count(&db, "SELECT COUNT(*) FROM figures"), figures);

    let history = |extra: &[&str]| {
        let mut args = vec!["history", "--db", path_arg(&db)];
        args.extend_from_slice(extra);
        calbench(&args)
    };
    let o = history(&["--regressions"]);
    assert!(
        o.status.success(),
        "{}{}",
        stdout(&o),
        String::from_utf8_lossy(&o.stderr)
    );

    // The planted regression: run b with its validation error 60 % larger, recorded under a
    // newer label (a run of a changed scenario would be "scenario changed", not compared).
    let worse = crate::results_team::planted(&dir.join("b"), &dir, "c", 1.6);
    rec(worse.file_name().unwrap().to_str().unwrap(), "v2");
    let o = history(&["--regressions"]);
    let text = stdout(&o);
    assert!(!o.status.success(), "{text}");
    assert!(
        text.contains("ci-guard")
            && text.contains("v1 → v2")
            && text.contains("validation_after_mm"),
        "{text}"
    );

    let out = dir.join("hist");
    let o = history(&["--out", path_arg(&out), "--scenario", "ci-guard"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = read(&out.join("history.csv"));
    assert!(
        csv.starts_with("scenario,machine,kind,entry,metric,label,"),
        "{csv}"
    );
    assert_eq!(
        csv.lines().filter(|l| l.contains(",v2,")).count(),
        3 * 5,
        "{csv}"
    );
    assert!(csv
        .lines()
        .any(|l| l.contains("validation_after_mm.mean") && l.ends_with(",regression")));
    let page = out.join("history.html");
    let html = self_contained(&page);
    assert!(html.contains("validation_after_mm.mean") && html.contains("class=\"warn\""));
    if let Some(chrome) = chromium() {
        browse(&chrome, &page, &dir.join("browser"), 5);
    } else {
        assert!(!ci(), "no Chromium on the PATH");
    }
}

/// A task folder as `calbench task` writes it (the `task.json` contract).
fn task_folder(dir: &Path, name: &str, value: f64, division: &str, models: &str) {
    task_folder_at(dir, name, value, division, models, "0f3c");
}

/// [`task_folder`] of the version `hash` of the task.
fn task_folder_at(dir: &Path, name: &str, value: f64, division: &str, models: &str, hash: &str) {
    std::fs::create_dir_all(dir.join(name)).unwrap();
    let json = format!(
        r#"{{
  "format": "calbench-task-1",
  "task": "barrett-wam",
  "task_hash": "{hash}",
  "metric": "validation_mean_mm",
  "value": {value},
  "ci95": [{}, {}],
  "division": "{division}",
  "method": "lm",
  "models": [{models}],
  "chosen_by": "cv",
  "entrant": "calbench",
  "calbench_version": "0.1.0", "git_commit": "0123456789abcdef0123456789abcdef01234567",
  "published": [ {{"label": "MDH + learned residual", "value": 2.92, "source": "Jacobi 2025, table 3", "division": "open"}} ]
}}
"#,
        value - 0.2,
        value + 0.2
    );
    std::fs::write(dir.join(name).join("task.json"), json).unwrap();
}

#[test]
fn leaderboard_ranks_task_entries_beside_the_published_figures() {
    let dir = tmp_dir("cli-results-board");
    let db = dir.join("calbench.sqlite");
    task_folder(&dir, "closed", 3.09, "closed", "\"kinematic\"");
    task_folder(&dir, "open", 2.80, "open", "\"kinematic\", \"harmonics\"");
    let closed = dir.join("closed");
    let open = dir.join("open");
    calbench_ok(&[
        "record",
        path_arg(&closed),
        path_arg(&open),
        "--db",
        path_arg(&db),
    ]);
    let again = calbench_ok(&["record", path_arg(&open), "--db", path_arg(&db)]);
    assert!(stdout(&again).contains("nothing added"));
    assert_eq!(count(&db, "SELECT COUNT(*) FROM tasks"), 2);
    let out = dir.join("board");
    calbench_ok(&[
        "leaderboard",
        "--db",
        path_arg(&db),
        "--out",
        path_arg(&out),
    ]);
    let csv = read(&out.join("leaderboard.csv"));
    let rows = cells(&csv);
    let pick: Vec<(&str, &str, &str, &str)> =
        rows.iter().map(|r| (r[3], r[4], r[5], r[8])).collect();
    // The open entry's interval (2.6 – 3.0) holds the published 2.92: one rank for both.
    assert_eq!(
        pick,
        [
            ("closed", "1", "entry", "3.09"),
            ("open", "1", "entry", "2.8"),
            ("open", "1", "published", "2.92"),
        ],
        "{csv}"
    );
    // Every entry, the closed one too, against the published figure: the difference and its
    // interval (the entry's interval less the published point); none for the published row.
    let num = |s: &str| s.parse::<f64>().unwrap();
    for (row, value) in [(&rows[0], 3.09), (&rows[1], 2.80)] {
        assert!((num(row[14]) - (value - 2.92)).abs() < 1e-12, "{csv}");
        assert!((num(row[15]) - (value - 0.2 - 2.92)).abs() < 1e-12, "{csv}");
        assert!((num(row[16]) - (value + 0.2 - 2.92)).abs() < 1e-12, "{csv}");
    }
    // (The published row's source holds a comma, quoted: its last three cells.)
    assert_eq!(&rows[2][rows[2].len() - 3..], ["", "", ""], "{csv}");
    let page = out.join("leaderboard.html");
    let html = self_contained(&page);
    assert!(html.contains("barrett-wam") && html.contains("MDH + learned residual"));
    assert!(html.contains("closed division") && html.contains("open division"));
    // Each entrant's score across tasks: its best figure over the published 2.92.
    assert!(html.contains("Across tasks") && html.contains(&format!("{:.4}", 2.80 / 2.92)));
    if let Some(chrome) = chromium() {
        browse(&chrome, &page, &dir.join("browser"), 0);
    } else {
        assert!(!ci(), "no Chromium on the PATH");
    }
}

/// The task folders `dir/NAME` recorded one by one into `db`, and the leaderboard written
/// from it into `dir/board` (returned).
fn recorded_board(dir: &Path, db: &Path, names: &[&str]) -> std::path::PathBuf {
    for name in names {
        calbench_ok(&["record", path_arg(&dir.join(name)), "--db", path_arg(db)]);
    }
    let out = dir.join("board");
    calbench_ok(&["leaderboard", "--db", path_arg(db), "--out", path_arg(&out)]);
    out
}

/// The cells of each data row of a `leaderboard.csv`, split at every comma (a quoted cell
/// that holds one is split too).
fn cells(csv: &str) -> Vec<Vec<&str>> {
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect()
}

/// Intervals that do not overlap rank apart, an empty division says so, and the score across
/// tasks takes the best figure recorded where no figure is published.
#[test]
fn leaderboard_ranks_apart_only_what_the_intervals_separate() {
    let dir = tmp_dir("cli-results-board-ranks");
    let db = dir.join("calbench.sqlite");
    // Two open entries whose intervals (± 0.2) do not meet, a third overlapping the second.
    task_folder(&dir, "a", 2.00, "open", "\"kinematic\", \"harmonics\"");
    task_folder(&dir, "b", 2.50, "open", "\"kinematic\", \"gravity\"");
    task_folder(&dir, "c", 2.60, "open", "\"kinematic\", \"harmonics2\"");
    let out = recorded_board(&dir, &db, &["a", "b", "c"]);
    let csv = read(&out.join("leaderboard.csv"));
    let ranks: Vec<(&str, &str, &str)> = cells(&csv)
        .into_iter()
        .map(|r| (r[4], r[5], r[8]))
        .collect();
    assert_eq!(
        ranks,
        [
            ("1", "entry", "2"),
            ("2", "entry", "2.5"),
            ("2", "entry", "2.6"),
            // Every entry's interval lies wholly below the published 2.92.
            ("4", "published", "2.92"),
        ],
        "{csv}"
    );
    let html = read(&out.join("leaderboard.html"));
    assert!(
        html.contains("closed division: no entry recorded."),
        "{html}"
    );
}

/// Entries of one task recorded at two versions of what it fixes (its split changed between
/// the records) are ranked on two boards, each against its own published figure, and count
/// as two tasks across tasks; they had been ranked together on one board under the first
/// entry's hash.
#[test]
fn leaderboard_ranks_each_version_of_a_task_apart() {
    let dir = tmp_dir("cli-results-board-versions");
    let db = dir.join("calbench.sqlite");
    let (old, new) = ("0f3c0f3c0f3c0f3c", "1a2b1a2b1a2b1a2b");
    task_folder_at(&dir, "a", 2.00, "open", "\"kinematic\", \"harmonics\"", old);
    task_folder_at(&dir, "b", 2.50, "open", "\"kinematic\", \"gravity\"", new);
    let out = recorded_board(&dir, &db, &["a", "b"]);
    let csv = read(&out.join("leaderboard.csv"));
    let ranks: Vec<(&str, &str, &str, &str)> = cells(&csv)
        .into_iter()
        .map(|r| (r[1], r[4], r[5], r[8]))
        .collect();
    assert_eq!(
        ranks,
        [
            (old, "1", "entry", "2"),
            (old, "2", "published", "2.92"),
            (new, "1", "entry", "2.5"),
            (new, "2", "published", "2.92"),
        ],
        "{csv}"
    );
    let html = read(&out.join("leaderboard.html"));
    // Each version's board by its title; the one entrant scored over both, as two tasks.
    let titles = [old, new].map(|h| format!("barrett-wam (task hash {})", &h[..12]));
    assert!(titles.iter().all(|t| html.contains(t)), "{html}");
    assert!(html.contains(&titles.join(", ")), "{html}");
    assert!(html.contains("entries are ranked apart"), "{html}");
}

#[test]
fn a_database_of_a_newer_schema_or_a_folder_of_nothing_is_refused() {
    let dir = tmp_dir("cli-results-refusals");
    let db = dir.join("new.sqlite");
    rusqlite::Connection::open(&db)
        .unwrap()
        .pragma_update(None, "user_version", 99)
        .unwrap();
    task_folder(&dir, "t", 3.0, "closed", "\"kinematic\"");
    let o = calbench(&["record", path_arg(&dir.join("t")), "--db", path_arg(&db)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("new.sqlite") && err.contains("schema version 99") && err.contains("newer"),
        "{err}"
    );
    assert_eq!(count(&db, "PRAGMA user_version"), 99);
    std::fs::create_dir_all(dir.join("empty")).unwrap();
    let o = calbench(&[
        "record",
        path_arg(&dir.join("empty")),
        "--db",
        path_arg(&dir.join("x.sqlite")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("empty") && err.contains("nothing to record"),
        "{err}"
    );
    // The document given in place of its folder: named as a file, with the folder to give.
    let document = dir.join("t/task.json");
    let o = calbench(&[
        "record",
        path_arg(&document),
        "--db",
        path_arg(&dir.join("x.sqlite")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    let want = "is a file: record takes the folder that holds summary.json";
    assert!(
        !o.status.success()
            && err.contains(want)
            && err.contains(&format!("(here {})", dir.join("t").display())),
        "{err}"
    );
    assert!(
        !dir.join("x.sqlite").exists()
            || count(&dir.join("x.sqlite"), "SELECT COUNT(*) FROM runs") == 0
    );
    let o = calbench(&[
        "history",
        "--regressions",
        "--db",
        path_arg(&dir.join("absent.sqlite")),
    ]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("absent.sqlite"));
    // An empty file (or `/dev/null`) holds no results; it had been called a database of schema
    // version 0 that `record` migrates.
    let blank = dir.join("blank.sqlite");
    std::fs::write(&blank, "").unwrap();
    for db in [blank.as_path(), Path::new("/dev/null")] {
        let lb = dir.join("lb");
        for cmd in [
            &["history", "--out", path_arg(&lb)][..],
            &["leaderboard", "--out", path_arg(&lb)][..],
        ] {
            let mut args = cmd.to_vec();
            args.extend(["--db", path_arg(db)]);
            let o = calbench(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(
                !o.status.success()
                    && err.contains(&format!(
                        "{}: database: holds no recorded results",
                        db.display()
                    ))
                    && !err.contains("migrates"),
                "{err}"
            );
        }
    }
    assert_eq!(read(&blank), "");
    let bad = dir.join("t/task.json");
    std::fs::write(&bad, read(&bad).replace("\"closed\"", "\"middle\"")).unwrap();
    let o = calbench(&[
        "record",
        path_arg(&dir.join("t")),
        "--db",
        path_arg(&dir.join("y.sqlite")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("task.json") && err.contains("division"),
        "{err}"
    );
    // A folder that does not exist, an empty --label or --machine: refused, nothing stored.
    let z = dir.join("z.sqlite");
    let o = calbench(&[
        "record",
        path_arg(&dir.join("nowhere")),
        "--db",
        path_arg(&z),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("nowhere does not exist"),
        "{err}"
    );
    std::fs::write(&bad, read(&bad).replace("\"middle\"", "\"closed\"")).unwrap();
    for flag in ["--label", "--machine"] {
        let o = calbench(&[
            "record",
            path_arg(&dir.join("t")),
            "--db",
            path_arg(&z),
            flag,
            " ",
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("must not be empty"),
            "{flag}: {err}"
        );
        // A control character, which history wrote raw into its CSV and onto the terminal.
        let t = dir.join("t");
        for name in ["a\nb", "m\u{1b}[31m", "v1\u{202e}"] {
            let db = path_arg(&z);
            let o = calbench(&["record", path_arg(&t), "--db", db, flag, name]);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(
                !o.status.success() && err.contains("without control characters"),
                "{flag} {name:?}: {err}"
            );
            // The refusal repeats the value escaped, never the character itself.
            assert!(
                !err.contains(['\u{1b}', '\u{202e}']),
                "{flag} {name:?}: {err:?}"
            );
        }
    }
    assert!(!z.exists());
    // history of a scenario or a metric the database does not hold: refused, naming it.
    calbench_ok(&["record", path_arg(&dir.join("t")), "--db", path_arg(&z)]);
    let out = dir.join("hist");
    for (flag, typo) in [
        ("--scenario", "ci-gaurd"),
        ("--metric", "validation_aftr_mm"),
    ] {
        let args = [
            "history",
            "--db",
            path_arg(&z),
            flag,
            typo,
            "--out",
            path_arg(&out),
        ];
        let o = calbench(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(typo) && err.contains("recorded:"),
            "{err}"
        );
        assert!(!out.exists());
    }
}

/// A task folder carries the task file it ran (`task.toml`), and `record` takes the published
/// figures of `task.json` only from it: a row edited in `task.json` is refused, naming the
/// file, the line and the row (docs/formats.md § 9.3).
#[test]
fn record_refuses_a_published_row_that_is_not_the_task_files() {
    let dir = tmp_dir("cli-results-published");
    let task = crate::record_task::small_task(&dir);
    crate::record_task::run_entry(&task, &dir.join("t"));
    let record = |db: &Path| {
        let t = dir.join("t");
        calbench(&[
            "record",
            path_arg(&t),
            "--db",
            path_arg(db),
            "--task",
            path_arg(&task),
        ])
    };
    let db = dir.join("ok.sqlite");
    assert!(record(&db).status.success());
    assert_eq!(count(&db, "SELECT COUNT(*) FROM tasks"), 1);
    // The published figure edited in task.json: 2.92 → 1.5.
    let json = dir.join("t/task.json");
    let original = read(&json);
    std::fs::write(
        &json,
        read(&json).replace("\"value\": 2.92", "\"value\": 1.5"),
    )
    .unwrap();
    // The row's `{`, the line after the key's (1-based).
    let line = read(&json)
        .lines()
        .position(|l| l.contains("\"published\""))
        .unwrap()
        + 2;
    let db = dir.join("forged.sqlite");
    let o = record(&db);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("task.json")
            && err.contains(&format!("line {line}, published[0]"))
            && err.contains("task.toml"),
        "{err}"
    );
    // The published rows dropped: refused, naming the task file's row that is missing.
    let mut v: serde_json::Value = serde_json::from_str(&original).unwrap();
    v["published"] = serde_json::json!([]);
    std::fs::write(&json, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let o = record(&dir.join("dropped.sqlite"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("task.json: published: lacks") && err.contains("2.92"),
        "{err}"
    );
    // A validation row's error made negative (a distance is ≥ 0): refused at that row.
    let mut v: serde_json::Value = serde_json::from_str(&original).unwrap();
    let first = v["validation_errors_mm"][0].as_f64().unwrap();
    v["validation_errors_mm"][0] = serde_json::json!(-first);
    std::fs::write(&json, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let o = record(&dir.join("negative.sqlite"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("task.json: validation_errors_mm[0]: is -"),
        "{err}"
    );
    // A folder written before entries carried their task file: recorded as it is.
    std::fs::write(&json, &original).unwrap();
    std::fs::remove_file(dir.join("t/task.toml")).unwrap();
    assert!(record(&db).status.success());
}

/// A task record keeps the calbench version and commit its `task.json` names, never the
/// recording calbench's: a commit it leaves `null` (a task file outside a git repository)
/// is stored as `unknown`, without a commit time.
#[test]
fn a_task_record_keeps_the_version_that_ran_it() {
    let dir = tmp_dir("cli-results-task-version");
    let db = dir.join("calbench.sqlite");
    task_folder(&dir, "t", 3.09, "closed", "\"kinematic\"");
    let json = dir.join("t/task.json");
    let text = read(&json).replace(
        "\"calbench_version\": \"0.1.0\", \"git_commit\": \"0123456789abcdef0123456789abcdef01234567\"",
        "\"calbench_version\": \"0.0.9\", \"git_commit\": null",
    );
    std::fs::write(&json, text).unwrap();
    calbench_ok(&["record", path_arg(&dir.join("t")), "--db", path_arg(&db)]);
    let sql = "SELECT COUNT(*) FROM runs WHERE calbench_version = '0.0.9' \
               AND git_commit = 'unknown' AND commit_time IS NULL";
    assert_eq!(count(&db, sql), 1);
}

/// A published figure of 0 mm is no reference for a score across tasks (a figure relative to
/// it is not defined): that task is left out, and the entrant is scored on its other task
/// (the score had been infinite).
#[test]
fn a_reference_of_zero_is_left_out_of_the_scores() {
    let dir = tmp_dir("cli-results-board-zero");
    let db = dir.join("calbench.sqlite");
    task_folder_at(
        &dir,
        "a",
        3.00,
        "open",
        "\"kinematic\", \"harmonics\"",
        "0f3c",
    );
    task_folder_at(
        &dir,
        "z",
        2.00,
        "open",
        "\"kinematic\", \"harmonics\"",
        "1a2b",
    );
    let json = dir.join("z/task.json");
    std::fs::write(
        &json,
        read(&json).replace("\"value\": 2.92", "\"value\": 0"),
    )
    .unwrap();
    let out = recorded_board(&dir, &db, &["a", "z"]);
    let html = read(&out.join("leaderboard.html"));
    let scores = &html[html.rfind("Across tasks").expect("a score table")..];
    let scores = &scores[..scores.find("</table>").unwrap()];
    assert!(scores.contains(&format!("{:.4}", 3.00 / 2.92)), "{scores}");
    assert!(
        !scores.contains("inf") && !scores.contains("NaN"),
        "{scores}"
    );
}

/// `history` and `leaderboard` read the database: an `--out` folder that holds it under the
/// name of a file they write is refused before any work, and the database is kept (the page's
/// table had been written over it).
#[test]
fn a_page_is_not_written_over_the_database_it_reads() {
    let dir = tmp_dir("cli-results-db-as-output");
    task_folder(&dir, "closed", 3.09, "closed", "\"kinematic\"");
    for (command, file) in [
        ("history", "history.csv"),
        ("leaderboard", "leaderboard.csv"),
    ] {
        let folder = dir.join(command);
        let db = folder.join(file);
        calbench_ok(&[
            "record",
            path_arg(&dir.join("closed")),
            "--db",
            path_arg(&db),
        ]);
        let before = std::fs::read(&db).unwrap();
        let o = calbench(&[command, "--db", path_arg(&db), "--out", path_arg(&folder)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{command}: {err}");
        let want = format!("is an input of this command, and the command writes its {file} there");
        assert!(err.contains(&want), "{command}: {err}");
        assert_eq!(std::fs::read(&db).unwrap(), before, "{command}");
        assert!(
            !folder.join(format!("{command}.html")).exists(),
            "{command}"
        );
    }
}

/// A `task.json` key that is unknown, or missing, is refused at that key once, as
/// docs/formats.md § 9.3 names it (`published[0].labl`, not `published[0].labl.labl`;
/// `division`, not `.`).
#[test]
fn a_task_json_key_unknown_or_missing_is_named_once() {
    let dir = tmp_dir("cli-results-task-keys");
    let db = dir.join("calbench.sqlite");
    task_folder(&dir, "t", 3.09, "closed", "\"kinematic\"");
    let file = dir.join("t").join("task.json");
    let good = read(&file);
    for (from, to, place) in [
        (
            "\"division\": \"closed\"",
            "\"divison\": \"closed\"",
            "divison",
        ),
        ("{\"label\"", "{\"labl\"", "published[0].labl"),
        ("\"division\": \"closed\",", "", "division"),
    ] {
        std::fs::write(&file, good.replacen(from, to, 1)).unwrap();
        let o = calbench(&["record", path_arg(&dir.join("t")), "--db", path_arg(&db)]);
        let err = String::from_utf8_lossy(&o.stderr);
        let want = format!("task.json: {place}: not a calbench task.json: ");
        assert!(!o.status.success() && err.contains(&want), "{place}: {err}");
    }
}

//! The results database as a team uses it (docs/formats.md § 2.15–2.16, § 7.11): concurrent
//! `record`s all land; a damaged database is refused; the reading commands write nothing;
//! `record` stores the scenario a run ran and refuses another file or edited figures;
//! `history --regressions` orders versions by version, flags a drift spread over several
//! versions, and reports a changed scenario as such rather than as a regression.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::common::{
    calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir, write_scenario,
};

fn count(db: &Path, sql: &str) -> i64 {
    let c = rusqlite::Connection::open(db).unwrap();
    c.query_row(sql, [], |r| r.get(0)).unwrap()
}

fn text(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr)
}

/// A run of `scenarios/ci-guard.toml` into `dir/NAME` (`trials` trials, `seed`).
fn guard_run(dir: &Path, name: &str, trials: &str, seed: &str) -> PathBuf {
    let out = dir.join(name);
    let sc = root().join("scenarios/ci-guard.toml");
    calbench_ok(&[
        "run",
        path_arg(&sc),
        "--trials",
        trials,
        "--seed",
        seed,
        "--threads",
        "2",
        "--out",
        path_arg(&out),
    ]);
    out
}

/// A copy of run folder `src` at `dir/name` whose summary's validation_after_mm figures and
/// their intervals are multiplied by `scale` (a planted change of the run's accuracy).
pub fn planted(src: &Path, dir: &Path, name: &str, scale: f64) -> PathBuf {
    let out = dir.join(name);
    std::fs::create_dir_all(&out).unwrap();
    for f in std::fs::read_dir(src).unwrap() {
        let f = f.unwrap().path();
        if f.is_file() {
            std::fs::copy(&f, out.join(f.file_name().unwrap())).unwrap();
        }
    }
    let mut s = load_json(&src.join("summary.json"));
    for e in s["results"].as_array_mut().unwrap() {
        for key in ["validation_after_mm", "validation_after_mm_ci95"] {
            let Some(m) = e.get_mut(key).and_then(Value::as_object_mut) else {
                continue;
            };
            for v in m.values_mut() {
                *v = match v.take() {
                    Value::Number(n) => (n.as_f64().unwrap() * scale).into(),
                    Value::Array(a) => a
                        .iter()
                        .map(|x| x.as_f64().map_or(Value::Null, |x| (x * scale).into()))
                        .collect(),
                    other => other,
                };
            }
        }
    }
    let text = serde_json::to_string_pretty(&s).unwrap() + "\n";
    std::fs::write(out.join("summary.json"), text).unwrap();
    out
}

fn record(dir: &Path, db: &Path, label: &str) -> std::process::Output {
    calbench(&[
        "record",
        path_arg(dir),
        "--db",
        path_arg(db),
        "--label",
        label,
    ])
}

fn regressions(db: &Path) -> (bool, String) {
    let o = calbench(&["history", "--db", path_arg(db), "--regressions"]);
    (o.status.success(), text(&o))
}

/// Twenty processes at once into a database none of them finds: each creates it or waits.
/// Ten rounds, each into a fresh database: a process that read the schema version before
/// another committed the tables, and the tables after, judged calbench's own tables against
/// version 0 and refused the database (a race: seen in 6 of 60 rounds of 20 processes
/// started from a shell, and less often from this test).
#[test]
fn twenty_concurrent_records_all_land() {
    let dir = tmp_dir("cli-team-concurrent");
    let run = guard_run(&dir, "a", "2", "1");
    for round in 0..10 {
        let db = dir.join(format!("fresh-{round}/calbench.sqlite"));
        let children: Vec<_> = (0..20)
            .map(|i| {
                crate::common::bin()
                    .args(["record", path_arg(&run), "--db", path_arg(&db)])
                    .args(["--label", &format!("v1.{i}")])
                    .stdout(std::process::Stdio::piped())
                    .stderr(std::process::Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for c in children {
            let o = c.wait_with_output().unwrap();
            assert!(o.status.success(), "round {round}: {}", text(&o));
        }
        assert_eq!(count(&db, "SELECT COUNT(*) FROM runs"), 20);
        assert_eq!(count(&db, "SELECT COUNT(DISTINCT label) FROM runs"), 20);
    }
}

#[test]
fn a_damaged_database_is_refused_and_reading_writes_nothing() {
    let dir = tmp_dir("cli-team-damaged");
    let run = guard_run(&dir, "a", "2", "1");
    let db = dir.join("calbench.sqlite");
    for label in ["v1", "v2"] {
        assert!(record(&run, &db, label).status.success());
    }
    // Reading: the database is the same bytes afterwards, and no write-ahead log holds a
    // change (a read-only connection may leave SQLite's empty shared-memory index beside it).
    let files = |p: &Path| -> (Vec<u8>, u64) {
        let wal = p.with_file_name("calbench.sqlite-wal");
        let logged = std::fs::metadata(&wal).map_or(0, |m| m.len());
        (std::fs::read(p).unwrap(), logged)
    };
    let before = files(&db);
    calbench_ok(&["history", "--db", path_arg(&db), "--regressions"]);
    calbench_ok(&[
        "history",
        "--db",
        path_arg(&db),
        "--out",
        path_arg(&dir.join("h")),
    ]);
    calbench_ok(&[
        "leaderboard",
        "--db",
        path_arg(&db),
        "--out",
        path_arg(&dir.join("b")),
    ]);
    assert!(
        files(&db) == before,
        "a reading command changed the database"
    );
    // Damage the head of every page but the first (the b-tree pages' headers, the overflow
    // pages' links): every command refuses the file.
    let mut bytes = std::fs::read(&db).unwrap();
    assert!(bytes.len() > 3 * 4096, "{}", bytes.len());
    for page in bytes.chunks_mut(4096).skip(1) {
        for b in &mut page[..12] {
            *b = 0x5a;
        }
    }
    std::fs::write(&db, &bytes).unwrap();
    for args in [
        vec!["history", "--regressions"],
        vec!["leaderboard", "--out", path_arg(&dir.join("b2"))],
        vec!["record", path_arg(&run), "--label", "v3"],
    ] {
        let mut a = args.clone();
        a.extend(["--db", path_arg(&db)]);
        let o = calbench(&a);
        let t = text(&o);
        assert!(
            !o.status.success() && t.contains("calbench.sqlite") && t.contains("integrity"),
            "{args:?}: {t}"
        );
    }
    // A folder given as the database is said to be one (it had been "disk I/O error").
    let folder = dir.join("b");
    for args in [
        vec!["history", "--regressions"],
        vec!["record", path_arg(&run), "--label", "v3"],
    ] {
        let o = calbench(&[&args[..], &["--db", path_arg(&folder)]].concat());
        let t = text(&o);
        let want = "b: database: is a folder: give the database's file";
        assert!(!o.status.success() && t.contains(want), "{args:?}: {t}");
    }
}

#[test]
fn record_stores_the_scenario_that_ran_and_refuses_another_or_edited_figures() {
    let dir = tmp_dir("cli-team-record");
    let run = guard_run(&dir, "a", "3", "1");
    let db = dir.join("calbench.sqlite");
    let ran = read(&run.join("scenario.toml"));
    // Another scenario file: the tracker eight times noisier, under the same name.
    let other = read(&root().join("scenarios/ci-guard.toml")).replace(
        "[tracker]\n",
        "[tracker]\nmpe_a_um = 120.0\nmpe_b_um_per_m = 48.0\n",
    );
    let other_path = dir.join("ci-guard.toml");
    std::fs::write(&other_path, other).unwrap();
    let o = calbench(&[
        "record",
        path_arg(&run),
        "--db",
        path_arg(&db),
        "--scenario",
        path_arg(&other_path),
    ]);
    let t = text(&o);
    let stated = ran.lines().next().unwrap().rsplit(' ').next().unwrap();
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("ci-guard.toml") && t.contains(stated) && t.contains("is not the scenario"),
        "{t}"
    );
    assert!(!db.exists() || count(&db, "SELECT COUNT(*) FROM runs") == 0);
    // The file it ran, and no file at all: both store the scenario as run.
    let given = root().join("scenarios/ci-guard.toml");
    calbench_ok(&[
        "record",
        path_arg(&run),
        "--db",
        path_arg(&db),
        "--scenario",
        path_arg(&given),
        "--label",
        "v1",
    ]);
    assert!(record(&run, &db, "v2").status.success());
    let c = rusqlite::Connection::open(&db).unwrap();
    let hashes: Vec<(String, String)> = c
        .prepare("SELECT scenario_hash, scenario_text FROM runs")
        .unwrap()
        .query_map([], |r| Ok((r.get(0)?, r.get(1)?)))
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(hashes.len(), 2);
    for (h, t) in &hashes {
        assert_eq!(h, stated);
        assert!(ran.ends_with(t.as_str()));
    }
    // An edited scenario.toml is refused by its own hash.
    let edited = planted(&run, &dir, "edited", 1.0);
    std::fs::write(
        edited.join("scenario.toml"),
        ran.replace("trials = 3", "trials = 4"),
    )
    .unwrap();
    let o = record(&edited, &db, "v3");
    assert!(
        !o.status.success() && text(&o).contains("scenario.toml") && text(&o).contains("edited"),
        "{}",
        text(&o)
    );
    // Edited figures: a mean outside its interval, a negative count of trials.
    let s = load_json(&run.join("summary.json"));
    let mut outside = s.clone();
    outside["results"][0]["validation_after_mm"]["mean"] = 99.0.into();
    let mut negative = s.clone();
    negative["trials"] = (-5).into();
    for (doc, key) in [(outside, "validation_after_mm.mean"), (negative, "trials")] {
        let bad = planted(&run, &dir, "bad", 1.0);
        std::fs::write(
            bad.join("summary.json"),
            serde_json::to_string_pretty(&doc).unwrap(),
        )
        .unwrap();
        let o = record(&bad, &db, "v4");
        let t = text(&o);
        assert!(
            !o.status.success() && t.contains("summary.json") && t.contains(key),
            "{key}: {t}"
        );
    }
    // The summary and trials of another run (seed 2, or 4 trials) beside this run's
    // scenario.toml: refused naming the summary's key and its line, which had been recorded
    // under the other run's seed.
    for (name, trials, seed, key, said) in [
        ("seed2", "3", "2", "seed", "is 2, but "),
        ("four", "4", "1", "trials", "is 4, but "),
    ] {
        let other = guard_run(&dir, name, trials, seed);
        std::fs::copy(run.join("scenario.toml"), other.join("scenario.toml")).unwrap();
        let o = record(&other, &db, "v5");
        let t = text(&o);
        let line = read(&other.join("summary.json"))
            .lines()
            .position(|l| l.trim_start().starts_with(&format!("\"{key}\"")))
            .unwrap();
        assert!(
            !o.status.success()
                && t.contains(&format!(
                    "{name}/summary.json: line {}, {key}: {said}",
                    line + 1
                ))
                && t.contains("is not of the run beside it"),
            "{name}: {t}"
        );
    }
    assert_eq!(count(&db, "SELECT COUNT(*) FROM runs"), 2);
}

#[test]
fn history_orders_versions_by_version_and_flags_a_drift() {
    let dir = tmp_dir("cli-team-history");
    let run = guard_run(&dir, "a", "60", "1");
    // v1.0, then v2.0 with the validation error 40 % worse, then a back-filled v0.9: the
    // latest version is v2.0, and it regressed against v1.0.
    let db = dir.join("order.sqlite");
    let worse = planted(&run, &dir, "worse", 1.4);
    let old = planted(&run, &dir, "old", 1.0);
    assert!(record(&run, &db, "v1.0").status.success());
    assert!(record(&worse, &db, "v2.0").status.success());
    assert!(record(&old, &db, "v0.9").status.success());
    let (ok, t) = regressions(&db);
    assert!(!ok, "{t}");
    assert!(
        t.contains("regression: ci-guard on ")
            && t.contains("v1.0 → v2.0")
            && t.contains("validation_after_mm"),
        "{t}"
    );
    // Three versions, each 4.9 % worse than the one before (within the tolerance of 5 %),
    // 15 % together: a drift from v1.0 to v1.3.
    let db = dir.join("drift.sqlite");
    assert!(record(&run, &db, "v1.0").status.success());
    for (k, label) in ["v1.1", "v1.2", "v1.3"].iter().enumerate() {
        let step = planted(&run, &dir, label, 1.049f64.powi(k as i32 + 1));
        assert!(record(&step, &db, label).status.success());
    }
    let (ok, t) = regressions(&db);
    assert!(!ok, "{t}");
    assert!(!t.contains("regression: ci-guard"), "{t}");
    assert!(
        t.contains("drift: ci-guard on ")
            && t.contains("v1.0 → v1.1 → v1.2 → v1.3 (3 steps, each within the tolerance)")
            && t.contains("validation_after_mm.mean"),
        "{t}"
    );
    // A version that ran another scenario: "scenario changed", not a regression.
    let db = dir.join("changed.sqlite");
    assert!(record(&run, &db, "v1.0").status.success());
    let changed = planted(&worse, &dir, "changed", 1.0);
    let sc = read(&changed.join("scenario.toml"));
    let body = sc
        .split_once('\n')
        .unwrap()
        .1
        .replace("count = 40", "count = 41");
    let head = sc.lines().next().unwrap();
    let (prefix, _) = head.rsplit_once(' ').unwrap();
    let hash = {
        use sha2::Digest;
        let d = sha2::Sha256::digest(body.as_bytes());
        d.iter().map(|b| format!("{b:02x}")).collect::<String>()
    };
    std::fs::write(
        changed.join("scenario.toml"),
        format!("{prefix} {hash}\n{body}"),
    )
    .unwrap();
    assert!(record(&changed, &db, "v2.0").status.success());
    let (ok, t) = regressions(&db);
    assert!(ok, "{t}");
    assert!(
        t.contains("scenario changed: ci-guard on ") && t.contains("v1.0 → v2.0"),
        "{t}"
    );
    assert!(!t.contains("regression: "), "{t}");
    // Back to v1.0's scenario, 40 % worse: judged against v1.0, the version before that
    // ran it (compared with v2.0 alone it had been "scenario changed", and passed).
    assert!(record(&worse, &db, "v3.0").status.success());
    let (ok, t) = regressions(&db);
    assert!(!ok, "{t}");
    assert!(
        t.contains("regression: ci-guard on ")
            && t.contains("v1.0 → v3.0")
            && t.contains("validation_after_mm"),
        "{t}"
    );
}

/// The guard's scenario written another way (integers for the tracker's pose, a default
/// written out; another description or `[report]`) runs the same bytes and is the same
/// scenario: `check` compares it with the
/// baseline, where it had refused it as another scenario's, and `history` flags a planted
/// regression of it, where it had said "scenario changed" and compared nothing.
#[test]
fn a_scenario_written_another_way_is_guarded_as_the_same() {
    let dir = tmp_dir("cli-team-spelling");
    let a = guard_run(&dir, "a", "10", "5");
    let spelled = read(&root().join("scenarios/ci-guard.toml"))
        .replace(
            "[2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]",
            "[2500, 0, 500, 0, 0, 180]",
        )
        .replace("[tracker]\n", "[tracker]\nmpe_a_um = 15.0\n");
    let sc = write_scenario(&dir, "spelled", &spelled);
    let b = dir.join("b");
    let args = ["--trials", "10", "--seed", "5", "--threads", "2", "--out"];
    calbench_ok(&[&["run", path_arg(&sc)][..], &args, &[path_arg(&b)]].concat());
    assert_eq!(read(&a.join("summary.json")), read(&b.join("summary.json")));
    assert_ne!(
        read(&a.join("scenario.toml")),
        read(&b.join("scenario.toml"))
    );
    let base = dir.join("base.json");
    calbench_ok(&["baseline", path_arg(&a), "--out", path_arg(&base)]);
    let summary = b.join("summary.json");
    let o = calbench(&["check", path_arg(&summary), "--baseline", path_arg(&base)]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("no regression beyond tolerance"),
        "{}",
        text(&o)
    );
    // Another description, and a `[report]` that reads the results another way, change no
    // trial (docs/formats.md § 2.4): `check` compares such a run too.
    let read_another_way = spelled
        .replace("description = \"", "description = \"edited: ")
        .replace(
            "[calibration]\n",
            "[report]\nbaseline = \"lm\"\n\n[calibration]\n",
        );
    let sc = write_scenario(&dir, "described", &read_another_way);
    let c = dir.join("c");
    calbench_ok(&[&["run", path_arg(&sc)][..], &args, &[path_arg(&c)]].concat());
    assert_eq!(read(&a.join("trials.csv")), read(&c.join("trials.csv")));
    let summary = c.join("summary.json");
    let o = calbench(&["check", path_arg(&summary), "--baseline", path_arg(&base)]);
    assert!(
        text(&o).contains("no regression beyond tolerance"),
        "{}",
        text(&o)
    );
    let db = dir.join("spelled.sqlite");
    assert!(record(&a, &db, "1.0.0").status.success());
    let worse = planted(&b, &dir, "worse", 2.0);
    assert!(record(&worse, &db, "1.1.0").status.success());
    let (ok, t) = regressions(&db);
    assert!(!ok, "{t}");
    assert!(
        t.contains("regression: ci-guard on ") && !t.contains("scenario changed"),
        "{t}"
    );
}

/// A merged folder holds a run's bytes and `record` reads it as a run: recorded by
/// `merge --record` and then by `record` (or the reverse) it is one record, where it was two
/// and `history` listed each point twice.
#[test]
fn a_merged_folder_recorded_twice_is_one_record() {
    let dir = tmp_dir("cli-team-merged");
    let sc = root().join("scenarios/ci-guard.toml");
    let shards: Vec<PathBuf> = (0..2)
        .map(|i| {
            let out = dir.join(format!("s{i}"));
            calbench_ok(&[
                "run",
                path_arg(&sc),
                "--trials",
                "4",
                "--shard",
                &format!("{i}/2"),
                "--out",
                path_arg(&out),
            ]);
            out
        })
        .collect();
    for (name, first_by_merge) in [("m1", true), ("m2", false)] {
        let (db, out) = (dir.join(format!("{name}.sqlite")), dir.join(name));
        let mut merge = vec!["merge", path_arg(&shards[0]), path_arg(&shards[1])];
        merge.extend(["--out", path_arg(&out)]);
        if first_by_merge {
            merge.extend(["--record", "--db", path_arg(&db), "--label", "v1"]);
        }
        calbench_ok(&merge);
        let o = record(&out, &db, "v1");
        assert!(o.status.success(), "{}", text(&o));
        if !first_by_merge {
            // The reverse: recorded as a run first, then merged again into another folder
            // with --record (the same bytes).
            let again = dir.join(format!("{name}-again"));
            let mut merge = vec!["merge", path_arg(&shards[0]), path_arg(&shards[1])];
            merge.extend(["--out", path_arg(&again), "--record", "--db", path_arg(&db)]);
            merge.extend(["--label", "v1"]);
            let o = calbench_ok(&merge);
            assert!(text(&o).contains("nothing added"), "{}", text(&o));
        } else {
            assert!(text(&o).contains("nothing added"), "{}", text(&o));
        }
        assert_eq!(count(&db, "SELECT COUNT(*) FROM runs"), 1, "{name}");
    }
}

/// `calbench ARGS` as a user who cannot write a folder its owner made read-only: this user,
/// or, under root (which writes anywhere), the user `nobody` through `setpriv`. `None` when
/// neither can be had outside CI.
fn unprivileged(args: &[&str]) -> Option<std::process::Output> {
    let uid = std::process::Command::new("id").arg("-u").output().unwrap();
    if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
        return Some(calbench(args));
    }
    let bin = env!("CARGO_BIN_EXE_calbench");
    let mut a = vec!["--reuid=65534", "--regid=65534", "--clear-groups", bin];
    a.extend(args);
    match std::process::Command::new("setpriv").args(&a).output() {
        Ok(o) => Some(o),
        Err(e) if matches!(std::env::var("CI").as_deref(), Ok("true" | "1")) => {
            panic!("setpriv: {e}")
        }
        Err(e) => {
            eprintln!("skipped: no setpriv to drop root's rights ({e})");
            None
        }
    }
}

/// A database in a folder its reader cannot write (a shared or published copy) is read by
/// `history` and `leaderboard`, which had refused it ("attempt to write a readonly database":
/// SQLite's write-ahead log wants its index file beside it), and nothing is written there; one
/// whose write-ahead log holds commits is refused, naming the log.
#[test]
fn a_database_in_a_folder_that_cannot_be_written_is_read() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tmp_dir("cli-team-readonly");
    let run = guard_run(&dir, "a", "2", "1");
    let (ro, outs) = (dir.join("ro"), dir.join("outs"));
    let db = ro.join("calbench.sqlite");
    for label in ["v1", "v2"] {
        assert!(record(&run, &db, label).status.success());
    }
    std::fs::create_dir_all(&outs).unwrap();
    let mode = |p: &Path, m: u32| std::fs::set_permissions(p, PermissionsExt::from_mode(m));
    mode(&outs, 0o777).unwrap();
    mode(&ro, 0o555).unwrap();
    let listing = |p: &Path| -> Vec<(String, Vec<u8>)> {
        let mut v: Vec<_> = std::fs::read_dir(p)
            .unwrap()
            .map(|f| f.unwrap().path())
            .map(|f| (f.display().to_string(), std::fs::read(&f).unwrap()))
            .collect();
        v.sort();
        v
    };
    let before = listing(&ro);
    for args in [
        vec!["history", "--regressions"],
        vec!["history", "--out", path_arg(&outs.join("h"))],
        vec!["leaderboard", "--out", path_arg(&outs.join("b"))],
    ] {
        let mut a = args.clone();
        a.extend(["--db", path_arg(&db)]);
        let Some(o) = unprivileged(&a) else { return };
        assert!(o.status.success(), "{args:?}: {}", text(&o));
    }
    assert!(read(&outs.join("h/history.csv")).contains("v2"));
    assert!(
        listing(&ro) == before,
        "a reader wrote into the read-only folder"
    );

    // A copy taken while a writer held commits in the log: they cannot be read here.
    let writable = dir.join("w");
    std::fs::create_dir_all(&writable).unwrap();
    std::fs::copy(&db, writable.join("calbench.sqlite")).unwrap();
    let c = rusqlite::Connection::open(writable.join("calbench.sqlite")).unwrap();
    c.execute_batch("PRAGMA wal_autocheckpoint = 0; UPDATE runs SET label = label || '-edited';")
        .unwrap();
    let logged = dir.join("logged");
    std::fs::create_dir_all(&logged).unwrap();
    for f in ["calbench.sqlite", "calbench.sqlite-wal"] {
        std::fs::copy(writable.join(f), logged.join(f)).unwrap();
    }
    drop(c);
    assert!(
        std::fs::metadata(logged.join("calbench.sqlite-wal"))
            .unwrap()
            .len()
            > 0
    );
    mode(&logged, 0o555).unwrap();
    let db = logged.join("calbench.sqlite");
    let Some(o) = unprivileged(&["history", "--regressions", "--db", path_arg(&db)]) else {
        return;
    };
    let t = text(&o);
    assert!(
        !o.status.success()
            && t.contains("logged/calbench.sqlite-wal")
            && t.contains("holds commits not yet written"),
        "{t}"
    );
}

/// A folder command whose `--out` lies in a folder its user cannot write is refused before
/// any work, naming `--out`'s path: the temporary folder the outputs are written through is
/// made beside `--out`, and `task` and `simulate` had been refused only after the work, naming
/// that temporary folder (`ro/.t.partial-31410: Permission denied`); `run` into a writable
/// folder inside a read-only one had run its trials first.
#[test]
fn an_out_that_cannot_be_written_beside_is_refused_before_the_work() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tmp_dir("cli-team-readonly-out");
    // The inputs copied where the unprivileged user reads them: the clone may stand in a
    // folder only its owner reads (a mkdtemp folder), and the task was then refused for its
    // own file, not for `--out`.
    let root = dir.join("repo");
    for f in [
        "tasks/barrett-wam.toml",
        "tasks/barrett-wam.mapping.toml",
        "examples/barrett-wam/wam.toml",
        "data/barrett-wam/3D_WAM_uncalibrated_grid_cleaned.csv",
        "data/barrett-wam/3D_WAM_uncalibrated_random_cleaned.csv",
        "scenarios/ci-guard.toml",
    ] {
        let to = root.join(f);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join(f), &to).unwrap();
    }
    let (ro, inside) = (dir.join("ro"), dir.join("ro/inside"));
    std::fs::create_dir_all(&inside).unwrap();
    let mode = |p: &Path, m: u32| std::fs::set_permissions(p, PermissionsExt::from_mode(m));
    mode(&inside, 0o777).unwrap();
    mode(&ro, 0o555).unwrap();
    let task = root.join("tasks/barrett-wam.toml");
    let scenario = root.join("scenarios/ci-guard.toml");
    let cases: [(Vec<&str>, PathBuf); 3] = [
        (
            vec!["task", path_arg(&task), "--method", "ls"],
            ro.join("t"),
        ),
        (vec!["simulate", path_arg(&scenario)], ro.join("s")),
        (
            vec!["run", path_arg(&scenario), "--trials", "2"],
            inside.clone(),
        ),
    ];
    for (args, out) in cases {
        let mut a = args.clone();
        a.extend(["--out", path_arg(&out)]);
        let Some(o) = unprivileged(&a) else { return };
        let t = text(&o);
        let want = format!("{}: Permission denied", out.display());
        assert!(
            !o.status.success() && t.contains(&want) && !t.contains("trials"),
            "{args:?}: {t}"
        );
    }
    let left: Vec<_> = std::fs::read_dir(&ro)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, ["inside"]);
    assert_eq!(std::fs::read_dir(&inside).unwrap().count(), 0);
}

//! The studies of cells on the runner of every study: Ban fig. 3's registration study run as
//! two shards and merged, and an instruments study killed (SIGKILL) once its checkpoint holds
//! a finished trial and resumed, each give the bytes of one run; both recorded in the results
//! database (`run --record`, `record`, `merge --record`), one entry per cell, and read by
//! `history` and `leaderboard`.

use std::path::Path;

use crate::common::{
    calbench, calbench_ok, files_in, kill_once_checkpointed, load_json, merge, one_line_naming,
    path_arg, read, resummed, root, tmp_dir, write_scenario,
};

/// The files of a registration study.
const FIG3: [&str; 3] = ["summary.json", "report.md", "heatmap_difference.svg"];

#[test]
fn ban_fig3_in_two_shards_merges_to_the_bytes_of_one_run() {
    let dir = tmp_dir("cells-fig3");
    let sc = root().join("scenarios/ban-fig3.toml");
    let run = |more: &[&str], out: &str| {
        let mut args = vec!["run", path_arg(&sc), "--trials", "5"];
        args.extend(more);
        let out = dir.join(out);
        args.extend(["--out", path_arg(&out)]);
        let o = calbench_ok(&args);
        (out, String::from_utf8_lossy(&o.stdout).into_owned())
    };
    let (one, said) = run(&["--threads", "2"], "one");
    // The finish line counts the trials, as a Monte-Carlo run's does (it said "in S s").
    assert!(said.contains("\n5 trials in "), "{said}");
    let run = |more: &[&str], out: &str| run(more, out).0;
    let s0 = run(&["--shard", "0/2", "--threads", "1"], "s0");
    let s1 = run(&["--shard", "1/2", "--threads", "1"], "s1");
    assert!(s0.join("records.txt").exists() && !s0.join("summary.json").exists());
    let merged = dir.join("merged");
    merge(&[&s0, &s1], &merged);
    for f in FIG3 {
        assert_eq!(read(&one.join(f)), read(&merged.join(f)), "{f}");
    }
    // A shard is not a run: its folder has no summary, and one shard alone does not merge.
    let o = calbench(&["merge", path_arg(&s0), "--out", path_arg(&dir.join("half"))]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("1/2"));
    // `check` compares Monte-Carlo summaries: a study of cells is named by its kind (it was
    // "not a calbench summary.json: missing field `results`").
    let summary = one.join("summary.json");
    let o = calbench(&[
        "check",
        path_arg(&summary),
        "--baseline",
        path_arg(&summary),
    ]);
    let line = crate::malformed::line_of(&read(&summary), "  \"kind\"");
    one_line_naming(
        &String::from_utf8_lossy(&o.stderr),
        &summary,
        &[&format!(
            "line {line}, kind: is \"registration_study\": the summary of a study of cells"
        )],
    );
}

/// The records of another registration run with the same name and seed but another trial
/// count (whose first draws are the same numbers), copied into a shard, are refused by
/// `merge`, naming `records.txt` and its line, and nothing is written; so is a draw of other
/// cells than the study's.
#[test]
fn merge_refuses_the_records_of_another_registration_run_with_the_same_name_and_seed() {
    let dir = tmp_dir("cells-foreign");
    let sc = root().join("scenarios/ban-fig3.toml");
    let run = |trials: &str, shard: &str, out: &str| {
        let out = dir.join(out);
        let args = ["run", path_arg(&sc), "--trials", trials, "--shard", shard];
        calbench_ok(&[&args[..], &["--out", path_arg(&out)]].concat());
        out
    };
    let (a0, a1) = (run("6", "0/2", "a0"), run("6", "1/2", "a1"));
    // Shard 0/3 of 9 draws holds draws 0–2, as shard 0/2 of 6 does.
    let b0 = run("9", "0/3", "b0");
    let records = a0.join("records.txt");
    let own = read(&records);
    let foreign = read(&b0.join("records.txt"));
    assert_eq!(own.lines().count(), foreign.lines().count());
    std::fs::write(&records, &foreign).unwrap();
    let merged = dir.join("merged");
    let args = [
        "merge",
        path_arg(&a0),
        path_arg(&a1),
        "--out",
        path_arg(&merged),
    ];
    let o = calbench(&args);
    assert!(!o.status.success(), "merged the records of another run");
    let err = String::from_utf8_lossy(&o.stderr);
    one_line_naming(&err, &records, &["line 1", "another run"]);
    assert!(!merged.exists(), "merge left the folder it made");
    std::fs::write(&records, &own).unwrap();
    // A draw of one cell fewer, its checksum made to match: refused naming its line, where
    // the merge panicked indexing past the draw's cells.
    let want = "registration errors of 39 cells, for a study of 40";
    merge_refuses_a_cut_record(&a0, ("result:[", "),"), &args, want);
    calbench_ok(&args);
}

/// Two instruments at 40 random poses: two cells of six trials.
pub(crate) const INSTRUMENTS: &str = r#"
name = "instruments-resume"
seed = 11
trials = 6
robot = "irb2600"

[instruments_study]
poses = [40]
strategies = ["random"]
candidates = 80
validation = 10

[errors]
kind = "paper"
length_mm = 0.1
angle_rad = 0.0005

[[measurement]]
kind = "position"

[[measurement]]
kind = "distance"
noise_um = 1.0
scale_um_per_m = 1.0
"#;

#[test]
fn an_instruments_study_killed_and_resumed_gives_the_bytes_of_one_run() {
    let dir = tmp_dir("cells-instruments");
    // 600 trials a cell: the checkpoint counts its first trials after 256 of the first cell's
    // 600, so the kill lands within the 944 trials left (about 1 s) rather than in the few
    // milliseconds between the first cell's end and the run's (6 trials a cell).
    let sc = write_scenario(
        &dir,
        "s.toml",
        &INSTRUMENTS.replace("trials = 6\n", "trials = 600\n"),
    );
    let (whole, killed) = (dir.join("whole"), dir.join("killed"));
    calbench_ok(&[
        "run",
        path_arg(&sc),
        "--threads",
        "2",
        "--out",
        path_arg(&whole),
    ]);
    let args = [
        "run",
        path_arg(&sc),
        "--threads",
        "1",
        "--out",
        path_arg(&killed),
    ];
    let meta = kill_once_checkpointed(&args, &killed, 600);
    assert!(
        !killed.join("summary.json").exists(),
        "the run ended before it was killed"
    );
    assert!(meta.exists());
    // Resumed, and recorded as it finishes.
    let db = dir.join("calbench.sqlite");
    let o = calbench_ok(&[
        "run",
        "--resume",
        path_arg(&killed),
        "--record",
        "--db",
        path_arg(&db),
    ]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        said.contains("as run #1 of instruments-resume (2 entries"),
        "{said}"
    );
    assert!(!meta.exists(), "the checkpoint outlived the resumed run");
    for f in ["summary.json", "report.md", "report.html"] {
        assert_eq!(read(&whole.join(f)), read(&killed.join(f)), "{f}");
    }
}

/// An instruments study's record edited to hold one identified value or one true error fewer
/// than its cell, its checksum made to match, is refused by `merge` naming `records.txt` and
/// the line, where the merge panicked indexing past the record's values; nothing is written.
#[test]
fn merge_refuses_an_instruments_record_that_does_not_fit_its_cell() {
    let dir = tmp_dir("cells-instruments-misfit");
    let sc = write_scenario(&dir, "s.toml", INSTRUMENTS);
    let shard = |s: &str, out: &str| {
        let out = dir.join(out);
        let args = ["run", path_arg(&sc), "--shard", s, "--threads", "1"];
        calbench_ok(&[&args[..], &["--out", path_arg(&out)]].concat());
        out
    };
    let (s0, s1) = (shard("0/2", "s0"), shard("1/2", "s1"));
    let merged = dir.join("merged");
    let args = [
        "merge",
        path_arg(&s0),
        path_arg(&s1),
        "--out",
        path_arg(&merged),
    ];
    // The first identified value (`x:[a,b,…]` becomes `x:[b,…]`), then the first
    // `(name,value)` pair of the true errors.
    let cuts = [
        (("x:[", ","), "identified values, for a cell of"),
        (("errors:[", "),"), "true errors, for a study of"),
    ];
    for (cut, want) in cuts {
        merge_refuses_a_cut_record(&s0, cut, &args, want);
    }
    calbench_ok(&args);
}

/// `merge ARGS` (whose last argument is the output folder) after the first record of the
/// shard folder `shard` is edited to lose what follows `key` up to and including the first
/// `till` after it, its checksum made to match: refused in one line naming `records.txt`, the
/// line and `want`, and nothing written; the record is then restored.
fn merge_refuses_a_cut_record(shard: &Path, (key, till): (&str, &str), args: &[&str], want: &str) {
    let records = shard.join("records.txt");
    let own = read(&records);
    let meta = load_json(&shard.join("shard.json"));
    let (settings, seed) = (
        meta["settings"].as_str().unwrap(),
        meta["seed"].as_u64().unwrap(),
    );
    let (first, rest) = own.split_once('\n').unwrap();
    let at = first.find(key).unwrap() + key.len();
    let end = at + first[at..].find(till).unwrap() + till.len();
    let fewer = resummed(
        &format!("{}{}", &first[..at], &first[end..]),
        settings,
        seed,
    );
    std::fs::write(&records, format!("{fewer}\n{rest}")).unwrap();
    let o = calbench(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    one_line_naming(&err, &records, &["line 1", want]);
    let merged = Path::new(args.last().unwrap());
    assert!(!merged.exists(), "merge left the folder it made");
    std::fs::write(&records, &own).unwrap();
}

/// `SELECT COUNT(*)`-like `sql` of the database `db`, one number.
fn number(db: &Path, sql: &str) -> i64 {
    let c = rusqlite::Connection::open(db).unwrap();
    c.query_row(sql, [], |r| r.get(0)).unwrap()
}

#[test]
fn registration_and_instruments_studies_are_recorded_and_history_and_the_board_read_them() {
    let dir = tmp_dir("cells-record");
    let db = dir.join("calbench.sqlite");
    let fig3 = root().join("scenarios/ban-fig3.toml");
    let ins = write_scenario(&dir, "s.toml", INSTRUMENTS);
    let run = |sc: &Path, seed: &str, out: &str, more: &[&str]| {
        let out = dir.join(out);
        let mut args = vec!["run", path_arg(sc), "--trials", "3", "--seed", seed];
        args.extend(["--out", path_arg(&out)]);
        args.extend(more);
        calbench_ok(&args);
        out
    };
    // A registration study recorded as it finishes, an instruments study by `record`.
    let v1 = ["--record", "--db", path_arg(&db), "--label", "v1"];
    let f1 = run(&fig3, "1", "f1", &v1);
    let i1 = run(&ins, "1", "i1", &[]);
    calbench_ok(&[
        "record",
        path_arg(&i1),
        "--db",
        path_arg(&db),
        "--label",
        "v1",
    ]);
    // One entry per cell: Ban's 8 × 5 grid, two instruments at one pose count and strategy.
    let entries = |name: &str| {
        let sql = format!(
            "SELECT COUNT(*) FROM entries e JOIN runs r ON r.id = e.run WHERE r.scenario = '{name}'"
        );
        number(&db, &sql)
    };
    assert_eq!(entries("ban-fig3"), 40);
    assert_eq!(entries("instruments-resume"), 2);
    // A cell's figure is the summary's, and the scenario stored is the one the folder ran.
    let summary = crate::common::load_json(&f1.join("summary.json"));
    let last = summary["cells"].as_array().unwrap().last().unwrap().clone();
    let c = rusqlite::Connection::open(&db).unwrap();
    let (value, text): (f64, String) = c
        .query_row(
            "SELECT f.value, r.scenario_text FROM figures f JOIN runs r ON r.id = f.run \
             WHERE f.entry = '16 × 0–1 mm' AND f.metric = 'difference_mm'",
            [],
            |r| Ok((r.get(0)?, r.get(1)?)),
        )
        .unwrap();
    assert_eq!(value, last["difference_mm"].as_f64().unwrap());
    let ran = read(&f1.join("scenario.toml"));
    assert_eq!(ran.split_once('\n').unwrap().1, text);
    let fig = |entry: &str, metric: &str| {
        let sql =
            format!("SELECT COUNT(*) FROM figures WHERE entry = '{entry}' AND metric = '{metric}'");
        number(&db, &sql)
    };
    assert_eq!(
        fig("distance / 40 poses / random", "validation_after_mm"),
        1
    );
    assert_eq!(
        fig("16 × 0–1 mm", "outlier_count"),
        0,
        "a setting is no figure"
    );
    // A second version of each, the registration study merged from two shards.
    let s0 = run(&fig3, "2", "s0", &["--shard", "0/2"]);
    let s1 = run(&fig3, "2", "s1", &["--shard", "1/2"]);
    let merged = dir.join("f2");
    calbench_ok(&[
        "merge",
        path_arg(&s0),
        path_arg(&s1),
        "--out",
        path_arg(&merged),
        "--record",
        "--db",
        path_arg(&db),
        "--label",
        "v2",
    ]);
    let i2 = run(
        &ins,
        "2",
        "i2",
        &["--record", "--db", path_arg(&db), "--label", "v2"],
    );
    assert_eq!(
        number(&db, "SELECT COUNT(*) FROM runs WHERE kind = 'merge'"),
        1
    );
    assert_eq!(number(&db, "SELECT COUNT(*) FROM runs"), 4);
    // history and the leaderboard read them.
    // Their cells are not judged by check's rule, and history says so: it had said it
    // compared 2 pairs, and passed a study made three times worse.
    let o = calbench_ok(&["history", "--db", path_arg(&db), "--regressions"]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        said.contains(
            "(0 scenario-machine pairs compared, 0 with a changed scenario; 2 pairs of a \
             registration or instruments study not judged"
        ),
        "{said}"
    );
    let out = dir.join("history");
    let args = ["history", "--db", path_arg(&db), "--scenario", "ban-fig3"];
    calbench_ok(&[&args[..], &["--metric", "svd_mm", "--out", path_arg(&out)]].concat());
    let csv = read(&out.join("history.csv"));
    assert_eq!(csv.lines().count(), 1 + 2 * 40, "{csv}");
    calbench_ok(&[
        "leaderboard",
        "--db",
        path_arg(&db),
        "--out",
        path_arg(&dir.join("board")),
    ]);
    // The scenario file given must be the one the folder ran: refused, naming both hashes.
    let o = calbench(&[
        "record",
        path_arg(&i2),
        "--db",
        path_arg(&db),
        "--scenario",
        path_arg(&fig3),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("is not the scenario the run ran"),
        "{err}"
    );
    let hashes: std::collections::BTreeSet<&str> = err
        .split(|c: char| !c.is_ascii_hexdigit())
        .filter(|w| w.len() == 64)
        .collect();
    assert_eq!(hashes.len(), 2, "{err}");
    // A figure that cannot be what the study wrote: refused, naming the file and the key.
    let edited = dir.join("edited");
    std::fs::create_dir_all(&edited).unwrap();
    for f in ["summary.json", "scenario.toml"] {
        std::fs::copy(i1.join(f), edited.join(f)).unwrap();
    }
    let text = read(&edited.join("summary.json"));
    let at = text.find("\"validation_after_mm\": ").unwrap() + "\"validation_after_mm\": ".len();
    std::fs::write(
        edited.join("summary.json"),
        format!("{}-{}", &text[..at], &text[at..]),
    )
    .unwrap();
    let o = calbench(&["record", path_arg(&edited), "--db", path_arg(&db)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("edited/summary.json")
            && err.contains("position / 40 poses / random")
            && err.contains("validation_after_mm"),
        "{err}"
    );
    assert_eq!(number(&db, "SELECT COUNT(*) FROM runs"), 4);
}

/// A folder named `report.html` in `--out` (docs/formats.md § 1.7): a registration study,
/// which writes no `report.html`, runs and leaves it; an instruments study finds it once its
/// work is done, as a Monte-Carlo run finds a plot's name taken, and writes nothing.
#[test]
fn a_report_html_folder_concerns_only_the_study_that_writes_one() {
    let dir = tmp_dir("cells-report-html");
    let fig3 = root().join("scenarios/ban-fig3.toml");
    let instruments = write_scenario(&dir, "s.toml", INSTRUMENTS);
    for (sc, writes) in [(&fig3, false), (&instruments, true)] {
        let out = dir.join(format!("out-{writes}"));
        std::fs::create_dir_all(out.join("report.html")).unwrap();
        let args = ["run", path_arg(sc), "--trials", "2", "--threads", "1"];
        let o = calbench(&[&args[..], &["--out", path_arg(&out)]].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        if writes {
            assert!(
                !o.status.success()
                    && err.contains(
                        "report.html is a folder where an output file of that name \
                                     is to be written; nothing was written"
                    ),
                "{err}"
            );
            assert_eq!(files_in(&out), ["report.html".to_string()].into());
        } else {
            assert!(o.status.success(), "{err}");
            assert!(files_in(&out).contains("summary.json"));
            assert!(out.join("report.html").is_dir());
        }
    }
}

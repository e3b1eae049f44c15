//! The edges of a sharded run (docs/formats.md `run --shard`, `merge`, § 7.3): a split into
//! more shares than the run has work units, a merge into the folder of an unfinished run, two
//! shards of runs that differ in one setting, `--record` on a refused command, a shard given
//! to `record`, and the line ends and blank lines of `records.txt`.

use std::path::Path;

use crate::common::{calbench, calbench_ok, merge, one_line_naming, path_arg, read, root, tmp_dir};
use crate::records::{killed_run, refused_merge, refused_resume, two_shards, with_field};

/// `args` refused with exit status 1; its standard error.
fn refused(args: &[&str]) -> String {
    let o = calbench(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    err
}

/// `--shard I/N` with N above the run's work units (sweep points × trials) is refused before
/// any work, naming `--shard` and the units, where it ran N − W empty shards and a `merge` of
/// `0/10¹²` aborted on a 16 TB allocation; a `shard.json` whose share count was altered so is
/// refused naming the file and `shard`, and shards whose wall times add up to more than any
/// number naming `seconds`.
#[test]
fn a_split_into_more_shares_than_work_units_is_refused() {
    let dir = tmp_dir("shard-edges-count");
    let sc = root().join("scenarios/ci-guard.toml");
    for share in ["0/5", "3/1000000000000"] {
        let out = dir.join("over");
        let args = ["run", path_arg(&sc), "--trials", "4", "--shard", share];
        let err = refused(&[&args[..], &["--out", path_arg(&out)]].concat());
        assert!(err.contains("--shard"), "{err}");
        assert!(err.contains("4 work units"), "{err}");
        assert!(err.contains("at most 4 shards"), "{err}");
        // Refused before the run is announced, where it said `running ci-guard: …` first.
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(!out.exists() && !dir.join(".over.checkpoint").exists());
    }
    calbench_ok(&[
        "run",
        path_arg(&sc),
        "--trials",
        "4",
        "--shard",
        "3/4",
        "--out",
        path_arg(&dir.join("last")),
    ]);
    let [a0, a1] = two_shards(&dir);
    let meta = a0.join("shard.json");
    let count = read(&meta).replace("\"count\": 2", "\"count\": 1000000000000");
    refused_merge(&[&a0], &[(&meta, count)], &["shard", "at most 4 shards"]);
    // Two wall times each finite but whose sum is not: refused, where timing.json took it.
    let meta1 = a1.join("shard.json");
    let big = |p: &Path| with_field(&read(p), "seconds", "1e308");
    let edits = [(meta.as_path(), big(&meta)), (meta1.as_path(), big(&meta1))];
    refused_merge(
        &[&a0, &a1],
        &edits,
        &["seconds", "add up beyond any number"],
    );
}

/// A merge into the folder of a run that was killed removes that run's checkpoint, with a
/// warning, where it was left beside the merged result and a later `run --resume` replaced
/// that result without a word.
#[test]
fn a_merge_removes_the_checkpoint_of_an_unfinished_run_into_its_folder() {
    let dir = tmp_dir("shard-edges-stale");
    let (killed, meta) = killed_run(&dir);
    let checkpoint = meta.parent().unwrap().to_path_buf();
    let [a0, a1] = two_shards(&dir);
    let o = merge(&[&a0, &a1], &killed);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("warning:"), "{err}");
    assert!(err.contains("the merged run replaces it"), "{err}");
    assert!(!checkpoint.exists(), "the checkpoint is left");
    let left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    let summary = read(&killed.join("summary.json"));
    let err = refused(&["run", "--resume", path_arg(&killed)]);
    assert!(err.contains("no checkpoint"), "{err}");
    assert_eq!(read(&killed.join("summary.json")), summary);
}

/// Shards of two runs with one name, seed and trial count but another setting are refused
/// naming the first setting that differs and its two values, as `run --resume` names it,
/// where the message said only "settings of scenario … against others".
#[test]
fn a_merge_names_the_setting_where_two_shards_differ() {
    let dir = tmp_dir("shard-edges-setting");
    let [a0, _] = two_shards(&dir);
    let edited = dir.join("ci-guard.toml");
    let text = read(&root().join("scenarios/ci-guard.toml"));
    std::fs::write(&edited, text.replacen("count = 40", "count = 41", 1)).unwrap();
    let b1 = dir.join("b1");
    calbench_ok(&[
        "run",
        path_arg(&edited),
        "--trials",
        "4",
        "--shard",
        "1/2",
        "--out",
        path_arg(&b1),
    ]);
    let err = refused(&["merge", path_arg(&a0), path_arg(&b1), "--out", "unused"]);
    assert!(err.contains("`calibration.count` 40 against 41"), "{err}");
}

/// `--record` on a command that is refused creates no database and no folder for one (it is
/// created once there is a result); a database path through a file is refused before any
/// work; a shard given to `record` is told to merge first.
#[test]
fn a_refused_command_with_record_creates_no_database() {
    let dir = tmp_dir("shard-edges-record");
    let db = dir.join("db/sub/results.sqlite");
    let err = refused(&[
        "merge",
        path_arg(&dir.join("none")),
        "--out",
        path_arg(&dir.join("m")),
        "--record",
        "--db",
        path_arg(&db),
    ]);
    assert!(err.contains("shard.json"), "{err}");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "name = \"bad\"\ntrials = \"x\"\n").unwrap();
    let out = dir.join("out");
    refused(&[
        "run",
        path_arg(&bad),
        "--out",
        path_arg(&out),
        "--record",
        "--db",
        path_arg(&db),
    ]);
    assert!(
        !dir.join("db").exists(),
        "a refused command made the database's folders"
    );
    std::fs::write(dir.join("file"), "").unwrap();
    let through = dir.join("file/results.sqlite");
    let sc = root().join("scenarios/ci-guard.toml");
    let err = refused(&[
        "run",
        path_arg(&sc),
        "--trials",
        "2",
        "--out",
        path_arg(&out),
        "--record",
        "--db",
        path_arg(&through),
    ]);
    one_line_naming(&err, &through, &["database", "is not a folder"]);
    assert!(!out.exists(), "the run ran before its database was refused");
    let [a0, a1] = two_shards(&dir);

    let err = refused(&["record", path_arg(&a0), "--db", path_arg(&db)]);
    one_line_naming(
        &err,
        &a0,
        &["is a shard of a run", "merge the run's shards first"],
    );
    assert!(!dir.join("db").exists());
    let merged = dir.join("merged");
    calbench_ok(&[
        "merge",
        path_arg(&a0),
        path_arg(&a1),
        "--out",
        path_arg(&merged),
        "--record",
        "--db",
        path_arg(&db),
    ]);
    assert!(db.is_file(), "the merge recorded nothing");
    // `baseline` of a shard says what it is, as `record` does, where it had said that its
    // summary.json did not exist.
    let err = refused(&[
        "baseline",
        path_arg(&a0),
        "--out",
        path_arg(&dir.join("b.json")),
    ]);
    one_line_naming(
        &err,
        &a0,
        &["is a shard of a run", "the baseline of the merged folder"],
    );
    // So do `compare` and `check`, either side, where they said that its summary.json did not
    // exist.
    let whole = path_arg(&merged);
    let summary = merged.join("summary.json");
    let cmp = dir.join("cmp");
    for args in [
        vec!["compare", whole, path_arg(&a0), "--out", path_arg(&cmp)],
        vec!["check", path_arg(&summary), "--baseline", path_arg(&a0)],
        vec!["check", path_arg(&a0), "--baseline", path_arg(&summary)],
    ] {
        let err = refused(&args);
        one_line_naming(
            &err,
            &a0,
            &["is a shard of a run", "give the merged folder"],
        );
    }
    assert!(!cmp.exists());
    // `record` says so as `run --record` does, where it had said "File exists".
    let err = refused(&["record", path_arg(&merged), "--db", path_arg(&through)]);
    one_line_naming(
        &err,
        &through,
        &["database", "cannot be created: ", "is not a folder"],
    );
}

/// `text` with `extra` inserted before its line `n` (from 0).
fn after_line(text: &str, n: usize, extra: &str) -> String {
    let mut lines: Vec<&str> = text.split_inclusive('\n').collect();
    lines.insert(n, extra);
    lines.concat()
}

/// A shard's `records.txt` with CR LF line ends (a copy that converted them) or blank lines
/// at its end merges to the same bytes; a blank line between records is refused at its line.
/// A checkpoint's `records.txt` with CR LF line ends is refused saying so (it is continued by
/// its byte count), where its first line failed its checksum; one with a record deleted is
/// refused at the line and trial where the record is missing, where it was named by byte.
/// A `checkpoint.json` that is not a checkpoint is refused at its line, where the message
/// named `checkpoint.json` twice.
#[test]
fn records_txt_line_ends_blank_lines_and_deleted_records() {
    let dir = tmp_dir("shard-edges-lines");
    let [a0, a1] = two_shards(&dir);
    let plain = dir.join("plain");
    merge(&[&a0, &a1], &plain);
    let (r0, r1) = (a0.join("records.txt"), a1.join("records.txt"));
    let (t0, t1) = (read(&r0), read(&r1));
    std::fs::write(&r0, t0.replace('\n', "\r\n")).unwrap();
    std::fs::write(&r1, format!("{t1}\n \n")).unwrap();
    let edited = dir.join("edited");
    merge(&[&a0, &a1], &edited);
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&plain.join(f)), read(&edited.join(f)), "{f}");
    }
    std::fs::write(&r1, &t1).unwrap();
    refused_merge(
        &[&a0, &a1],
        &[(&r0, after_line(&t0, 1, "\n"))],
        &["line 2", "a blank line between records"],
    );

    let (killed, meta) = killed_run(&dir);
    let records = meta.with_file_name("records.txt");
    let text = read(&records);
    let crlf = text.replace('\n', "\r\n");
    refused_resume(&killed, &[(&records, crlf)], &["line 1", "CR LF"]);
    let deleted = text.split_once('\n').unwrap().1.to_string();
    refused_resume(&killed, &[(&records, deleted)], &["line 1", "trial 0"]);
    let json = read(&meta);
    let host = json.find("\"host\"").unwrap();
    let end = host + json[host..].find('\n').unwrap() + 1;
    let without = format!("{}{}", &json[..host], &json[end..]);
    refused_resume(
        &killed,
        &[(&meta, without)],
        &["checkpoint.json: host: ", "missing field `host`"],
    );
}

/// A sweep value given twice is refused at the line of its second writing, where the line of
/// `values = [` was named; a table and a key inside it swept on two axes are refused at the
/// later axis's key, where one silently overrode the other.
#[test]
fn a_sweep_value_given_twice_or_a_table_and_its_key_on_two_axes_are_refused() {
    let dir = tmp_dir("shard-edges-sweep");
    let values = "\n[sweep]\nkey = \"calibration.count\"\nvalues = [\n  30,\n  40,\n  30.0,\n]\n";
    swept_refused(
        &dir,
        values,
        "  30.0,",
        "sweep.values[2]",
        "30.0 is given twice",
    );
    let axes = "\n[[sweep]]\nkey = \"outliers\"\nvalues = [{count = 1}, {count = 3}]\n\n\
                [[sweep]]\nkey = \"outliers.count\"\nvalues = [2, 4]\n";
    let inside = "are a table and a key inside it";
    swept_refused(
        &dir,
        axes,
        "key = \"outliers.count\"",
        "sweep[1].key",
        inside,
    );
    // A grid of 10⁹ points is refused at the values that take it past 10⁶ points, at once:
    // each point had been checked as a scenario, 8 GB and more before a word.
    let list = |from: u32| {
        let v: Vec<String> = (from..from + 1000).map(|v| v.to_string()).collect();
        format!("[{}]", v.join(", "))
    };
    let grid = format!(
        "\n[[sweep]]\nkey = \"calibration.count\"\nvalues = {}\n\n[[sweep]]\n\
         key = \"validation.count\"\nvalues = {}\n\n[[sweep]]\nkey = \"outliers.count\"\n\
         values = {}\n",
        list(30),
        list(30),
        list(0)
    );
    let at = format!("values = {}", list(0));
    let started = std::time::Instant::now();
    let past = "\"outliers.count\": 1000 values make a grid of 1000000000 points";
    swept_refused(&dir, &grid, &at, "sweep[2].values", past);
    assert!(started.elapsed().as_secs() < 20, "{:?}", started.elapsed());
}

/// ci-guard with `sweep` appended, run: refused in one line naming the line `at_line` (its
/// text), the key `key` and holding `want`, with nothing written.
fn swept_refused(dir: &Path, sweep: &str, at_line: &str, key: &str, want: &str) {
    let text = format!("{}{sweep}", read(&root().join("scenarios/ci-guard.toml")));
    let line = text.lines().position(|l| l == at_line).unwrap() + 1;
    let sc = dir.join("swept.toml");
    std::fs::write(&sc, &text).unwrap();
    let out = dir.join("out");
    let err = refused(&[
        "run",
        path_arg(&sc),
        "--trials",
        "2",
        "--out",
        path_arg(&out),
    ]);
    one_line_naming(&err, &sc, &[&format!("line {line}, {key}"), want]);
    assert!(!out.exists());
}

/// A sweep point whose every entry has an earlier point's figures to the bit (an outlier
/// magnitude swept with no outliers) is warned of once, by `run` and by `merge` alike, where
/// the sweep table showed equal rows without a word; a point that differs (outliers drawn) is
/// not, and the files are those of the sweep as given.
#[test]
fn a_sweep_point_that_changed_nothing_is_warned_of() {
    let dir = tmp_dir("shard-edges-idle");
    let sweep = "\n[sweep]\nkey = \"outliers\"\nvalues = [\n  { count = 0, magnitude_mm = [0.5, 1.0] },\n  { count = 0, magnitude_mm = [2.0, 3.0] },\n  { count = 2, magnitude_mm = [0.5, 1.0] },\n]\n";
    let study = read(&root().join("scenarios/ci-guard.toml"));
    let sc = crate::common::write_scenario(&dir, "idle", &format!("{study}{sweep}"));
    let warned = |args: &[&str]| {
        let o = calbench_ok(args);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        let lines: Vec<&str> = err.lines().filter(|l| l.contains("no effect")).collect();
        assert_eq!(lines.len(), 1, "{err}");
        assert!(
            lines[0].starts_with("warning: sweep point outliers = ")
                && lines[0].contains("magnitude_mm\":[2.0,3.0]")
                && lines[0].contains("gave every entry the figures of outliers = "),
            "{err}"
        );
    };
    let whole = dir.join("whole");
    let run = ["run", path_arg(&sc), "--trials", "3"];
    warned(&[&run[..], &["--out", path_arg(&whole)]].concat());
    let shards: Vec<_> = (0..2).map(|i| dir.join(format!("s{i}"))).collect();
    for (i, s) in shards.iter().enumerate() {
        let share = format!("{i}/2");
        calbench_ok(&[&run[..], &["--shard", &share, "--out", path_arg(s)]].concat());
    }
    let merged = dir.join("merged");
    warned(&[
        "merge",
        path_arg(&shards[0]),
        path_arg(&shards[1]),
        "--out",
        path_arg(&merged),
    ]);
    assert!(read(&merged.join("summary.json")) == read(&whole.join("summary.json")));
}

//! A record of `records.txt` binds its run (docs/formats.md § 7.3): the records of another run
//! with the same scenario name and seed but other settings (here another trial count, whose
//! first trials draw the same numbers, so only the run's identity tells them apart), copied
//! into a shard or a checkpoint, are refused by `merge` and `run --resume`, naming the file
//! and the line, and nothing is written or changed. So are a `shard.json`, a `checkpoint.json`
//! or a record altered in other ways (docs/formats.md § 8.3): each refusal is one line naming
//! the file and its key or line, writes nothing, leaves no output folder and, on `run
//! --resume`, leaves the checkpoint as it was.

use std::path::{Path, PathBuf};

use crate::common::{
    calbench, calbench_ok, kill_once_checkpointed, load_json, one_line_naming, path_arg, read,
    reblocked, resummed, root, tmp_dir,
};

/// `calbench run ci-guard --trials N --threads 1` with `more` arguments, into `out`.
fn run(trials: &str, more: &[&str], out: &Path) {
    let sc = root().join("scenarios/ci-guard.toml");
    let mut args = vec!["run", path_arg(&sc), "--trials", trials, "--threads", "1"];
    args.extend(more);
    args.extend(["--out", path_arg(out)]);
    calbench_ok(&args);
}

#[test]
fn merge_refuses_the_records_of_another_run_with_the_same_name_and_seed() {
    let dir = tmp_dir("records-foreign-merge");
    let (a0, a1, b0) = (dir.join("a0"), dir.join("a1"), dir.join("b0"));
    run("6", &["--shard", "0/2"], &a0);
    run("6", &["--shard", "1/2"], &a1);
    // Shard 0/3 of 9 trials holds trials 0–2, as shard 0/2 of 6 does.
    run("9", &["--shard", "0/3"], &b0);
    let records = a0.join("records.txt");
    let own = read(&records);
    let foreign = read(&b0.join("records.txt"));
    let body = |l: &str| {
        l.rsplit_once(" #")
            .unwrap()
            .0
            .split("seconds:")
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(
        own.lines().map(body).collect::<Vec<_>>(),
        foreign.lines().map(body).collect::<Vec<_>>(),
        "the two runs' first trials differ"
    );
    std::fs::write(&records, &foreign).unwrap();
    let out = dir.join("merged");
    let o = calbench(&[
        "merge",
        path_arg(&a0),
        path_arg(&a1),
        "--out",
        path_arg(&out),
    ]);
    assert!(!o.status.success(), "merged the records of another run");
    let err = String::from_utf8_lossy(&o.stderr);
    one_line_naming(&err, &records, &["line 1", "trial 0", "another run"]);
    assert!(!out.exists(), "merge left the folder it made");
    std::fs::write(&records, &own).unwrap();
    calbench_ok(&[
        "merge",
        path_arg(&a0),
        path_arg(&a1),
        "--out",
        path_arg(&out),
    ]);
}

#[test]
fn resume_refuses_the_records_of_another_run_with_the_same_name_and_seed() {
    let dir = tmp_dir("records-foreign-resume");
    let other = dir.join("other");
    let (killed, meta) = killed_run(&dir);
    // 260 trials of a run of 520: as many as the checkpoint counts, with the same numbers.
    run("520", &["--shard", "0/2"], &other);
    let json = read(&meta);
    let field = |k: &str| -> usize {
        let l = json
            .lines()
            .find_map(|l| l.trim().strip_prefix(&format!("\"{k}\": ")));
        l.unwrap().trim_end_matches(',').parse().unwrap()
    };
    let (done, bytes) = (field("done"), field("bytes"));
    let foreign: String = read(&other.join("records.txt"))
        .lines()
        .take(done)
        .map(|l| format!("{l}\n"))
        .collect();
    let records = meta.with_file_name("records.txt");
    std::fs::write(&records, &foreign).unwrap();
    let json = json.replace(
        &format!("\"bytes\": {bytes}"),
        &format!("\"bytes\": {}", foreign.len()),
    );
    std::fs::write(&meta, &json).unwrap();
    let edits = [(records.as_path(), foreign), (meta.as_path(), json)];
    refused_resume(&killed, &edits, &["line 1", "trial 0", "another run"]);
}

/// A `shard.json` whose block lists other methods or parameters than its records hold (a
/// method line deleted, a parameter listed twice), its checksum made to match, is refused
/// naming it, where the merge panicked indexing past the lists, and nothing is written.
#[test]
fn merge_refuses_a_shard_json_whose_blocks_do_not_fit_its_records() {
    let dir = tmp_dir("records-altered-blocks");
    let [a0, a1] = two_shards(&dir);
    let meta = a0.join("shard.json");
    let own = read(&meta);
    for (from, to, why) in [
        (
            "\"methods\": [\n          \"ls\",\n",
            "\"methods\": [\n",
            "an outcome of method 2 and strategy 0",
        ),
        (
            "\"params\": [\n          \"a1\",\n",
            "\"params\": [\n          \"a1\",\n          \"a1\",\n",
            "injected errors for 25 parameters",
        ),
    ] {
        assert!(own.contains(from), "{from}");
        let edit = [(meta.as_path(), reblocked(&own.replacen(from, to, 1)))];
        refused_merge(&[&a0, &a1], &edit, &["blocks", "records.txt, line 1", why]);
    }
}

/// A `shard.json` block is bound to its run as the records are (docs/formats.md § 7.3): one
/// edited where the records cannot tell (the robot's name, trial 0's first validation error,
/// which the reports show) or copied from a run of the same name and seed but other settings
/// is refused naming the file, the block and its checksum, and nothing is written. The sums
/// computed apart from calbench's code ([`reblocked`]) are the ones it writes. So is one whose
/// blocks were deleted.
#[test]
fn merge_refuses_a_shard_json_block_altered_or_of_another_run() {
    let dir = tmp_dir("records-block-sums");
    let [a0, a1] = two_shards(&dir);
    let meta = a0.join("shard.json");
    let own = read(&meta);
    let sums = |text: &str| -> Vec<serde_json::Value> {
        let v: serde_json::Value = serde_json::from_str(text).unwrap();
        v["blocks"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["sum"].clone())
            .collect()
    };
    assert_eq!(
        sums(&own),
        sums(&reblocked(&own)),
        "the sums of {}",
        meta.display()
    );
    let v: serde_json::Value = serde_json::from_str(&own).unwrap();
    let first = v["blocks"][0]["trial0"]["per_point"][2][0]
        .as_f64()
        .unwrap();
    for (from, to) in [
        (
            "\"robot\": \"irb2600\"".to_string(),
            "\"robot\": \"irb2400\"".to_string(),
        ),
        (format!("{first:?}"), format!("{:?}", first * 0.5)),
    ] {
        assert!(own.contains(&from), "{from}");
        let edit = [(meta.as_path(), own.replacen(&from, &to, 1))];
        refused_merge(
            &[&a0, &a1],
            &edit,
            &["blocks[0]", "sweep point 0", "checksum"],
        );
    }
    let other = dir.join("other");
    run("5", &["--shard", "0/2"], &other);
    let theirs: serde_json::Value = serde_json::from_str(&read(&other.join("shard.json"))).unwrap();
    let mut copied = v.clone();
    copied["blocks"] = theirs["blocks"].clone();
    let edit = [(
        meta.as_path(),
        serde_json::to_string_pretty(&copied).unwrap(),
    )];
    refused_merge(&[&a0, &a1], &edit, &["blocks[0]", "another run"]);
    // Its blocks deleted: the merge had dropped trial 0's plots from report.md without a word.
    copied["blocks"] = serde_json::json!([]);
    let edit = [(
        meta.as_path(),
        serde_json::to_string_pretty(&copied).unwrap(),
    )];
    let want = ["blocks", "no block of sweep point 0", "altered"];
    refused_merge(&[&a0, &a1], &edit, &want);
}

/// Shards 0/2 and 1/2 of ci-guard with 4 trials, in `dir/a0` and `dir/a1`.
pub(crate) fn two_shards(dir: &Path) -> [PathBuf; 2] {
    let (a0, a1) = (dir.join("a0"), dir.join("a1"));
    run("4", &["--shard", "0/2"], &a0);
    run("4", &["--shard", "1/2"], &a1);
    [a0, a1]
}

/// `calbench merge SHARDS --out …/new/merged` after each file of `edits` is given its text:
/// refused (exit status 1) in one line naming the first file and holding each of `want`,
/// with nothing written, not even the output folder or its parent; the files then restored.
pub(crate) fn refused_merge(shards: &[&Path], edits: &[(&Path, String)], want: &[&str]) {
    let own: Vec<String> = edits.iter().map(|(f, _)| read(f)).collect();
    for (f, text) in edits {
        std::fs::write(f, text).unwrap();
    }
    let parent = shards[0].with_file_name("new");
    let out = parent.join("merged");
    let mut args = vec!["merge"];
    args.extend(shards.iter().map(|s| path_arg(s)));
    args.extend(["--out", path_arg(&out)]);
    let o = calbench(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    one_line_naming(&err, edits[0].0, want);
    assert!(!parent.exists(), "{} was left behind", parent.display());
    for ((f, _), text) in edits.iter().zip(own) {
        std::fs::write(f, text).unwrap();
    }
}

/// A run of ci-guard (600 trials, one thread) into `dir/killed`, killed once its checkpoint
/// counts a trial: the output folder and the checkpoint's `checkpoint.json`.
pub(crate) fn killed_run(dir: &Path) -> (PathBuf, PathBuf) {
    let killed = dir.join("killed");
    let sc = root().join("scenarios/ci-guard.toml");
    let args = ["run", path_arg(&sc), "--trials", "600", "--threads", "1"];
    let meta = kill_once_checkpointed(
        &[&args[..], &["--out", path_arg(&killed)]].concat(),
        &killed,
        300,
    );
    assert!(
        !killed.join("summary.json").exists(),
        "the run ended before it was killed"
    );
    (killed, meta)
}

/// `calbench run --resume KILLED` after each file of `edits` (in its checkpoint) is given its
/// text: refused (exit status 1) in one line naming the first file and holding each of
/// `want`, the checkpoint's files left as the edits made them and no output folder written;
/// the files then restored.
pub(crate) fn refused_resume(killed: &Path, edits: &[(&Path, String)], want: &[&str]) {
    let own: Vec<String> = edits.iter().map(|(f, _)| read(f)).collect();
    for (f, text) in edits {
        std::fs::write(f, text).unwrap();
    }
    let checkpoint = edits[0].0.parent().unwrap();
    let files = ["checkpoint.json", "records.txt"].map(|f| read(&checkpoint.join(f)));
    let o = calbench(&["run", "--resume", path_arg(killed)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    one_line_naming(&err, edits[0].0, want);
    let now = ["checkpoint.json", "records.txt"].map(|f| read(&checkpoint.join(f)));
    assert!(
        now == files,
        "the refused resume changed the checkpoint: {err}"
    );
    assert!(!killed.exists(), "{} was left behind", killed.display());
    for ((f, _), text) in edits.iter().zip(own) {
        std::fs::write(f, text).unwrap();
    }
}

/// The first record line of `text` (a `records.txt`) with `from` replaced by `to`.
fn first_record_with(text: &str, from: &str, to: &str) -> String {
    let (first, rest) = text.split_once('\n').unwrap();
    assert!(first.contains(from), "{from}");
    format!("{}\n{rest}", first.replacen(from, to, 1))
}

/// A share I ≥ N or N = 0 in `shard.json` and a record whose sweep point is so large that its
/// work unit overflows are refused naming the file and key or line, where `merge` panicked
/// (indexing the shards past their count; multiplying the point by the trial count); a trial
/// count other than the settings' is refused naming `trials`, where it was read as given.
#[test]
fn merge_refuses_a_share_trial_count_or_sweep_point_out_of_range() {
    let dir = tmp_dir("records-range-merge");
    let [a0, a1] = two_shards(&dir);
    let (meta, records) = (a0.join("shard.json"), a0.join("records.txt"));
    let own = read(&meta);
    let share = |i: &str, n: &str| {
        own.replace("\"index\": 0", &format!("\"index\": {i}"))
            .replace("\"count\": 2", &format!("\"count\": {n}"))
    };
    refused_merge(
        &[&a0, &a1],
        &[(&meta, share("5", "2"))],
        &["shard 5/2", "0 ≤ I < N"],
    );
    refused_merge(
        &[&a0, &a1],
        &[(&meta, share("0", "0"))],
        &["shard 0/0", "0 ≤ I < N"],
    );
    let trials = |p: &Path| read(p).replace("\"trials\": 4,", "\"trials\": 5,");
    let meta1 = a1.join("shard.json");
    let edits = [
        (meta.as_path(), trials(&meta)),
        (meta1.as_path(), trials(&meta1)),
    ];
    refused_merge(
        &[&a0, &a1],
        &edits,
        &["trials: 5", "its settings run 4 trials"],
    );
    let point = first_record_with(&read(&records), "(point:0,", "(point:18446744073709551615,");
    refused_merge(
        &[&a0, &a1],
        &[(&records, point)],
        &["line 1", "sweep point 18446744073709551615 is beyond"],
    );
}

/// The same for a checkpoint: a share with N = 0, more trials done than the run's share
/// holds, a trial count other than the settings' and a record's overflowing sweep point are
/// refused naming `checkpoint.json` and the key, or `records.txt` and the line, where `run
/// --resume` panicked dividing by the share count or overflowing a unit, or named a missing
/// trial.
#[test]
fn resume_refuses_a_share_trial_count_or_sweep_point_out_of_range() {
    let dir = tmp_dir("records-range-resume");
    let (killed, meta) = killed_run(&dir);
    let (json, records) = (read(&meta), meta.with_file_name("records.txt"));
    let shard = json.replace("\"shard\": null", "\"shard\": {\"index\": 0, \"count\": 0}");
    refused_resume(&killed, &[(&meta, shard)], &["shard 0/0", "0 ≤ I < N"]);
    let done = with_field(&json, "done", "601");
    refused_resume(&killed, &[(&meta, done)], &["done", "601 trials complete"]);
    // A value of the wrong type, a key the checkpoint does not have (passed over, before),
    // an unknown key of the share: named by their line and key path.
    let line = |key: &str| {
        json.lines()
            .position(|l| l.contains(&format!("\"{key}\"")))
            .unwrap()
            + 1
    };
    let seed = with_field(&json, "seed", "\"42\"");
    let at = format!("line {}, seed", line("seed"));
    refused_resume(&killed, &[(&meta, seed)], &[&at, "expected a whole number"]);
    let unknown = json.replacen("\"done\"", "\"bogus\": 1,\n  \"done\"", 1);
    refused_resume(
        &killed,
        &[(&meta, unknown)],
        &["bogus", "unknown field `bogus`"],
    );
    let extra = json.replace(
        "\"shard\": null",
        "\"shard\": {\"index\": 0, \"count\": 1, \"x\": 1}",
    );
    refused_resume(
        &killed,
        &[(&meta, extra)],
        &["shard.x", "unknown field `x`"],
    );
    let trials = with_field(&json, "trials", "7");
    refused_resume(
        &killed,
        &[(&meta, trials)],
        &["trials", "its settings run 600"],
    );
    let text = read(&records);
    let point = first_record_with(&text, "(point:0,", "(point:18446744073709551615,");
    let bytes = with_field(&json, "bytes", &point.len().to_string());
    let edits = [(records.as_path(), point), (meta.as_path(), bytes)];
    refused_resume(
        &killed,
        &edits,
        &["line 1", "sweep point 18446744073709551615"],
    );
}

/// `json` (a `checkpoint.json`) with the number of `key` replaced by `value`.
pub(crate) fn with_field(json: &str, key: &str, value: &str) -> String {
    let at = json.find(&format!("\"{key}\": ")).unwrap() + key.len() + 4;
    let end = at + json[at..].find([',', '\n']).unwrap();
    format!("{}{value}{}", &json[..at], &json[end..])
}

/// A refused `merge` or `run --resume` leaves no output folder: the folder (and its parents)
/// that the check of `--out` creates to probe that it can write is removed again, where a
/// refusal after it left it empty.
#[test]
fn a_refused_merge_or_resume_leaves_no_output_folder() {
    let dir = tmp_dir("records-no-folder");
    let [a0, _] = two_shards(&dir);
    let meta = a0.join("shard.json");
    let format = read(&meta).replace("calbench-shard-10", "calbench-shard-9");
    refused_merge(&[&a0], &[(&meta, format)], &["format", "calbench-shard-9"]);
    let out = dir.join("new/killed");
    let o = calbench(&["run", "--resume", path_arg(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    one_line_naming(&err, &out, &["--resume", "no checkpoint"]);
    assert!(
        !dir.join("new").exists(),
        "the resume left {}",
        out.display()
    );
}

/// A record that its checksum passes but that reads as no trial (a number made a string, the
/// sum made to match) is refused before the checkpoint changes, naming the line, where the
/// resume began, failed at that record and removed the checkpoint; the scenario as run that
/// `checkpoint.json` holds, altered, is refused naming it and `settings`, where the message
/// named the scenario file, whose line it gave; so is a malformed `precision`.
#[test]
fn resume_refuses_a_checkpoint_it_cannot_replay_before_changing_it() {
    let dir = tmp_dir("records-unreadable-resume");
    let (killed, meta) = killed_run(&dir);
    let (json, records) = (read(&meta), meta.with_file_name("records.txt"));
    let (line, bytes) = first_record_resummed(&meta, |first| {
        let from = first.find("truth:[").unwrap() + "truth:[".len();
        let end = from + first[from..].find(',').unwrap();
        format!("{}\"x\"{}", &first[..from], &first[end..])
    });
    let edits = [(records.as_path(), line), (meta.as_path(), bytes)];
    refused_resume(&killed, &edits, &["line 1", "cannot be read"]);
    let at = json.find("count = 40").unwrap();
    let toml = format!("{}count = \\\"x\\\"{}", &json[..at], &json[at + 10..]);
    refused_resume(
        &killed,
        &[(&meta, toml)],
        &["settings", "calibration.count"],
    );
    // A malformed `precision` is named as the checkpoint's key, before the checkpoint is
    // rewritten, where the resume rewrote it and then blamed `--precision`.
    let garbage = json.replacen("\"pid\"", "\"precision\": \"garbage\",\n  \"pid\"", 1);
    refused_resume(
        &killed,
        &[(&meta, garbage)],
        &["checkpoint.json: precision", "has no unit"],
    );
    // Resumed with a scenario of other settings: the first setting that differs is named with
    // its two values as TOML writes them, where the message printed two tables' debug forms.
    let edited = dir.join("ci-guard.toml");
    let text = read(&root().join("scenarios/ci-guard.toml"));
    std::fs::write(&edited, text.replacen("count = 40", "count = 41", 1)).unwrap();
    let o = calbench(&[
        "run",
        "--resume",
        path_arg(&killed),
        path_arg(&edited),
        "--trials",
        "600",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    one_line_naming(
        &err,
        &meta,
        &["the checkpoint was written with `calibration.count` 40, this run has 41"],
    );
    // Merged before its run finished: the folder is named with how to finish it.
    let o = calbench(&[
        "merge",
        path_arg(&killed),
        "--out",
        path_arg(&dir.join("m")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("shard.json: this shard's run did not finish")
            && err.contains(&format!("calbench run --resume {}", killed.display())),
        "{err}"
    );
}

/// `merge` of shards whose scenario as run (`settings`) was altered alike names the first
/// `shard.json` and `settings`, on one line, where it named the scenario file, and altered in
/// one shard alone names that shard's, where it called them shards of different runs; a negative
/// `seconds` and an unknown key are refused naming the file.
#[test]
fn merge_refuses_altered_settings_naming_shard_json() {
    let dir = tmp_dir("records-settings-merge");
    let [a0, a1] = two_shards(&dir);
    let (m0, m1) = (a0.join("shard.json"), a1.join("shard.json"));
    let bad = |p: &Path| read(p).replace("count = 40", "count = [");
    let edits = [(m0.as_path(), bad(&m0)), (m1.as_path(), bad(&m1))];
    refused_merge(
        &[&a0, &a1],
        &edits,
        &["settings", "cannot be read (line 8: unexpected"],
    );
    // Altered in the second shard alone: that file's fault, where merge called the two
    // "shards of different runs".
    refused_merge(
        &[&a0, &a1],
        &edits[1..],
        &["settings", "cannot be read (line 8: unexpected"],
    );
    // A wall time no run has, which merge summed into timing.json, and a key shard.json
    // does not have, which merge passed over.
    let negative = with_field(&read(&m0), "seconds", "-5");
    refused_merge(
        &[&a0, &a1],
        &[(&m0, negative)],
        &["seconds", "-5 is not a run's wall time"],
    );
    let unknown = read(&m0).replacen("\"seconds\"", "\"foo\": 1,\n  \"seconds\"", 1);
    refused_merge(
        &[&a0, &a1],
        &[(&m0, unknown)],
        &["shard.json", "unknown field `foo`"],
    );
    // A byte that is not UTF-8, which was "not a shard folder", naming no line.
    let own = read(&m0);
    let mut bytes = own.clone().into_bytes();
    let at = own.find("\"seconds\"").unwrap() + 2;
    bytes[at] = 0xFE;
    std::fs::write(&m0, &bytes).unwrap();
    let o = calbench(&[
        "merge",
        path_arg(&a0),
        path_arg(&a1),
        "--out",
        path_arg(&dir.join("m")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    let line = own[..at].lines().count();
    let want = format!("shard.json: line {line}: not UTF-8 text: byte");
    assert!(!o.status.success() && err.contains(&want), "{want}: {err}");
    assert!(!err.contains("not a shard folder"), "{err}");
    std::fs::write(&m0, own).unwrap();
    // Of the wrong type or unknown deeper down: named by the key's line and path.
    let text = read(&m0);
    let line = text
        .lines()
        .position(|l| l.contains("\"seconds\""))
        .unwrap()
        + 1;
    let null = with_field(&text, "seconds", "null");
    let at = format!("line {line}, seconds");
    refused_merge(&[&a0, &a1], &[(&m0, null)], &[&at, "invalid type: null"]);
    let index = text.replacen("\"index\": 0,", "\"index\": 0,\n    \"extra\": 1,", 1);
    refused_merge(
        &[&a0, &a1],
        &[(&m0, index)],
        &["shard.extra", "unknown field `extra`"],
    );
    // A byte-order mark (an editor's UTF-8) is not part of the text.
    std::fs::write(&m0, format!("\u{feff}{text}")).unwrap();
    calbench_ok(&[
        "merge",
        path_arg(&a0),
        path_arg(&a1),
        "--out",
        path_arg(&dir.join("bom")),
    ]);
    std::fs::write(&m0, text).unwrap();
}

/// The checkpoint `meta`'s `records.txt` with its first record edited by `edit` and its
/// checksum made to match, and `meta` with `bytes` counting the records so edited.
fn first_record_resummed(meta: &Path, edit: impl Fn(&str) -> String) -> (String, String) {
    let v = load_json(meta);
    let (settings, seed) = (v["settings"].as_str().unwrap(), v["seed"].as_u64().unwrap());
    let text = read(&meta.with_file_name("records.txt"));
    let (first, rest) = text.split_once('\n').unwrap();
    let records = format!("{}\n{rest}", resummed(&edit(first), settings, seed));
    let bytes = with_field(&read(meta), "bytes", &records.len().to_string());
    (records, bytes)
}

/// A record whose checksum was made to match an edit that gives it a method the run does not
/// have is refused when the replay reaches it, naming `records.txt` and its line, where `run
/// --resume` panicked indexing past the run's methods; the run ends as a failed run does,
/// without output.
#[test]
fn resume_refuses_a_record_that_does_not_fit_its_run() {
    let dir = tmp_dir("records-unfit-resume");
    let (killed, meta) = killed_run(&dir);
    let records = meta.with_file_name("records.txt");
    let (line, bytes) =
        first_record_resummed(&meta, |first| first.replacen("(method:0,", "(method:7,", 1));
    std::fs::write(&records, line).unwrap();
    std::fs::write(&meta, bytes).unwrap();
    let o = calbench(&["run", "--resume", path_arg(&killed)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let last = err.trim_end().lines().last().unwrap();
    one_line_naming(
        last,
        &records,
        &["line 1", "does not fit its run", "method 7"],
    );
    assert!(!killed.join("summary.json").exists());
}

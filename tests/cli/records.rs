//! A record of `records.txt` binds its run (docs/formats.md § 7.3): the records of another run
//! with the same scenario name and seed but other settings (here another trial count, whose
//! first trials draw the same numbers, so only the run's identity tells them apart), copied
//! into a shard or a checkpoint, are refused by `merge` and `run --resume`, naming the file
//! and the line, and nothing is written or changed.

use std::path::Path;

use crate::common::{
    calbench, calbench_ok, kill_once_checkpointed, one_line_naming, path_arg, read, root, tmp_dir,
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
    let (killed, other) = (dir.join("killed"), dir.join("other"));
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
    let o = calbench(&["run", "--resume", path_arg(&killed)]);
    assert!(
        !o.status.success(),
        "resumed from the records of another run"
    );
    let err = String::from_utf8_lossy(&o.stderr);
    one_line_naming(&err, &records, &["line 1", "trial 0", "another run"]);
    assert_eq!(read(&records), foreign);
    assert_eq!(read(&meta), json);
}

/// A `shard.json` whose block lists other methods or parameters than its records hold (a
/// method line deleted, a parameter listed twice) is refused naming it, where the merge
/// panicked indexing past the lists, and nothing is written.
#[test]
fn merge_refuses_a_shard_json_whose_blocks_do_not_fit_its_records() {
    let dir = tmp_dir("records-altered-blocks");
    let (a0, a1) = (dir.join("a0"), dir.join("a1"));
    run("4", &["--shard", "0/2"], &a0);
    run("4", &["--shard", "1/2"], &a1);
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
        std::fs::write(&meta, own.replacen(from, to, 1)).unwrap();
        let out = dir.join("merged");
        let o = calbench(&[
            "merge",
            path_arg(&a0),
            path_arg(&a1),
            "--out",
            path_arg(&out),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        one_line_naming(&err, &meta, &["blocks", "records.txt, line 1", why]);
        assert!(!out.join("summary.json").exists());
    }
}

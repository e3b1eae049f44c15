//! A scenario written otherwise (`2500` for `2500.0`) sets the same (docs/formats.md § 2.4):
//! `run --resume` given it goes on as the checkpoint wrote it, where it had been refused as
//! another run's; `merge` refuses a shard of it beside shards of the other text, naming the key
//! and asking for that shard again (a run's `scenario.toml` holds one text), where it had said
//! "shards of different runs". A missing shard's command says where its relative scenario
//! path is from, when it does not reach the file from where `merge` runs (§ 2.3).

use std::path::Path;

use crate::common::{
    bin, calbench_ok, kill_once_checkpointed, path_arg, read, refused, root, tmp_dir,
};

/// The guard's scenario with the tracker's pose written in integers, in `dir`.
fn written_otherwise(dir: &Path) -> std::path::PathBuf {
    let text = read(&root().join("scenarios/ci-guard.toml")).replace(
        "[2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]",
        "[2500, 0, 500, 0, 0, 180]",
    );
    let p = dir.join("ints.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn a_resume_takes_the_scenario_written_otherwise() {
    let dir = tmp_dir("cli-written-resume");
    let guard = root().join("scenarios/ci-guard.toml");
    let killed = dir.join("killed");
    let run = ["run", path_arg(&guard), "--trials", "600", "--threads", "1"];
    kill_once_checkpointed(
        &[&run[..], &["--out", path_arg(&killed)]].concat(),
        &killed,
        300,
    );
    let ints = written_otherwise(&dir);
    let resume = ["run", "--resume", path_arg(&killed), path_arg(&ints)];
    calbench_ok(&[&resume[..], &["--trials", "600"]].concat());
    let whole = dir.join("whole");
    calbench_ok(&[&run[..], &["--out", path_arg(&whole)]].concat());
    for f in ["summary.json", "trials.csv", "scenario.toml"] {
        assert!(read(&killed.join(f)) == read(&whole.join(f)), "{f}");
    }
}

#[test]
fn a_shard_of_the_scenario_written_otherwise_is_asked_for_again() {
    let dir = tmp_dir("cli-written-merge");
    std::fs::create_dir_all(dir.join("scen")).unwrap();
    std::fs::copy(
        root().join("scenarios/ci-guard.toml"),
        dir.join("scen/guard.toml"),
    )
    .unwrap();
    let ints = written_otherwise(&dir);
    let in_dir = |args: &[&str]| bin().current_dir(&dir).args(args).output().unwrap();
    for (i, scenario) in [(0, "scen/guard.toml"), (1, path_arg(&ints))] {
        let share = format!("{i}/2");
        let out = format!("sh/{i}");
        let o = in_dir(&[
            "run", scenario, "--trials", "4", "--shard", &share, "--out", &out,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let o = in_dir(&["merge", "sh/0", "sh/1", "--out", "merged"]);
    let err = refused(
        &o,
        &[
            "write `tracker.pose` otherwise",
            "they set the same",
            "run sh/1 again from the scenario sh/0 ran",
        ],
    );
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!dir.join("merged").exists());
    // Shard 1 missing, merged from another folder: the scenario path shard 0 was started
    // with is relative to its own folder.
    let elsewhere = dir.join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    let o = bin()
        .current_dir(&elsewhere)
        .args(["merge", "../sh/0", "--out", "merged"])
        .output()
        .unwrap();
    let err = refused(
        &o,
        &[
            "calbench run scen/guard.toml --trials 4 --seed 42 --shard 1/2 --out ../sh/1",
            "(from the folder the shards were run in: scen/guard.toml is relative to it)",
        ],
    );
    assert_eq!(o.status.code(), Some(1), "{err}");
}

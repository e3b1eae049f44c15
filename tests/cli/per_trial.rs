//! Optimised pose sets drawn per trial (docs/formats.md `calibration.optimise`): each trial
//! optimises its own set from its own seed, so the trials vary the set the optimiser happens
//! to choose; the run stays the same bytes whatever the thread count, shard split or resume;
//! and Guo 2024's claims no longer flip between "reproduces" and "contradicts" with the
//! study seed.

use std::collections::BTreeMap;
use std::path::Path;

use crate::common::{
    calbench_ok, kill_once_checkpointed, load_json, path_arg, read, root,
    threads_and_merged_shards, tmp_dir, write_scenario,
};

/// One strategy, DETMAX over a small pool, so that `simulate` (which measures the first
/// strategy's poses) shows the trial's set.
const SMALL: &str = r#"
name = "per-trial"
description = "DETMAX sets optimised per trial"
seed = 11
trials = 40
[robot]
builtin = "irb2600"
[errors]
kind = "paper"
[tracker]
pose = [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]
[compliance]
model = "none"
[calibration]
count = 14
strategies = ["detmax"]
candidates = 40
[validation]
count = 10
[[methods]]
name = "ls"
"#;

/// The joint columns (`q1`…) of a measurement file, row by row.
fn joints(csv: &Path) -> Vec<String> {
    let text = read(csv);
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let cols: Vec<usize> = (0..head.len())
        .filter(|&i| head[i].starts_with('q'))
        .collect();
    assert_eq!(cols.len(), 6, "{head:?}");
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            cols.iter().map(|&i| f[i]).collect::<Vec<_>>().join(",")
        })
        .collect()
}

/// The calibration poses `simulate` measures in trials 1 and 2 of `scenario`.
fn poses_of_trials(dir: &Path, scenario: &Path) -> [Vec<String>; 2] {
    [1, 2].map(|i| {
        let out = dir.join(format!("sim{i}"));
        let trial = i.to_string();
        calbench_ok(&[
            "simulate",
            path_arg(scenario),
            "--trial",
            &trial,
            "--out",
            path_arg(&out),
        ]);
        joints(&out.join("measurements.csv"))
    })
}

#[test]
fn each_trial_optimises_its_own_set_unless_told_once_per_study() {
    let dir = tmp_dir("cli-per-trial-sets");
    let per_trial = write_scenario(&dir, "trial", SMALL);
    let [a, b] = poses_of_trials(&dir.join("trial"), &per_trial);
    assert_eq!(a.len(), 14);
    assert_ne!(a, b, "trials 1 and 2 measured the same optimised set");
    let once = SMALL.replace("candidates = 40", "candidates = 40\noptimise = \"study\"");
    let once = write_scenario(&dir, "study", &once);
    let [a, b] = poses_of_trials(&dir.join("study"), &once);
    assert_eq!(
        a, b,
        "a set optimised once per study differs between trials"
    );
}

#[test]
fn sets_optimised_per_trial_give_the_same_bytes_across_threads_shards_and_resume() {
    let dir = tmp_dir("cli-per-trial-bytes");
    let sc = write_scenario(&dir, "s", SMALL);
    let [one, two, merged] = threads_and_merged_shards(&dir, &sc);
    // A checkpoint is written every 256 trials: the killed run needs more than that, and
    // enough after its first checkpoint (344 trials, about 2 s) for the poll to see it.
    let long = write_scenario(&dir, "long", &SMALL.replace("trials = 40", "trials = 600"));
    let long = path_arg(&long);
    let (whole, killed) = (dir.join("whole"), dir.join("killed"));
    calbench_ok(&["run", long, "--threads", "2", "--out", path_arg(&whole)]);
    let args = ["run", long, "--threads", "1", "--out", path_arg(&killed)];
    kill_once_checkpointed(&args, &killed, 600);
    assert!(
        !killed.join("summary.json").exists(),
        "the run ended before it was killed"
    );
    calbench_ok(&["run", "--resume", path_arg(&killed)]);
    // Everything but the wall times.
    let strip = |d: &Path, f: &str| {
        read(&d.join(f))
            .lines()
            .filter(|l| !l.contains("seconds"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    let trials = |d: &Path| {
        let text = read(&d.join("trials.csv"));
        let mut lines = text.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let keep: Vec<usize> = (0..head.len())
            .filter(|&i| !head[i].contains("seconds"))
            .collect();
        lines
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                keep.iter().map(|&i| f[i]).collect::<Vec<_>>().join(",")
            })
            .collect::<Vec<_>>()
    };
    for (a, b) in [(&one, &two), (&one, &merged), (&whole, &killed)] {
        assert_eq!(trials(a), trials(b), "{}", b.display());
        assert_eq!(
            strip(a, "summary.json"),
            strip(b, "summary.json"),
            "{}",
            b.display()
        );
    }
}

/// Guo's claims at 100 trials and study seeds 1 to 5 (the issue's seeds 1–10 gave
/// "contradicts" at three seeds and "reproduces" at five for `guo-eta-separated` when the
/// sets were optimised once per study): no claim reads "reproduces" at one seed and
/// "contradicts" at another. Minutes in a release build:
/// `cargo test --release --test cli per_trial::guo_verdicts -- --ignored`.
#[test]
#[ignore]
fn guo_verdicts_do_not_flip_with_the_study_seed() {
    let dir = tmp_dir("cli-per-trial-guo");
    let sc = root().join("scenarios/guo2024-3t2r.toml");
    let mut seen: BTreeMap<String, BTreeMap<String, Vec<u64>>> = BTreeMap::new();
    for seed in 1..=5u64 {
        let out = dir.join(format!("seed{seed}"));
        let s = seed.to_string();
        calbench_ok(&[
            "run",
            path_arg(&sc),
            "--trials",
            "100",
            "--seed",
            &s,
            "--out",
            path_arg(&out),
        ]);
        let summary = load_json(&out.join("summary.json"));
        let claims = summary["claims"].as_array().expect("the scenario's claims");
        assert!(!claims.is_empty());
        for c in claims {
            let id = c["id"].as_str().unwrap().to_string();
            let verdict = c["verdict"].as_str().unwrap().to_string();
            seen.entry(id)
                .or_default()
                .entry(verdict)
                .or_default()
                .push(seed);
        }
    }
    eprintln!("{seen:#?}");
    for (id, verdicts) in &seen {
        assert!(
            !(verdicts.contains_key("reproduces") && verdicts.contains_key("contradicts")),
            "{id}: {verdicts:?}"
        );
    }
}

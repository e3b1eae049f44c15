//! A refused command leaves no folder it created (docs/formats.md § 1, "Output folders"):
//! `run` and `merge` make their output folder before the work, to refuse one they cannot
//! write in; refused later (a shard missing, a scenario refused once the run starts, a
//! folder to resume that holds no run), they remove it again with the folders made to hold
//! it, and an empty folder that existed before stays as it was.

use std::path::Path;

use crate::common::{calbench, path_arg, tmp_dir, write_scenario, SMALL_STUDY};

/// Runs `args`, which must be refused naming each of `words`, and checks that `dir` holds
/// exactly `kept` afterwards.
fn refused_leaving(args: &[&str], words: &[&str], dir: &Path, kept: &[&str]) {
    let o = calbench(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    for w in words {
        assert!(err.contains(w), "{args:?}: {w} not in {err}");
    }
    let mut left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, kept, "{args:?} left folders behind");
}

#[test]
fn a_refused_run_merge_or_resume_leaves_no_folder_it_created() {
    let dir = tmp_dir("refused-out");
    // LS cannot take parameters the data do not determine: refused once the run starts.
    let text = format!("{SMALL_STUDY}[identification]\nparams = \"all\"\n");
    let sc = write_scenario(&dir, "all", &text);
    let nested = dir.join("new").join("out");
    let kept = ["all.toml"];
    let run = ["run", path_arg(&sc), "--threads", "1", "--out"];
    let params = ["identification.params", "all.toml"];
    refused_leaving(
        &[&run[..], &[path_arg(&nested)]].concat(),
        &params,
        &dir,
        &kept,
    );
    let missing = dir.join("missing");
    let merge = ["merge", path_arg(&missing), "--out", path_arg(&nested)];
    refused_leaving(&merge, &["missing", "shard.json"], &dir, &kept);
    let resume = ["run", "--resume", path_arg(&nested)];
    refused_leaving(&resume, &["checkpoint"], &dir, &kept);
    // An empty folder given as --out was there before: it stays, empty.
    let empty = dir.join("empty");
    std::fs::create_dir(&empty).unwrap();
    let kept = ["all.toml", "empty"];
    refused_leaving(
        &[&run[..], &[path_arg(&empty)]].concat(),
        &params,
        &dir,
        &kept,
    );
    let merge = ["merge", path_arg(&missing), "--out", path_arg(&empty)];
    refused_leaving(&merge, &["shard.json"], &dir, &kept);
    assert_eq!(std::fs::read_dir(&empty).unwrap().count(), 0);
}

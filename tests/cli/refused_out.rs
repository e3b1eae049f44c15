//! A refused command leaves no folder it created (docs/formats.md § 1, "Output folders"):
//! `run` and `merge` make their output folder before the work, to refuse one they cannot
//! write in; refused later (a shard missing, a scenario refused once the run starts, a
//! folder to resume that holds no run), they remove it again with the folders made to hold
//! it, and an empty folder that existed before stays as it was.

use std::path::Path;

use crate::common::{calbench, files_in, path_arg, tmp_dir, write_scenario, SMALL_STUDY};

/// Runs `args`, which must be refused naming each of `words`, and checks that `dir` holds
/// exactly `kept` afterwards.
fn refused_leaving(args: &[&str], words: &[&str], dir: &Path, kept: &[&str]) {
    let o = calbench(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    for w in words {
        assert!(err.contains(w), "{args:?}: {w} not in {err}");
    }
    let left: Vec<String> = files_in(dir).into_iter().collect();
    assert_eq!(left, kept, "{args:?} left folders behind");
}

#[test]
fn a_refused_run_merge_or_resume_leaves_no_folder_it_created() {
    let dir = tmp_dir("refused-out");
    // LS cannot take parameters the data do not determine: refused once the run starts.
    let text = format!("{SMALL_STUDY}[identification]\nparams = \"all\"\n");
    let sc = write_scenario(&dir, "all", &text);
    let (missing, empty) = (dir.join("missing"), dir.join("empty"));
    // A folder and the one holding it made by each command, then an empty folder given as
    // --out that was there before: it stays, empty.
    let cases = [
        (dir.join("new").join("out"), &["all.toml"][..]),
        (empty.clone(), &["all.toml", "empty"][..]),
    ];
    for (out, kept) in cases {
        if out == empty {
            std::fs::create_dir(&empty).unwrap();
        }
        let o = path_arg(&out);
        let run = ["run", path_arg(&sc), "--threads", "1", "--out", o];
        refused_leaving(&run, &["identification.params", "all.toml"], &dir, kept);
        let merge = ["merge", path_arg(&missing), "--out", o];
        refused_leaving(&merge, &["missing", "shard.json"], &dir, kept);
        refused_leaving(&["run", "--resume", o], &["checkpoint"], &dir, kept);
    }
    assert_eq!(std::fs::read_dir(&empty).unwrap().count(), 0);
}

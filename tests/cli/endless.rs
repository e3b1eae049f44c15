//! A file calbench reads whole as text is read no further than 256 MiB (docs/formats.md
//! § 8.1): `/dev/zero` given for a robot, a scenario, a task, a mapping, a summary, a
//! baseline or a shard's `shard.json` is refused at once naming it, where it filled the
//! memory until the system killed the process. Each command runs with its address space
//! capped at 1.5 GB, so that a read without end fails the test rather than the machine.

use std::path::Path;

use crate::common::{path_arg, refused, tmp_dir};

/// `calbench ARGS` in `dir` with its virtual memory capped at 1.5 GB (`ulimit -v`).
fn capped(dir: &Path, args: &[&str]) -> std::process::Output {
    let mut sh = std::process::Command::new("sh");
    sh.current_dir(dir)
        .arg("-c")
        .arg("ulimit -v 1500000 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_calbench"))
        .args(args);
    sh.output().unwrap()
}

#[test]
fn an_endless_file_read_as_text_is_refused_naming_it() {
    if !Path::new("/dev/zero").exists() {
        assert!(
            !crate::html::ci(),
            "no /dev/zero (CI=true: a missing file is a failure)"
        );
        eprintln!("skipped: no /dev/zero to stand for an endless file");
        return;
    }
    let d = tmp_dir("cli-endless");
    std::fs::write(d.join("j.csv"), "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n").unwrap();
    let summary = crate::common::root().join("results/readme/summary.json");
    let summary = path_arg(&summary);
    std::fs::create_dir(d.join("s0")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", d.join("s0/shard.json")).unwrap();
    let z = "/dev/zero";
    let cases: [&[&str]; 7] = [
        &["fk", "--robot", z, "--q", "0,0,0,0,0,0"],
        &["run", z, "--trials", "1"],
        &["check", z, "--baseline", summary],
        &["check", summary, "--baseline", z],
        &["task", z, "--method", "ls", "--out", "o"],
        &["import", "j.csv", "--mapping", z, "--out", "m.csv"],
        &["merge", "s0", "--out", "m"],
    ];
    for args in cases {
        let o = capped(&d, args);
        let err = refused(&o, &["longer than 256 MiB: not a robot, scenario, task"]);
        let named = if args[0] == "merge" {
            "s0: shard.json"
        } else {
            z
        };
        assert!(
            err.starts_with(&format!("error: {named}: ")),
            "{args:?}: {err}"
        );
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    }
    assert!(!d.join("o").exists() && !d.join("m").exists() && !d.join("m.csv").exists());
}

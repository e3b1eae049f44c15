//! A killed run resumed ([`super`]): the bytes of an uninterrupted run, and the refusals of
//! a resume that names another run or a checkpoint still being written.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::write_small;
use crate::common::{
    another_digit, calbench, calbench_ok, kill_once_checkpointed, one_line_naming, path_arg, read,
    tmp_dir, SMALL_STUDY as SMALL,
};

/// A run killed (SIGKILL) once its checkpoint holds trials, resumed with `run --resume`,
/// gives the bytes of an uninterrupted run; a resume naming another seed or scenario is
/// refused, naming what differs; merge names a missing shard and its command.
#[test]
fn a_killed_run_resumes_into_the_same_bytes() {
    let dir = tmp_dir("sweeps-resume");
    let sc = write_small(&dir, "long", &SMALL.replace("trials = 5", "trials = 1200"));
    let full = dir.join("full");
    calbench_ok(&["run", &sc, "--out", path_arg(&full)]);
    let out = dir.join("killed");
    let args = ["run", &sc, "--threads", "1", "--out", path_arg(&out)];
    let meta = kill_once_checkpointed(&args, &out, 120);
    assert!(!out.join("summary.json").exists());
    refused_checkpoints_stay_as_they_were(&dir, &meta);
    let other = write_small(&dir, "other", SMALL);
    for (args, named) in [
        (vec!["run", &sc, "--seed", "3", "--resume"], "seed"),
        (vec!["run", &other, "--resume"], "scenario"),
    ] {
        let mut a = args.clone();
        a.push(path_arg(&out));
        let o = calbench(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(named), "{a:?}: {err}");
    }
    // A checkpoint whose writer still runs on this host is refused unless --force.
    let mut alive = Command::new("sleep").arg("120").spawn().unwrap();
    let text = read(&meta);
    let pid_line = text.lines().find(|l| l.contains("\"pid\"")).unwrap();
    let live = text.replace(pid_line, &format!("  \"pid\": {},", alive.id()));
    std::fs::write(&meta, &live).unwrap();
    let o = calbench(&["run", "--resume", path_arg(&out)]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    one_line_naming(&err, &meta, &["still running", "--force"]);
    assert_eq!(
        read(&meta),
        live,
        "a refused resume leaves the checkpoint as it was"
    );
    calbench_ok(&["run", "--resume", path_arg(&out), "--force"]);
    alive.kill().unwrap();
    alive.wait().unwrap();
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&full.join(f)), read(&out.join(f)), "{f}");
    }
    assert!(
        !meta.exists(),
        "the checkpoint is removed once the run is written"
    );
    let shards: Vec<PathBuf> = (0..3).map(|i| dir.join(format!("shards/{i}"))).collect();
    for i in [0, 2] {
        let s = format!("{i}/3");
        calbench_ok(&[
            "run",
            &sc,
            "--trials",
            "6",
            "--shard",
            &s,
            "--out",
            path_arg(&shards[i]),
        ]);
    }
    let o = calbench(&[
        "merge",
        path_arg(&shards[0]),
        path_arg(&shards[2]),
        "--out",
        "m",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    let cmd = err
        .lines()
        .find(|l| l.contains("--shard 1/3"))
        .expect("the command");
    let words: Vec<&str> = cmd.split_whitespace().skip(1).collect();
    assert_eq!(words.last(), Some(&path_arg(&dir.join("shards/1"))));
    calbench_ok(&words);
    calbench_ok(&[
        "merge",
        path_arg(&shards[0]),
        path_arg(&shards[1]),
        path_arg(&shards[2]),
        "--out",
        path_arg(&dir.join("m")),
    ]);
}

/// Copies of the checkpoint `meta`'s folder, each damaged one way (records cut short, `done`
/// raised by hand, a digit changed, a record twice, a record removed), are each refused by
/// `run --resume` in one line of under 1 kB naming the file, and left byte for byte as they
/// were.
fn refused_checkpoints_stay_as_they_were(dir: &Path, meta: &Path) {
    let from = meta.parent().unwrap();
    let records = read(&from.join("records.txt"));
    let json = read(meta);
    let lines: Vec<&str> = records.lines().collect();
    assert!(lines.len() >= 256, "{} records", lines.len());
    let done_line = json.lines().find(|l| l.contains("\"done\"")).unwrap();
    let bytes: usize = json
        .lines()
        .find_map(|l| l.trim().strip_prefix("\"bytes\": "))
        .unwrap()
        .trim_end_matches(',')
        .parse()
        .unwrap();
    let raised = json.replace(done_line, &done_line.replace(": ", ": 1"));
    let joined = |l: &[&str]| l.iter().map(|l| format!("{l}\n")).collect::<String>();
    let digit = {
        let mut l = lines.clone();
        let line = another_digit(l[1]);
        l[1] = &line;
        joined(&l)
    };
    let twice = {
        let mut l = lines.clone();
        l.insert(1, lines[0]);
        joined(&l)
    };
    let removed = {
        let mut l = lines.clone();
        l.remove(1);
        joined(&l)
    };
    let cases: [(&str, String, String, &str, &[&str]); 5] = [
        (
            "cut",
            records[..bytes / 2].to_string(),
            json.clone(),
            "records.txt",
            &["cut short", "inside the record where trial"],
        ),
        // `done` of at least 256 raised by a leading 1 is more than the share's 1200 trials.
        (
            "raised",
            records.clone(),
            raised,
            "checkpoint.json",
            &["done", "where the run's share holds"],
        ),
        (
            "digit",
            digit,
            json.clone(),
            "records.txt",
            &["line 2", "trial 1", "checksum"],
        ),
        (
            "twice",
            twice,
            json.clone(),
            "records.txt",
            &["line 2", "trial 0 again"],
        ),
        ("removed", removed, json.clone(), "records.txt", &[]),
    ];
    for (name, rec, js, file, want) in cases {
        let cp = dir.join(format!(".{name}.checkpoint"));
        std::fs::create_dir_all(&cp).unwrap();
        std::fs::write(cp.join("records.txt"), &rec).unwrap();
        std::fs::write(cp.join("checkpoint.json"), &js).unwrap();
        let o = calbench(&["run", "--resume", path_arg(&dir.join(name))]);
        assert!(!o.status.success(), "{name}: accepted");
        one_line_naming(&String::from_utf8_lossy(&o.stderr), &cp.join(file), want);
        assert!(
            read(&cp.join("records.txt")) == rec,
            "{name}: records.txt changed"
        );
        assert_eq!(read(&cp.join("checkpoint.json")), js, "{name}");
    }
}

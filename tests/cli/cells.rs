//! The studies of cells on the runner of every study: Ban fig. 3's registration study run as
//! two shards and merged, and an instruments study killed (SIGKILL) once its checkpoint holds
//! a finished trial and resumed, each give the bytes of one run.

use crate::common::{
    calbench, calbench_ok, kill_once_checkpointed, path_arg, read, root, tmp_dir, write_scenario,
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
        calbench_ok(&args);
        out
    };
    let one = run(&["--threads", "2"], "one");
    let s0 = run(&["--shard", "0/2", "--threads", "1"], "s0");
    let s1 = run(&["--shard", "1/2", "--threads", "1"], "s1");
    assert!(s0.join("records.txt").exists() && !s0.join("summary.json").exists());
    let merged = dir.join("merged");
    calbench_ok(&[
        "merge",
        path_arg(&s0),
        path_arg(&s1),
        "--out",
        path_arg(&merged),
    ]);
    for f in FIG3 {
        assert_eq!(read(&one.join(f)), read(&merged.join(f)), "{f}");
    }
    // A shard is not a run: its folder has no summary, and one shard alone does not merge.
    let o = calbench(&["merge", path_arg(&s0), "--out", path_arg(&dir.join("half"))]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("1/2"));
}

/// Two instruments at 40 random poses: two cells of six trials.
const INSTRUMENTS: &str = r#"
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
    let sc = write_scenario(&dir, "s.toml", INSTRUMENTS);
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
    calbench_ok(&["run", "--resume", path_arg(&killed)]);
    assert!(!meta.exists(), "the checkpoint outlived the resumed run");
    for f in ["summary.json", "report.md", "report.html"] {
        assert_eq!(read(&whole.join(f)), read(&killed.join(f)), "{f}");
    }
}

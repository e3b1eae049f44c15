//! The files a scenario reads besides itself (docs/formats.md § 7.3 `inputs`): a shard or a
//! checkpoint records each with its SHA-256, and `merge` and `run --resume` refuse one that
//! has changed since the run started or cannot be found, naming the file and `inputs[k]`,
//! where they read the file as it is now (a merge of shards run on two versions of a robot
//! file went through) and blamed an altered `shard.json` for a path relative to another
//! folder.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::{
    bin, kill_once_checkpointed, one_line_naming, path_arg, read, root, tmp_dir, write_scenario,
};

/// The scenario inside the project folder [`project`] makes.
const SCENARIO: &str = "scen/ban-irb2600.toml";

/// A project folder `dir` holding [`SCENARIO`] and the robot file it names
/// (`../robots/ban-irb2600.toml`); the robot file's path.
fn project(dir: &Path) -> PathBuf {
    for (from, to) in [
        ("scenarios/ban-irb2600.toml", SCENARIO),
        ("robots/ban-irb2600.toml", "robots/ban-irb2600.toml"),
    ] {
        let to = dir.join(to);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(root().join(from), &to).unwrap();
    }
    dir.join("robots/ban-irb2600.toml")
}

/// `calbench ARGS` run in the folder `cwd`.
fn in_folder(cwd: &Path, args: &[&str]) -> Output {
    bin().current_dir(cwd).args(args).output().unwrap()
}

/// `o` succeeded.
fn ok(o: &Output) {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `o` refused with exit status 1, in one line naming `path` and holding each of `want`.
fn refused(o: &Output, path: &Path, want: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    one_line_naming(&err, path, want);
}

/// `run SCENARIO EXTRA… --shard I/2 --out sh/I` in the folder `dir`, an earlier `sh/I`
/// removed first; the shard's folder.
fn shard(dir: &Path, scenario: &str, extra: &[&str], i: usize) -> PathBuf {
    let (share, out) = (format!("{i}/2"), format!("sh/{i}"));
    let _ = std::fs::remove_dir_all(dir.join(&out));
    let mut args = vec!["run", scenario];
    args.extend(extra);
    args.extend(["--shard", &share, "--out", &out]);
    ok(&in_folder(dir, &args));
    dir.join(out)
}

/// `merge` of the two shards [`shard`] writes, in the folder it ran in.
const MERGE: [&str; 5] = ["merge", "sh/0", "sh/1", "--out", "merged"];

/// [`MERGE`] in `dir` refused naming `sh/K/shard.json` and its `inputs[0]` as changed, with
/// nothing written.
fn refused_as_changed(dir: &Path, k: usize) {
    let changed = ["inputs[0]", "has changed since the run started"];
    let shard_json = format!("sh/{k}/shard.json");
    refused(&in_folder(dir, &MERGE), Path::new(&shard_json), &changed);
    assert!(!dir.join("merged").exists());
}

/// `text` with a comment line added: the same robot, another file.
fn commented(text: &str) -> String {
    format!("{text}# edited\n")
}

/// Two shards, one run on the robot file as the other ran it with a comment added, are
/// refused by `merge` naming the shard whose file is not as it is now, and merge to the bytes
/// of one run once both ran on the same file; from another folder, where the path the shards
/// resolved (relative to the folder they ran in) does not reach the file, the merge is
/// refused saying so, with nothing written.
#[test]
fn a_merge_refuses_shards_whose_robot_file_changed_or_cannot_be_found() {
    let dir = tmp_dir("inputs-merge");
    let robot = project(&dir);
    let own = read(&robot);
    let shard = |i: usize| shard(&dir, SCENARIO, &["--trials", "4"], i);
    shard(0);
    std::fs::write(&robot, commented(&own)).unwrap();
    shard(1);
    refused_as_changed(&dir, 0);
    std::fs::write(&robot, &own).unwrap();
    refused_as_changed(&dir, 1);
    shard(1);
    ok(&in_folder(&dir, &MERGE));
    ok(&in_folder(
        &dir,
        &["run", SCENARIO, "--trials", "4", "--out", "whole"],
    ));
    for f in ["summary.json", "trials.csv", "scenario.toml"] {
        let (a, b) = (dir.join("merged").join(f), dir.join("whole").join(f));
        assert!(read(&a) == read(&b), "{f} differs from one run's");
    }
    let elsewhere = dir.join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    let (s0, s1) = (dir.join("sh/0"), dir.join("sh/1"));
    let args = ["merge", path_arg(&s0), path_arg(&s1), "--out", "merged"];
    let want = [
        "inputs[0]",
        "cannot be read",
        "run this command from that folder",
    ];
    refused(&in_folder(&elsewhere, &args), &s0.join("shard.json"), &want);
    assert!(!elsewhere.join("merged").exists());
}

/// Shards of one scenario started by other paths (a relative one and an absolute one), or
/// from a copy of the project holding the same bytes, merge to the bytes of one run: the
/// files' bytes are what the records bind, where `merge` had refused the second shard's
/// `inputs` as altered for naming the robot file by another path. A copy whose robot file
/// holds other bytes is refused as another run's, naming the files read.
#[test]
fn shards_started_by_other_paths_to_the_same_files_merge() {
    let dir = tmp_dir("inputs-paths");
    project(&dir);
    let copy = dir.join("copy");
    let copied_robot = project(&copy);
    shard(&dir, SCENARIO, &["--trials", "4"], 0);
    let absolute = dir.join(SCENARIO);
    shard(&dir, path_arg(&absolute), &["--trials", "4"], 1);
    ok(&in_folder(&dir, &MERGE));
    ok(&in_folder(
        &dir,
        &["run", SCENARIO, "--trials", "4", "--out", "whole"],
    ));
    for f in ["summary.json", "trials.csv"] {
        let (a, b) = (dir.join("merged").join(f), dir.join("whole").join(f));
        assert!(read(&a) == read(&b), "{f} differs from one run's");
    }
    let from_copy = copy.join(SCENARIO);
    shard(&dir, path_arg(&from_copy), &["--trials", "4"], 1);
    let again = ["merge", "sh/0", "sh/1", "--out", "merged-copy"];
    ok(&in_folder(&dir, &again));
    let (a, b) = (
        dir.join("merged-copy/trials.csv"),
        dir.join("whole/trials.csv"),
    );
    assert!(read(&a) == read(&b));
    std::fs::write(&copied_robot, commented(&read(&copied_robot))).unwrap();
    shard(&dir, path_arg(&from_copy), &["--trials", "4"], 1);
    let o = in_folder(&dir, &["merge", "sh/0", "sh/1", "--out", "refused"]);
    let want = ["are shards of different runs: files read", "SHA-256"];
    refused(&o, Path::new("sh/0"), &want);
    assert!(!dir.join("refused").exists());
}

/// A killed run whose robot file then changed is refused by `run --resume` naming its
/// `checkpoint.json` and `inputs[0]`, its checkpoint untouched; with the file restored it
/// resumes.
#[test]
fn a_resume_refuses_a_checkpoint_whose_robot_file_changed() {
    let dir = tmp_dir("inputs-resume");
    let robot = project(&dir);
    let own = read(&robot);
    let killed = dir.join("killed");
    let sc = dir.join(SCENARIO);
    let args = ["run", path_arg(&sc), "--trials", "600", "--threads", "1"];
    let meta = kill_once_checkpointed(
        &[&args[..], &["--out", path_arg(&killed)]].concat(),
        &killed,
        300,
    );
    let checkpoint = read(&meta);
    std::fs::write(&robot, commented(&own)).unwrap();
    let resume = ["run", "--resume", path_arg(&killed)];
    refused(
        &in_folder(&dir, &resume),
        &meta,
        &["inputs[0]", "has changed since the run started"],
    );
    assert!(read(&meta) == checkpoint && !killed.exists());
    std::fs::write(&robot, &own).unwrap();
    ok(&in_folder(&dir, &resume));
    assert!(killed.join("summary.json").exists());
}

/// A pose list swept over is an input at each sweep point: both files are recorded in the
/// order first read, and a shard run before the second was edited is refused by `merge` at
/// `inputs[1]`.
#[test]
fn every_pose_list_a_sweep_reads_is_recorded_and_checked() {
    let dir = tmp_dir("inputs-poses");
    for (name, shift) in [("a.csv", 0.0), ("b.csv", 7.5)] {
        let rows: Vec<String> = (0..30)
            .map(|i| {
                let q: Vec<String> = (0..6)
                    .map(|j| format!("{}", ((i * 7 + j * 13) % 90) as f64 - 45.0 + shift))
                    .collect();
                q.join(",")
            })
            .collect();
        let text = format!("q1,q2,q3,q4,q5,q6\n{}\n", rows.join("\n"));
        std::fs::write(dir.join(name), text).unwrap();
    }
    let study = read(&root().join("scenarios/ci-guard.toml")).replace(
        "strategies = [\"random\"]",
        "strategies = [\"random\", \"file\"]\nposes_file = \"a.csv\"",
    );
    let sweep = "\n[sweep]\nkey = \"calibration.poses_file\"\nvalues = [\"a.csv\", \"b.csv\"]\n";
    let sc = write_scenario(&dir, "s", &format!("{study}{sweep}"));
    let shard = |i: usize| shard(&dir, path_arg(&sc), &["--trials", "2"], i);
    let s0 = shard(0);
    let meta: serde_json::Value = serde_json::from_str(&read(&s0.join("shard.json"))).unwrap();
    let paths: Vec<&str> = meta["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["path"].as_str().unwrap())
        .collect();
    let named = [dir.join("a.csv"), dir.join("b.csv")];
    assert_eq!(paths, named.iter().map(|p| path_arg(p)).collect::<Vec<_>>());
    let b = read(&named[1]);
    std::fs::write(&named[1], b.replacen("\n", "\n0,0,0,0,0,0\n", 1)).unwrap();
    let s1 = shard(1);
    let args = ["merge", path_arg(&s0), path_arg(&s1), "--out", "merged"];
    refused(
        &in_folder(&dir, &args),
        &s0.join("shard.json"),
        &["inputs[1]", "b.csv has changed since the run started"],
    );
}

/// An instruments study's robot file is bound to its shards as a Monte-Carlo study's is: a
/// shard run on the file as it was, merged after the file changed, is refused naming
/// `inputs[0]` (its file had been read relative to the folder the run started in and bound
/// to nothing, so shards of two robots merged).
#[test]
fn an_instruments_study_s_robot_file_is_bound_to_its_shards() {
    let dir = tmp_dir("inputs-instruments");
    let robot = project(&dir);
    let text = r#"
name = "instruments-file-robot"
seed = 3
trials = 2
robot = "../robots/ban-irb2600.toml"

[instruments_study]
poses = [20]
strategies = ["random"]
candidates = 40
validation = 5

[errors]
kind = "paper"
length_mm = 0.5
angle_rad = 0.001

[[measurement]]
kind = "position"
noise_um = 7.5
scale_um_per_m = 3.0
"#;
    write_scenario(&dir.join("scen"), "instruments", text);
    shard(&dir, "scen/instruments.toml", &[], 0);
    std::fs::write(&robot, commented(&read(&robot))).unwrap();
    shard(&dir, "scen/instruments.toml", &[], 1);
    refused_as_changed(&dir, 0);
}

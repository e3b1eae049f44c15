//! `run --shard auto` under the schedulers' conventions: the share from a Slurm job array's
//! or a Kubernetes Indexed Job's environment, merged into the same bytes as one run; the
//! refusals when the variables are missing or inconsistent; `SLURM_CPUS_PER_TASK` as the
//! default of `--threads`; a stepped Slurm array (`--array=0-8:2`) mapped onto its shards;
//! `--threads` capped at the work.

use std::process::Output;

use crate::common::{bin, calbench_ok, merge, path_arg, read, root, tmp_dir};

const VARS: [&str; 7] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_STEP",
    "SLURM_ARRAY_TASK_MAX",
    "SLURM_CPUS_PER_TASK",
    "JOB_COMPLETION_INDEX",
];

fn run_with(env: &[(&str, &str)], args: &[&str]) -> Output {
    let mut c = bin();
    for v in VARS {
        c.env_remove(v);
    }
    c.envs(env.iter().copied()).args(args);
    c.output().unwrap()
}

#[test]
fn shard_auto_reads_slurm_and_kubernetes_and_merges_to_the_bytes_of_one_run() {
    let dir = tmp_dir("cli-cluster");
    let sc = root().join("scenarios/ci-guard.toml");
    let sc = path_arg(&sc);
    let (s0, s1, merged, full) = (dir.join("s0"), dir.join("s1"), dir.join("m"), dir.join("f"));
    // Slurm: array 4-5, task 5 is shard 1 of 2; SLURM_CPUS_PER_TASK sets the threads.
    let slurm = [
        ("SLURM_ARRAY_TASK_ID", "5"),
        ("SLURM_ARRAY_TASK_MIN", "4"),
        ("SLURM_ARRAY_TASK_COUNT", "2"),
        ("SLURM_CPUS_PER_TASK", "1"),
    ];
    let o = run_with(
        &slurm,
        &[
            "run",
            sc,
            "--trials",
            "4",
            "--shard",
            "auto",
            "--out",
            path_arg(&s1),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("shard 1/2"));
    // Kubernetes: the index from JOB_COMPLETION_INDEX, the count from the command line.
    let k8s = [("JOB_COMPLETION_INDEX", "0")];
    let args = [
        "run",
        sc,
        "--trials",
        "4",
        "--shard",
        "auto",
        "--shard-count",
        "2",
        "--out",
    ];
    let o = run_with(&k8s, &[&args[..], &[path_arg(&s0)]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    merge(&[&s0, &s1], &merged);
    calbench_ok(&["run", sc, "--trials", "4", "--out", path_arg(&full)]);
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&merged.join(f)), read(&full.join(f)), "{f}");
    }

    let refused = |env: &[(&str, &str)], extra: &[&str], words: &[&str]| {
        let out = dir.join("refused");
        let mut args = vec![
            "run",
            sc,
            "--trials",
            "4",
            "--shard",
            "auto",
            "--out",
            path_arg(&out),
        ];
        args.extend_from_slice(extra);
        let o = run_with(env, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{env:?} {extra:?}");
        for w in words {
            assert!(err.contains(w), "{err} lacks {w}");
        }
        assert!(!out.join("summary.json").exists() && !out.join("shard.json").exists());
    };
    refused(
        &[],
        &[],
        &["--shard", "SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"],
    );
    refused(&k8s, &[], &["--shard-count"]);
    refused(
        &[("SLURM_ARRAY_TASK_ID", "3")],
        &[],
        &["SLURM_ARRAY_TASK_MIN"],
    );
    refused(
        &slurm,
        &["--shard-count", "3"],
        &["--shard-count 3", "SLURM_ARRAY_TASK_COUNT 2"],
    );
    refused(
        &[
            ("SLURM_ARRAY_TASK_ID", "9"),
            ("SLURM_ARRAY_TASK_MIN", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "2"),
        ],
        &[],
        &["SLURM_ARRAY_TASK_ID 9", "not one of the array's IDs"],
    );
    refused(
        &[("JOB_COMPLETION_INDEX", "x")],
        &["--shard-count", "2"],
        &["JOB_COMPLETION_INDEX", "\"x\""],
    );
    let o = run_with(
        &[("SLURM_CPUS_PER_TASK", "many")],
        &[
            "run",
            sc,
            "--trials",
            "2",
            "--out",
            path_arg(&dir.join("t")),
        ],
    );
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("SLURM_CPUS_PER_TASK"));
    // --shard-count without --shard is refused, not ignored while the whole study runs.
    let alone = dir.join("alone");
    let o = run_with(
        &[],
        &[
            "run",
            sc,
            "--trials",
            "2",
            "--shard-count",
            "2",
            "--out",
            path_arg(&alone),
        ],
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--shard <I/N|auto>"), "{err}");
    assert!(!alone.exists());
}

/// A stepped Slurm array (`sbatch --array=0-8:2`: IDs 0, 2, 4, 6, 8) runs shard ID/2 of 5;
/// an ID off the step, an array whose MAX is not MIN + (COUNT − 1) × STEP, a
/// JOB_COMPLETION_INDEX not below --shard-count and a --shard-count against --shard I/N are
/// refused naming the variables.
#[test]
fn a_stepped_slurm_array_maps_onto_its_shards_and_contradictions_are_refused() {
    let dir = tmp_dir("cli-cluster-step");
    let sc = root().join("scenarios/ci-guard.toml");
    let sc = path_arg(&sc);
    let array = |id: &'static str, max: &'static str| {
        [
            ("SLURM_ARRAY_TASK_ID", id),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_MAX", max),
            ("SLURM_ARRAY_TASK_STEP", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "5"),
        ]
    };
    let run = |env: &[(&str, &str)], extra: &[&str]| {
        let out = dir.join("s");
        let _ = std::fs::remove_dir_all(&out);
        let mut args = vec!["run", sc, "--trials", "5", "--out", path_arg(&out)];
        args.extend_from_slice(extra);
        run_with(env, &args)
    };
    for (id, shard) in [("0", "shard 0/5"), ("4", "shard 2/5"), ("8", "shard 4/5")] {
        let o = run(&array(id, "8"), &["--shard", "auto"]);
        assert!(
            o.status.success(),
            "{id}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(String::from_utf8_lossy(&o.stdout).contains(shard), "{id}");
    }
    let refused = |env: &[(&str, &str)], extra: &[&str], words: &[&str]| {
        let o = run(env, extra);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(!o.status.success(), "{env:?} {extra:?}");
        for w in words {
            assert!(err.contains(w), "{err} lacks {w}");
        }
        assert_eq!(err.matches("setting").count(), 1, "one prefix: {err}");
        assert!(!dir.join("s").join("shard.json").exists());
    };
    refused(
        &array("3", "8"),
        &["--shard", "auto"],
        &["SLURM_ARRAY_TASK_ID 3", "SLURM_ARRAY_TASK_STEP 2"],
    );
    refused(
        &array("4", "9"),
        &["--shard", "auto"],
        &["SLURM_ARRAY_TASK_MAX 9", "SLURM_ARRAY_TASK_STEP 2"],
    );
    refused(
        &[("JOB_COMPLETION_INDEX", "5")],
        &["--shard", "auto", "--shard-count", "3"],
        &["JOB_COMPLETION_INDEX 5", "--shard-count 3"],
    );
    refused(
        &[],
        &["--shard", "0/2", "--shard-count", "3"],
        &["--shard-count", "contradicts --shard 0/2"],
    );
}

/// `--threads 99999` on 4 trials runs on at most 4 threads, with a note, in about the time
/// of `--threads 4`, and writes the same bytes.
#[test]
fn threads_are_capped_at_the_work() {
    let dir = tmp_dir("cli-threads-cap");
    let sc = root().join("scenarios/ci-guard.toml");
    let run = |threads: &str, name: &str| {
        let out = dir.join(name);
        let t0 = std::time::Instant::now();
        let o = run_with(
            &[],
            &[
                "run",
                path_arg(&sc),
                "--trials",
                "4",
                "--threads",
                threads,
                "--out",
                path_arg(&out),
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            t0.elapsed().as_secs_f64(),
            String::from_utf8_lossy(&o.stderr).to_string(),
            out,
        )
    };
    let (four, _, a) = run("4", "four");
    let (many, err, b) = run("99999", "many");
    assert!(err.contains("99999 threads asked for; running on"), "{err}");
    assert!(
        many < 3.0 * four + 2.0,
        "99999 threads: {many:.1} s, 4 threads: {four:.1} s"
    );
    assert_eq!(read(&a.join("summary.json")), read(&b.join("summary.json")));
    let o = run_with(
        &[("SLURM_CPUS_PER_TASK", "0")],
        &[
            "run",
            path_arg(&sc),
            "--trials",
            "2",
            "--out",
            path_arg(&dir.join("z")),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("SLURM_CPUS_PER_TASK"),
        "{err}"
    );
}

/// Every file of `dir` but `shard.json` and `records.txt` (which hold wall times) with a
/// hash of its bytes, in name order.
fn files(dir: &std::path::Path) -> Vec<(std::ffi::OsString, u64)> {
    use std::hash::{Hash, Hasher};
    let mut all: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && !p.ends_with("shard.json") && !p.ends_with("records.txt"))
        .map(|p| {
            let mut h = std::collections::hash_map::DefaultHasher::new();
            std::fs::read(&p).unwrap().hash(&mut h);
            (p.file_name().unwrap().to_owned(), h.finish())
        })
        .collect();
    all.sort();
    all
}

#[test]
fn a_shard_and_a_whole_run_refuse_each_others_folder_and_a_shard_resumes_into_its_own() {
    // A shard written into a whole run's folder replaced its trials.csv beside the run's
    // summary.json and report; a whole run into a shard's folder left the old records.txt
    // and shard.json beside it, which `merge` would read. Both are refused, before any work.
    let dir = tmp_dir("cli-cluster-kinds");
    let sc = root().join("scenarios/ci-guard.toml");
    let sc = path_arg(&sc);
    let (whole, shard) = (dir.join("whole"), dir.join("shard"));
    calbench_ok(&["run", sc, "--trials", "4", "--out", path_arg(&whole)]);
    // A checkpoint is written every 256 trials: the shard runs 2 000, so that the run killed
    // below is still running well after its first checkpoint, on a loaded machine too.
    let shard_args = [
        "run",
        sc,
        "--trials",
        "4000",
        "--threads",
        "1",
        "--shard",
        "0/2",
    ];
    calbench_ok(&[&shard_args[..], &["--out", path_arg(&shard)]].concat());
    let (whole_files, shard_files) = (files(&whole), files(&shard));
    let kept: std::collections::HashMap<&str, String> = ["shard.json", "records.txt"]
        .map(|f| (f, read(&shard.join(f))))
        .into();
    let refused = |args: &[&str], folder: &std::path::Path, marker: &str| {
        let o = run_with(&[], args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        assert!(
            err.contains(&format!("{} holds the results of", folder.display()))
                && err.contains(marker)
                && err.contains("nothing was written"),
            "{err}"
        );
    };
    let into_whole = ["run", sc, "--trials", "4", "--shard", "1/2", "--out"];
    refused(
        &[&into_whole[..], &[path_arg(&whole)]].concat(),
        &whole,
        "a study's run (summary.json)",
    );
    let into_shard = ["run", sc, "--trials", "4", "--out", path_arg(&shard)];
    refused(&into_shard, &shard, "a shard of a run (shard.json)");
    let merged = ["merge", path_arg(&whole), "--out", path_arg(&shard)];
    refused(&merged, &shard, "a shard of a run (shard.json)");
    assert_eq!(files(&whole), whole_files);
    assert_eq!(files(&shard), shard_files);
    for f in ["shard.json", "records.txt"] {
        assert_eq!(read(&shard.join(f)), kept[f], "{f}");
    }

    // The same shard again into its own folder, killed and resumed there: the same bytes.
    crate::common::kill_once_checkpointed(
        &[&shard_args[..], &["--out", path_arg(&shard)]].concat(),
        &shard,
        300,
    );
    calbench_ok(&["run", "--resume", path_arg(&shard)]);
    assert_eq!(files(&shard), shard_files);
    let records = read(&shard.join("records.txt"));
    assert_eq!(records.lines().count(), kept["records.txt"].lines().count());
}

/// A `merge` killed before it moved its files into `--out` leaves its temporary folder
/// `.OUT.partial-PID` (SIGKILL, or Slurm's SIGTERM on pre-emption); the next merge into the
/// same `--out` removes it, and keeps one whose process still runs.
#[test]
fn a_merge_removes_the_temporary_folder_of_a_killed_merge_into_its_folder() {
    let dir = tmp_dir("cli-cluster-dead-partial");
    let sc = root().join("scenarios/ci-guard.toml");
    let merged = crate::common::sharded_and_merged(path_arg(&sc), &dir, 2, &["--trials", "20"]);
    // A process that has ended: its pid names the killed merge's temporary folder.
    let mut gone = std::process::Command::new("true").spawn().unwrap();
    gone.wait().unwrap();
    let dead = dir.join(format!(".merged.partial-{}", gone.id()));
    let live = dir.join(format!(".merged.partial-{}", std::process::id()));
    for p in [&dead, &live] {
        std::fs::create_dir(p).unwrap();
        std::fs::write(p.join("trials.csv"), "half").unwrap();
    }
    let o = merge(&[&dir.join("s0"), &dir.join("s1")], &merged);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        !dead.exists(),
        "the killed merge's temporary folder is removed"
    );
    assert!(live.exists(), "a live process's temporary folder is kept");
    assert!(merged.join("summary.json").exists());
}

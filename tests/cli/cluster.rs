//! `run --shard auto` under the schedulers' conventions: the share from a Slurm job array's
//! or a Kubernetes Indexed Job's environment, merged into the same bytes as one run; the
//! refusals when the variables are missing or inconsistent; `SLURM_CPUS_PER_TASK` as the
//! default of `--threads`.

use std::process::Output;

use crate::common::{bin, calbench_ok, path_arg, read, root, tmp_dir};

const VARS: [&str; 5] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_COUNT",
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
    calbench_ok(&[
        "merge",
        path_arg(&s0),
        path_arg(&s1),
        "--out",
        path_arg(&merged),
    ]);
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
        &["SLURM_ARRAY_TASK_ID 9", "outside"],
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
}

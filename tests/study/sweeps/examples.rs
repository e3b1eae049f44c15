//! The cluster examples of the sweeps ([`super`]) run as a user would: examples/slurm (as
//! array tasks, and on a one-node Slurm where one is installed), examples/k8s's Indexed Job,
//! the GNU parallel example and the README's shard commands, each merged into the bytes of
//! the unsharded run.

use std::path::Path;
use std::process::Command;

use calbench::study::scenario::Scenario;

use super::write_small;
use crate::common::{bin, calbench_ok, path_arg, read, root, tmp_dir, SMALL_STUDY as SMALL};

/// The Slurm example run as a cluster would: each array task, then the merge step.
#[test]
fn the_slurm_example_runs_and_merges() {
    let root = root();
    let dir = tmp_dir("sweeps-slurm");
    let sc = write_small(
        &dir,
        "cluster",
        &format!("{SMALL}\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 2]\n"),
    );
    let script = |name: &str, task: Option<usize>| {
        let mut c = Command::new("bash");
        c.arg(root.join("examples/slurm").join(name))
            .current_dir(&dir)
            .env("SCENARIO", &sc)
            .env("N", "4")
            .env("CALBENCH", env!("CARGO_BIN_EXE_calbench"));
        if let Some(t) = task {
            // As sbatch --array=3-6 --cpus-per-task=T would: `--shard auto` takes the share
            // (task ID − MIN of COUNT) and the threads from these.
            c.env("SLURM_ARRAY_TASK_ID", (t + 3).to_string())
                .env("SLURM_ARRAY_TASK_MIN", "3")
                .env("SLURM_ARRAY_TASK_COUNT", "4")
                .env("SLURM_CPUS_PER_TASK", (1 + t % 2).to_string());
        }
        let o = c.output().unwrap();
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    for t in 0..4 {
        script("run-shards.sbatch", Some(t));
    }
    script("merge.sbatch", None);
    let full = dir.join("full");
    calbench_ok(&["run", &sc, "--out", path_arg(&full)]);
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(
            read(&full.join(f)),
            read(&dir.join("results/cluster").join(f))
        );
    }
    Scenario::load(&root.join("examples/slurm/sweep-1e6.toml")).unwrap();
}

/// The README's sharded-run commands, as written (with this build's binary).
#[test]
fn the_readme_shard_commands_run() {
    let root = root();
    let readme = read(&root.join("README.md"));
    let block = readme
        .split("```sh\n")
        .skip(1)
        .map(|b| &b[..b.find("```").unwrap()])
        .find(|b| b.contains("--shard"))
        .expect("a README example with --shard");
    let dir = tmp_dir("sweeps-readme");
    let mut n = 0;
    for line in block.lines().filter(|l| l.starts_with("calbench ")) {
        let words: Vec<String> = line
            .split_whitespace()
            .skip(1)
            .map(|w| {
                if w.starts_with("scenarios/") {
                    root.join(w).to_string_lossy().into_owned()
                } else {
                    w.to_string()
                }
            })
            .collect();
        let o = bin().args(&words).current_dir(&dir).output().unwrap();
        assert!(
            o.status.success(),
            "{line}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        n += 1;
    }
    assert_eq!(n, 3);
    let full = dir.join("full");
    calbench_ok(&[
        "run",
        path_arg(&root.join("scenarios/ci-guard.toml")),
        "--out",
        path_arg(&full),
    ]);
    assert_eq!(
        read(&full.join("summary.json")),
        read(&dir.join("results/ci-guard/summary.json"))
    );
}

/// A folder holding this build's `calbench`, for examples that call it by name, and the
/// `PATH` that puts it first.
fn path_with_calbench(dir: &Path) -> String {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let link = bin.join("calbench");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_calbench"), &link).unwrap();
    format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    )
}

/// A scratch folder with the project's `scenarios/ci-guard.toml` (8 trials), where the
/// cluster examples run as written.
fn with_ci_guard(name: &str) -> crate::common::TmpDir {
    let dir = tmp_dir(name);
    std::fs::create_dir_all(dir.join("scenarios")).unwrap();
    std::fs::copy(
        root().join("scenarios/ci-guard.toml"),
        dir.join("scenarios/ci-guard.toml"),
    )
    .unwrap();
    dir
}

/// `summary.json` and `trials.csv` of `merged` are those of an unsharded run of ci-guard.
fn assert_unsharded_bytes(dir: &Path, merged: &Path) {
    let full = dir.join("unsharded");
    let sc = dir.join("scenarios/ci-guard.toml");
    calbench_ok(&["run", path_arg(&sc), "--out", path_arg(&full)]);
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&full.join(f)), read(&merged.join(f)), "{f}");
    }
}

/// The shell command of a Kubernetes job of `examples/k8s/` (the folded `bash -c` text).
fn k8s_command(file: &str) -> String {
    let text = read(&root().join("examples/k8s").join(file));
    let mut lines = text.lines().skip_while(|l| !l.trim_end().ends_with("- >-"));
    let head = lines.next().expect("a `- >-` command");
    let indent = head.len() - head.trim_start().len();
    lines
        .take_while(|l| l.len() - l.trim_start().len() > indent)
        .map(str::trim)
        .collect::<Vec<_>>()
        .join(" ")
}

/// The Kubernetes Indexed Job as its pods run it: the shard command with
/// `JOB_COMPLETION_INDEX` = 0 … completions − 1, then the merge job's command; the bytes
/// are the unsharded run's.
#[test]
fn the_kubernetes_indexed_job_runs_and_merges() {
    let dir = with_ci_guard("sweeps-k8s");
    let path = path_with_calbench(&dir);
    let jobs = read(&root().join("examples/k8s/shards.yaml"));
    let completions: usize = jobs
        .lines()
        .find_map(|l| l.trim().strip_prefix("completions:"))
        .expect("completions")
        .trim()
        .parse()
        .unwrap();
    let shard = k8s_command("shards.yaml");
    assert!(
        shard.contains(&format!("--shard auto --shard-count {completions}")),
        "{shard}"
    );
    let bash = |cmd: &str, index: Option<usize>| {
        let mut c = Command::new("bash");
        c.args(["-c", cmd]).current_dir(&dir).env("PATH", &path);
        if let Some(i) = index {
            c.env("JOB_COMPLETION_INDEX", i.to_string());
        }
        let o = c.output().unwrap();
        assert!(
            o.status.success(),
            "{cmd}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    for i in 0..completions {
        bash(&shard, Some(i));
    }
    bash(&k8s_command("merge.yaml"), None);
    assert_unsharded_bytes(&dir, &dir.join("results/ci-guard"));
}

/// Whether `tool` is on PATH; without it the test says it was skipped, or fails under CI.
fn have(tool: &str, test: &str) -> bool {
    let found = Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            !matches!(std::env::var("CI").as_deref(), Ok("true" | "1")),
            "{test}: `{tool}` is not installed (CI installs it in .ci/run)"
        );
        eprintln!("{test}: skipped, `{tool}` is not installed");
    }
    found
}

/// The GNU parallel example on one machine: the script, and the one-liner in its header as
/// written; both merge into the unsharded bytes.
#[test]
fn the_gnu_parallel_example_runs_and_merges() {
    if !have("parallel", "the_gnu_parallel_example_runs_and_merges") {
        return;
    }
    let script = root().join("examples/parallel/run.sh");
    let one_liner = read(&script)
        .lines()
        .find_map(|l| l.strip_prefix("#   parallel "))
        .map(|l| format!("parallel --will-cite {l}"))
        .expect("the one-liner");
    for (name, cmd) in [
        (
            "sweeps-parallel-script",
            format!("bash {} scenarios/ci-guard.toml 3 2", script.display()),
        ),
        ("sweeps-parallel-one-liner", one_liner),
    ] {
        let dir = with_ci_guard(name);
        let o = Command::new("bash")
            .args(["-c", &cmd])
            .current_dir(&dir)
            .env("PATH", path_with_calbench(&dir))
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{cmd}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_unsharded_bytes(&dir, &dir.join("results/ci-guard"));
    }
}

/// The Slurm example on a real one-node Slurm (`scripts/slurm-one-node.sh`: Debian's
/// slurm-wlm and munge, started here; `CPUS=1 examples/slurm/submit.sh` with 4 shards of
/// ci-guard against an unsharded run). Under CI it must run; elsewhere it runs where Slurm
/// is installed and says it was skipped otherwise.
#[test]
fn the_slurm_example_runs_on_a_one_node_slurm() {
    let ci = matches!(std::env::var("CI").as_deref(), Ok("true" | "1"));
    let installed = Command::new("sh")
        .args(["-c", "command -v slurmctld || command -v sinfo"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ci && !installed {
        eprintln!("the_slurm_example_runs_on_a_one_node_slurm: skipped, Slurm is not installed");
        return;
    }
    let o = Command::new("bash")
        .arg(root().join("scripts/slurm-one-node.sh"))
        .arg(env!("CARGO_BIN_EXE_calbench"))
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    if o.status.code() == Some(2) && !ci {
        eprintln!("the_slurm_example_runs_on_a_one_node_slurm: {text}");
        return;
    }
    assert!(o.status.success(), "{text}");
}

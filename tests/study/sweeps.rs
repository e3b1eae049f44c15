//! Research sweeps and sharded runs: grid sweeps and their refusals, the sweep plots, shards
//! merged into the bytes of the unsharded run (N = 1, 3, 7), the merge's refusals, the Slurm
//! example, and the streaming statistics against trials.csv.

use std::path::{Path, PathBuf};
use std::process::Command;

use calbench::study::scenario::Scenario;

use crate::common::{
    another_digit, bin, calbench, calbench_ok, kill_once_checkpointed, load_json, one_line_naming,
    path_arg, read, root, tmp_dir, write_scenario, SMALL_STUDY as SMALL,
};

/// Writes `text`, a variant of [`SMALL`], as `dir/name.toml` and named `name`; returns the
/// file's path as an argument.
fn write_small(dir: &Path, name: &str, text: &str) -> String {
    let text = text.replace("name = \"small\"", &format!("name = \"{name}\""));
    path_arg(&write_scenario(dir, name, &text)).to_string()
}

#[test]
fn shards_merge_into_the_bytes_of_the_unsharded_run() {
    let dir = tmp_dir("sweeps-shards");
    let sc = write_small(
        &dir,
        "sharded",
        &format!("{SMALL}\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 3]\n"),
    );
    let full = dir.join("full");
    calbench_ok(&["run", &sc, "--threads", "2", "--out", path_arg(&full)]);
    for n in [1usize, 3, 7] {
        let shards: Vec<PathBuf> = (0..n).map(|i| dir.join(format!("s{n}_{i}"))).collect();
        for (i, d) in shards.iter().enumerate() {
            // Thread counts differ between shards: the bytes must not.
            let threads = (1 + i % 2).to_string();
            calbench_ok(&[
                "run",
                &sc,
                "--shard",
                &format!("{i}/{n}"),
                "--threads",
                &threads,
                "--out",
                path_arg(d),
            ]);
        }
        let merged = dir.join(format!("m{n}"));
        let mut args = vec!["merge"];
        args.extend(shards.iter().rev().map(|d| d.to_str().unwrap()));
        args.extend(["--out", path_arg(&merged)]);
        calbench_ok(&args);
        for f in ["summary.json", "trials.csv", "report.md"] {
            let (a, b) = (read(&full.join(f)), read(&merged.join(f)));
            if f == "report.md" {
                // Timings differ; everything before the timing column must not.
                let cut = |t: &str| t.lines().filter(|l| !l.contains('|')).collect::<String>();
                assert_eq!(cut(&a), cut(&b), "{f}, {n} shards");
            } else {
                assert_eq!(a, b, "{f} of {n} shards differs from the unsharded run");
            }
        }
        assert!(merged.join("sweep_validation_rms.png").is_file());
        // The merged run has its page too, with every plot of the unsharded run inlined.
        let svgs = |d: &Path| read(&d.join("report.html")).matches("<svg").count();
        assert_eq!(svgs(&merged), svgs(&full), "{n} shards");
    }
    // 10 units (2 points × 5 trials) among 7 shards: every trial once, in order.
    let rows: Vec<String> = read(&full.join("trials.csv"))
        .lines()
        .skip(1)
        .map(|l| l.split(',').take(2).collect::<Vec<_>>().join(","))
        .collect();
    assert_eq!(rows.len(), 2 * 5 * 2);
    assert_eq!(rows[0], "0,0");
    assert_eq!(rows[19], "4,3");
}

#[test]
fn merge_refuses_missing_duplicate_and_foreign_shards() {
    let dir = tmp_dir("sweeps-refuse");
    let sc = write_small(&dir, "refused", SMALL);
    let d = |n: &str| dir.join(n);
    for i in 0..3 {
        calbench_ok(&[
            "run",
            &sc,
            "--shard",
            &format!("{i}/3"),
            "--out",
            path_arg(&d(&format!("a{i}"))),
        ]);
    }
    calbench_ok(&[
        "run",
        &sc,
        "--seed",
        "10",
        "--shard",
        "2/3",
        "--out",
        path_arg(&d("seed10")),
    ]);
    let err = |args: &[&str]| {
        let o = calbench(args);
        assert!(!o.status.success(), "accepted: {args:?}");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let m = err(&[
        "merge",
        path_arg(&d("a0")),
        path_arg(&d("a1")),
        "--out",
        path_arg(&d("x")),
    ]);
    assert!(m.contains("missing") && m.contains("2/3"), "{m}");
    let m = err(&[
        "merge",
        path_arg(&d("a0")),
        path_arg(&d("a1")),
        path_arg(&d("a1")),
        "--out",
        path_arg(&d("x")),
    ]);
    assert!(m.contains("twice") && m.contains("1/3"), "{m}");
    let m = err(&[
        "merge",
        path_arg(&d("a0")),
        path_arg(&d("a1")),
        path_arg(&d("seed10")),
        "--out",
        path_arg(&d("x")),
    ]);
    assert!(m.contains("seed") && m.contains("seed10"), "{m}");
    let m = err(&[
        "merge",
        path_arg(&d("a0")),
        path_arg(&dir),
        "--out",
        path_arg(&d("x")),
    ]);
    assert!(m.contains("shard.json"), "{m}");
    assert!(!d("x").join("summary.json").exists());
    for bad in ["3/3", "1/0", "x"] {
        let m = err(&["run", &sc, "--shard", bad, "--out", path_arg(&d("y"))]);
        assert!(m.contains("--shard"), "{m}");
    }
}

/// Three shards of ci-guard with 6 trials: a `records.txt` with its last line removed, one
/// digit changed or one record twice is refused by `merge`, naming the file, the line and the
/// trial, and nothing is written; the untouched shards merge into the unsharded bytes.
#[test]
fn merge_refuses_missing_changed_and_duplicated_records() {
    let dir = tmp_dir("sweeps-records");
    let sc = root().join("scenarios/ci-guard.toml");
    let full = dir.join("full");
    calbench_ok(&[
        "run",
        path_arg(&sc),
        "--trials",
        "6",
        "--out",
        path_arg(&full),
    ]);
    let shards: Vec<PathBuf> = (0..3).map(|i| dir.join(format!("s{i}"))).collect();
    for (i, d) in shards.iter().enumerate() {
        let share = format!("{i}/3");
        calbench_ok(&[
            "run",
            path_arg(&sc),
            "--trials",
            "6",
            "--shard",
            &share,
            "--out",
            path_arg(d),
        ]);
    }
    let records = shards[1].join("records.txt");
    let good = read(&records);
    let lines: Vec<&str> = good.lines().collect();
    assert_eq!(lines.len(), 2, "{good}");
    let merge = |out: &str| {
        let mut args = vec!["merge"];
        args.extend(shards.iter().map(|d| path_arg(d)));
        let out = dir.join(out);
        args.extend(["--out", path_arg(&out)]);
        (calbench(&args), out)
    };
    // Shard 1 holds trials 2 and 3.
    let digit = format!("{}\n{}\n", lines[0], another_digit(lines[1]));
    for (damaged, want) in [
        (
            format!("{}\n", lines[0]),
            vec!["line 2", "before trial 3", "missing"],
        ),
        (digit, vec!["line 2", "trial 3", "checksum"]),
        (
            format!("{}\n{}\n{}\n", lines[0], lines[0], lines[1]),
            vec!["line 2", "trial 2 again", "duplicated"],
        ),
    ] {
        std::fs::write(&records, &damaged).unwrap();
        let (o, out) = merge("bad");
        assert!(!o.status.success(), "accepted: {damaged}");
        one_line_naming(&String::from_utf8_lossy(&o.stderr), &records, &want);
        assert!(!out.join("summary.json").exists());
    }
    std::fs::write(&records, &good).unwrap();
    let (o, out) = merge("merged");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&full.join(f)), read(&out.join(f)), "{f}");
    }
}

#[test]
fn a_grid_runs_its_product_and_draws_heat_maps() {
    let dir = tmp_dir("sweeps-grid");
    let sc = write_small(
        &dir,
        "grid",
        &format!(
            "{SMALL}\n[[sweep]]\nkey = \"outliers.count\"\nvalues = [0, 2, 4]\n\
             [[sweep]]\nkey = \"methods.rob.k0\"\nvalues = [1.0, 2.0]\n"
        )
        .replace("trials = 5", "trials = 2"),
    );
    let out = dir.join("out");
    calbench_ok(&["run", &sc, "--out", path_arg(&out)]);
    let sm = load_json(&out.join("summary.json"));
    assert_eq!(
        sm["sweep_keys"],
        serde_json::json!(["outliers.count", "methods.rob.k0"])
    );
    let results = sm["results"].as_array().unwrap();
    assert_eq!(results.len(), 3 * 2 * 2);
    // Product order: the last axis varies fastest.
    let points: Vec<(i64, f64)> = results
        .iter()
        .step_by(2)
        .map(|e| {
            (
                e["sweep"]["outliers.count"].as_i64().unwrap(),
                e["sweep"]["methods.rob.k0"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        points,
        [(0, 1.0), (0, 2.0), (2, 1.0), (2, 2.0), (4, 1.0), (4, 2.0)]
    );
    for stem in ["heatmap_ls_random", "heatmap_rob_random"] {
        for ext in ["png", "svg"] {
            assert!(out.join(format!("{stem}.{ext}")).is_file(), "{stem}.{ext}");
        }
    }
    let report = read(&out.join("report.md"));
    assert!(report.contains("## Sweep") && report.contains("heatmap_rob_random.png"));
    // LS does not read k0: its results are the same for both values.
    let ls: Vec<&serde_json::Value> = results.iter().filter(|e| e["method"] == "ls").collect();
    assert_eq!(ls[0]["validation_after_mm"], ls[1]["validation_after_mm"]);
}

#[test]
fn zipped_axes_pair_their_values_and_method_keys_follow_the_label() {
    let text = format!(
        "{SMALL}\n[[sweep]]\nkey = \"outliers.count\"\nvalues = [0, 2, 4]\nzip = true\n\
         [[sweep]]\nkey = \"methods.rob.k0\"\nvalues = [1.0, 1.5, 2.0]\n"
    );
    let sc = Scenario::parse(&text, Some(Path::new("zip.toml"))).unwrap();
    let plans = sc.sweep_plans().unwrap();
    assert_eq!(plans.len(), 3);
    for ((point, plan), (n, k0)) in plans.iter().zip([(0, "1.0"), (2, "1.5"), (4, "2.0")]) {
        let point = point.as_ref().unwrap();
        assert_eq!(point[0].as_integer(), Some(n));
        assert_eq!(plan.outliers.count, Some(n as usize));
        let igg3 = format!("{:?}", plan.methods[1].method);
        assert!(igg3.contains(&format!("k0: {k0}")), "{igg3}");
        assert!(plan.sweep.is_none());
    }
}

#[test]
fn bad_sweeps_are_refused_naming_the_file_and_the_key() {
    let cases = [
        ("[sweep]\nkey = \"outliers.cuont\"\nvalues = [1]\n", "cuont"),
        (
            "[sweep]\nkey = \"outliers.count\"\nvalues = [\"many\"]\n",
            "outliers.count",
        ),
        (
            "[sweep]\nkey = \"outliers.count\"\nvalues = []\n",
            "outliers.count",
        ),
        (
            "[sweep]\nkey = \"methods.nope.k0\"\nvalues = [1.0]\n",
            "nope",
        ),
        ("[sweep]\nkey = \"methods.rob.k9\"\nvalues = [1.0]\n", "k9"),
        (
            "[sweep]\nkey = \"tracker.mpe_a_um\"\nvalues = [-1.0]\n",
            "mpe_a_um",
        ),
        ("[sweep]\nkey = \"name\"\nvalues = [\"x\"]\n", "name"),
        (
            "[[sweep]]\nkey = \"outliers.count\"\nvalues = [0, 1]\nzip = true\n\
             [[sweep]]\nkey = \"methods.rob.k0\"\nvalues = [1.0]\n",
            "methods.rob.k0",
        ),
        (
            "[[sweep]]\nkey = \"outliers.count\"\nvalues = [0]\n\
             [[sweep]]\nkey = \"outliers.count\"\nvalues = [1]\n",
            "outliers.count",
        ),
    ];
    for (sweep, key) in cases {
        let text = format!("{SMALL}\n{sweep}");
        let e = Scenario::parse(&text, Some(Path::new("dir/bad-sweep.toml")))
            .err()
            .unwrap_or_else(|| panic!("accepted: {sweep}"))
            .to_string();
        assert!(
            e.contains(key) && e.contains("bad-sweep.toml"),
            "`{e}` lacks `{key}` or the file"
        );
    }
}

/// The streaming statistics of summary.json against trials.csv, computed here directly.
#[test]
fn summary_means_are_the_means_of_trials_csv() {
    let dir = tmp_dir("sweeps-means");
    let sc = write_small(&dir, "means", &SMALL.replace("trials = 5", "trials = 300"));
    let out = dir.join("out");
    calbench_ok(&["run", &sc, "--out", path_arg(&out)]);
    let csv = read(&out.join("trials.csv"));
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (m, rms, term) = (col("method"), col("after_rms_mm"), col("termination"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 600);
    let sm = load_json(&out.join("summary.json"));
    for e in sm["results"].as_array().unwrap() {
        let v: Vec<f64> = rows
            .iter()
            .filter(|r| {
                r[m] == e["method"].as_str().unwrap()
                    && !["diverged", "singular", "rank-deficient", "invalid-input"]
                        .contains(&r[term])
                    && !r[rms].is_empty()
            })
            .map(|r| r[rms].parse::<f64>().unwrap())
            .collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let got = e["validation_after_mm"]["rms"].as_f64().unwrap();
        assert!((got - mean).abs() <= 1e-12 * mean, "{got} against {mean}");
    }
}

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
            std::env::var("CI").as_deref() != Ok("true"),
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
    let ci = std::env::var("CI").as_deref() == Ok("true");
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
            &["cut short"],
        ),
        (
            "raised",
            records.clone(),
            raised,
            "records.txt",
            &["missing"],
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

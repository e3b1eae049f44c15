//! Research sweeps and sharded runs: grid sweeps and their refusals, the sweep plots, shards
//! merged into the bytes of the unsharded run (N = 1, 3, 7), the merge's refusals, and the
//! streaming statistics against trials.csv. The cluster examples (Slurm, Kubernetes, GNU
//! parallel, the README's shard commands) are in `sweeps/examples.rs`, a killed run's resume
//! in `sweeps/resume.rs`.

mod columns;
mod examples;
mod resume;

use std::path::{Path, PathBuf};

use calbench::study::scenario::Scenario;

use crate::common::{
    another_digit, calbench, calbench_ok, load_json, one_line_naming, path_arg, read, root,
    tmp_dir, write_scenario, SMALL_STUDY as SMALL,
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
        // Every point draws from the run's seeds (`--seed`): a swept seed was run, and the
        // summary said the run's.
        (
            "[sweep]\nkey = \"seed\"\nvalues = [3, 4]\n",
            "\"seed\" cannot be swept",
        ),
        (
            "[sweep]\nkey = \"outliers.count\"\nvalues = [0, 1]\nzip = true\n",
            "one [sweep] has none",
        ),
        // One point written twice, as an integer and as a float.
        (
            "[sweep]\nkey = \"tracker.mpe_a_um\"\nvalues = [5, 5.0]\n",
            "5.0 is given twice",
        ),
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

/// A swept key's numbers written as integers (`values = [5, 40]` for `tracker.mpe_a_um`, a
/// claim's `paper_point = 5`) are the points a file writing `5.0` and `40.0` names: the same
/// `summary.json` and `trials.csv`, byte for byte, and `check` pairs one with the other's
/// baseline. The integers had named other points ("5" against "5.0"), so that `check` found no
/// entry in common. An integer-only key (`outliers.count`) keeps its integers.
#[test]
fn a_sweep_of_integers_for_a_float_key_names_the_points_of_its_floats() {
    let dir = tmp_dir("sweeps-typed");
    let claim = "[[claims]]\nid = \"c\"\nstatement = \"s\"\npaper = \"p\"\nvalue = \"1 mm\"\n\
                 metric = \"validation_after_mm.mean\"\nrelation = '\"ls\" ~ 1.0'\n\
                 tolerance = { relative = 0.25 }\n";
    let written = |name: &str, values: &str, point: &str| {
        let text = format!(
            "{SMALL}\n{claim}paper_point = {point}\n[sweep]\nkey = \"tracker.mpe_a_um\"\n\
             values = {values}\n"
        )
        .replace("trials = 5", "trials = 3");
        let sc = write_scenario(&dir, name, &text);
        let out = dir.join(name);
        calbench_ok(&["run", path_arg(&sc), "--out", path_arg(&out)]);
        out
    };
    let ints = written("ints", "[5, 40]", "5");
    let floats = written("floats", "[5.0, 40.0]", "5.0");
    for file in ["summary.json", "trials.csv"] {
        assert_eq!(read(&ints.join(file)), read(&floats.join(file)), "{file}");
    }
    let s = load_json(&ints.join("summary.json"));
    assert_eq!(s["sweep_values"], serde_json::json!([5.0, 40.0]));
    assert_eq!(s["claims"][0]["sweep_value"], serde_json::json!(5.0));
    let baseline = dir.join("b.json");
    calbench_ok(&["baseline", path_arg(&floats), "--out", path_arg(&baseline)]);
    let summary = ints.join("summary.json");
    calbench_ok(&[
        "check",
        path_arg(&summary),
        "--baseline",
        path_arg(&baseline),
    ]);
    let counts = format!("{SMALL}\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 2]\n");
    let sc = Scenario::parse(&counts, None).expect("a sweep of counts");
    assert_eq!(
        sc.sweep.expect("a sweep").points(),
        [[toml::Value::Integer(0)], [toml::Value::Integer(2)]]
    );
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

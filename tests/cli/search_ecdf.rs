//! The searches compared as COCO does (docs/formats.md "search_ecdf" and "fixed_budget"):
//! runtime ECDFs at targets relative to the best search of each trial and the best fitness at
//! fixed budgets, the same bytes for any thread count and shard split.

use serde_json::Value;

use crate::common::{calbench_ok, load_json, path_arg, read, root, tmp_dir, write_scenario};

/// `scenarios/qiao2021-tx60.toml` with its three searches at 3000 evaluations each and LM,
/// without the error models and the claims, written into `dir`.
fn small_qiao(dir: &std::path::Path) -> std::path::PathBuf {
    let text = read(&root().join("scenarios/qiao2021-tx60.toml"));
    let head = text[..text.find("[[methods]]").unwrap()]
        .replace("trials = 20\n", "trials = 20\nclaims = []\n");
    let methods = "[[methods]]\nname = \"bas\"\niterations = 1000\nmax_evaluations = 3000\n\n\
                   [[methods]]\nname = \"pso\"\niterations = 100\nmax_evaluations = 3000\n\n\
                   [[methods]]\nname = \"bas-pso\"\nmax_evaluations = 3000\n\n\
                   [[methods]]\nname = \"lm\"\nadaptive = true\n";
    write_scenario(dir, "qiao-small", &format!("{head}{methods}"))
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn search_ecdfs_are_monotone_shares_and_the_same_bytes_for_threads_and_shards() {
    let dir = tmp_dir("search-ecdf");
    let sc = small_qiao(&dir);
    let run = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec![
            "run",
            path_arg(&sc),
            "--trials",
            "6",
            "--out",
            path_arg(&out),
        ];
        args.extend_from_slice(extra);
        calbench_ok(&args);
        out
    };
    let t1 = run("t1", &["--threads", "1"]);
    let t2 = run("t2", &["--threads", "2"]);
    let s0 = run("s0", &["--shard", "0/2"]);
    let s1 = run("s1", &["--shard", "1/2"]);
    let merged = dir.join("m");
    calbench_ok(&[
        "merge",
        path_arg(&s0),
        path_arg(&s1),
        "--out",
        path_arg(&merged),
    ]);
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&t1.join(f)), read(&t2.join(f)), "{f}");
    }
    // Merged shards: the searches' numbers are those of the whole run.
    let (whole, m) = (
        load_json(&t1.join("summary.json")),
        load_json(&merged.join("summary.json")),
    );
    for (a, b) in whole["results"]
        .as_array()
        .unwrap()
        .iter()
        .zip(m["results"].as_array().unwrap())
    {
        assert_eq!(a["search_ecdf"], b["search_ecdf"]);
        assert_eq!(a["fixed_budget"], b["fixed_budget"]);
    }

    let s = load_json(&t1.join("summary.json"));
    let csv = read(&t1.join("trials.csv"));
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |k: &str| header.iter().position(|h| *h == k).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let results = s["results"].as_array().unwrap();
    let entry = |m: &str| results.iter().find(|e| e["method"] == m).unwrap();
    assert!(entry("lm").get("search_ecdf").is_none());
    assert!(entry("lm").get("fixed_budget").is_none());
    let mut reached_sum = [0.0; 4];
    let mut smallest_mean_evals = f64::INFINITY;
    for m in ["bas", "pso", "bas-pso"] {
        let e = entry(m);
        let ecdf = &e["search_ecdf"];
        // Every trial of trials.csv that ran the search is counted.
        let n = rows
            .iter()
            .filter(|r| r[col("method")] == m && !r[col("iterations")].is_empty())
            .count();
        assert_eq!(ecdf["trials"], n as u64, "{m}");
        let targets = ecdf["targets"].as_array().unwrap();
        let deltas: Vec<f64> = targets.iter().map(|t| num(&t["delta"])).collect();
        assert_eq!(deltas, [1.0, 0.1, 0.01, 0.001]);
        let evals_mean = num(&e["evaluations_mean"]);
        smallest_mean_evals = smallest_mean_evals.min(evals_mean);
        let mut previous_reached = 1.0;
        for (k, t) in targets.iter().enumerate() {
            let points = t["points"].as_array().unwrap();
            let (mut last_e, mut last_share) = (0.0, 0.0);
            for p in points {
                let (ev, share) = (num(&p["evaluations"]), num(&p["share"]));
                assert!(ev > last_e && share > last_share, "{m} {t}");
                assert!((0.0..=1.0).contains(&share), "{m} {t}");
                // A share is a whole number of trials.
                assert!((share * n as f64 - (share * n as f64).round()).abs() < 1e-9);
                (last_e, last_share) = (ev, share);
            }
            let reached = num(&t["reached"]);
            assert_eq!(reached, last_share, "{m} {t}");
            // A tighter target is reached by no more trials.
            assert!(reached <= previous_reached, "{m} {t}");
            previous_reached = reached;
            let ci = t["reached_ci95"].as_array().unwrap();
            let (lo, hi) = (num(&ci[0]), num(&ci[1]));
            assert!(
                0.0 <= lo && lo <= reached && reached <= hi && hi <= 1.0,
                "{m} {t}"
            );
            reached_sum[k] += reached;
        }
        // The best fitness within a budget falls as the budget grows.
        let fb = e["fixed_budget"].as_array().unwrap();
        let fractions: Vec<f64> = fb.iter().map(|b| num(&b["fraction"])).collect();
        assert_eq!(fractions, [0.1, 0.25, 0.5, 1.0]);
        let full: Vec<&Value> = fb.iter().filter(|b| b["n"] == n as u64).collect();
        assert!(!full.is_empty(), "{m}: no budget with every trial");
        for w in full.windows(2) {
            assert!(
                num(&w[1]["fitness_mean"]) <= num(&w[0]["fitness_mean"]),
                "{m}"
            );
            assert!(
                num(&w[1]["evaluations_mean"]) > num(&w[0]["evaluations_mean"]),
                "{m}"
            );
        }
        for b in &full {
            let ci = b["fitness_mean_ci95"].as_array().unwrap();
            let mean = num(&b["fitness_mean"]);
            assert!(
                mean > 0.0 && num(&ci[0]) <= mean && mean <= num(&ci[1]),
                "{m} {b}"
            );
        }
    }
    // The reference is the best search of each trial: on every trial some search reaches
    // every target, so the shares reached at the end sum to at least 1.
    for (k, r) in reached_sum.iter().enumerate() {
        assert!(*r >= 1.0 - 1e-12, "target {k}: {r}");
    }
    // The budget is the smallest evaluation count of the trial's searches: on average no
    // more than the smallest mean.
    let full_budget = num(&entry("bas")["fixed_budget"][3]["evaluations_mean"]);
    assert!(full_budget <= smallest_mean_evals && full_budget > 0.0);
    for m in ["pso", "bas-pso"] {
        assert_eq!(entry(m)["fixed_budget"][3]["evaluations_mean"], full_budget);
    }
}

//! The searches compared as COCO does (docs/formats.md "search_ecdf" and "fixed_budget"):
//! runtime ECDFs at targets relative to the best search of each trial and the best fitness at
//! fixed budgets, the same bytes for any thread count, shard split and a killed and resumed
//! run.

use serde_json::Value;

use crate::common::{
    calbench_ok, kill_once_checkpointed, load_json, merge, path_arg, read, root, tmp_dir,
    write_scenario,
};
use crate::html::{browse, chromium, ci, self_contained};

/// The trials of the small study: more than one checkpoint block (256 trials), so that a run
/// killed after its first checkpoint has trials left to resume.
const TRIALS: &str = "300";

/// `scenarios/qiao2021-tx60.toml` with 12 calibration and 5 validation poses, its three
/// searches at 160 evaluations each (the least BAS-PSO takes), BAS-PSO on the differential
/// model (another fitness, compared apart) and LM, without the claims, written into `dir`.
pub fn small_qiao(dir: &std::path::Path) -> std::path::PathBuf {
    let text = read(&root().join("scenarios/qiao2021-tx60.toml"));
    let head = text[..text.find("[[methods]]").unwrap()]
        .replace("trials = 20\n", "trials = 20\nclaims = []\n")
        .replace("count = 50\n", "count = 12\n")
        .replace("count = 30\n", "count = 5\n");
    let methods = "[[methods]]\nname = \"bas\"\niterations = 60\nmax_evaluations = 160\n\n\
                   [[methods]]\nname = \"pso\"\niterations = 6\nmax_evaluations = 160\n\n\
                   [[methods]]\nname = \"bas-pso\"\nmax_evaluations = 160\n\n\
                   [[methods]]\nname = \"bas-pso\"\nlabel = \"bas-pso-differential\"\n\
                   error_model = \"differential\"\nmax_evaluations = 160\n\n\
                   [[methods]]\nname = \"lm\"\nadaptive = true\n";
    write_scenario(dir, "qiao-small", &format!("{head}{methods}"))
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Runs `sc` with `--threads 1` into `out`, kills it (SIGKILL) once its checkpoint holds
/// trials, and resumes it.
fn killed_and_resumed(sc: &std::path::Path, out: &std::path::Path) {
    let args = ["run", path_arg(sc), "--trials", TRIALS, "--threads", "1"];
    let meta = kill_once_checkpointed(&[&args[..], &["--out", path_arg(out)]].concat(), out, 300);
    assert!(
        !out.join("summary.json").exists(),
        "the run ended before it was killed"
    );
    // The checkpoint carries the searches' per-trial numbers (`search:Some((budget:…))`).
    let records = read(&meta.with_file_name("records.txt"));
    assert!(
        records
            .lines()
            .next()
            .unwrap()
            .contains("search:Some((budget:"),
        "{records:.300}"
    );
    calbench_ok(&["run", "--resume", path_arg(out)]);
}

#[test]
fn search_ecdfs_are_monotone_shares_and_the_same_bytes_for_threads_shards_and_resume() {
    let dir = tmp_dir("search-ecdf");
    let sc = small_qiao(&dir);
    let run = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec![
            "run",
            path_arg(&sc),
            "--trials",
            TRIALS,
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
    merge(&[&s0, &s1], &merged);
    let resumed = dir.join("resumed");
    killed_and_resumed(&sc, &resumed);
    for other in [&t2, &merged, &resumed] {
        for f in ["summary.json", "trials.csv"] {
            assert_eq!(read(&t1.join(f)), read(&other.join(f)), "{other:?} {f}");
        }
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
    for m in ["bas", "pso", "bas-pso", "bas-pso-differential"] {
        let e = entry(m);
        let ecdf = &e["search_ecdf"];
        // Every trial of trials.csv that ran the search is counted.
        let n = rows
            .iter()
            .filter(|r| r[col("method")] == m && !r[col("iterations")].is_empty())
            .count();
        assert_eq!(ecdf["trials"], n as u64, "{m}");
        let targets = ecdf["targets"].as_array().unwrap();
        // The aggregate over targets: shares of the (trial, target) pairs, rising to the mean
        // of the targets' shares reached.
        let all = ecdf["all_targets"].as_array().unwrap();
        let steps: Vec<(f64, f64)> = all
            .iter()
            .map(|p| (num(&p["evaluations"]), num(&p["share"])))
            .collect();
        assert!(
            steps.windows(2).all(|w| w[0].0 < w[1].0 && w[0].1 < w[1].1),
            "{m}"
        );
        let pairs = 4.0 * n as f64;
        assert!(steps
            .iter()
            .all(|s| (s.1 * pairs - (s.1 * pairs).round()).abs() < 1e-9));
        let mean_reached = targets.iter().map(|t| num(&t["reached"])).sum::<f64>() / 4.0;
        assert!(
            // (no step when the search reached no target on any trial)
            (steps.last().map_or(0.0, |s| s.1) - mean_reached).abs() < 1e-12,
            "{m}"
        );
        let deltas: Vec<f64> = targets.iter().map(|t| num(&t["delta"])).collect();
        assert_eq!(deltas, [1.0, 0.1, 0.01, 0.001]);
        // BAS-PSO on the differential model minimises another fitness: it is compared with
        // no other search, so it is its own reference and reaches every target.
        let alone = m == "bas-pso-differential";
        if !alone {
            smallest_mean_evals = smallest_mean_evals.min(num(&e["evaluations_mean"]));
        }
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
            if alone {
                assert_eq!(reached, 1.0, "{m} {t}");
            } else {
                reached_sum[k] += reached;
            }
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
    // The reference is the best of the searches of one fitness on each trial: on every trial
    // one of BAS, PSO and BAS-PSO reaches every target, so their shares reached at the end
    // sum to at least 1.
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

    // The reports: the table of the searches and the two plots, on report.md and inlined in
    // report.html, which a browser draws.
    let md = read(&t1.join("report.md"));
    let heading = "## Searches compared\n";
    let section = &md[md.find(heading).expect("the section of the searches") + heading.len()..];
    let section = &section[..section.find("\n## ").unwrap_or(section.len())];
    // One row per search (the table pads its cells), none for LM.
    for m in ["bas", "pso", "bas-pso", "bas-pso-differential"] {
        let row = format!("| {m} / random ");
        assert!(
            section.lines().any(|l| l.starts_with(&row)),
            "{m}: {section}"
        );
    }
    assert!(!section.contains("| lm / random "), "LM is not a search");
    for stem in ["search_ecdf", "fixed_budget"] {
        assert!(md.contains(&format!("]({stem}.png)")), "{stem}");
        for ext in ["png", "svg"] {
            let f = t1.join(format!("{stem}.{ext}"));
            assert!(std::fs::metadata(&f).unwrap().len() > 1000, "{f:?}");
            // The plots read the summary: the same bytes from the merged and resumed runs.
            assert!(
                std::fs::read(&f).unwrap()
                    == std::fs::read(merged.join(format!("{stem}.{ext}"))).unwrap(),
                "{f:?}"
            );
        }
        let svg = read(&t1.join(format!("{stem}.svg")));
        assert!(
            svg.contains("bas-pso-differential / random"),
            "{stem}: legend"
        );
    }
    let page = t1.join("report.html");
    let html = self_contained(&page);
    assert!(html.contains(">Searches compared</h2>"));
    let svgs = std::fs::read_dir(&t1)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension() == Some("svg".as_ref()))
        .count();
    assert_eq!(html.matches("<svg").count(), svgs);
    let heading = ">Searches compared</h2>";
    let section = &html[html.find(heading).unwrap() + heading.len()..];
    let section = &section[..section.find("<h2").unwrap_or(section.len())];
    assert!(
        section.contains("Runtime ECDF") && section.contains("Mean best fitness"),
        "the section's figures"
    );
    match chromium() {
        Some(chrome) => {
            browse(&chrome, &page, &dir.join("browser"), svgs);
        }
        None => assert!(
            !ci(),
            "no Chromium on the PATH (CI=true: a missing browser is a failure)"
        ),
    }
}

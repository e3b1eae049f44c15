//! A search's best fitness at the end of its budget (docs/formats.md `final_fitness`): in
//! `trials.csv` and `summary.json` only for a run with a search, each trial's value the last
//! point of its fitness trace, the summary's figures those of the column, and a claim on it
//! judged as any per-trial metric.

use serde_json::Value;

use crate::common::{calbench, calbench_ok, load_json, one_line_naming, path_arg, read, tmp_dir};
use crate::search_ecdf::small_qiao;

/// The claim that BAS ends below PSO on `small_qiao`'s direct fitness.
const CLAIM: &str = "\n[[claims]]\nid = \"bas-below-pso\"\nstatement = \"s\"\npaper = \"§1\"\n\
                     value = \"v\"\nmetric = \"final_fitness.mean\"\n\
                     relation = '\"bas\" < \"pso\"'\n";

/// The rows of `csv` as (header, rows).
fn table(csv: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut lines = csv.lines();
    let split = |l: &str| l.split(',').map(String::from).collect::<Vec<_>>();
    let header = split(lines.next().expect("a header"));
    (header, lines.map(split).collect())
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn final_fitness_is_each_searchs_last_best_fitness_and_only_where_a_search_ran() {
    let dir = tmp_dir("final-fitness");
    let sc = small_qiao(&dir);
    let text = read(&sc).replace("claims = []\n", "") + CLAIM;
    std::fs::write(&sc, text).unwrap();
    let out = dir.join("run");
    calbench_ok(&[
        "run",
        path_arg(&sc),
        "--trials",
        "8",
        "--out",
        path_arg(&out),
    ]);
    let (header, rows) = table(&read(&out.join("trials.csv")));
    let col = |k: &str| {
        header
            .iter()
            .position(|h| h == k)
            .unwrap_or_else(|| panic!("{k}"))
    };
    // Between `iterations` and `termination`.
    assert_eq!(col("final_fitness"), col("iterations") + 1);
    assert_eq!(col("termination"), col("final_fitness") + 1);
    let s = load_json(&out.join("summary.json"));
    let results = s["results"].as_array().unwrap();
    for m in ["bas", "pso", "bas-pso", "bas-pso-differential", "lm"] {
        let mine: Vec<&Vec<String>> = rows.iter().filter(|r| r[col("method")] == m).collect();
        assert_eq!(mine.len(), 8, "{m}");
        let entry = results.iter().find(|e| e["method"] == m).unwrap();
        if m == "lm" {
            assert!(mine.iter().all(|r| r[col("final_fitness")].is_empty()));
            assert!(entry.get("final_fitness").is_none(), "{entry}");
            continue;
        }
        let v: Vec<f64> = mine
            .iter()
            .map(|r| r[col("final_fitness")].parse().unwrap())
            .collect();
        // Trial 0's value is the last point of its trace, a separate record of the search.
        let trace = s["fitness_trace_trial0"][format!("{m} / random")]
            .as_array()
            .unwrap_or_else(|| panic!("{m}: no trace"));
        assert_eq!(v[0], num(trace.last().unwrap()), "{m}");
        // The summary's figures are those of the column, recomputed here.
        let f = &entry["final_fitness"];
        let mean = v.iter().sum::<f64>() / 8.0;
        assert!((num(&f["mean"]) - mean).abs() <= 1e-12 * mean, "{m} {f}");
        let mut sorted = v.clone();
        sorted.sort_by(f64::total_cmp);
        assert_eq!(num(&f["median"]), 0.5 * (sorted[3] + sorted[4]), "{m}");
        // With 8 trials the median's interval is the extreme values (Conover § 3.2).
        assert_eq!(
            f["median_ci95"],
            serde_json::json!([sorted[0], sorted[7]]),
            "{m}"
        );
        let ci = f["mean_ci95"].as_array().unwrap();
        assert!(num(&ci[0]) < mean && mean < num(&ci[1]), "{m} {f}");
    }
    // The claim is judged on the paired per-trial values, with a margin and a test.
    let claim = &s["claims"][0];
    assert_eq!(claim["metric"], "final_fitness.mean");
    assert!(claim["margin"].as_f64().is_some_and(|m| m > 0.0), "{claim}");
    assert!(
        ["t", "sign"].contains(&claim["test"].as_str().unwrap()),
        "{claim}"
    );
    let d: Vec<f64> = (0..8)
        .map(|t| {
            let at = |m: &str| {
                let r = rows
                    .iter()
                    .find(|r| r[col("method")] == m && r[col("trial")] == t.to_string())
                    .unwrap();
                r[col("final_fitness")].parse::<f64>().unwrap()
            };
            at("bas") - at("pso")
        })
        .collect();
    let estimate = match claim["test"].as_str() {
        Some("t") => d.iter().sum::<f64>() / 8.0,
        _ => {
            let mut d = d.clone();
            d.sort_by(f64::total_cmp);
            0.5 * (d[3] + d[4])
        }
    };
    assert!((num(&claim["estimate"]) - estimate).abs() <= 1e-12 * estimate.abs());

    // Without a search: no column, no figure, and a claim on it is refused.
    let lm = dir.join("lm.toml");
    let text = read(&sc);
    let head = &text[..text.find("[[methods]]").unwrap()];
    std::fs::write(&lm, format!("{head}[[methods]]\nname = \"lm\"\n")).unwrap();
    let out = dir.join("lm");
    calbench_ok(&[
        "run",
        path_arg(&lm),
        "--trials",
        "2",
        "--out",
        path_arg(&out),
    ]);
    assert!(!read(&out.join("trials.csv")).contains("final_fitness"));
    assert!(!read(&out.join("summary.json")).contains("final_fitness"));
    let refused = dir.join("refused.toml");
    let claim = CLAIM.replace("'\"bas\" < \"pso\"'", "'\"lm\" < 1.0'");
    std::fs::write(
        &refused,
        format!("{head}[[methods]]\nname = \"lm\"\n{claim}"),
    )
    .unwrap();
    let o = calbench(&[
        "run",
        path_arg(&refused),
        "--out",
        path_arg(&dir.join("no")),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    one_line_naming(&err, &refused, &["claims[0].metric", "needs a search"]);
}

/// A search estimates no covariance: `identified.json` gives no σ for its parameters and no
/// predicted position σ (`null`), `report.md` says so, and `dh-table.csv` leaves `sigma`
/// empty. All three had said 0 (`f64::max` of the covariance's NaN), a σ that claims the
/// parameters known exactly. Least squares on the same data gives them.
#[test]
fn a_search_writes_no_standard_errors() {
    let d = tmp_dir("search-sigma");
    let data = crate::plausible::simulated(&d, "scenarios/ci-guard.toml", None);
    for (method, given) in [("pso", false), ("ls", true)] {
        let out = d.join(method);
        calbench_ok(&[
            "identify",
            "--robot",
            "irb2600",
            "--data",
            path_arg(&data),
            "--method",
            method,
            "--export",
            "dh-csv",
            "--out",
            path_arg(&out),
        ]);
        let record = load_json(&out.join("identified.json"));
        let diagnostics = &record["diagnostics"];
        let sigma = diagnostics["sigma"].as_array().unwrap();
        assert!(!sigma.is_empty());
        // Given: a positive σ; not given: `null`, never 0.
        let given_as = |v: &Value| match given {
            true => v.as_f64().is_some_and(|v| v > 0.0),
            false => v.is_null(),
        };
        assert!(sigma.iter().all(given_as), "{method}: {sigma:?}");
        let predicted = &diagnostics["predicted"];
        assert!(given_as(&predicted["rms_mm"]), "{method}: {predicted}");
        assert!(given_as(&predicted["max_mm"]), "{method}: {predicted}");
        let report = read(&out.join("report.md"));
        let none = "the calibration poses: none, as there is no covariance; measured RMS there";
        assert_eq!(report.contains(none), !given, "{report}");
        let csv = read(&out.join("dh-table.csv"));
        let (header, rows) = table(&csv);
        let col = header.iter().position(|h| h == "sigma").unwrap();
        let a2 = rows
            .iter()
            .find(|r| r[0] == "2" && r[1] == "a")
            .expect("a2's row");
        assert_eq!(a2[col].is_empty(), !given, "{method}: {csv}");
    }
}

/// A search whose box holds the errors' minimum nowhere inside ends on the box's edge: its
/// result is the box's corner, not the data's answer. `pso`'s default box (±2 mm, ±0.02 rad)
/// on the papers' 0.05 rad errors ended 87 mm from the readings with nothing said but the
/// iteration limit; the identification now names the parameters on the edge and the options
/// that widen the box. Widened (±5 mm, ±0.1 rad), it fits the readings to 0.3 mm and says
/// nothing of the box; `ls` has none.
#[test]
fn a_search_that_ends_on_the_edge_of_its_box_says_so() {
    let d = tmp_dir("search-box");
    let data = crate::plausible::simulated(&d, "scenarios/ci-guard.toml", None);
    let run = |method: &str, set: &[&str]| {
        let out = d.join(format!("{method}-{}", set.len()));
        let mut args = vec!["identify", "--robot", "irb2600", "--data", path_arg(&data)];
        args.extend(["--method", method, "--out", path_arg(&out)]);
        args.extend(set.iter().flat_map(|s| ["--set", *s]));
        let o = calbench(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let rms = load_json(&out.join("identified.json"))["rms_residual_mm"]
            .as_f64()
            .unwrap();
        // The warning is said on the page and in report.md alike, or in neither.
        let said = |file: &str| {
            let text = std::fs::read_to_string(out.join(file)).unwrap();
            text.contains("the search ended with ")
        };
        let on_page = said("report.html");
        assert_eq!(said("report.md"), on_page);
        (
            String::from_utf8_lossy(&o.stderr).into_owned(),
            rms,
            on_page,
        )
    };
    let (err, rms, on_page) = run("pso", &[]);
    let edge = "warning: the search ended with ";
    assert!(err.contains(edge) && rms > 10.0, "{rms} mm: {err}");
    // The page's warnings say it too, and report.md's, with the solve stopped at its
    // iteration limit, as identify says on stderr.
    assert!(on_page);
    let stopped = "after 500 iterations (RMS residual";
    assert!(err.contains(stopped), "{err}");
    for file in ["report.md", "report.html"] {
        let text = std::fs::read_to_string(d.join("pso-0").join(file)).unwrap();
        assert!(text.contains(stopped), "{file}: {text}");
        assert!(
            text.contains("a solve that did not converge"),
            "{file}: {text}"
        );
    }
    assert!(
        err.contains("; bound_mm = 2, bound_rad = 0.02): the errors may lie beyond it")
            && err.contains("widen the box (the method's options bound_mm and bound_rad)"),
        "{err}"
    );
    let (err, rms, on_page) = run("pso", &["bound_mm=5", "bound_rad=0.1"]);
    assert!(
        !err.contains(edge) && !on_page && rms < 0.5,
        "{rms} mm: {err}"
    );
    let (err, _, on_page) = run("ls", &[]);
    assert!(!err.contains(edge) && !on_page, "{err}");
}

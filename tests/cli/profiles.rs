//! The performance profiles of a sweep (docs/formats.md `performance_profile`; Dolan & Moré
//! 2002): recomputed from the sweep's own results, and shown in the report.

use crate::common::{calbench_ok, load_json, path_arg, read, root, tmp_dir, write_scenario};

#[test]
fn a_sweep_has_performance_profiles_recomputed_from_its_results() {
    let dir = tmp_dir("profiles");
    let text = read(&root().join("scenarios/ci-guard.toml"))
        + "\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 2, 4]\n";
    let sc = write_scenario(&dir, "sweep", &text);
    let out = dir.join("out");
    calbench_ok(&[
        "run",
        path_arg(&sc),
        "--trials",
        "3",
        "--out",
        path_arg(&out),
    ]);
    let s = load_json(&out.join("summary.json"));
    let p = &s["performance_profile"];
    assert_eq!(p["metric"], "validation_after_mm.rms");
    let tau: Vec<f64> = p["tau"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_f64().unwrap())
        .collect();
    assert_eq!(tau[0], 1.0);
    let results = s["results"].as_array().unwrap();
    let profiles = p["profiles"].as_array().unwrap();
    let (points, entries) = (3, profiles.len());
    assert_eq!(results.len(), points * entries);
    let rms = |i: usize, k: usize| {
        results[i * entries + k]["validation_after_mm"]["rms"]
            .as_f64()
            .unwrap()
    };
    for (k, prof) in profiles.iter().enumerate() {
        assert_eq!(prof["method"], results[k]["method"]);
        for i in 0..points {
            let best = (0..entries)
                .map(|j| rms(i, j))
                .fold(f64::INFINITY, f64::min);
            let ratio = prof["ratio"][i].as_f64().unwrap();
            assert!((ratio - rms(i, k) / best).abs() < 1e-12);
        }
        let share: Vec<f64> = prof["share"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        for (t, sh) in tau.iter().zip(&share) {
            let within = (0..points)
                .filter(|&i| prof["ratio"][i].as_f64().unwrap() <= *t)
                .count();
            assert_eq!(*sh, within as f64 / points as f64);
        }
        assert!(share.windows(2).all(|w| w[0] <= w[1]));
    }
    // At every point some entry is the best.
    for i in 0..points {
        assert!(profiles
            .iter()
            .any(|prof| prof["ratio"][i].as_f64() == Some(1.0)));
    }
    assert!(read(&out.join("report.md")).contains("Performance profile"));
    assert!(out.join("performance_profile.png").is_file());
    // Without a sweep there is none.
    let plain = dir.join("plain");
    let guard = root().join("scenarios/ci-guard.toml");
    calbench_ok(&[
        "run",
        path_arg(&guard),
        "--trials",
        "2",
        "--out",
        path_arg(&plain),
    ]);
    assert!(load_json(&plain.join("summary.json"))
        .get("performance_profile")
        .is_none());
}

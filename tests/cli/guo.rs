//! Guo 2024's two pose optimisers as a user runs them: the separated one scores the
//! reconstructed model J_p (every ill-conditioned parameter removed, eq. 27), the full one the
//! full rank-deficient model, so their pose sets and scored parameters differ.

use crate::common::{calbench_ok, load_json, path_arg, read, root, tmp_dir};

#[test]
fn separated_and_full_optimisers_choose_different_poses_on_different_models() {
    let dir = tmp_dir("cli-guo-models");
    let sc = root().join("scenarios/guo2024-3t2r.toml");
    let run = |strategy: &str| {
        let out = dir.join(strategy);
        calbench_ok(&[
            "poses",
            path_arg(&sc),
            "--strategy",
            strategy,
            "--count",
            "30",
            "--out",
            path_arg(&out),
        ]);
        out
    };
    let (sep, full) = (run("detmax-ide"), run("detmax-ide-full"));
    assert_ne!(read(&sep.join("poses.csv")), read(&full.join("poses.csv")));
    let names = |d: &std::path::Path| -> Vec<String> {
        let s = load_json(&d.join("scores.json"));
        s["parameters"]
            .as_array()
            .unwrap_or_else(|| panic!("{s}"))
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect()
    };
    let (ps, pf) = (names(&sep), names(&full));
    assert_ne!(ps, pf);
    // J_p leaves out both members of each dependent pair (Guo's a4, a5, d2, d3: here d2, d3,
    // a4, a5 of the chosen chain); the full model keeps all 21 joint parameters.
    for p in ["d2", "d3", "a4", "a5"] {
        assert!(!ps.iter().any(|n| n == p), "{p} in {ps:?}");
        assert!(pf.iter().any(|n| n == p), "{p} not in {pf:?}");
    }
    let sepj = load_json(&sep.join("scores.json"));
    let ill = sepj["separation"]["ill_conditioned"].as_array().unwrap();
    assert_eq!(ill.len(), 4, "{ill:?}");
    // Both models are scored on their nonzero spectrum: finite, positive indices.
    for d in [&sep, &full] {
        let s = load_json(&d.join("scores.json"));
        assert!(s["composite"].as_f64().unwrap() > 0.0, "{s}");
        assert!(s["gcn"].as_f64().is_some(), "{s}");
    }
}

//! A study's sag under `[compliance]`'s payload: identified under the payload the rows sagged
//! under (docs/formats.md § 4.7).

use crate::common::{calbench_ok, load_json, tmp_dir, write_scenario};

/// A study whose arm sags under `compliance.payload_kg` alone identifies the compliances as
/// the same study written with that payload for every row and pose
/// (`calibration.payloads_kg`, `validation.payload_kg`): the same trials.csv, the true c2 and
/// c3 recovered. The rows had been identified under no payload and validated under 50 kg:
/// η −346 %, `converged`. `simulate` writes the payload the rows sagged under.
#[test]
fn a_study_under_the_compliance_payload_alone_identifies_under_it() {
    let dir = tmp_dir("compliance-payload");
    let head = "seed = 3\ntrials = 2\n[robot]\nbuiltin = \"irb2600\"\n[errors]\nkind = \"none\"\n\
                [tracker]\nmpe_a_um = 0.0\nmpe_b_um_per_m = 0.0\n";
    let tail = "[identification]\ncompliance = [\"c2\", \"c3\"]\n[[methods]]\nname = \"ls\"\n";
    let alone = format!(
        "name = \"alone\"\n{head}[compliance]\nmodel = \"linear\"\npayload_kg = 50.0\n\
         [calibration]\ncount = 60\n[validation]\ncount = 30\n{tail}"
    );
    let written = format!(
        "name = \"alone\"\n{head}[compliance]\nmodel = \"linear\"\n\
         [calibration]\ncount = 60\npayloads_kg = [50.0]\n[validation]\ncount = 30\n\
         payload_kg = 50.0\n{tail}"
    );
    let mut trials = Vec::new();
    for (name, text) in [("alone", &alone), ("written", &written)] {
        let sc = write_scenario(&dir, name, text);
        let out = dir.join(format!("run-{name}"));
        calbench_ok(&["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        trials.push(std::fs::read_to_string(out.join("trials.csv")).unwrap());
        let summary = load_json(&out.join("summary.json"));
        let eta = summary["results"][0]["eta_mean_pct"].as_f64().unwrap();
        assert!(eta > 98.0, "{name}: η {eta} %");
    }
    assert_eq!(trials[0], trials[1]);
    let sc = dir.join("alone.toml");
    let sim = dir.join("sim");
    calbench_ok(&[
        "simulate",
        sc.to_str().unwrap(),
        "--out",
        sim.to_str().unwrap(),
    ]);
    for file in ["measurements.csv", "validation.csv"] {
        let text = std::fs::read_to_string(sim.join(file)).unwrap();
        let mut lines = text.lines();
        assert!(lines.next().unwrap().ends_with(",payload_kg"), "{file}");
        assert!(lines.all(|l| l.ends_with(",50.000000")), "{file}");
    }
}

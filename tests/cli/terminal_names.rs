//! Names reach the terminal escaped: a method's `label` with a control or bidirectional
//! override character is refused as the scenario's `name` is, and a name from a summary
//! edited by hand is shown escaped on every line `check` prints, stdout and stderr
//! (docs/formats.md § 8.1).

use crate::common::{calbench, load_json, path_arg, read, refused, root, tmp_dir, write_scenario};
use crate::impossible::good_run;

#[test]
fn a_label_with_control_characters_is_refused_and_check_shows_names_escaped() {
    let dir = tmp_dir("cli-terminal-names");
    let label = "label = \"igg\\u001b[31mRED\\u202e\"";
    let text = read(&root().join("scenarios/ci-guard.toml")).replacen(
        "name = \"igg3\"",
        &format!("name = \"igg3\"\n{label}"),
        1,
    );
    let line = text.lines().position(|l| l == label).unwrap() + 1;
    for (name, text) in [
        ("esc", text.clone()),
        ("rlo", text.replace("\\u001b[31m", "")),
    ] {
        let sc = write_scenario(&dir, name, &text);
        let out = dir.join(name);
        let o = calbench(&[
            "run",
            path_arg(&sc),
            "--trials",
            "1",
            "--out",
            path_arg(&out),
        ]);
        let place = format!("{}: line {line}, methods[1].label: ", sc.display());
        refused(&o, &[&place, "without control characters"]);
        assert!(!out.exists());
    }
    // A summary whose entry was renamed by hand, and lacks a figure of the baseline's.
    let good = good_run(&dir);
    let mut base = load_json(&good.join("summary.json"));
    base["results"][1]["method"] = "igg\u{1b}[31mRED\u{202e}".into();
    let mut s = base.clone();
    s["results"][1]["eta_median_pct"] = serde_json::Value::Null;
    let (sp, bp) = (dir.join("s.json"), dir.join("b.json"));
    std::fs::write(&sp, s.to_string()).unwrap();
    std::fs::write(&bp, base.to_string()).unwrap();
    let o = calbench(&["check", path_arg(&sp), "--baseline", path_arg(&bp)]);
    let all = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(
        all.contains("regression: igg\\u{1b}[31mRED\\u{202e} / random: eta_median_pct"),
        "{all}"
    );
    assert!(!all.contains(['\u{1b}', '\u{202e}']), "{all:?}");
}

//! `calbench check` compares one scenario from version to version (docs/formats.md § 2.4): a
//! run of an edited scenario is refused against a run folder and against a `calbench
//! baseline` file, naming each setting that differs; seed and trials may differ. `calbench
//! compare` (§ 2.13) compares such a pair all the same, warning with the same settings.

use crate::common::{calbench_ok, path_arg, read, root, tmp_dir, write_scenario};
use crate::guard::{check, run, three_trials_and_baseline};

/// A run of an edited scenario (fewer calibration poses, same name and seed) is refused
/// against a run folder and against a `calbench baseline` file of the original, naming the
/// setting that differs: its results differ because its settings do, not because the program
/// changed. Another seed or trial count of the same scenario is still compared.
#[test]
fn a_run_of_an_edited_scenario_is_refused_naming_the_setting_that_differs() {
    let dir = tmp_dir("cli-guard-edited");
    let (a, base) = three_trials_and_baseline(&dir);
    let edited = read(&root().join("scenarios/ci-guard.toml"))
        .replace("[calibration]\ncount = 40\n", "[calibration]\ncount = 25\n");
    let edited = write_scenario(&dir, "edited", &edited);
    let b = dir.join("b");
    run(&edited, &b, &["--trials", "3", "--seed", "5"]);
    let summary = b.join("summary.json");
    for against in [a.join("summary.json"), base.clone()] {
        let (ok, text) = check(&summary, &against, &[]);
        assert!(
            !ok && text.starts_with(&format!("error: {}: scenario: ", summary.display()))
                && text.contains("calibration.count: 40 → 25")
                && text.contains(&against.display().to_string())
                && !text.contains("seed:"),
            "{text}"
        );
    }
    // compare compares the pair, and its pages name the setting; the same scenario is not
    // warned of.
    for (against, warned) in [(&a, false), (&b, true)] {
        let out = dir.join(format!("compare-{warned}"));
        calbench_ok(&[
            "compare",
            path_arg(&a),
            path_arg(against),
            "--out",
            path_arg(&out),
        ]);
        let note = "A and B ran scenario \"ci-guard\" with other settings \
                    (calibration.count: 40 → 25): calbench check refuses such a pair";
        for page in ["compare.md", "compare.html"] {
            let text = read(&out.join(page));
            assert_eq!(
                text.contains(
                    &note.replace('"', if page == "compare.md" { "\"" } else { "&quot;" })
                ),
                warned,
                "{page}: {text}"
            );
        }
    }
    // The same scenario on another seed and trial count: compared, unpaired.
    let c = dir.join("c");
    run(
        &root().join("scenarios/ci-guard.toml"),
        &c,
        &["--trials", "4", "--seed", "6"],
    );
    for against in [a.join("summary.json"), base] {
        let (ok, text) = check(&c.join("summary.json"), &against, &[]);
        assert!(
            ok && text.contains("unpaired: the runs differ in their seed"),
            "{text}"
        );
    }
}

//! `run`'s `--trials` and `--seed` on every kind of study (docs/formats.md § 2.2): a value out
//! of range is refused naming the option, not a line of the scenario file, which does not hold
//! it; and a registration study's start line counts its cells.

use crate::common::{calbench, path_arg, refused, root, tmp_dir};

#[test]
fn trials_out_of_range_are_refused_naming_the_option() {
    let dir = tmp_dir("run-options");
    for (scenario, trials, range) in [
        ("scenarios/ci-guard.toml", "0", "between 1 and"),
        ("scenarios/ban-fig3.toml", "0", "between 1 and"),
        ("scenarios/instruments.toml", "1", "between 2 and"),
    ] {
        let sc = root().join(scenario);
        let out = dir.join("out");
        let o = calbench(&[
            "run",
            path_arg(&sc),
            "--trials",
            trials,
            "--out",
            path_arg(&out),
        ]);
        let err = refused(&o, &["--trials", range]);
        assert!(!err.contains("line "), "{scenario}: {err}");
        assert!(!out.exists(), "{scenario}: {} written", out.display());
    }
}

#[test]
fn a_registration_study_says_how_many_cells_it_runs() {
    let dir = tmp_dir("run-options-cells");
    let sc = root().join("scenarios/ban-fig3.toml");
    let out = dir.join("out");
    let o = calbench(&[
        "run",
        path_arg(&sc),
        "--trials",
        "2",
        "--out",
        path_arg(&out),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("40 cells × 2 trials"), "{err}");
}

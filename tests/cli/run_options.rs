//! `run`'s `--trials` and `--seed` on every kind of study (docs/formats.md § 2.2): a value out
//! of range is refused naming the option, not a line of the scenario file, which does not hold
//! it; a registration study's start line counts its cells; and a run started anew where a
//! killed one left its checkpoint takes the killed run's temporary folder away with it; a
//! region that yields too few poses while the study runs is refused at its line.

use crate::common::{
    calbench, calbench_ok, kill_once_checkpointed, path_arg, refused, root, tmp_dir,
};

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

/// A killed run leaves its checkpoint and its temporary output folder (`.NAME.partial-PID`)
/// beside `--out`; `--resume` took both away, but a new run into the same folder removed the
/// checkpoint only, and the temporary folder stayed for good (docs/formats.md § 1.7).
#[test]
fn a_new_run_over_a_killed_ones_checkpoint_leaves_no_temporary_folder() {
    let dir = tmp_dir("run-options-anew");
    let sc = root().join("scenarios/ci-guard.toml");
    let out = dir.join("z");
    let args = [
        "run",
        path_arg(&sc),
        "--trials",
        "100000",
        "--threads",
        "1",
        "--out",
        path_arg(&out),
    ];
    kill_once_checkpointed(&args, &out, 600);
    let partial = || -> Vec<String> {
        std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".z.partial-"))
            .collect()
    };
    assert_eq!(
        partial().len(),
        1,
        "the killed run left no temporary folder"
    );
    let o = calbench_ok(&[
        "run",
        path_arg(&sc),
        "--trials",
        "2",
        "--out",
        path_arg(&out),
    ]);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("starting anew"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.join("summary.json").exists());
    assert_eq!(partial(), Vec::<String>::new());
}

/// A box only partly reachable passes the load's check (some pose reaches it) and then yields
/// too few poses while the study runs: the refusal names the scenario's line of the key, as
/// a refusal at load does (it had named the key alone), and leaves no output folder.
#[test]
fn a_region_too_few_poses_reach_is_refused_at_its_line() {
    let dir = tmp_dir("run-options-region");
    let sc = dir.join("box.toml");
    let text = "name = \"box\"\ntrials = 1\n[robot]\nbuiltin = \"irb2600\"\n[calibration]\n\
                strategies = [\"box\"]\ncount = 200\nregion = { kind = \"box\", center_mm = \
                [1000.0, 0.0, 900.0], size_mm = [100.0, 100.0, 100.0] }\n[[methods]]\n\
                name = \"ls\"\n";
    std::fs::write(&sc, text).unwrap();
    let out = dir.join("out");
    let o = calbench(&["run", path_arg(&sc), "--out", path_arg(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("box.toml: line 8, calibration.region: only ")
            && err.contains("of 200 poses found with the tool point in the box"),
        "{err}"
    );
    assert!(!out.exists());
}

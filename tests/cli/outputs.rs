//! Every file of `calbench run` and `calbench compare` comes from one of the report's
//! outputs (`calbench::report::output::Output`): the names the writers give are exactly the
//! files of the folder the command writes, no file written by hand beside them, none missing.

use std::collections::BTreeSet;
use std::path::Path;

use calbench::report::html::compare::{outputs as compare_outputs, Comparison, Side};
use calbench::report::output::file_names;
use calbench::report::run::trials_csv;
use calbench::report::run_outputs;
use calbench::runner::run::InMemoryRun;
use calbench::study::scenario::Scenario;
use calbench::study::RunOptions;

use crate::common::{calbench_ok, files_in, path_arg, read, root, tmp_dir, write_scenario};

/// Runs the scenario `sc` with `calbench run --out OUT` and checks that OUT holds exactly the
/// files of the run's outputs (the same study held in memory): `trials.csv` and the names of
/// `report::run_outputs`, each written by one output.
fn run_folder_is_its_outputs(sc: &Path, out: &Path) {
    calbench_ok(&[
        "run",
        path_arg(sc),
        "--threads",
        "2",
        "--out",
        path_arg(out),
    ]);
    let opts = RunOptions {
        threads: Some(2),
        ..RunOptions::default()
    };
    let run = InMemoryRun::run(Scenario::load(sc).unwrap(), &opts).unwrap();
    let outputs = run_outputs(&run.result, &run.summary).unwrap();
    let mut names = file_names(&outputs);
    names.push(trials_csv::NAME.to_string());
    let listed: BTreeSet<String> = names.iter().cloned().collect();
    assert_eq!(
        listed.len(),
        names.len(),
        "two outputs write one file: {names:?}"
    );
    assert_eq!(files_in(out), listed, "{}", out.display());
    // The run held in memory writes the same folder: the same files, and the seeded ones
    // byte for byte.
    let again = out.with_extension("again");
    run.write(&again).unwrap();
    assert_eq!(files_in(&again), listed);
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&again.join(f)), read(&out.join(f)), "{f}");
    }
}

#[test]
fn the_files_of_run_and_compare_are_those_of_their_outputs() {
    let dir = tmp_dir("outputs");
    let guard = read(&root().join("scenarios/ci-guard.toml")).replace("trials = 8", "trials = 3");
    // A plain study (paired comparisons of three methods) and a grid of two crossed axes
    // (heat maps, performance profile).
    let plain = write_scenario(&dir, "plain", &guard);
    let grid = write_scenario(
        &dir,
        "grid",
        &(guard.clone()
            + "\n[[sweep]]\nkey = \"outliers.count\"\nvalues = [0, 2]\n\
               [[sweep]]\nkey = \"outliers.magnitude_mm\"\nvalues = [[0.2, 0.4], [0.5, 1.0]]\n"),
    );
    let (a, b) = (dir.join("a"), dir.join("b"));
    run_folder_is_its_outputs(&plain, &a);
    run_folder_is_its_outputs(&grid, &b);
    let shown = files_in(&b);
    assert!(shown.contains("heatmap_lm_random.svg") && shown.contains("performance_profile.png"));

    let cmp = dir.join("compare");
    calbench_ok(&[
        "compare",
        path_arg(&a),
        path_arg(&b),
        "--out",
        path_arg(&cmp),
    ]);
    let c = Comparison::new(Side::read(&a).unwrap(), Side::read(&b).unwrap(), 0.05).unwrap();
    let outputs = compare_outputs(&c);
    let names: BTreeSet<String> = file_names(&outputs).into_iter().collect();
    assert_eq!(files_in(&cmp), names);
    let md = outputs.iter().find(|o| o.name() == "compare.md").unwrap();
    md.write(&dir.join("compare.md")).unwrap();
    assert_eq!(read(&dir.join("compare.md")), read(&cmp.join("compare.md")));
}

/// A folder holding another command's results (docs/formats.md § 1, "Output folders") is
/// refused before any work, naming the file that marks it: an identification into a run's
/// folder, a run into an identification's; each command still writes again into its own.
#[test]
fn a_folder_of_another_commands_results_is_refused() {
    let d = tmp_dir("outputs-foreign");
    let guard = root().join("scenarios/ci-guard.toml");
    let (sim, run, id) = (d.join("sim"), d.join("run"), d.join("id"));
    calbench_ok(&["simulate", path_arg(&guard), "--out", path_arg(&sim)]);
    let run_into = |out: &Path| {
        crate::common::calbench(&[
            "run",
            path_arg(&guard),
            "--trials",
            "2",
            "--out",
            path_arg(out),
        ])
    };
    let data = sim.join("measurements.csv");
    let identify_into = |out: &Path| {
        crate::common::calbench(&[
            "identify",
            "--robot",
            "irb2600",
            "--data",
            path_arg(&data),
            "--method",
            "ls",
            "--out",
            path_arg(out),
        ])
    };
    for (o, what) in [(run_into(&run), "run"), (identify_into(&id), "identify")] {
        assert!(
            o.status.success(),
            "{what}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let before = files_in(&run);
    for (o, marker) in [
        (identify_into(&run), "(trials.csv)"),
        (run_into(&id), "(identified.json)"),
    ] {
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(marker) && err.contains("mix two results"),
            "{err}"
        );
    }
    assert_eq!(files_in(&run), before, "the run's folder is left as it was");
    for (o, what) in [(run_into(&run), "run"), (identify_into(&id), "identify")] {
        assert!(
            o.status.success(),
            "{what} again: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

/// Names written into Markdown read as written: `compare.md` of two runs whose folders'
/// names hold Markdown's emphasis characters escapes them (`run_*a*` is not italic).
#[test]
fn compare_md_writes_names_as_they_are() {
    let d = tmp_dir("outputs-md-names");
    let guard = root().join("scenarios/ci-guard.toml");
    let (a, b) = (d.join("run_*a*"), d.join("b"));
    for out in [&a, &b] {
        calbench_ok(&[
            "run",
            path_arg(&guard),
            "--trials",
            "2",
            "--out",
            path_arg(out),
        ]);
    }
    let cmp = d.join("cmp");
    calbench_ok(&[
        "compare",
        path_arg(&a),
        path_arg(&b),
        "--out",
        path_arg(&cmp),
    ]);
    let md = read(&cmp.join("compare.md"));
    assert!(md.contains("run\\_\\*a\\*"), "{md}");
    assert!(!md.contains("run_*a*"), "{md}");
}

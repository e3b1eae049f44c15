//! `record` of a run folder, whatever the scenario's own layout (docs/formats.md § 2.15): a
//! scenario that reads its robot file by a path relative to its own folder (the shipped
//! `scenarios/ban-irb2600.toml` reads `../robots/ban-irb2600.toml`) ran, and its folder's
//! `scenario.toml` keeps that path, which does not lead from the run folder to the robot;
//! `record` had refused every such folder, with or without `--scenario`.

use crate::common::{calbench_ok, path_arg, read, refused, root, tmp_dir};

#[test]
fn a_run_of_a_scenario_reading_a_robot_file_is_recorded_from_its_folder() {
    let dir = tmp_dir("cli-record-layout");
    std::fs::create_dir_all(dir.join("scenarios")).unwrap();
    std::fs::create_dir_all(dir.join("robots")).unwrap();
    for f in ["scenarios/ban-irb2600.toml", "robots/ban-irb2600.toml"] {
        std::fs::copy(root().join(f), dir.join(f)).unwrap();
    }
    let sc = dir.join("scenarios/ban-irb2600.toml");
    assert!(read(&sc).contains("file = \"../robots/ban-irb2600.toml\""));
    // The same robot beside a scenario that names no seed: its table as run has none.
    let flat = dir.join("flat.toml");
    let text = read(&sc)
        .replace("../robots/ban-irb2600.toml", "robot.toml")
        .replace("seed = 2600\n", "");
    assert!(!text.contains("\nseed"));
    std::fs::write(&flat, text).unwrap();
    std::fs::copy(
        root().join("robots/ban-irb2600.toml"),
        dir.join("robot.toml"),
    )
    .unwrap();
    let db = dir.join("db.sqlite");
    for (i, (scenario, given)) in [(&sc, false), (&sc, true), (&flat, false)]
        .into_iter()
        .enumerate()
    {
        let out = dir.join(format!("run{i}"));
        // Each run its own seed: the same bytes would be recorded once.
        let seed = format!("{}", 2600 + i);
        let run = [
            "run",
            path_arg(scenario),
            "--trials",
            "1",
            "--out",
            path_arg(&out),
        ];
        let mut args = run.to_vec();
        if i == 1 {
            args.extend(["--seed", &seed]);
        }
        calbench_ok(&args);
        let mut rec = vec!["record", path_arg(&out), "--db", path_arg(&db)];
        if given {
            rec.extend(["--scenario", path_arg(scenario)]);
        }
        let o = calbench_ok(&rec);
        let said = String::from_utf8_lossy(&o.stdout);
        assert!(said.contains(&format!("as run #{}", i + 1)), "{said}");
    }
    // The summary of another run beside a folder's scenario.toml is still refused.
    let other = dir.join("run0/summary.json");
    let edited = read(&other).replacen("\"seed\": 2600", "\"seed\": 7", 1);
    assert_ne!(edited, read(&other));
    std::fs::write(&other, edited).unwrap();
    let o =
        crate::common::calbench(&["record", path_arg(&dir.join("run0")), "--db", path_arg(&db)]);
    refused(&o, &["summary.json", "seed", "is 7, but", "has seed 2600"]);
}

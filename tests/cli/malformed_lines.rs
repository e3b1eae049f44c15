//! Refusals the malformed-file corpus found naming the file and the key but not the line,
//! each now `FILE: line N, KEY: MESSAGE` as every other refusal of a file (docs/formats.md
//! § 8.1), checked whole, run the way a user runs calbench: from the folder of the files.

use std::path::Path;

use crate::common::{bin, read, refused, root, tmp_dir};
use crate::malformed::{ci_guard_with, line_of};
use crate::task::task;

/// The whole message (`error: …` and its newline) of `calbench ARGS` run in `dir`, which
/// must refuse.
fn refusal(dir: &Path, args: &[&str]) -> String {
    let o = bin().current_dir(dir).args(args).output().unwrap();
    refused(&o, &[])
}

/// A mapped column the export's header lacks is refused at the line of its entry in the
/// mapping file (the line after the key where the list goes on), naming the key.
#[test]
fn a_mapped_column_not_in_the_header_is_refused_at_its_line() {
    let d = tmp_dir("cli-lines-import");
    std::fs::write(d.join("raw.csv"), "q1,q2,q3,x,y,z\n0,0,0,1,2,3\n").unwrap();
    let mapping = "[joints]\ncolumns = [\"q1\", \"q2\",\n           \"JOINT\"]\nunit = \"deg\"\n\n\
                   [position]\ncolumns = [\"x\", \"y\", \"POINT\"]\nunit = \"mm\"\n";
    for (joint, point, want) in [
        ("q3x", "z", "line 3, joints.columns: column \"q3x\""),
        ("q3", "zz", "line 7, position.columns: column \"zz\""),
    ] {
        let text = mapping.replace("JOINT", joint).replace("POINT", point);
        std::fs::write(d.join("map.toml"), text).unwrap();
        let args = [
            "import",
            "raw.csv",
            "--mapping",
            "map.toml",
            "--out",
            "out.csv",
        ];
        assert_eq!(
            refusal(&d, &args),
            format!(
                "error: map.toml: {want} is not in the header of raw.csv (q1, q2, q3, x, y, z)\n"
            )
        );
        assert!(!d.join("out.csv").exists());
    }
}

/// A sweep point refused once its values are set is named at the line of the value refused,
/// in a `[sweep]` or a `[[sweep]]` grid (its element's own line in a list of several), and a
/// swept key the scenario does not take at the line of the axis's `key`.
#[test]
fn a_refused_sweep_point_is_named_at_the_line_of_its_value() {
    let d = tmp_dir("cli-lines-sweep");
    let count = "outliers.count: COUNT outliers but only 40 calibration poses";
    let grid = "[[sweep]]\nkey = \"outliers.magnitude_mm\"\nvalues = [[0.2, 0.4]]\n\n[[sweep]]\n\
                key = \"outliers.count\"\nvalues = [\n  1,\n  80,\n]";
    let cases = [
        (
            "key",
            "[sweep]\nkey = \"outliers.cont\"\nvalues = [1, 2]".to_string(),
            "key = ",
            "sweep (outliers.cont = 1): outliers: unknown field `cont`, expected one of \
             `count`, `fraction`, `magnitude_mm`"
                .to_string(),
        ),
        (
            "value",
            "[sweep]\nkey = \"outliers.count\"\nvalues = [1, 99]".to_string(),
            "values = ",
            format!(
                "sweep (outliers.count = 99): {}",
                count.replace("COUNT", "99")
            ),
        ),
        (
            "grid",
            grid.to_string(),
            "  80,",
            format!(
                "sweep (outliers.magnitude_mm = [0.2, 0.4], outliers.count = 80): {}",
                count.replace("COUNT", "80")
            ),
        ),
    ];
    for (name, sweep, at, want) in cases {
        let sc = ci_guard_with(&d, name, |t| format!("{t}\n{sweep}\n"));
        let line = line_of(&read(&sc), at);
        let file = format!("{name}.toml");
        assert_eq!(
            refusal(&d, &["run", &file, "--trials", "2", "--out", name]),
            format!("error: {file}: line {line}, {want}\n")
        );
        assert!(!d.join(name).exists());
    }
}

/// A Monte-Carlo scenario's unknown top-level key is refused at its line, naming beside its
/// keys the sections that make a study of another kind, which the refusal had left out.
#[test]
fn an_unknown_scenario_key_names_the_sections_of_the_other_kinds() {
    let d = tmp_dir("cli-lines-kinds");
    let sc = ci_guard_with(&d, "trails", |t| t.replacen("\ntrials =", "\ntrails =", 1));
    let line = line_of(&read(&sc), "trails =");
    let err = refusal(&d, &["run", "trails.toml", "--out", "o"]);
    assert!(
        err.starts_with(&format!(
            "error: trails.toml: line {line}, scenario: unknown field `trails`, expected one of \
             `name`, "
        )) && err.ends_with(
            ", `claims`, or `registration_study` or `instruments_study`, the section of a study \
             of another kind\n"
        ),
        "{err}"
    );
    assert!(!d.join("o").exists());
}

/// A registration study (and an instruments study) holding `[[methods]]`, which only a
/// Monte-Carlo study reads, is refused at the line of that `[[methods]]`.
#[test]
fn methods_in_a_study_that_runs_whole_are_refused_at_their_line() {
    let d = tmp_dir("cli-lines-whole");
    for (file, takes) in [
        (
            "ban-fig3.toml",
            "scenario: unknown field `methods`, expected `registration_study` or `claims` (a \
             scenario with [registration_study] takes only name, description, seed, trials, \
             that table and [[claims]])",
        ),
        (
            "instruments.toml",
            "methods: unknown key: a scenario with [instruments_study] takes name, \
             description, seed, trials, robot, [errors], [instruments_study] and its \
             [[measurement]] tables",
        ),
    ] {
        let text = read(&root().join("scenarios").join(file));
        let text = format!("{text}\n[[methods]]\nname = \"ls\"\n");
        std::fs::write(d.join(file), &text).unwrap();
        let line = line_of(&text, "[[methods]]");
        assert_eq!(
            refusal(&d, &["run", file, "--trials", "2", "--out", "o"]),
            format!("error: {file}: line {line}, {takes}\n")
        );
        assert!(!d.join("o").exists());
    }
}

/// A task whose validation file is its calibration file is refused at the line of the key
/// that gives the validation rows, `data` named as before.
#[test]
fn a_task_whose_validation_rows_are_its_calibration_rows_is_refused_at_the_line() {
    let d = tmp_dir("cli-lines-task");
    let data = root().join("data/ipa-ur10-series-d/measurements_iso_cubes.csv");
    let mapping = root().join("tasks/ipa-ur10.mapping.toml");
    let text = read(&task("ipa-ur10-series-d"))
        .replace("\"../", &format!("\"{}/", root().display()))
        .replace(
            "\"ipa-ur10.mapping.toml\"",
            &format!("\"{}\"", mapping.display()),
        );
    let (head, _) = text.split_once("[data]").unwrap();
    let data = data.display();
    let text = format!("{head}[data]\ncalibration = \"{data}\"\nvalidation = \"{data}\"\n");
    std::fs::write(d.join("t.toml"), &text).unwrap();
    let pairs: Vec<String> = (0..5)
        .map(|i| format!("calibration row {i} = validation row {i}"))
        .collect();
    assert_eq!(
        refusal(&d, &["task", "t.toml", "--method", "ls", "--out", "o"]),
        format!(
            "error: t.toml: line {}, data: 632 validation row(s) repeat a calibration row (the \
             same joint values and measured point; 0-based data rows of {data} and {data}): \
             {}, and 627 more; a validation row must not calibrate\n",
            line_of(&text, "validation = "),
            pairs.join(", ")
        )
    );
    assert!(!d.join("o").exists());
}

/// `check` refuses a summary whose `results` is of the wrong type, and a baseline whose
/// per-trial values are of another format, at the line of the key.
#[test]
fn check_refuses_a_summary_or_baseline_key_at_its_line() {
    let d = tmp_dir("cli-lines-check");
    let base = read(&root().join("results/baselines/ci-guard.json"));
    std::fs::write(d.join("base.json"), &base).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&base).unwrap();
    v["results"] = serde_json::json!("x");
    let summary = serde_json::to_string_pretty(&v).unwrap();
    std::fs::create_dir(d.join("r")).unwrap();
    std::fs::write(d.join("r/summary.json"), &summary).unwrap();
    assert_eq!(
        refusal(&d, &["check", "r/summary.json", "--baseline", "base.json"]),
        format!(
            "error: r/summary.json: line {}, results: not a calbench summary.json: invalid type: \
             string \"x\", expected a sequence, so this is not a calbench summary (summary.json \
             from `calbench run`: an object with a `scenario` name and `results`, a list of \
             entries with `method`, `poses` and metrics)\n",
            line_of(&summary, "  \"results\": ")
        )
    );
    let bl = base.replace("calbench-per-trial-1", "calbench-per-trial-9");
    std::fs::write(d.join("bl.json"), &bl).unwrap();
    assert_eq!(
        refusal(&d, &["check", "base.json", "--baseline", "bl.json"]),
        format!(
            "error: bl.json: line {}, per_trial.format: is \"calbench-per-trial-9\", not \
             \"calbench-per-trial-1\"\n",
            line_of(&bl, "    \"format\": \"calbench-per-trial-9\"")
        )
    );
}

/// A key missing from a file itself (a scenario's `name`, a task's `title`, a robot file's
/// `convention`) is named by the key with no line, where line 1 had been named (a comment,
/// or another key, stands there); one missing from a table keeps the line of that table.
#[test]
fn a_key_missing_from_the_file_itself_is_named_without_a_line() {
    let d = tmp_dir("cli-lines-missing");
    let drop = |src: &Path, to: &str, key: &str| {
        let text = read(src);
        let text: Vec<&str> = text
            .lines()
            .filter(|l| !l.starts_with(&format!("{key} = ")))
            .collect();
        std::fs::write(d.join(to), text.join("\n") + "\n").unwrap();
    };
    let scenarios = root().join("scenarios");
    drop(&scenarios.join("ci-guard.toml"), "s.toml", "name");
    drop(&scenarios.join("ban-fig3.toml"), "b.toml", "name");
    drop(&task("barrett-wam"), "t.toml", "title");
    drop(
        &root().join("robots/ban-irb2600.toml"),
        "r.toml",
        "convention",
    );
    let q = "--q=0,0,0,0,0,0";
    for (args, want) in [
        (&["run", "s.toml"][..], "s.toml: name: missing field `name`"),
        (&["run", "b.toml"][..], "b.toml: name: missing field `name`"),
        (
            &["task", "t.toml", "--method", "ls", "--out", "o"][..],
            "t.toml: title: missing field `title`",
        ),
        (
            &["fk", "--robot", "r.toml", q][..],
            "r.toml: convention: missing field `convention`",
        ),
    ] {
        assert_eq!(refusal(&d, args), format!("error: {want}\n"), "{args:?}");
    }
    // A key missing from a table: at the line of the table's header.
    let text = read(&root().join("robots/ban-irb2600.toml"));
    let second = text.match_indices("[[joints]]").nth(1).unwrap().0;
    let line = text[..second].lines().count() + 1;
    let (head, tail) = text.split_at(second);
    let tail = tail.replacen("\nd = ", "\n# d = ", 1);
    std::fs::write(d.join("r2.toml"), format!("{head}{tail}")).unwrap();
    assert_eq!(
        refusal(&d, &["fk", "--robot", "r2.toml", q]),
        format!("error: r2.toml: line {line}, joints[1].d: missing field `d`\n")
    );
}

/// A name `[errors.values]` does not know is refused at its own line and key, where it had
/// been refused at the table's header (docs/formats.md § 4.4: "refused by its key"), a name
/// with a dot by its quoted key; and a whole number beyond TOML's 64 bits is refused saying
/// so, where toml's words were `u64 value was too large` and `as i128, expected any valid
/// TOML value`.
#[test]
fn an_unknown_error_name_and_a_number_beyond_toml_are_refused_at_their_line() {
    let d = tmp_dir("cli-lines-values");
    let range = "beyond TOML's whole numbers, -9223372036854775808 to 9223372036854775807";
    let ci = read(&root().join("scenarios/ci-guard.toml"));
    let values = |names: &str| {
        let with = format!("kind = \"values\"\n[errors.values]\na2 = 0.1\n{names}");
        ci.replace("kind = \"paper\"", &with)
    };
    let seed = |v: &str| ci.replace("seed = 42", &format!("seed = {v}"));
    let cases = [
        (
            "a9",
            values("a9 = 0.1"),
            "a9 = ",
            "errors.values.a9: \"a9\" is not a parameter of robot \"irb2600\"".to_string(),
        ),
        (
            "dotted",
            values("\"tool.q\" = 0.1"),
            "\"tool.q\"",
            "errors.values.\"tool.q\": unknown parameter \"tool.q\"".into(),
        ),
        (
            "u64",
            seed("9223372036854775808"),
            "seed = ",
            format!("seed: the whole number is {range}"),
        ),
        (
            "i128",
            seed("99999999999999999999"),
            "seed = ",
            format!("seed: `99999999999999999999` is {range}"),
        ),
    ];
    for (name, text, start, want) in cases {
        std::fs::write(d.join(format!("{name}.toml")), &text).unwrap();
        let line = line_of(&text, start);
        let said = refusal(&d, &["run", &format!("{name}.toml"), "--out", "o"]);
        let at = format!("error: {name}.toml: line {line}, {want}");
        assert!(said.starts_with(&at), "{said}\nwanted: {at}");
        assert!(!d.join("o").exists());
    }
}

/// A value of the wrong type or an unknown key in `[sweep]` or `[[sweep]]` is refused at its
/// own line (and, in `[sweep]`, its key), where every such refusal had named the line of the
/// first section's header.
#[test]
fn a_sweep_s_malformed_value_is_refused_at_its_line() {
    let d = tmp_dir("cli-lines-sweep-type");
    let ci = read(&root().join("scenarios/ci-guard.toml"));
    let one = "[sweep]\nkey = \"outliers.count\"\n";
    let grid = "[[sweep]]\nkey = \"outliers.count\"\nvalues = [0, 1]\n\n[[sweep]]\n\
                key = \"outliers.magnitude_mm\"\n";
    for (name, sweep, start, words) in [
        (
            "values",
            format!("{one}values = \"0,1\"\n"),
            "values = \"",
            "sweep.values: invalid type: string \"0,1\", expected a sequence",
        ),
        (
            "unknown",
            format!("{one}values = [0, 1]\nzap = 3\n"),
            "zap = ",
            "sweep: unknown field `zap`, expected one of `key`, `values`, `zip`",
        ),
        (
            "grid",
            format!("{grid}values = \"x\"\n"),
            "values = \"",
            "invalid type: string \"x\", expected a sequence",
        ),
        (
            "zip",
            format!("{grid}values = [[0.1, 0.2]]\nzip = 3\n"),
            "zip = ",
            "invalid type: integer `3`, expected a boolean",
        ),
    ] {
        let text = format!("{ci}\n{sweep}");
        std::fs::write(d.join(format!("{name}.toml")), &text).unwrap();
        let at = format!("error: {name}.toml: line {}, ", line_of(&text, start));
        let said = refusal(&d, &["run", &format!("{name}.toml"), "--out", "o"]);
        assert!(
            said.starts_with(&at) && said.contains(words),
            "{said}\nwanted: {at}…{words}"
        );
        assert!(!d.join("o").exists());
    }
}

//! `calbench task`: the shipped real-data tasks run the way a user runs them, `task.json`
//! checked against its contract (docs/formats.md § 9.3), the model chosen by cross-validation
//! on the calibration rows alone, and task files and splits that do not fit refused by name.

use std::path::{Path, PathBuf};

use crate::common::{calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir};

/// `calbench task TASK --method lm [--models MODELS] --out OUT` through `run` (`calbench`,
/// or `calbench_ok` to require success).
pub(crate) fn task_lm(
    run: fn(&[&str]) -> std::process::Output,
    task: &Path,
    models: Option<&str>,
    out: &Path,
) -> std::process::Output {
    let mut args = vec!["task", path_arg(task), "--method", "lm"];
    if let Some(m) = models {
        args.extend_from_slice(&["--models", m]);
    }
    args.extend_from_slice(&["--out", path_arg(out)]);
    run(&args)
}

pub(crate) fn task(name: &str) -> PathBuf {
    root().join("tasks").join(format!("{name}.toml"))
}

/// The keys and values `task.json` must hold for an entry of `calbench` with `lm`; returns
/// the value.
fn check_contract(dir: &Path, name: &str, metric: &str) -> f64 {
    let j = load_json(&dir.join("task.json"));
    let keys: Vec<&str> = j.as_object().unwrap().keys().map(String::as_str).collect();
    let mut want = vec![
        "calbench_version",
        "candidates",
        "candidates_fixed_by",
        "chosen_by",
        "cv_choice",
        "ci95",
        "division",
        "entrant",
        "format",
        "git_commit",
        "method",
        "metric",
        "models",
        "published",
        "task",
        "task_hash",
        "validation_errors_mm",
        "value",
    ];
    want.sort();
    let mut got = keys.clone();
    got.sort();
    assert_eq!(got, want);
    assert_eq!(j["format"], "calbench-task-1");
    assert_eq!(j["task"], name);
    let hash = j["task_hash"].as_str().unwrap();
    assert!(
        hash.len() == 64 && hash.bytes().all(|b| b.is_ascii_hexdigit()),
        "{hash}"
    );
    assert_eq!(j["metric"], metric);
    assert_eq!(j["method"], "lm");
    assert_eq!(j["entrant"], "calbench");
    assert_eq!(j["calbench_version"], env!("CARGO_PKG_VERSION"));
    assert!(j["git_commit"].is_null() || j["git_commit"].as_str().unwrap().len() == 40);
    assert_eq!(j["models"][0], "kinematic");
    let value = j["value"].as_f64().unwrap();
    let ci = j["ci95"].as_array().unwrap();
    let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
    assert!(lo < value && value < hi, "{lo} {value} {hi}");
    // The figure is the identification's own validation figure.
    let id = load_json(&dir.join("identified.json"));
    let key = if metric == "validation_mean_mm" {
        "mean"
    } else {
        "rms"
    };
    let v = id["validation_after_mm"][key].as_f64().unwrap();
    assert!((v - value).abs() < 1e-9 * v, "{v} {value}");
    value
}

#[test]
fn the_wam_task_scores_the_20_random_poses_beside_the_published_figure() {
    let d = tmp_dir("cli-task-wam");
    let out = d.join("wam");
    let o = task_lm(calbench_ok, &task("barrett-wam"), Some("kinematic"), &out);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("validation_mean_mm = 3.09"), "{stdout}");
    let value = check_contract(&out, "barrett-wam", "validation_mean_mm");
    // docs/results.md: 3.09 mm with the kinematic model.
    assert!((value - 3.09).abs() < 0.005, "{value}");
    let j = load_json(&out.join("task.json"));
    assert_eq!(j["division"], "closed");
    assert_eq!(j["chosen_by"], "given");
    assert_eq!(j["models"], serde_json::json!(["kinematic"]));
    let p = &j["published"][0];
    assert_eq!(p["value"], 2.92);
    assert_eq!(p["division"], "open");
    assert!(p["source"].as_str().unwrap().contains("Jacobi (2025)"));
    for f in [
        "identified.json",
        "robot.toml",
        "report.html",
        "residuals.csv",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let id = load_json(&out.join("identified.json"));
    assert_eq!(id["validation_after_mm"]["mean"], j["value"]);
    // The folder carries the task file it ran, as read, and record takes it.
    assert_eq!(
        read(&out.join("task.toml")),
        read(&root().join("tasks/barrett-wam.toml"))
    );
    let db = d.join("wam.sqlite");
    calbench_ok(&["record", path_arg(&out), "--db", path_arg(&db)]);
}

#[test]
fn a_ur10_task_chooses_its_model_by_cv_on_its_split() {
    let d = tmp_dir("cli-task-ur10");
    let out = d.join("d");
    let o = task_lm(
        calbench_ok,
        &task("ipa-ur10-series-d"),
        Some("kinematic,beta"),
        &out,
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("not published in a source found"),
        "{stdout}"
    );
    let value = check_contract(&out, "ipa-ur10-series-d", "validation_rms_mm");
    let j = load_json(&out.join("task.json"));
    assert_eq!(j["chosen_by"], "cv");
    assert_eq!(j["division"], "closed");
    assert_eq!(j["published"], serde_json::json!([]));
    let id = load_json(&out.join("identified.json"));
    // The split's 443 calibration rows (of every 10 rows the first 7 of 632) calibrate.
    let cvs = id["cv_models"].as_array().unwrap();
    assert_eq!(cvs.len(), 2);
    let best = id["cv_best"].as_str().unwrap();
    let chosen = if best == "kinematic" {
        vec!["kinematic"]
    } else {
        vec!["kinematic", best]
    };
    assert_eq!(j["models"], serde_json::json!(chosen));
    // docs/results.md: Series D, β chosen, 0.393 mm held out.
    assert!((value - 0.393).abs() < 0.001, "{value}");
    let again = d.join("again");
    task_lm(
        calbench_ok,
        &task("ipa-ur10-series-d"),
        Some("kinematic,beta"),
        &again,
    );
    assert_eq!(
        std::fs::read(out.join("task.json")).unwrap(),
        std::fs::read(again.join("task.json")).unwrap(),
        "a task's entry is reproducible byte for byte"
    );
}

/// A copy of the WAM task whose validation file holds only the random poses `rows`.
pub(crate) fn wam_with_validation(dir: &Path, rows: std::ops::Range<usize>) -> PathBuf {
    let data = root().join("data/barrett-wam");
    let text =
        std::fs::read_to_string(data.join("3D_WAM_uncalibrated_random_cleaned.csv")).unwrap();
    let mut lines = text.lines();
    let mut kept = vec![lines.next().unwrap()];
    kept.extend(lines.skip(rows.start).take(rows.len()));
    let val = dir.join("random.csv");
    std::fs::write(&val, kept.join("\n") + "\n").unwrap();
    let t = std::fs::read_to_string(task("barrett-wam"))
        .unwrap()
        .replace("../examples/", &format!("{}/examples/", root().display()))
        .replace(
            "\"../data/barrett-wam/3D_WAM_uncalibrated_grid_cleaned.csv\"",
            &format!(
                "\"{}\"",
                data.join("3D_WAM_uncalibrated_grid_cleaned.csv").display()
            ),
        )
        .replace(
            "\"../data/barrett-wam/3D_WAM_uncalibrated_random_cleaned.csv\"",
            &format!("\"{}\"", val.display()),
        )
        .replace(
            "\"barrett-wam.mapping.toml\"",
            &format!(
                "\"{}\"",
                root().join("tasks/barrett-wam.mapping.toml").display()
            ),
        );
    let p = dir.join("barrett-wam.toml");
    std::fs::write(&p, t).unwrap();
    p
}

#[test]
fn the_validation_rows_do_not_change_the_chosen_model() {
    let d = tmp_dir("cli-task-cv-only");
    let mut runs = Vec::new();
    for (i, rows) in [0..20, 5..13].into_iter().enumerate() {
        let sub = d.join(format!("v{i}"));
        std::fs::create_dir_all(&sub).unwrap();
        let t = wam_with_validation(&sub, rows);
        let out = sub.join("out");
        task_lm(calbench_ok, &t, Some("kinematic,beta"), &out);
        runs.push((
            load_json(&out.join("identified.json")),
            load_json(&out.join("task.json")),
        ));
    }
    let (a, b) = (&runs[0], &runs[1]);
    assert_eq!(
        a.0["cv_models"], b.0["cv_models"],
        "the CV sees the calibration rows only"
    );
    assert_eq!(a.0["cv_best"], b.0["cv_best"]);
    assert_eq!(a.1["models"], b.1["models"]);
    assert_eq!(a.1["chosen_by"], "cv");
    assert_ne!(a.1["value"], b.1["value"], "the validation rows did change");
    assert_ne!(a.1["task_hash"], b.1["task_hash"]);
}

#[test]
fn task_files_and_splits_that_do_not_fit_are_refused_by_name() {
    let d = tmp_dir("cli-task-refusals");
    // An empty task name is refused as such, where it was looked up as `tasks/.toml`.
    let out = d.join("empty-name");
    let o = calbench(&["task", "", "--method", "lm", "--out", path_arg(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("'<TASK>'"), "{err}");
    assert!(!err.contains("tasks/.toml") && !out.exists(), "{err}");
    let src = std::fs::read_to_string(task("ipa-ur10-series-d")).unwrap();
    let abs = |s: &str| {
        s.replace("\"../", &format!("\"{}/", root().display()))
            .replace(
                "\"ipa-ur10.mapping.toml\"",
                &format!(
                    "\"{}\"",
                    root().join("tasks/ipa-ur10.mapping.toml").display()
                ),
            )
    };
    let refused = |name: &str, text: &str, split: Option<&str>| -> String {
        let p = d.join(format!("{name}.toml"));
        let mut text = abs(text);
        if let Some(s) = split {
            let sp = d.join(format!("{name}.split"));
            std::fs::write(&sp, s).unwrap();
            text = text.replace(
                "\"ipa-ur10-series-d.split\"",
                &format!("\"{}\"", sp.display()),
            );
        } else {
            text = text.replace(
                "\"ipa-ur10-series-d.split\"",
                &format!(
                    "\"{}\"",
                    root().join("tasks/ipa-ur10-series-d.split").display()
                ),
            );
        }
        std::fs::write(&p, text).unwrap();
        let o = task_lm(calbench, &p, None, &d.join("out"));
        assert!(!o.status.success(), "{name} was accepted");
        assert!(!d.join("out").exists(), "nothing is written");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let e = refused("key", &src.replace("metric =", "metrik ="), None);
    assert!(e.contains("key.toml: line") && e.contains("metrik"), "{e}");
    // A candidate the robot cannot take is the task file's, named at its key, where the
    // refusal blamed the command's `--models`, which was not given.
    let text = src.clone() + "\n[models]\ncandidates = [\"kinematic\", \"h1q9\"]\n";
    let e = refused("term", &text, None);
    assert!(
        e.contains("term.toml: line ")
            && e.contains(", models.candidates[1]: `h1q9`: robot")
            && !e.contains("--models"),
        "{e}"
    );
    // A mapping of another joint count is refused at the line of its columns.
    let five = d.join("five.mapping.toml");
    let mapping = read(&root().join("tasks/ipa-ur10.mapping.toml"));
    std::fs::write(&five, mapping.replacen(", \"wrist_3_joint\"", "", 1)).unwrap();
    let text = src.replace(
        "\"ipa-ur10.mapping.toml\"",
        &format!("\"{}\"", five.display()),
    );
    let e = refused("five", &text, None);
    assert!(
        e.contains("five.mapping.toml: line 8, joints.columns: 5 joint columns for the 6-joint"),
        "{e}"
    );
    // A key given twice is named, where toml's words name none.
    let twice = src.replacen("metric =", "metric = \"validation_rms_mm\"\nmetric =", 1);
    let line = twice
        .lines()
        .position(|l| l.starts_with("metric ="))
        .unwrap()
        + 2;
    let e = refused("twice", &twice, None);
    assert!(
        e.contains(&format!("twice.toml: line {line}: duplicate key `metric`")),
        "{e}"
    );
    // A key of the wrong type, and an unknown key in a table: the line and the key's path.
    let typed = format!("{src}\n[models]\ncandidates = [\"kinematic\"]\nfolds = \"five\"\n");
    let e = refused("typed", &typed, None);
    assert!(
        e.contains("typed.toml: line 15, models.folds: invalid type: string \"five\""),
        "{e}"
    );
    let e = refused("nested", &src.replace("[data]", "[data]\nfiel = 1"), None);
    assert!(
        e.contains("nested.toml: line ") && e.contains(", data.fiel: unknown field `fiel`"),
        "{e}"
    );
    let e = refused(
        "metric",
        &src.replace("validation_rms_mm", "validation_p95"),
        None,
    );
    assert!(
        e.contains("metric.toml: line") && e.contains("validation_p95"),
        "{e}"
    );
    let both = format!(
        "{src}\n[[published]]\nlabel = \"x\"\nvalue = 1.0\nsource = \"s\"\ndivision = \"open\"\n"
    );
    let e = refused("both", &both, None);
    assert!(
        e.contains("both.toml: line 7, unpublished") && e.contains("one or the other"),
        "{e}"
    );
    // Blank text where a reader is told what the task is, or why no figure is given, or
    // which figure it is: each named at its own key (a blank label was named `source`).
    let title = src.replace(
        "title = \"IPA UR10 Series D, positions, interleaved 70/30 split\"",
        "title = \" \"",
    );
    let e = refused("title", &title, None);
    assert!(e.contains("title.toml: line 3, title: is blank"), "{e}");
    let why = src.replace("\"not published in a source found\"", "\"\"");
    let e = refused("why", &why, None);
    assert!(e.contains("why.toml: line 7, unpublished: is blank"), "{e}");
    let label = both
        .replace("unpublished = \"not published in a source found\"\n", "")
        .replace("label = \"x\"", "label = \"\"");
    let e = refused("label", &label, None);
    assert!(e.contains(", published[0].label: is blank"), "{e}");
    let e = refused(
        "rows",
        &src,
        Some("rows 631\ncalibration 0-400\nvalidation 401-630\n"),
    );
    assert!(
        e.contains("rows.split: rows:")
            && e.contains("the split is of 631 rows")
            && e.contains("has 632"),
        "{e}"
    );
    // A count far beyond what the data file can hold is refused before its rows are listed
    // (2·10⁹ rows had taken 16 GB and 40 s before the data were read).
    let e = refused(
        "huge",
        &src,
        Some(
            "rows 2000000000
calibration 0-999999999
validation 1000000000-1999999999
",
        ),
    );
    assert!(
        e.contains("huge.split: line 1: `rows 2000000000`: ")
            && e.contains("measurements_iso_cubes.csv is ")
            && e.contains("bytes, too short for that many rows"),
        "{e}"
    );
    // A count above the data file's, with parts that cover the data's rows: the count at its
    // line, where it was "row 632 is in neither part" at no line.
    let e = refused(
        "more",
        &src,
        Some("rows 633\ncalibration 0-400\nvalidation 401-631\n"),
    );
    assert!(
        e.contains("more.split: line 1: `rows 633`, but the parts end at row 631")
            && e.contains("the data file's number of rows"),
        "{e}"
    );
    // A split that is a link to itself: the system's reason, where it was "is not a file".
    let looped = d.join("loop.split");
    std::os::unix::fs::symlink(&looped, &looped).unwrap();
    let text = src.replace(
        "\"ipa-ur10-series-d.split\"",
        &format!("\"{}\"", looped.display()),
    );
    let e = refused("loop", &text, None);
    assert!(
        e.contains("loop.toml: line ") && e.contains("symbolic links"),
        "{e}"
    );
    let e = refused(
        "overlap",
        &src,
        Some("rows 632\ncalibration 0-400\nvalidation 400-631\n"),
    );
    assert!(
        e.contains("overlap.split: line 3") && e.contains("row 400 is already in calibration"),
        "{e}"
    );
    let e = refused(
        "range",
        &src,
        Some("rows 632\ncalibration 0-400\nvalidation 401-632\n"),
    );
    assert!(
        e.contains("range.split: line 3") && e.contains("row 632 is out of range"),
        "{e}"
    );
    // More folds than calibration rows: refused naming the task file's key, not `--cv`, which
    // the entry was not given.
    let models =
        |extra: &str| format!("{src}\n[models]\ncandidates = [\"kinematic\", \"beta\"]\n{extra}\n");
    let e = refused("folds", &models("folds = 1000"), None);
    assert!(
        e.contains("folds.toml: line 15, models.folds: 1000 folds but only 443 calibration rows")
            && !e.contains("--cv"),
        "{e}"
    );
    // One candidate is identified without a cross-validation: folds or fold seeds given
    // with it would enter `task_hash` and change nothing, and are refused at their line.
    for (name, extra) in [("one", "folds = 3"), ("seeds1", "fold_seeds = [0, 1]")] {
        let one = format!("{src}\n[models]\ncandidates = [\"kinematic\"]\n{extra}\n");
        let e = refused(name, &one, None);
        let key = extra.split(' ').next().unwrap();
        let said =
            format!("{name}.toml: line 15, models.{key}: is read only with two or more candidates");
        assert!(e.contains(&said), "{e}");
    }
    // A fold seed given twice repeats the same folds: refused as a candidate given twice is.
    let e = refused("seeds", &models("fold_seeds = [0, 1, 0]"), None);
    assert!(
        e.contains(
            "seeds.toml: line 15, models.fold_seeds: models.fold_seeds[2]: seed 0 is listed twice"
        ),
        "{e}"
    );
}

/// Series D's kinematic entry with `lm` stops at its iteration limit; the entry is written
/// and scored, and a warning says the solve did not converge, which task.json does not.
#[test]
fn an_entry_whose_solve_did_not_converge_is_warned_of() {
    let d = tmp_dir("cli-task-unconverged");
    let out = d.join("d");
    let o = task_lm(
        calbench_ok,
        &task("ipa-ur10-series-d"),
        Some("kinematic"),
        &out,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        load_json(&out.join("identified.json"))["termination"],
        "max-iterations"
    );
    assert!(
        err.contains("warning: the identification ended `max-iterations` after 50 iterations"),
        "{err}"
    );
}

#[test]
fn a_published_figure_of_a_hidden_character_or_a_label_given_twice_is_refused() {
    let d = tmp_dir("cli-task-published");
    let task = crate::record_task::small_task(&d);
    let text = read(&task);
    let figure = "\n[[published]]\nlabel = \"MDH + learned residual\"\nvalue = 3.1\n\
                  source = \"another paper\"\ndivision = \"open\"\n";
    for (edited, want) in [
        (
            text.clone() + figure,
            "published[1].label: \"MDH + learned residual\" is the label of published[0] too",
        ),
        (
            text.replace("label = \"MDH", "label = \"\\u001b[31mMDH"),
            "published[0].label: must be text without control characters",
        ),
    ] {
        std::fs::write(&task, edited).unwrap();
        let out = d.join("out");
        let o = task_lm(calbench, &task, None, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("small.toml: line ") && err.contains(want),
            "{err}"
        );
        assert!(!out.exists(), "{err}");
    }
}

/// A task's name is looked up under tasks/ of the current folder: run elsewhere, it had been
/// refused as "tasks/barrett-wam.toml: No such file or directory", saying neither that it was
/// taken for a name nor where names are found. The refusal says both; the task file's path
/// runs from anywhere.
#[test]
fn a_task_name_outside_the_repository_says_where_names_are_looked_up() {
    let d = tmp_dir("task-name-elsewhere");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_calbench"))
        .args(["task", "barrett-wam", "--method", "lm", "--out", "entry"])
        .current_dir(&d)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with(
            "error: setting `task`: no task named \"barrett-wam\": tasks/barrett-wam.toml is \
             not a file (a task's name is looked up under tasks/ of the current folder"
        ),
        "{err}"
    );
    assert!(!d.join("entry").exists());
}

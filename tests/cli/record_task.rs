//! `record` of a task folder stores only what ran (docs/formats.md § 2.15, § 9.3): the task
//! file the folder carries (`task.toml`), with the files it fixes as they are now, must have
//! the `task_hash` of `task.json`, and the figure must be what the entry's per-row validation
//! errors give; an entry whose data, task file or figure changed after it ran is refused,
//! naming the file, the key and both hashes or figures.

use std::path::{Path, PathBuf};

use crate::common::{calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir};

/// A user's small task in `dir/tasks/small.toml`: the Barrett WAM's 216 grid rows calibrate
/// and its 20 random rows validate (copies in `dir/tasks/`, so that the test may edit them),
/// the robot and the mapping of the shipped task, and one published figure.
pub(crate) fn small_task(dir: &Path) -> PathBuf {
    let tasks = dir.join("tasks");
    std::fs::create_dir_all(&tasks).unwrap();
    let data = root().join("data/barrett-wam");
    for (from, to) in [
        ("3D_WAM_uncalibrated_grid_cleaned.csv", "cal.csv"),
        ("3D_WAM_uncalibrated_random_cleaned.csv", "val.csv"),
    ] {
        std::fs::copy(data.join(from), tasks.join(to)).unwrap();
    }
    let file = tasks.join("small.toml");
    let text = format!(
        "title = \"A small task\"\nrobot = {:?}\nmapping = {:?}\n\
         metric = \"validation_mean_mm\"\n\n[data]\ncalibration = \"cal.csv\"\n\
         validation = \"val.csv\"\n\n[[published]]\nlabel = \"MDH + learned residual\"\n\
         value = 2.92\nsource = \"Jacobi 2025, table 3\"\ndivision = \"open\"\n",
        root().join("examples/barrett-wam/wam.toml"),
        root().join("tasks/barrett-wam.mapping.toml"),
    );
    std::fs::write(&file, text).unwrap();
    file
}

/// `calbench task TASK --method lm --models kinematic --out OUT`, as a user runs an entry.
pub(crate) fn run_entry(task: &Path, out: &Path) {
    calbench_ok(&[
        "task",
        path_arg(task),
        "--method",
        "lm",
        "--models",
        "kinematic",
        "--out",
        path_arg(out),
    ]);
}

/// `calbench record DIR --db DB [more]`.
fn record(dir: &Path, db: &Path, more: &[&str]) -> std::process::Output {
    let mut args = vec!["record", path_arg(dir), "--db", path_arg(db)];
    args.extend(more);
    calbench(&args)
}

/// The refusal of `o`, which must have failed, naming `task.json`'s `task_hash`, the hash
/// the entry states and another 64-digit hash.
fn refused_naming_both_hashes(o: &std::process::Output, stated: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "recorded a task that changed: {err}");
    assert!(err.contains("task.json: task_hash: is "), "{err}");
    let hashes: Vec<&str> = err
        .split(|c: char| !c.is_ascii_hexdigit())
        .filter(|w| w.len() == 64)
        .collect();
    assert!(
        hashes.len() == 2 && hashes[0] == stated && hashes[1] != stated,
        "{err}"
    );
}

#[test]
fn a_task_whose_data_or_task_file_changed_after_the_entry_ran_is_refused_naming_both_hashes() {
    let dir = tmp_dir("record-task-hash");
    let task = small_task(&dir);
    let out = dir.join("entry");
    run_entry(&task, &out);
    let stated = load_json(&out.join("task.json"))["task_hash"]
        .as_str()
        .unwrap()
        .to_string();
    let given = ["--task", path_arg(&task)];
    // Unedited: recorded.
    let o = record(&out, &dir.join("ok.sqlite"), &given);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Without the task file: tasks/small.toml is not under the current folder, so the files
    // cannot be found; refused, saying how to give it.
    let o = record(&out, &dir.join("none.sqlite"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("task_hash") && err.contains("--task"),
        "{err}"
    );
    // One row of the validation data edited (a measured x, 0.1 mm): refused.
    let val = dir.join("tasks/val.csv");
    let rows = read(&val);
    let mut lines: Vec<String> = rows.lines().map(str::to_string).collect();
    let mut cells: Vec<String> = lines[2].split(',').map(str::to_string).collect();
    let x: f64 = cells[1].parse().unwrap();
    cells[1] = format!("{}", x + 0.1);
    lines[2] = cells.join(",");
    std::fs::write(&val, lines.join("\n") + "\n").unwrap();
    let o = record(&out, &dir.join("data.sqlite"), &given);
    refused_naming_both_hashes(&o, &stated);
    assert!(!dir.join("data.sqlite").exists());
    std::fs::write(&val, &rows).unwrap();
    // The task file the folder carries edited (its metric): refused.
    let carried = out.join("task.toml");
    let text = read(&carried);
    std::fs::write(
        &carried,
        text.replace("validation_mean_mm", "validation_rms_mm"),
    )
    .unwrap();
    let o = record(&out, &dir.join("toml.sqlite"), &given);
    refused_naming_both_hashes(&o, &stated);
    std::fs::write(&carried, &text).unwrap();
    assert!(record(&out, &dir.join("again.sqlite"), &given)
        .status
        .success());
}

/// `record` of the entry `out` of `task` with its `task.json` edited by `edit`: it must be
/// refused and write no database; the file is restored; the refusal.
fn refused_edit(out: &Path, task: &Path, edit: impl Fn(&mut serde_json::Value)) -> String {
    let json = out.join("task.json");
    let written = read(&json);
    let mut j: serde_json::Value = serde_json::from_str(&written).unwrap();
    edit(&mut j);
    std::fs::write(&json, serde_json::to_string_pretty(&j).unwrap() + "\n").unwrap();
    let db = out.with_extension("sqlite");
    let o = record(out, &db, &["--task", path_arg(task)]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(!o.status.success(), "recorded an edited task.json: {err}");
    assert!(!db.exists());
    std::fs::write(&json, written).unwrap();
    err
}

/// An edited figure is refused, naming the file, `value` and the figure the per-row errors
/// give, or without them the figure of `identified.json`; so are an edited `task` and `metric`; and `chosen_by` and `entrant`, in every `task.json` calbench wrote, are required:
/// a file without one is refused naming the file and the key, where it was recorded as
/// chosen by nothing, or as calbench's own entry.
#[test]
fn an_edited_figure_or_a_missing_key_is_refused_naming_file_and_key() {
    let dir = tmp_dir("record-task-figure");
    let task = small_task(&dir);
    let out = dir.join("entry");
    run_entry(&task, &out);
    let value = load_json(&out.join("task.json"))["value"].as_f64().unwrap();
    // Within its own interval, which the interval check cannot tell.
    let err = refused_edit(&out, &task, |j| {
        j["value"] = serde_json::json!(value + 0.001)
    });
    assert!(
        err.contains("entry/task.json: value:")
            && err.contains(&format!("{}", value + 0.001))
            && err.contains(&format!("{value}"))
            && err.contains("validation_errors_mm"),
        "{err}"
    );
    // With its per-row errors removed too (a file of before they were recorded), the figure
    // is still the validation mean of the identified.json beside it.
    let err = refused_edit(&out, &task, |j| {
        j["value"] = serde_json::json!(value + 0.001);
        j["validation_errors_mm"] = serde_json::json!([]);
    });
    assert!(
        err.contains("entry/task.json: value: states the figure")
            && err.contains("entry/identified.json beside it gives the validation mean")
            && err.contains(&format!("{value}")),
        "{err}"
    );
    // Rows dropped from the per-row errors (its figure recomputed from those left would be
    // stated as they give): one error for each of the task's 20 validation rows.
    let err = refused_edit(&out, &task, |j| {
        j["validation_errors_mm"]
            .as_array_mut()
            .unwrap()
            .truncate(17);
    });
    assert!(
        err.contains("entry/task.json: line ")
            && err.contains(
                "validation_errors_mm: holds 17 errors, but the task validates on 20 rows"
            ),
        "{err}"
    );
    // Without the task file it carries, an entry is checked against the one `--task`
    // gives, where its hash and published figures had not been checked at all.
    let carried = out.join("task.toml");
    let kept = read(&carried);
    std::fs::remove_file(&carried).unwrap();
    let err = refused_edit(&out, &task, |j| j["task_hash"] = "0".repeat(64).into());
    assert!(err.contains("entry/task.json: task_hash: is 0000"), "{err}");
    let err = refused_edit(&out, &task, |j| {
        j["published"][0]["value"] = serde_json::json!(0.1)
    });
    assert!(
        err.contains("entry/task.json: line ") && err.contains("published[0]"),
        "{err}"
    );
    std::fs::write(&carried, kept).unwrap();
    // An entry filed under another task or metric: the task is the given file's name, the
    // metric the task file's, where both were recorded as edited.
    let err = refused_edit(&out, &task, |j| {
        j["task"] = serde_json::json!("barrett-wam")
    });
    assert!(
        err.contains("entry/task.json: task: is \"barrett-wam\"") && err.contains("small.toml"),
        "{err}"
    );
    let err = refused_edit(&out, &task, |j| {
        j["metric"] = serde_json::json!("socket_spread_mm")
    });
    assert!(
        err.contains("entry/task.json: metric: is socket_spread_mm")
            && err.contains("ranks by validation_mean_mm"),
        "{err}"
    );
    for key in ["chosen_by", "entrant"] {
        let err = refused_edit(&out, &task, |j| {
            j.as_object_mut().unwrap().remove(key);
        });
        assert!(err.contains(&format!("entry/task.json: {key}: ")), "{err}");
    }
    let o = record(
        &out,
        &dir.join("calbench.sqlite"),
        &["--task", path_arg(&task)],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// An entry whose model was chosen by cross-validation (`--models kinematic,harmonics`) and
/// whose `task.json` then states another model, or a given one, or another method, is refused
/// by what `identified.json` beside it chose: it would rank as a model it did not identify
/// (a kinematic one, in the closed division).
#[test]
fn an_entry_stating_another_model_than_it_identified_is_refused() {
    let dir = tmp_dir("record-task-choice");
    let task = small_task(&dir);
    let out = dir.join("entry");
    calbench_ok(&[
        "task",
        path_arg(&task),
        "--method",
        "lm",
        "--models",
        "kinematic,harmonics",
        "--out",
        path_arg(&out),
    ]);
    let chosen = load_json(&out.join("identified.json"))["cv_best"]
        .as_str()
        .unwrap()
        .to_string();
    let other = if chosen == "kinematic" {
        "harmonics"
    } else {
        "kinematic"
    };
    let err = refused_edit(&out, &task, |j| {
        j["models"] = serde_json::json!(other.split('+').collect::<Vec<_>>());
        j["division"] = serde_json::json!(if other == "kinematic" {
            "closed"
        } else {
            "open"
        });
    });
    assert!(
        err.contains("entry/task.json: models: are")
            && err.contains(&format!("identified `{chosen}` (cv_best)")),
        "{err}"
    );
    let err = refused_edit(&out, &task, |j| j["chosen_by"] = serde_json::json!("given"));
    assert!(
        err.contains("entry/task.json: chosen_by: is \"given\""),
        "{err}"
    );
    let err = refused_edit(&out, &task, |j| j["method"] = serde_json::json!("ls"));
    assert!(err.contains("entry/task.json: method: is \"ls\""), "{err}");
    let o = record(
        &out,
        &dir.join("calbench.sqlite"),
        &["--task", path_arg(&task)],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// An entry whose `task.json` names another task than it ran is refused, naming `task`: the
/// hash it states is that of the task file it carries, not of the task file of the name it
/// gives (`tasks/<task>.toml` under the current folder, as a user records it), so it would
/// rank on a board of a task it did not run. `leaderboard --verify` refuses such a row of a
/// database: one task's hash under two names, or a row whose task is not its `task.json`'s.
#[test]
fn an_entry_filed_under_another_task_is_refused_and_verify_refuses_such_a_row() {
    let dir = tmp_dir("record-task-other");
    let task = small_task(&dir);
    let other = dir.join("tasks/other.toml");
    std::fs::write(&other, read(&task).replace("A small task", "Another task")).unwrap();
    let out = dir.join("entry");
    run_entry(&task, &out);
    let json = out.join("task.json");
    let written = read(&json);
    let renamed = written.replace("\"task\": \"small\"", "\"task\": \"other\"");
    assert_ne!(renamed, written);
    std::fs::write(&json, &renamed).unwrap();
    let db = dir.join("other.sqlite");
    let o = crate::common::bin()
        .current_dir(&dir)
        .args(["record", path_arg(&out), "--db", path_arg(&db)])
        .output()
        .unwrap();
    crate::common::refused(
        &o,
        &[
            "entry/task.json: task: is \"other\", but the task file of that name, \
             tasks/other.toml, is not the task file the entry ran",
            "entry/task.toml",
        ],
    );
    assert!(!db.exists());
    std::fs::write(&json, &written).unwrap();
    // A database holding the entry twice, the second row filed under the other name.
    let db = dir.join("calbench.sqlite");
    for label in ["v1", "v2"] {
        let given = ["--task", path_arg(&task), "--label", label];
        assert!(record(&out, &db, &given).status.success());
    }
    let verify = || calbench(&["leaderboard", "--db", path_arg(&db), "--verify"]);
    assert!(verify().status.success());
    let c = rusqlite::Connection::open(&db).unwrap();
    c.execute("UPDATE tasks SET task = 'other' WHERE run = 2", [])
        .unwrap();
    crate::common::refused(
        &verify(),
        &[
            "entry/task.json: task: the entry recorded as run 2 is ranked as task `other`",
            "but its task.json names `small`",
        ],
    );
    let sql = "UPDATE runs SET document = replace(document, '\"task\": \"small\"', \
               '\"task\": \"other\"') WHERE id = 2";
    c.execute(sql, []).unwrap();
    crate::common::refused(
        &verify(),
        &[
            "entry/task.json: task: the entry recorded as run 2 is of task `other`",
            "is that of task `small` (recorded as run 1)",
        ],
    );
}

/// An entry of one model beyond the kinematic one (`--models beta`, as docs/results.md's loop
/// runs them) is recorded and verified: its identification cross-validates that one model,
/// which chooses nothing, and its task.json says the model was given. `record` had refused
/// every such entry, as if the identification had chosen its model.
#[test]
fn an_entry_of_one_given_model_is_recorded() {
    let dir = tmp_dir("record-task-one-model");
    let task = small_task(&dir);
    let out = dir.join("entry");
    let args = [
        "--method",
        "lm",
        "--models",
        "beta",
        "--out",
        path_arg(&out),
    ];
    calbench_ok(&[&["task", path_arg(&task)][..], &args].concat());
    assert_eq!(load_json(&out.join("task.json"))["chosen_by"], "given");
    let identified = load_json(&out.join("identified.json"));
    assert_eq!(identified["cv_models"].as_array().map(Vec::len), Some(1));
    let db = dir.join("calbench.sqlite");
    let o = record(&out, &db, &["--task", path_arg(&task)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    calbench_ok(&["leaderboard", "--db", path_arg(&db), "--verify"]);
}

/// The `identified.json` beside a task entry is held to what an identification writes, as
/// an identify folder's is (docs/formats.md § 2.15): only its validation mean had been
/// compared, and a rank above the unknowns or an error of no identified parameter was stored.
#[test]
fn the_identified_json_beside_an_entry_is_checked_as_an_identify_folders() {
    let dir = tmp_dir("record-task-identified");
    let task = small_task(&dir);
    let out = dir.join("entry");
    run_entry(&task, &out);
    let file = out.join("identified.json");
    let written = read(&file);
    let j: serde_json::Value = serde_json::from_str(&written).unwrap();
    let mut rank = j.clone();
    rank["rank"] = 999.into();
    let mut extra = j.clone();
    extra["errors"]["zz9"] = serde_json::json!(0.0);
    let db = dir.join("calbench.sqlite");
    for (edited, want) in [
        (rank, "rank: is 999, above the "),
        (extra, "errors.zz9: is not one of the"),
    ] {
        std::fs::write(&file, serde_json::to_string_pretty(&edited).unwrap() + "\n").unwrap();
        let o = record(&out, &db, &["--task", path_arg(&task)]);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(
            !o.status.success(),
            "recorded an edited identified.json: {err}"
        );
        assert!(
            err.contains("entry/identified.json: line ") && err.contains(want),
            "{want}: {err}"
        );
        assert!(!db.exists(), "{want}: stored");
    }
    std::fs::write(&file, &written).unwrap();
    let o = record(&out, &db, &["--task", path_arg(&task)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `leaderboard --verify` finds again every value the board shows of an entry: its division,
/// models and method in `tasks` and the published figures it stands against. An edit of
/// those had passed it, and the board ranked the edited rows.
#[test]
fn verify_refuses_a_database_whose_ranked_rows_were_edited() {
    let dir = tmp_dir("record-task-verify-rows");
    let task = small_task(&dir);
    let out = dir.join("entry");
    run_entry(&task, &out);
    let db = dir.join("calbench.sqlite");
    assert!(record(&out, &db, &["--task", path_arg(&task)])
        .status
        .success());
    let verify = |db: &Path| calbench(&["leaderboard", "--db", path_arg(db), "--verify"]);
    assert!(verify(&db).status.success());
    let edits = [
        (
            "UPDATE tasks SET division = 'open'",
            "division: the entry recorded as run 1 is ranked with division \"open\", but its \
             task.json says \"closed\"",
        ),
        (
            "UPDATE tasks SET models = 'kinematic+beta'",
            "models: the entry recorded as run 1 is ranked with models \"kinematic+beta\"",
        ),
        (
            "UPDATE tasks SET method = 'ls'",
            "method: the entry recorded as run 1 is ranked with method \"ls\"",
        ),
        (
            "UPDATE published SET value = 9.0",
            "published[0].value: the entry recorded as run 1 is ranked with published[0].value \
             9 mm, but its task.json says 2.92 mm: the database was edited",
        ),
        (
            "UPDATE published SET division = 'closed'",
            "published[0].division:",
        ),
        (
            "DELETE FROM published",
            "published[0]: the entry recorded as run 1 is ranked with published[0] none",
        ),
    ];
    for (i, (sql, says)) in edits.iter().enumerate() {
        let edited = dir.join(format!("edited-{i}.sqlite"));
        std::fs::copy(&db, &edited).unwrap();
        let c = rusqlite::Connection::open(&edited).unwrap();
        assert_eq!(c.execute(sql, []).unwrap(), 1, "{sql}");
        drop(c);
        crate::common::refused(&verify(&edited), &["entry/task.json: ", says]);
    }
}

/// A `task.json` edit `calbench task` cannot write is refused naming `task.json` and the key:
/// a calbench kinematic entry in the open division, no model, a choice by cross-validation
/// of one candidate, no candidates, what fixed them of another name, an entrant that is
/// neither calbench nor a Python method, and a Python entrant whose identification beside it
/// is calbench's own method.
#[test]
fn a_task_json_calbench_cannot_write_is_refused_naming_the_key() {
    let dir = tmp_dir("record-task-written");
    let task = small_task(&dir);
    let out = dir.join("entry");
    run_entry(&task, &out);
    let edits: [(&str, serde_json::Value, &str); 12] = [
        (
            "division",
            "open".into(),
            "division: \"open\" is for a model beyond the kinematic one",
        ),
        ("models", serde_json::json!([]), "models: are []"),
        (
            "chosen_by",
            "cv".into(),
            "chosen_by: is \"cv\", but the entry considered 1 candidate model",
        ),
        ("candidates", serde_json::json!([]), "candidates: is empty"),
        (
            "candidates_fixed_by",
            "bogus".into(),
            "candidates_fixed_by: is \"bogus\"",
        ),
        (
            "candidates_fixed_by",
            "task".into(),
            "candidates_fixed_by: is \"task\", but the task file the entry ran",
        ),
        (
            "calbench_version",
            "banana".into(),
            "calbench_version: is \"banana\", which is no version",
        ),
        (
            "calbench_version",
            "9.9".into(),
            "calbench_version: is \"9.9\", which is no version",
        ),
        (
            "calbench_version",
            "01.2.3".into(),
            "calbench_version: is \"01.2.3\", which is no version",
        ),
        (
            "git_commit",
            "deadbeef".into(),
            "git_commit: is \"deadbeef\", which is no commit",
        ),
        (
            "entrant",
            "someone".into(),
            "entrant: is \"someone\": an entry is calbench's",
        ),
        (
            "entrant",
            "python:foo".into(),
            "entrant: is \"python:foo\", a Python method's entry, but",
        ),
    ];
    for (key, to, want) in edits {
        let err = refused_edit(&out, &task, |j| j[key] = to.clone());
        assert!(
            err.contains("entry/task.json: ") && err.contains(want),
            "{err}"
        );
    }
    let err = refused_edit(&out, &task, |j| j["entrant"] = "python:foo".into());
    assert!(
        err.contains("identified by calbench's method \"lm\""),
        "{err}"
    );
    // A task whose [models] fixes the candidates: its entry run without the command's models
    // is fixed by "task", never by "default", and by the task's candidates alone.
    let fixed = dir.join("tasks/fixed.toml");
    let text = read(&task) + "\n[models]\ncandidates = [\"kinematic\"]\n";
    std::fs::write(&fixed, text).unwrap();
    let out = dir.join("fixed-entry");
    calbench_ok(&[
        "task",
        path_arg(&fixed),
        "--method",
        "lm",
        "--out",
        path_arg(&out),
    ]);
    assert_eq!(
        load_json(&out.join("task.json"))["candidates_fixed_by"],
        "task"
    );
    assert!(record(
        &out,
        &dir.join("fixed.sqlite"),
        &["--task", path_arg(&fixed)]
    )
    .status
    .success());
    let err = refused_edit(&out, &fixed, |j| {
        j["candidates_fixed_by"] = "default".into()
    });
    assert!(
        err.contains("candidates_fixed_by: is \"default\", but the task file the entry ran"),
        "{err}"
    );
}

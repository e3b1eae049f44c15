//! `calbench task` on the MUKCa socket tasks (docs/formats.md § 9.4), run as a user runs them
//! from the repository's folder: calbench's figures printed beside the authors', `task.json`'s
//! figure the RMS of its per-row distances, the authors' calibrated model scored by calbench
//! reproducing their own `kpis.yaml`, the task's hash over every file it fixes, and socket
//! task files that do not fit refused by key.

use std::path::Path;

use crate::common::{bin, calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir};

/// `calbench task TASK --method ls --out OUT`, refused: exit status 1 and nothing written at
/// `out`. Returns its stderr.
fn refused_task(task: &Path, out: &Path) -> String {
    let r = calbench(&[
        "task",
        path_arg(task),
        "--method",
        "ls",
        "--out",
        path_arg(out),
    ]);
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(!out.exists(), "{err}");
    err
}

/// The MUKCa tasks, and whether each has the authors' calibrated model and their kpis.yaml.
const TASKS: [(&str, bool, bool); 6] = [
    ("mukca-panda-2", true, false),
    ("mukca-panda-3", true, false),
    ("mukca-panda-4", true, false),
    ("mukca-panda-6", true, true),
    ("mukca-panda-7", true, true),
    ("mukca-iiwa14", false, false),
];

/// `calbench task NAME --method … --out OUT` from the repository's folder, with `method`'s
/// words: its exit status, stdout and stderr.
fn task_with(name: &str, method: &[&str], out: &Path) -> std::process::Output {
    bin()
        .current_dir(root())
        .args(["task", name, "--method"])
        .args(method)
        .args(["--out", path_arg(out)])
        .output()
        .unwrap()
}

/// The method of each task as docs/results.md runs it: `ls`, and on Panda 7 `lm` with
/// adaptive damping, where `ls` is refused ([`LS_ON_PANDA_7`]).
fn method_of(name: &str) -> &'static [&'static str] {
    match name {
        "mukca-panda-7" => &["lm", "--set", "adaptive=true"],
        _ => &["ls"],
    }
}

/// What `ls` is refused with on Panda 7 (docs/results.md): Gauss–Newton from the nominal
/// robot overshoots to the mirror image of DH frame 6, which the plausibility bounds refuse.
const LS_ON_PANDA_7: [&str; 4] = [
    "cannot be physically right",
    "theta6 moved by 3.1",
    "alpha6 moved by 3.1",
    "a6 moved by -179",
];

/// `calbench task NAME` by [`method_of`] from the repository's folder: its stdout.
fn run_task(name: &str, out: &Path) -> String {
    let o = task_with(name, method_of(name), out);
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

/// `spread / distance error` as the table prints it.
fn cell(f: &serde_json::Value) -> String {
    format!(
        "{:.3} / {:.3}",
        f["spread_mm"].as_f64().unwrap(),
        f["distance_error_mm"].as_f64().unwrap()
    )
}

/// The table's row starting with `label`, and it holds `cells`.
fn printed(stdout: &str, label: &str, cells: &[String]) {
    let row = stdout
        .lines()
        .find(|l| l.trim_start().starts_with(label))
        .unwrap_or_else(|| panic!("no row \"{label}\":\n{stdout}"));
    for c in cells {
        assert!(row.contains(c.as_str()), "{row}: no {c}\n{stdout}");
    }
}

#[test]
fn every_mukca_task_prints_calbench_beside_the_authors() {
    let dir = tmp_dir("cli-socket-tasks");
    for (name, model, kpis) in TASKS {
        let out = dir.join(name);
        let stdout = run_task(name, &out);
        let j = load_json(&out.join("task.json"));
        assert_eq!(j["task"], name);
        assert_eq!(j["metric"], "socket_spread_mm");
        assert_eq!(j["division"], "closed");
        // The figure: the RMS distance of each validation tool point from its socket's mean.
        let rows: Vec<f64> = j["validation_errors_mm"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let rms = (rows.iter().map(|e| e * e).sum::<f64>() / rows.len() as f64).sqrt();
        let value = j["value"].as_f64().unwrap();
        assert!((value - rms).abs() < 1e-12, "{name}: {value} {rms}");
        let s = &j["socket"];
        let pooled = s["calbench"]["validation"]["spread_mm"].as_f64().unwrap();
        assert!((pooled - value).abs() < 1e-12, "{name}: {pooled} {value}");
        // Calibrated far better than the nominal model, on the placement no fit saw.
        let nominal = s["nominal"]["validation"]["spread_mm"].as_f64().unwrap();
        assert!(value < nominal / 2.0, "{name}: {value} against {nominal}");
        assert!(
            stdout.contains(&format!("socket_spread_mm = {value:.3} mm")),
            "{stdout}"
        );
        let both = |p: &serde_json::Value| [cell(&p["calibration"]), cell(&p["validation"])];
        printed(&stdout, "nominal", &both(&s["nominal"]));
        let label = format!("calbench ({})", method_of(name)[0]);
        printed(&stdout, &label, &both(&s["calbench"]));
        assert_eq!(model, !s["authors_model"].is_null(), "{name}");
        if model {
            printed(
                &stdout,
                "the authors' calibrated model",
                &both(&s["authors_model"]),
            );
        }
        assert_eq!(kpis, !s["authors_kpis"].is_null(), "{name}");
        if kpis {
            printed(
                &stdout,
                "the authors' kpis.yaml",
                &[cell(&s["authors_kpis"])],
            );
            // calbench's reading of the authors' calibrated model is their own: per socket
            // their spreads (kpis.yaml's variances are rounded to two or three digits) and
            // their distance error.
            let (a, k) = (&s["authors_model"]["calibration"], &s["authors_kpis"]);
            for i in 0..2 {
                let (x, y) = (
                    a["spread_per_socket_mm"][i].as_f64().unwrap(),
                    k["spread_per_socket_mm"][i].as_f64().unwrap(),
                );
                assert!((x - y).abs() < 0.01 * y, "{name} socket {i}: {x} {y}");
            }
            let (x, y) = (
                a["distance_error_mm"].as_f64().unwrap(),
                k["distance_error_mm"].as_f64().unwrap(),
            );
            assert!((x - y).abs() < 5e-4, "{name}: {x} {y}");
        }
        assert_eq!(
            read(&out.join("task.toml")),
            read(&root().join(format!("tasks/{name}.toml")))
        );
    }
    // `ls` on Panda 7, refused as docs/results.md says, writing nothing.
    let ls = dir.join("panda-7-ls");
    let o = task_with("mukca-panda-7", &["ls"], &ls);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    for w in LS_ON_PANDA_7 {
        assert!(err.contains(w), "{w}: {err}");
    }
    assert!(!ls.exists());
    // Its first step: the calibration residual from 10 mm to 508 mm.
    let o = task_with("mukca-panda-7", &["ls", "--set", "max_iter=1"], &ls);
    let err = String::from_utf8_lossy(&o.stderr);
    let first = "RMS residual on the calibration readings is 507.7";
    assert!(err.contains(first) && err.contains("against 10.1"), "{err}");
    // Each entry recorded, and its figure computed again from its per-row distances.
    let db = dir.join("results.sqlite");
    let mut args = vec!["record", "--db", path_arg(&db)];
    let outs: Vec<_> = TASKS.iter().map(|(n, _, _)| dir.join(n)).collect();
    args.extend(outs.iter().map(|o| path_arg(o)));
    calbench_ok(&args);
    let v = calbench_ok(&["leaderboard", "--db", path_arg(&db), "--verify"]);
    let said = String::from_utf8_lossy(&v.stdout) + String::from_utf8_lossy(&v.stderr);
    assert!(said.contains("6 task entries verified"), "{said}");
    // A socket task's folder whose task file differs from the one its entry ran is refused,
    // naming both hashes.
    let toml = outs[0].join("task.toml");
    let text = read(&toml);
    std::fs::write(&toml, text.replacen("title = \"", "title = \"edited ", 1)).unwrap();
    let db2 = dir.join("edited.sqlite");
    let o = calbench(&["record", "--db", path_arg(&db2), path_arg(&outs[0])]);
    let err = String::from_utf8_lossy(&o.stderr);
    let stated = serde_json::from_str::<serde_json::Value>(&read(&outs[0].join("task.json")))
        .unwrap()["task_hash"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(!o.status.success(), "an edited socket task was recorded");
    assert!(err.contains("task_hash") && err.contains(&stated), "{err}");
}

/// A copy of Panda 6's task with absolute paths, its joint files in `dir`.
fn copied_task(dir: &Path, extra: &str, metric: &str, name: &str) -> std::path::PathBuf {
    let data = root().join("data/mukca");
    for place in ["front", "right"] {
        for h in ["hole_0.csv", "hole_1.csv"] {
            let to = dir.join(place);
            std::fs::create_dir_all(&to).unwrap();
            std::fs::copy(data.join("panda_6").join(place).join(h), to.join(h)).unwrap();
        }
    }
    let d = dir.display();
    let text = format!(
        "title = \"Panda 6\"\nrobot = \"{}\"\ntip = \"ball_link\"\nmetric = \"{metric}\"\n\
         unpublished = \"none\"\nfix = [\"theta7\"]\n{extra}\n[sockets]\n\
         distances_mm = [0.0, 50.0]\n\
         calibration = [\"{d}/front/hole_0.csv\", \"{d}/front/hole_1.csv\"]\n\
         validation = [\"{d}/right/hole_0.csv\", \"{d}/right/hole_1.csv\"]\n",
        data.join("panda.urdf").display()
    );
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn the_hash_covers_every_joint_file_and_bad_socket_tasks_are_refused_by_key() {
    let dir = tmp_dir("cli-socket-task-hash");
    let task = copied_task(&dir, "", "socket_spread_mm", "socket-task");
    let hash = |out: &str| {
        let o = dir.join(out);
        let r = calbench(&[
            "task",
            path_arg(&task),
            "--method",
            "ls",
            "--out",
            path_arg(&o),
        ]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        load_json(&o.join("task.json"))["task_hash"]
            .as_str()
            .unwrap()
            .to_string()
    };
    let before = hash("a");
    // One digit of one validation row changed: another task.
    let f = dir.join("right/hole_1.csv");
    let text = read(&f);
    let at = text.find('.').unwrap() + 3;
    let digit = if &text[at..=at] == "7" { "8" } else { "7" };
    std::fs::write(&f, format!("{}{digit}{}", &text[..at], &text[at + 1..])).unwrap();
    assert_ne!(hash("b"), before);
    let refused = |task: &Path, want: &[&str]| {
        let err = refused_task(task, &dir.join("refused"));
        for w in want {
            assert!(err.contains(w), "{err}: no {w}");
        }
    };
    let t = copied_task(&dir, "", "validation_rms_mm", "rms");
    refused(&t, &["rms.toml", "metric", "socket_spread_mm"]);
    // `--models` is refused as every setting is.
    let o = dir.join("models");
    let args = [
        "task",
        path_arg(&task),
        "--method",
        "ls",
        "--models",
        "gravity",
    ];
    let r = calbench(&[&args[..], &["--out", path_arg(&o)]].concat());
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.starts_with("error: setting `--models`: ") && !o.exists(),
        "{err}"
    );
    let t = copied_task(&dir, "tool = \"x\"\n", "socket_spread_mm", "tool");
    refused(&t, &["tool.toml", "line 7", "tool"]);
    // A parameter fixed twice is the task file's, where it was blamed on `--fix`.
    let t = dir.join("twice.toml");
    std::fs::write(
        &t,
        read(&task).replace("[\"theta7\"]", "[\"theta7\", \"theta7\"]"),
    )
    .unwrap();
    refused(
        &t,
        &[
            "twice.toml",
            "line 6, fix",
            "`theta7` is given twice (fix[0])",
        ],
    );
    // One joint file for both sockets is refused at its key, where it was identified as
    // readings that make the robot worse.
    let t = dir.join("one-file.toml");
    let d = dir.display();
    let one = format!("[\"{d}/front/hole_0.csv\", \"{d}/front/./hole_0.csv\"]");
    let text = read(&task).replace(
        &format!("[\"{d}/front/hole_0.csv\", \"{d}/front/hole_1.csv\"]"),
        &one,
    );
    std::fs::write(&t, text).unwrap();
    refused(
        &t,
        &[
            "one-file.toml",
            "sockets.calibration",
            "sockets.calibration[1]: ",
            "/front/./hole_0.csv` is given twice (sockets.calibration[0]): each socket has its own file",
        ],
    );
    let text = read(&task).replace("[0.0, 50.0]", "[0.0, 50.0, 70.0]");
    std::fs::write(&task, text).unwrap();
    refused(
        &task,
        &[
            "socket-task.toml",
            "sockets.calibration",
            "one file per socket",
        ],
    );
    // A tracker's task scored by the socket metric.
    let wam = read(&root().join("tasks/barrett-wam.toml"))
        .replace("validation_mean_mm", "socket_spread_mm")
        .replace("\"../", &format!("\"{}/", root().display()))
        .replace(
            "\"barrett-wam.mapping",
            &format!("\"{}/tasks/barrett-wam.mapping", root().display()),
        );
    let t = dir.join("wam.toml");
    std::fs::write(&t, wam).unwrap();
    refused(&t, &["wam.toml", "metric", "socket task"]);
}

/// A gross reading in the second socket's joint file is named by that file and its line: the
/// refusal names the placement's first file (the data), and the reading's line was read as a
/// line of that file, a comment line before its first and a blank one before it counted.
#[test]
fn a_gross_reading_is_named_by_its_own_joint_file() {
    let dir = tmp_dir("cli-socket-task-gross");
    let task = copied_task(&dir, "", "socket_spread_mm", "gross");
    let f = dir.join("front/hole_1.csv");
    let mut lines: Vec<String> = read(&f).lines().map(String::from).collect();
    let mut cells: Vec<&str> = lines[9].split(',').collect();
    cells[0] = "0";
    lines[9] = cells.join(",");
    lines.insert(9, String::new());
    lines.insert(0, "# the holds of the second socket".into());
    std::fs::write(&f, lines.join("\n") + "\n").unwrap();
    let err = refused_task(&task, &dir.join("out"));
    assert!(
        err.contains(&format!(
            "the reading of line 12 of {} has a residual",
            f.display()
        )),
        "{err}"
    );
}

/// A `tip` the URDF has no link of is refused naming the task file's line and key, not the
/// command line's `--tip`, which the entry was not given.
#[test]
fn a_tip_the_urdf_lacks_is_refused_naming_the_task_key() {
    let dir = tmp_dir("cli-socket-task-tip");
    let task = copied_task(&dir, "", "socket_spread_mm", "tip");
    std::fs::write(
        &task,
        read(&task).replace("tip = \"ball_link\"", "tip = \"ball\""),
    )
    .unwrap();
    let err = refused_task(&task, &dir.join("out"));
    assert!(
        err.contains("tip.toml: line 3, tip: no link \"ball\" in") && !err.contains("--tip"),
        "{err}"
    );
}

/// With a `tip`, a robot or an authors' model that is not a URDF (a robot file) is refused
/// naming the task file's line and key: it had been refused as the command line's `--base`
/// and `--tip`, which a task is not given, naming neither the file nor the key.
#[test]
fn a_tip_with_a_model_that_is_not_a_urdf_is_refused_naming_the_task_key() {
    let dir = tmp_dir("cli-socket-task-toml-model");
    let robot_file = root().join("robots/ban-irb2600.toml");
    let authors = format!(
        "\n[authors]\nmodel = \"{}\"\nsource = \"a test\"\n",
        robot_file.display()
    );
    let task = copied_task(&dir, "", "socket_spread_mm", "model");
    let text = read(&task) + &authors;
    std::fs::write(&task, &text).unwrap();
    let err = refused_task(&task, &dir.join("out"));
    let line = text.lines().position(|l| l.starts_with("model =")).unwrap() + 1;
    assert!(
        err.contains(&format!("model.toml: line {line}, authors.model: "))
            && err.contains("ban-irb2600.toml is not a URDF, and `tip` names a link of a URDF")
            && !err.contains("--tip"),
        "{err}"
    );
    // An [authors] of a source alone scores nothing, and is refused at its header.
    let task = copied_task(
        &dir,
        "\n[authors]\nsource = \"a test\"\n",
        "socket_spread_mm",
        "empty",
    );
    let err = refused_task(&task, &dir.join("out"));
    let line = read(&task).lines().position(|l| l == "[authors]").unwrap() + 1;
    assert!(
        err.contains(&format!(
            "empty.toml: line {line}, authors: names neither `model` nor `kpis`"
        )),
        "{err}"
    );
    let task = copied_task(&dir, "", "socket_spread_mm", "robot");
    let urdf = root().join("data/mukca/panda.urdf");
    let text = read(&task).replace(
        &urdf.display().to_string(),
        &robot_file.display().to_string(),
    );
    std::fs::write(&task, &text).unwrap();
    let err = refused_task(&task, &dir.join("out"));
    assert!(
        err.contains("robot.toml: line 2, robot: ") && err.contains("is not a URDF"),
        "{err}"
    );
}

/// A socket task without `tip` on a URDF of several leaf links is refused naming the task
/// file's `tip` and the leaves, not the command line's `--tip`, which a task is not given.
#[test]
fn a_task_without_a_tip_on_a_branched_urdf_is_refused_naming_the_task_key() {
    let dir = tmp_dir("cli-socket-task-no-tip");
    let task = copied_task(&dir, "", "socket_spread_mm", "notip");
    std::fs::write(&task, read(&task).replace("tip = \"ball_link\"\n", "")).unwrap();
    let err = refused_task(&task, &dir.join("out"));
    assert!(
        err.contains("notip.toml: tip: ")
            && err.contains("3 leaf links (ball_link, panda_leftfinger, panda_rightfinger)")
            && err.contains("tip = \"LINK\"")
            && !err.contains("--tip"),
        "{err}"
    );
}

/// A socket joint file (header-less: each line the robot's joint values) with a cell that is
/// not a number, or a line of too few values, is refused naming the file, its own line and
/// its own count, with nothing written.
#[test]
fn a_bad_line_of_a_joint_file_is_named_by_its_own_line() {
    let dir = tmp_dir("cli-socket-task-bad-line");
    let task = copied_task(&dir, "", "socket_spread_mm", "socket-task");
    let f = dir.join("front/hole_0.csv");
    let good = read(&f);
    let edited = |n: usize, edit: &dyn Fn(&str) -> String| {
        let lines: Vec<String> = good
            .lines()
            .enumerate()
            .map(|(i, l)| if i + 1 == n { edit(l) } else { l.to_string() })
            .collect();
        std::fs::write(&f, lines.join("\n") + "\n").unwrap();
    };
    let at = format!(
        "{}: line 3, column q4: \"abc\" is not a finite number",
        f.display()
    );
    edited(3, &|l| {
        let mut cells: Vec<&str> = l.split(',').collect();
        cells[3] = "abc";
        cells.join(",")
    });
    let err = refused_task(&task, &dir.join("out"));
    assert!(err.contains(&at) && err.lines().count() == 1, "{err}");
    let at = format!(
        "{}: line 5: 6 values, expected 7 (the robot's joints)",
        f.display()
    );
    edited(5, &|l| l.rsplit_once(',').unwrap().0.to_string());
    let err = refused_task(&task, &dir.join("out"));
    assert!(err.contains(&at) && err.lines().count() == 1, "{err}");
}

/// A joint file of too few distinct poses, or of none, is refused at its own lines (a joint
/// file has no header, so its first row is line 1) and an empty file is called empty, where
/// the lines were counted as under a header: "all 5 rows (lines 2 to 6)" of a file of five
/// lines, "the file has a header but no data rows" at line 0.
#[test]
fn a_joint_file_of_too_few_poses_is_named_by_its_own_lines() {
    let dir = tmp_dir("cli-socket-task-few-poses");
    let task = copied_task(&dir, "", "socket_spread_mm", "socket-task");
    let f = dir.join("front/hole_0.csv");
    let first = read(&f).lines().next().unwrap().to_string();
    let refused_with = |text: String, want: &str| {
        std::fs::write(&f, text).unwrap();
        let err = refused_task(&task, &dir.join("out"));
        let want = format!("{}: {want}", f.display());
        assert!(err.contains(&want) && err.lines().count() == 1, "{err}");
    };
    refused_with(
        format!("{first}\n").repeat(5),
        "line 1: all 5 rows (lines 1 to 5) are the same pose, the joint values of line 1:",
    );
    refused_with(
        format!("# one hold\n\n{first}\n"),
        "line 3: the file has one row (line 3), one pose:",
    );
    refused_with(
        String::new(),
        "line 1: empty file: expected rows of joint values q1,…,q7, one pose a line, no header",
    );
}

/// A parameter in the task file's `fix` that the robot's model lacks is refused naming the
/// task file, the line and `fix`, as a name given twice is; it was blamed on `identify`'s
/// `--fix`, an option the entry was not given.
#[test]
fn a_fixed_parameter_the_robot_lacks_is_refused_naming_the_task_key() {
    let dir = tmp_dir("cli-socket-task-fix");
    let task = copied_task(&dir, "", "socket_spread_mm", "theta9");
    std::fs::write(&task, read(&task).replace("\"theta7\"", "\"theta9\"")).unwrap();
    let err = refused_task(&task, &dir.join("out"));
    assert!(
        err.contains("theta9.toml: line 6, fix: `theta9` is not a parameter of robot `panda`")
            && !err.contains("--fix"),
        "{err}"
    );
}

/// Socket distances in metres (or inches) are refused at their key and line, the nominal
/// robot's own distance beside them; they had been identified and refused as a robot that
/// cannot be right, naming the first joint file.
#[test]
fn socket_distances_in_another_unit_are_refused_at_their_key() {
    let dir = tmp_dir("cli-socket-task-unit");
    for (name, given, way) in [
        ("metres", "0.05", "farther"),
        ("inches", "1.9685", "farther"),
    ] {
        let task = copied_task(&dir, "", "socket_spread_mm", name);
        let text = read(&task).replace("[0.0, 50.0]", &format!("[0.0, {given}]"));
        std::fs::write(&task, &text).unwrap();
        let line = text
            .lines()
            .position(|l| l.starts_with("distances_mm"))
            .unwrap()
            + 1;
        let err = refused_task(&task, &dir.join("out"));
        let want = format!(
            "{name}.toml: line {line}, sockets.distances_mm: socket 2 is {given} mm from socket 1, \
             where the nominal robot puts the tool points of its file "
        );
        assert!(
            err.contains(&want) && err.contains(&format!("times {way}):")),
            "{err}"
        );
        assert!(!err.contains("hole_0.csv"), "{err}");
    }
    // A hundred times the distance: nearer.
    let task = copied_task(&dir, "", "socket_spread_mm", "far");
    std::fs::write(&task, read(&task).replace("[0.0, 50.0]", "[0.0, 5000.0]")).unwrap();
    let err = refused_task(&task, &dir.join("out"));
    assert!(err.contains("times nearer): are these distances"), "{err}");
}

/// Socket 2's calibration file holding socket 1's poses is refused by its own name; it had
/// been refused at `sockets.distances_mm` as "inf times nearer", a unit.
#[test]
fn one_sockets_poses_given_twice_are_refused_by_the_second_file() {
    let dir = tmp_dir("cli-socket-task-twice");
    let task = copied_task(&dir, "", "socket_spread_mm", "twice");
    let (first, second) = (dir.join("front/hole_0.csv"), dir.join("front/hole_1.csv"));
    std::fs::copy(&first, &second).unwrap();
    let err = refused_task(&task, &dir.join("out"));
    let want = format!(
        "{}: every row: the nominal robot puts the tool points of this file's poses where it \
         puts those of socket 1's file {} (under 0.05 mm apart), where sockets.distances_mm \
         puts socket 2 50 mm from socket 1: do the two files hold the same socket's poses?",
        second.display(),
        first.display()
    );
    assert!(err.contains(&want), "{err}");
    assert!(!err.contains("inf"), "{err}");
}

/// The validation placement's files copies of the calibration placement's, under other
/// names: refused at `sockets.validation`, naming the rows; the validation figure had been
/// the calibration fit's (0.194 mm where Panda 6's right placement gives 0.306).
#[test]
fn a_validation_placement_that_repeats_the_calibration_rows_is_refused() {
    let dir = tmp_dir("cli-socket-task-copied");
    let task = copied_task(&dir, "", "socket_spread_mm", "copied");
    for h in ["hole_0.csv", "hole_1.csv"] {
        std::fs::copy(dir.join("front").join(h), dir.join("right").join(h)).unwrap();
    }
    let err = refused_task(&task, &dir.join("out"));
    assert!(
        err.contains("sockets.validation: ")
            && err.contains("validation row(s) repeat a calibration row (the same joint values;")
            && err.contains("each by its file's line): "),
        "{err}"
    );
    // Each row by its own file's line (headerless files: the first row is on line 1).
    let line = |place: &str, l: usize| {
        format!(
            "line {l} of {}",
            dir.join(place).join("hole_0.csv").display()
        )
    };
    assert!(
        err.contains(&format!("{} = {}", line("front", 1), line("right", 1))),
        "{err}"
    );
}

/// A row of socket 2's calibration file repeated at its end is refused, named by that file's
/// lines: a 0-based row had counted across the placement's files.
#[test]
fn a_placement_row_repeated_is_refused_by_its_files_line() {
    let dir = tmp_dir("cli-socket-task-repeated-row");
    let task = copied_task(&dir, "", "socket_spread_mm", "repeated");
    let file = dir.join("front/hole_1.csv");
    let text = read(&file);
    let lines: Vec<&str> = text.lines().collect();
    std::fs::write(&file, format!("{text}{}\n", lines[2])).unwrap();
    let err = refused_task(&task, &dir.join("out"));
    let want = format!(
        "1 row(s) repeat an earlier row (the same joint values and socket; each by its file's \
         line): line 3 of {0} = line {1} of {0}; a copy counts one reading twice",
        file.display(),
        lines.len() + 1
    );
    assert!(err.contains(&want), "{err}");
}

//! What a task fixes, checked the way a user meets it: `task_hash` covers the bytes of every
//! file the task names (docs/formats.md § 9.3), and a task whose validation rows repeat
//! calibration rows is refused naming the rows, whether the rows come from a split file or
//! from two files (§ 9.1).

use std::path::{Path, PathBuf};

use crate::common::{calbench, calbench_ok, load_json, read, root, tmp_dir};
use crate::malformed::line_of;
use crate::task::{task, task_lm};

/// The WAM task file rewritten into `dir` with absolute paths, its `[data]` table replaced by
/// `data` (the lines of the table, paths absolute).
fn wam_task(dir: &Path, data: &str) -> PathBuf {
    let text = std::fs::read_to_string(task("barrett-wam")).unwrap();
    let (head, rest) = text.split_once("[data]").unwrap();
    let published = &rest[rest.find("[[published]]").unwrap()..];
    let head = head
        .replace(
            "\"../examples/",
            &format!("\"{}/examples/", root().display()),
        )
        .replace(
            "\"barrett-wam.mapping.toml\"",
            &format!(
                "\"{}\"",
                root().join("tasks/barrett-wam.mapping.toml").display()
            ),
        );
    let p = dir.join("barrett-wam.toml");
    std::fs::write(&p, format!("{head}[data]\n{data}\n\n{published}")).unwrap();
    p
}

pub(crate) fn wam_file(name: &str) -> PathBuf {
    root().join("data/barrett-wam").join(name)
}

/// The WAM task of one data file `data` split by `split`, written into `dir`.
pub(crate) fn split_task(dir: &Path, data: &Path, split: &Path) -> PathBuf {
    let form = format!(
        "file = \"{}\"\nsplit = \"{}\"",
        data.display(),
        split.display()
    );
    wam_task(dir, &form)
}

/// The WAM grid file with a copy of its data row `row` (0-based) appended, as `dir/name`.
fn grid_with_copy(dir: &Path, name: &str, row: usize) -> PathBuf {
    let text = std::fs::read_to_string(wam_file(GRID)).unwrap();
    let copy = text.lines().nth(row + 1).unwrap();
    let data = dir.join(name);
    std::fs::write(&data, format!("{text}{copy}\n")).unwrap();
    data
}

/// Where task `t` refuses its rows: `barrett-wam.toml: line N, data: ` at the line of `key`.
fn at(t: &Path, key: &str) -> String {
    format!("barrett-wam.toml: line {}, data: ", line_of(&read(t), key))
}

pub(crate) const GRID: &str = "3D_WAM_uncalibrated_grid_cleaned.csv";
const RANDOM: &str = "3D_WAM_uncalibrated_random_cleaned.csv";

#[test]
fn changing_one_row_of_a_data_file_changes_the_task_hash() {
    let d = tmp_dir("cli-task-hash");
    let mut hashes = Vec::new();
    for (i, edit) in [false, true].into_iter().enumerate() {
        let sub = d.join(format!("t{i}"));
        std::fs::create_dir_all(&sub).unwrap();
        let mut text = std::fs::read_to_string(wam_file(RANDOM)).unwrap();
        if edit {
            // Row 3's x difference, its last digit changed: the same task file, other data.
            let line = text.lines().nth(4).unwrap().to_string();
            let cells: Vec<&str> = line.split(',').collect();
            let x = cells[4].to_string();
            let last = x.chars().last().unwrap();
            let changed = format!(
                "{}{}",
                &x[..x.len() - 1],
                if last == '1' { '2' } else { '1' }
            );
            let edited = line.replacen(&x, &changed, 1);
            assert_ne!(edited, line);
            text = text.replacen(&line, &edited, 1);
        }
        let val = sub.join(RANDOM);
        std::fs::write(&val, text).unwrap();
        let t = wam_task(
            &sub,
            &format!(
                "calibration = \"{}\"\nvalidation = \"{}\"",
                wam_file(GRID).display(),
                val.display()
            ),
        );
        let out = sub.join("out");
        task_lm(calbench_ok, &t, Some("kinematic"), &out);
        hashes.push(load_json(&out.join("task.json"))["task_hash"].clone());
    }
    assert_ne!(hashes[0], hashes[1], "one data row changed, the same hash");
}

#[test]
fn validation_rows_that_repeat_calibration_rows_are_refused_naming_them() {
    let d = tmp_dir("cli-task-overlap");
    // Two files: the committed WAM task with its grid file as validation too.
    let t = wam_task(
        &d,
        &format!(
            "calibration = \"{}\"\nvalidation = \"{}\"",
            wam_file(GRID).display(),
            wam_file(GRID).display()
        ),
    );
    let o = task_lm(calbench, &t, Some("kinematic"), &d.join("out"));
    assert!(
        !o.status.success(),
        "a validation file equal to the calibration file ran"
    );
    assert!(!d.join("out").exists(), "nothing is written");
    let e = String::from_utf8_lossy(&o.stderr);
    // At the line of the key that gives the validation rows.
    assert!(
        e.contains(&at(&t, "validation = "))
            && e.contains("216 validation row(s) repeat a calibration row")
            && e.contains("calibration row 0 = validation row 0")
            && e.contains("and 211 more"),
        "{e}"
    );
    // A split of one file whose last row repeats row 5: distinct indices, the same row.
    let data = grid_with_copy(&d, "grid-plus.csv", 5);
    let split = d.join("grid-plus.split");
    std::fs::write(&split, "rows 217\ncalibration 0-215\nvalidation 216\n").unwrap();
    let t = split_task(&d, &data, &split);
    let o = task_lm(calbench, &t, Some("kinematic"), &d.join("out"));
    assert!(!o.status.success(), "a repeated row across the split ran");
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains(&at(&t, "split = "))
            && e.contains("1 validation row(s) repeat a calibration row")
            && e.contains("calibration row 5 = validation row 216"),
        "{e}"
    );
    // The repeat among the calibration rows is named by the data file's rows, where it had
    // been named by its place among the calibration rows (`row 0 = row 201`).
    std::fs::write(
        &split,
        "rows 217\nvalidation 0-4\ncalibration 5-199\nvalidation 200-215\ncalibration 216\n",
    )
    .unwrap();
    let o = task_lm(calbench, &t, Some("kinematic"), &d.join("out"));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && e.contains("1 row(s) repeat an earlier row")
            && e.contains("0-based rows): row 5 = row 216;"),
        "{e}"
    );
    // Without the repeat the same split file form runs.
    std::fs::copy(wam_file(GRID), &data).unwrap();
    std::fs::write(&split, "rows 216\ncalibration 0-199\nvalidation 200-215\n").unwrap();
    task_lm(calbench_ok, &t, Some("kinematic"), &d.join("ok"));
}

/// A refusal of a task's rows read through its mapping names the data file and the mapping
/// (docs/formats.md § 9.1), never a temporary file: a WAM grid pose whose joint 1 lies far
/// outside its limits, named by the export's column and its value as the export writes it
/// (it had been named `column q1`, the measurement CSV's, which the user never sees).
#[test]
fn a_refusal_of_mapped_rows_names_the_data_file_and_its_mapping() {
    let d = tmp_dir("cli-task-mapped-refusal");
    let text = std::fs::read_to_string(wam_file(GRID)).unwrap();
    let line = text.lines().nth(3).unwrap();
    let cells: Vec<&str> = line.split(',').collect();
    let far = line.replacen(cells[7], "9000", 1);
    let grid = d.join(GRID);
    std::fs::write(&grid, text.replacen(line, &far, 1)).unwrap();
    let t = wam_task(
        &d,
        &format!(
            "calibration = \"{}\"\nvalidation = \"{}\"",
            grid.display(),
            wam_file(RANDOM).display()
        ),
    );
    let o = task_lm(calbench, &t, Some("kinematic"), &d.join("out"));
    assert!(!o.status.success(), "a pose outside the limits ran");
    assert!(!d.join("out").exists(), "nothing is written");
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains(&format!("{} as mapped by", grid.display()))
            && e.contains("barrett-wam.mapping.toml: line 4, column joint_1: 9000 is outside")
            && !e.contains("written")
            && !e.contains("calbench-task-"),
        "{e}"
    );
    // An export in radians mapped to the robot's degrees: the refusal shows both.
    let ipa = root().join("data/ipa-ur10-series-a/measurements_grid.csv");
    let text = std::fs::read_to_string(ipa).unwrap();
    let line = text.lines().nth(3).unwrap();
    let cells: Vec<&str> = line.split(';').collect();
    let far = [&cells[..7], &["-446,788"], &cells[8..]].concat().join(";");
    let data = d.join("grid.csv");
    std::fs::write(&data, text.replacen(line, &far, 1)).unwrap();
    let t = d.join("ipa.toml");
    let tasks = root().join("tasks");
    let task = std::fs::read_to_string(tasks.join("ipa-ur10-series-a.toml"))
        .unwrap()
        .replace(
            "../examples",
            &root().join("examples").display().to_string(),
        )
        .replace("\"ipa-ur10", &format!("\"{}/ipa-ur10", tasks.display()))
        .replace(
            "../data/ipa-ur10-series-a/measurements_grid.csv",
            &data.display().to_string(),
        );
    std::fs::write(&t, task).unwrap();
    let o = task_lm(calbench, &t, None, &d.join("ipa-out"));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains(
            "ipa-ur10.mapping.toml: line 4, column shoulder_pan_joint: -25599.0667371 is \
             outside the joint limits [-360, 360] (written \"-446,788\" rad)"
        ),
        "{e}"
    );
}

/// A task whose mapping swaps two position columns (a mirror image of the robot) is refused as
/// physically implausible, the refusal naming the way past it as `identify`'s option (`task`
/// takes none), with its one model and with the task's candidate models alike. One that
/// reads millimetres as metres is refused before any identification, at its data: its
/// validation points in another unit score no robot (they had gone on to the identification,
/// which `--allow-implausible` would have kept).
#[test]
fn an_implausible_entry_names_the_option_as_identify_s() {
    let d = tmp_dir("cli-task-implausible");
    let mapping = std::fs::read_to_string(root().join("tasks/barrett-wam.mapping.toml")).unwrap();
    let data = format!(
        "calibration = \"{}\"\nvalidation = \"{}\"",
        wam_file(GRID).display(),
        wam_file(RANDOM).display()
    );
    let file = wam_task(&d, &data);
    let text = std::fs::read_to_string(&file).unwrap().replace(
        &root()
            .join("tasks/barrett-wam.mapping.toml")
            .display()
            .to_string(),
        &d.join("edited.mapping.toml").display().to_string(),
    );
    std::fs::write(&file, text).unwrap();
    let out = d.join("out");
    // `task FILE --method lm` with `models` (the task's candidates when empty) and the mapping
    // edited by `edit`: its stderr, after an exit status of 1 with no output folder.
    let refusal = |edit: &dyn Fn(&str) -> String, models: &[&str]| {
        std::fs::write(d.join("edited.mapping.toml"), edit(&mapping)).unwrap();
        let mut args = vec!["task", file.to_str().unwrap(), "--method", "lm"];
        args.extend(models);
        args.extend(["--out", out.to_str().unwrap()]);
        let o = calbench(&args);
        let msg = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(1), "{msg}");
        assert!(!out.exists());
        msg
    };
    let mirror = |m: &str| {
        m.replace("[\"x_t\", \"y_t\"", "[\"y_t\", \"x_t\"")
            .replace("[\"x_dif\", \"y_dif\"", "[\"y_dif\", \"x_dif\"")
    };
    assert_ne!(mirror(&mapping), mapping);
    for models in [&["--models", "kinematic"][..], &[]] {
        let msg = refusal(&mirror, models);
        assert!(
            msg.contains("cannot be physically right")
                && msg.contains("the points are a mirror image of the robot's")
                && msg.contains("or pass identify's --allow-implausible to write it"),
            "{models:?}: {msg}"
        );
    }
    // Joint values written in rad for a robot in degrees: refused at the mapping's key,
    // before any row is read as degrees.
    let rad = |m: &str| m.replacen("unit = \"deg\"", "unit = \"deg\"\nwrite_unit = \"rad\"", 1);
    let msg = refusal(&rad, &["--models", "kinematic"]);
    assert!(
        msg.contains(
            "edited.mapping.toml: line 6, joints.write_unit: writes the joint values in rad, \
             and robot \"barrett-wam\" takes its joint angles in deg"
        ),
        "{msg}"
    );
    let metres = |m: &str| m.replace("unit = \"mm\"", "unit = \"m\"");
    let msg = refusal(&metres, &["--models", "kinematic"]);
    let line = line_of(&read(&file), "validation = ");
    assert!(
        msg.contains(&format!(
            "barrett-wam.toml: line {line}, data: the validation points"
        )) && msg.contains(
            "they are likely in micrometres, not millimetres; so do the \
                 calibration points"
        ),
        "{msg}"
    );
}

/// A validation file of the two-file form in metres, or measured from another placement (the
/// rows turned by 90° about z and moved by a metre), is refused at the line of `validation`
/// before any identification: no calibration can be scored on it. (The mapping adds the
/// columns `x_dif`, … to `x_t`, …: both are edited.)
#[test]
fn validation_rows_off_the_calibration_s_unit_or_frame_are_refused_at_their_key() {
    let d = tmp_dir("cli-task-misfit");
    let text = std::fs::read_to_string(wam_file(RANDOM)).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let point = [col("x_t"), col("y_t"), col("z_t")];
    let dif = [col("x_dif"), col("y_dif"), col("z_dif")];
    // Each row's point and difference passed through `edit` (the second argument: whether
    // it is the point, which a move shifts).
    let edited = |name: &str, edit: &dyn Fn(&mut [f64; 3], bool)| {
        let mut out = header.join(",") + "\n";
        for line in text.lines().skip(1) {
            let mut cells: Vec<String> = line.split(',').map(String::from).collect();
            for (cols, is_point) in [(point, true), (dif, false)] {
                let mut v = cols.map(|k| cells[k].parse::<f64>().unwrap());
                edit(&mut v, is_point);
                for (k, x) in cols.into_iter().zip(v) {
                    cells[k] = format!("{x}");
                }
            }
            out += &(cells.join(",") + "\n");
        }
        let file = d.join(name);
        std::fs::write(&file, out).unwrap();
        file
    };
    let metres = edited("metres.csv", &|v, _| {
        v.iter_mut().for_each(|x| *x /= 1000.0)
    });
    let moved = edited("moved.csv", &|v, is_point| {
        let shift = if is_point { 1000.0 } else { 0.0 };
        *v = [-v[1] + shift, v[0], v[2]];
    });
    for (file, words) in [
        (&metres, "they are likely in metres, not millimetres"),
        (
            &moved,
            "the calibration and validation rows do not lie in one frame",
        ),
    ] {
        let t = wam_task(
            &d,
            &format!(
                "calibration = \"{}\"\nvalidation = \"{}\"",
                wam_file(GRID).display(),
                file.display()
            ),
        );
        let o = task_lm(calbench, &t, Some("kinematic"), &d.join("out"));
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{e}");
        assert!(!d.join("out").exists(), "nothing is written");
        let at = format!("{}the ", at(&t, "validation = "));
        assert!(e.contains(&at) && e.contains(words), "{e}");
    }
}

/// A split whose validation part holds fewer than 3 distinct poses had been run and scored
/// (two rows of the real export in metres gave `validation_rms_mm = 2783.865` and exit 0),
/// where the same rows as a validation file are refused, as a `--validate` file or a
/// `--holdout` of such rows is. Each part of a split is now refused as a file of its rows,
/// at the line of `split`; three distinct validation rows run.
#[test]
fn a_split_part_of_fewer_than_three_distinct_poses_is_refused() {
    let d = tmp_dir("task-rows-split-part");
    let split = d.join("grid.split");
    let t = split_task(&d, &wam_file(GRID), &split);
    for (text, part) in [
        (
            "rows 216\ncalibration 0-213\nvalidation 214-215\n",
            "validation",
        ),
        ("rows 216\ncalibration 0\nvalidation 1-215\n", "calibration"),
    ] {
        std::fs::write(&split, text).unwrap();
        let o = task_lm(calbench, &t, Some("kinematic"), &d.join("out"));
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{text}: {e}");
        let said = format!("the {part} rows of {} (", split.display());
        assert!(e.contains(&at(&t, "split = ")) && e.contains(&said), "{e}");
        assert!(e.contains("hold fewer than 3 distinct poses"), "{e}");
        assert!(!d.join("out").exists());
    }
    std::fs::write(&split, "rows 216\ncalibration 0-212\nvalidation 213-215\n").unwrap();
    task_lm(calbench_ok, &t, Some("kinematic"), &d.join("ok"));
}

/// A split that puts two copies of a row in its validation part had its point counted twice;
/// the copies are refused at the line of `split`, named by the data file's rows.
#[test]
fn repeated_validation_rows_of_a_split_are_refused_naming_the_data_rows() {
    let d = tmp_dir("task-rows-split-repeats");
    let data = grid_with_copy(&d, "grid-plus.csv", 210);
    let split = d.join("grid.split");
    std::fs::write(&split, "rows 217\ncalibration 0-199\nvalidation 200-216\n").unwrap();
    let t = split_task(&d, &data, &split);
    let o = task_lm(calbench, &t, Some("kinematic"), &d.join("out"));
    let e = String::from_utf8_lossy(&o.stderr);
    let said = format!(
        "{}{}: 1 row(s) repeat an earlier row",
        at(&t, "split = "),
        data.display()
    );
    assert!(!o.status.success() && e.contains(&said), "{e}");
    assert!(e.contains("row 210 = row 216;"), "{e}");
    assert!(!d.join("out").exists());
}

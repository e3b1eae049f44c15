//! A reading is named by its line in the file it came from (docs/formats.md § 5.1, § 2.6
//! "Physical plausibility"), whatever `#` comment and blank lines come before it: a bad cell,
//! and a gross reading a refusal of the identification points to, in a tracker's file, in the
//! rows a `--holdout` keeps, and in a task's export through its mapping.

use std::path::Path;

use crate::common::{calbench, path_arg, read, refused, tmp_dir, ur10_example, ur10_positions};

/// The lines of the UR10 positions file with a comment and a blank line before the header,
/// and `# moved` and a blank line before data row `row` (0-based), whose `x` is `x(old)`:
/// written to `dir/name`, with the file line of that row.
fn commented(dir: &Path, name: &str, row: usize, x: impl Fn(f64) -> String) -> (String, usize) {
    let text = read(&ur10_positions(dir));
    let mut lines = vec![
        "# the UR10 sample, positions only".to_string(),
        String::new(),
    ];
    for (i, line) in text.lines().enumerate() {
        if i == row + 1 {
            lines.extend(["# moved".to_string(), String::new()]);
            let mut cells: Vec<String> = line.split(',').map(String::from).collect();
            cells[6] = x(cells[6].parse().unwrap());
            lines.push(cells.join(","));
        } else {
            lines.push(line.to_string());
        }
    }
    std::fs::write(dir.join(name), lines.join("\n") + "\n").unwrap();
    // Two lines before the header, the header, `row` rows, two lines before the row.
    (dir.join(name).display().to_string(), 2 + 1 + row + 2 + 1)
}

/// `calbench identify` of the UR10 robot on `data` with `extra` arguments, into `dir/out`.
fn identify(dir: &Path, data: &str, extra: &[&str]) -> std::process::Output {
    let (robot, out) = (ur10_example("ur10.toml"), dir.join("out"));
    let mut args = vec![
        "identify", "--robot", &robot, "--data", data, "--method", "lm",
    ];
    args.extend(extra);
    args.extend(["--out", path_arg(&out)]);
    let o = calbench(&args);
    assert!(
        !out.exists(),
        "written: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// A bad cell after comment and blank lines, with others before the header, is refused at
/// its own line: the reader had named the first of the blank and comment lines before it.
#[test]
fn a_bad_cell_after_comment_lines_is_refused_at_its_own_line() {
    let d = tmp_dir("cli-reading-lines-cell");
    let (data, line) = commented(&d, "cell.csv", 10, |_| "2x".into());
    assert_eq!(line, 16);
    let err = refused(&identify(&d, &data, &[]), &[]);
    assert_eq!(
        err,
        format!("error: {data}: line 16, column x: \"2x\" is not a finite number\n"),
    );
}

/// A reading moved by 5 m after comment lines, in a tracker's file: the refusal's likely
/// cause names it by its line in the file, with or without `--holdout` (row 10 calibrates
/// under `3/10`, as the calibration's eighth row): it had been `the point of row 10 of the
/// data (0-based)`.
#[test]
fn a_gross_reading_is_named_by_its_line_in_the_tracker_file() {
    let d = tmp_dir("cli-reading-lines-gross");
    let (data, line) = commented(&d, "gross.csv", 10, |x| (x + 5000.0).to_string());
    let point = format!("the point on line {line} of {data} has a residual");
    for extra in [&[][..], &["--holdout", "3/10"][..]] {
        let err = refused(&identify(&d, &data, extra), &[&point, "a gross reading"]);
        assert!(err.starts_with(&format!("error: {data}: data: ")), "{err}");
        assert!(!err.contains("0-based"), "{err}");
    }
}

/// A reading moved by 5 m in a task's export (the WAM grid through its mapping), after blank
/// lines, on row 50 of the data, which the split makes the calibration's row 30: named by its
/// line in the export.
#[test]
fn a_gross_reading_of_a_task_is_named_by_its_line_in_the_export() {
    use crate::task::task_lm;
    use crate::task_rows::{split_task, wam_file, GRID};
    let d = tmp_dir("cli-reading-lines-task");
    let text = read(&wam_file(GRID));
    let mut lines = vec![String::new()];
    for (i, line) in text.lines().enumerate() {
        let mut line = line.to_string();
        if i == 51 {
            lines.extend([String::new(), String::new()]);
            let mut cells: Vec<String> = line.split(',').map(String::from).collect();
            cells[4] = (cells[4].parse::<f64>().unwrap() + 5000.0).to_string();
            line = cells.join(",");
        }
        lines.push(line);
    }
    let data = d.join("grid.csv");
    std::fs::write(&data, lines.join("\n") + "\n").unwrap();
    let split = d.join("grid.split");
    std::fs::write(&split, "rows 216\nvalidation 0-19\ncalibration 20-215\n").unwrap();
    let t = split_task(&d, &data, &split);
    let out = d.join("out");
    let err = refused(&task_lm(calbench, &t, Some("kinematic"), &out), &[]);
    // A blank line, the header, rows 0 to 49, two blank lines: row 50 is on line 55.
    let point = format!("the point on line 55 of {}", data.display());
    assert!(err.contains(&point) && !err.contains("0-based"), "{err}");
    assert!(!out.exists());
}

/// The UR10 positions split as docs/formats.md § 2.6 splits them (rows whose index % 10 < 7
/// calibrate), the validation rows' points edited by `edit` (the row's index among them and
/// its cells), after a comment line: `dir/cal.csv` and `dir/NAME`.
fn split_edited(dir: &Path, name: &str, edit: impl Fn(usize, &mut [String])) -> (String, String) {
    let text = read(&ur10_positions(dir));
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let (mut cal, mut val) = (vec![header.clone()], vec!["# validation".into(), header]);
    for (i, line) in lines.enumerate() {
        if i % 10 < 7 {
            cal.push(line.to_string());
            continue;
        }
        let mut cells: Vec<String> = line.split(',').map(String::from).collect();
        edit(val.len() - 2, &mut cells);
        val.push(cells.join(","));
    }
    let write = |n: &str, l: &[String]| {
        std::fs::write(dir.join(n), l.join("\n") + "\n").unwrap();
        dir.join(n).display().to_string()
    };
    (write("cal.csv", &cal), write(name, &val))
}

/// A `--validate` file in metres had been refused as `setting --validate` naming neither the
/// file nor its rows; it is refused at the file, all its rows named. One row of it in metres
/// is named by its line.
#[test]
fn a_validation_file_in_metres_is_refused_naming_the_file_and_the_rows() {
    let d = tmp_dir("cli-reading-lines-metres");
    let metres = |c: &mut [String]| {
        for v in &mut c[6..9] {
            *v = (v.parse::<f64>().unwrap() / 1000.0).to_string();
        }
    };
    let (cal, val) = split_edited(&d, "val-m.csv", |_, c| metres(c));
    let err = refused(&identify(&d, &cal, &["--validate", &val]), &[]);
    let want = format!(
        "error: {val}: data: the validation points spread 0.0010 times as far as the nominal \
         robot's tool points (bound ±10 %): they are likely in metres, not millimetres (all 59 \
         rows); validate on points measured as the calibration's were\n"
    );
    assert_eq!(err, want);
    // Validation row 3: a comment line, the header, rows 0 to 2.
    let (cal, val) = split_edited(&d, "val-1.csv", |i, c| {
        if i == 3 {
            metres(c)
        }
    });
    let err = refused(&identify(&d, &cal, &["--validate", &val]), &[]);
    let at = format!("error: {val}: data: the validation points spread ");
    let row = format!("; the point on line 6 of {val} stands out: its distance from the points'");
    assert!(err.starts_with(&at) && err.contains(&row), "{err}");
    // Twelve rows, row 3's x 40 m off: it had moved the rows' centroid so far that every
    // row's distance changed, and the refusal named "all 12 rows".
    let (cal, val) = split_edited(&d, "val-12.csv", |i, c| {
        if i == 3 {
            c[6] = (c[6].parse::<f64>().unwrap() + 40_000.0).to_string();
        }
    });
    let kept: Vec<String> = read(Path::new(&val))
        .lines()
        .take(14)
        .map(String::from)
        .collect();
    std::fs::write(&val, kept.join("\n") + "\n").unwrap();
    let err = refused(&identify(&d, &cal, &["--validate", &val]), &[]);
    let row = format!("; the point on line 6 of {val} stands out: its distance from the points'");
    assert!(
        err.starts_with(&at.replace("val-1.csv", "val-12.csv")),
        "{err}"
    );
    assert!(err.contains(&row) && !err.contains("all 12 rows"), "{err}");
}

/// A validation file with rows copied had its copies counted again in its figures; it is
/// refused naming the file and the rows, as the data's own copies are, and runs without them.
#[test]
fn a_validation_file_with_repeated_rows_is_refused_naming_them() {
    let d = tmp_dir("cli-plausible-val-repeats");
    let pos = crate::plausible::simulated(&d, "scenarios/ci-guard.toml", None);
    let val = pos.with_file_name("validation.csv");
    let text = read(&val);
    let rows: Vec<&str> = text.lines().collect();
    let copied = d.join("val-copied.csv");
    std::fs::write(&copied, format!("{text}{}\n{}\n", rows[1], rows[3])).unwrap();
    let n = rows.len() - 1;
    let out = d.join("out");
    let o = crate::plausible::identify(&pos, &out, &["--validate", path_arg(&copied)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && !out.exists(), "{err}");
    let said = format!(
        "setting `--validate`: {}: 2 row(s) repeat an earlier row (the same joint values and \
         measured point; 0-based rows): row 0 = row {n}, row 2 = row {};",
        copied.display(),
        n + 1
    );
    assert!(err.contains(&said), "{err}");
    assert!(err.contains("weighs one point twice"), "{err}");
    let o = crate::plausible::identify(&pos, &out, &["--validate", path_arg(&val)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

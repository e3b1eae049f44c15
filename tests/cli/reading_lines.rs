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

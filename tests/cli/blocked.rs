//! The blocked splits of the IPA UR10 Series A and D tasks (docs/formats.md § 9,
//! docs/results.md "Real-data tasks"): no validation row is measured at a commanded position
//! that a calibration row was, where the interleaved splits of the same rows do put them side
//! by side; docs/results.md reports every candidate of Series A and D on both splits, as the
//! task command gives it.

use std::collections::HashSet;
use std::path::Path;

use crate::common::{calbench_ok, load_json, root, tmp_dir};
use crate::task::{task, task_lm};

/// The commanded positions (`Goal x/y/z`, m) of a Leica export, to 1 mm.
fn goals(data: &Path) -> Vec<[i64; 3]> {
    let text = std::fs::read_to_string(data).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(';').collect();
    let cols: Vec<usize> = ["Goal x", "Goal y", "Goal z"]
        .iter()
        .map(|c| head.iter().position(|h| h == c).unwrap())
        .collect();
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(';').collect();
            let v = |k: usize| -> i64 {
                let x: f64 = cells[cols[k]].replace(',', ".").parse().unwrap();
                (x * 1000.0).round() as i64
            };
            [v(0), v(1), v(2)]
        })
        .collect()
}

/// The calibration and validation rows of a split file.
fn split(path: &Path) -> (Vec<usize>, Vec<usize>) {
    let (mut cal, mut val) = (Vec::new(), Vec::new());
    for line in std::fs::read_to_string(path).unwrap().lines() {
        let body = line.split('#').next().unwrap().trim();
        let w: Vec<&str> = body.split_whitespace().collect();
        if w.len() != 2 || w[0] == "rows" {
            continue;
        }
        let (a, b) = w[1].split_once('-').unwrap_or((w[1], w[1]));
        let rows = a.parse::<usize>().unwrap()..=b.parse::<usize>().unwrap();
        if w[0] == "calibration" {
            cal.extend(rows);
        } else {
            val.extend(rows);
        }
    }
    (cal, val)
}

/// How many validation rows of the split were commanded to a position a calibration row was.
fn shared(series: &str, data: &str, variant: &str) -> (usize, usize) {
    let g = goals(&root().join(data));
    let (cal, val) = split(&root().join(format!("tasks/ipa-ur10-series-{series}{variant}.split")));
    assert_eq!(cal.len() + val.len(), g.len());
    let seen: HashSet<[i64; 3]> = cal.iter().map(|&i| g[i]).collect();
    (
        val.iter().filter(|&&i| seen.contains(&g[i])).count(),
        val.len(),
    )
}

#[test]
fn blocked_splits_hold_no_calibration_position_and_interleaved_ones_do() {
    let a = "data/ipa-ur10-series-a/measurements_grid.csv";
    let d = "data/ipa-ur10-series-d/measurements_iso_cubes.csv";
    // Series A: every grid point is measured in several orientations; interleaved, every
    // validation row's grid point also calibrates.
    let (n, of) = shared("a", a, "");
    assert_eq!((n, of), (3573, 3573));
    assert_eq!(shared("a", a, "-blocked"), (0, 4005));
    // Series D: the cubes' cycles repeat; interleaved, some validation rows repeat a
    // calibration position exactly.
    let (n, of) = shared("d", d, "");
    assert!(n > 0 && of == 189, "{n} of {of}");
    assert_eq!(shared("d", d, "-blocked"), (0, 189));
}

/// The body rows of the table of docs/results.md whose header line starts with `header`, each
/// row's cells trimmed of spaces and backticks.
pub(crate) fn results_table(header: &str) -> Vec<Vec<String>> {
    let doc = std::fs::read_to_string(root().join("docs/results.md")).unwrap();
    let start = doc
        .find(header)
        .unwrap_or_else(|| panic!("docs/results.md has a table headed {header}"));
    doc[start..]
        .lines()
        .take_while(|l| l.starts_with('|'))
        .skip(2)
        .map(|l| {
            l.trim()
                .trim_matches('|')
                .split('|')
                .map(|c| c.trim().trim_matches('`').to_string())
                .collect()
        })
        .collect()
}

/// docs/results.md reports Series A and D on both splits (issue 54, "Series A and D have
/// blocked splits and report both"): every cell of its blocked-splits table is what
/// `calbench task` gives, the CV RMS of each candidate from the run with all four (as the page's
/// commands run it), the validation RMS and its interval from the run with that model alone,
/// and the row marked as the CV's choice is the one chosen on every task.
#[test]
fn results_md_reports_series_a_and_d_on_both_splits() {
    let rows = results_table("| model | Series A, interleaved |");
    let models = ["kinematic", "beta", "harmonics", "harmonics2"];
    assert_eq!(rows.len(), models.len(), "{rows:?}");
    let tasks = [
        "ipa-ur10-series-a",
        "ipa-ur10-series-a-blocked",
        "ipa-ur10-series-d",
        "ipa-ur10-series-d-blocked",
    ];
    let dir = tmp_dir("cli-blocked-docs");
    for (col, name) in tasks.iter().enumerate() {
        let out = task_lm(
            calbench_ok,
            &task(name),
            Some(&models.join(",")),
            &dir.join(name),
        );
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        let mut cv = Vec::new();
        let mut chosen = None;
        for l in stdout.lines() {
            let w: Vec<&str> = l.split_whitespace().collect();
            if w.len() >= 4 && w[1] == "CV" && w[2] == "RMS" {
                cv.push((w[0].to_string(), w[3].parse::<f64>().unwrap()));
                if l.contains("(chosen)") {
                    chosen = Some(w[0].to_string());
                }
            }
        }
        assert_eq!(cv.len(), models.len(), "{name}: {stdout}");
        for (row, (model, cv_rms)) in rows.iter().zip(&cv) {
            assert!(
                row[0].starts_with(model.as_str()),
                "{row:?} against {model}"
            );
            let one = dir.join(format!("{name}-{model}"));
            task_lm(calbench_ok, &task(name), Some(model), &one);
            let j = load_json(&one.join("task.json"));
            let (v, ci) = (j["value"].as_f64().unwrap(), &j["ci95"]);
            let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
            let cell = format!("{cv_rms:.4} / {v:.3} ({lo:.3}–{hi:.3})");
            assert_eq!(row[col + 1], cell, "{name}, {model}");
            let marked = row[0].contains("CV's choice");
            assert_eq!(
                marked,
                chosen.as_deref() == Some(model.as_str()),
                "{name}: {row:?}"
            );
        }
    }
}

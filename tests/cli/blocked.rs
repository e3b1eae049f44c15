//! The blocked splits of the IPA UR10 Series A and D tasks (docs/formats.md § 9,
//! docs/results.md "Real-data tasks"): no validation row is measured at a commanded position
//! that a calibration row was, where the interleaved splits of the same rows do put them side
//! by side; the blocked Series D task runs beside its interleaved twin.

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

#[test]
fn the_blocked_series_d_task_runs_beside_its_interleaved_twin() {
    let dir = tmp_dir("cli-blocked-d");
    let mut values = Vec::new();
    for name in ["ipa-ur10-series-d", "ipa-ur10-series-d-blocked"] {
        let out = dir.join(name);
        task_lm(calbench_ok, &task(name), Some("kinematic"), &out);
        let j = load_json(&out.join("task.json"));
        assert_eq!(j["task"], name);
        values.push(j["value"].as_f64().unwrap());
    }
    // docs/results.md: kinematic, interleaved 0.396 mm.
    assert!((values[0] - 0.396).abs() < 0.001, "{values:?}");
    assert!(values[1].is_finite() && values[1] > 0.0, "{values:?}");
}

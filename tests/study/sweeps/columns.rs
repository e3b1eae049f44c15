//! A sweep whose points differ in their `trials.csv` columns ([`super`]): one header, the
//! union of every point's columns, each row as long as it, the cells a point lacks empty;
//! the same bytes sharded and merged, and `compare` reads the file.

use super::write_small;
use crate::common::{
    calbench_ok, kill_once_checkpointed, path_arg, read, sharded_and_merged, tmp_dir,
    SMALL_STUDY as SMALL,
};

/// Full-pose measurement with joint compliances identified at the middle point only: the
/// first and last points (the last with outliers) have neither the attitude columns nor `true_c2`…
const SWEEP: &str = "\n[[sweep]]\nkey = \"tracker.measure\"\n\
                     values = [\"position\", \"pose\", \"position\"]\nzip = true\n\
                     [[sweep]]\nkey = \"identification.compliance\"\n\
                     values = [[], \"gravity\", []]\n\
                     [[sweep]]\nkey = \"outliers.count\"\nvalues = [0, 0, 2]\n";

#[test]
fn a_sweep_whose_points_differ_in_columns_writes_one_header_for_every_row() {
    let dir = tmp_dir("sweeps-columns");
    let sc = write_small(&dir, "columns", &format!("{SMALL}{SWEEP}"));
    let full = dir.join("full");
    calbench_ok(&["run", &sc, "--out", path_arg(&full)]);
    let text = read(&full.join("trials.csv"));
    let mut rows = csv::Reader::from_reader(text.as_bytes());
    let head: Vec<String> = rows.headers().unwrap().iter().map(String::from).collect();
    let col = |name: &str| {
        head.iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {head:?}"))
    };
    let (deg, c2, measure) = (
        col("after_rms_deg"),
        col("identified_c2"),
        col("tracker.measure"),
    );
    let mut seen = [0usize; 2];
    for row in rows.records() {
        // The reader refuses a row of another length than the header.
        let row = row.unwrap();
        let pose = &row[measure] == "pose";
        seen[pose as usize] += 1;
        for at in [deg, c2, col("true_c5")] {
            let cell = &row[at];
            assert_eq!(
                cell.parse::<f64>().is_ok(),
                pose,
                "{}: {cell:?} in {row:?}",
                head[at]
            );
            assert!(pose || cell.is_empty(), "{row:?}");
        }
        assert!(row[col("identified_a1")].parse::<f64>().is_ok(), "{row:?}");
    }
    assert_eq!(
        seen,
        [2 * 5 * 2, 5 * 2],
        "rows of position and of pose points"
    );

    let merged = sharded_and_merged(&sc, &dir, 2, &[]);
    for f in ["trials.csv", "summary.json"] {
        assert_eq!(read(&full.join(f)), read(&merged.join(f)), "{f}");
    }
    let o = calbench_ok(&[
        "compare",
        path_arg(&full),
        path_arg(&merged),
        "--out",
        path_arg(&dir.join("cmp")),
    ]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(said.contains(" 0 regressed"), "{said}");
}

/// The same sweep killed (SIGKILL) once its checkpoint holds trials and resumed gives the
/// bytes of one run.
#[test]
fn a_sweep_whose_points_differ_in_columns_resumes_into_the_same_bytes() {
    let dir = tmp_dir("sweeps-columns-resume");
    let sc = write_small(&dir, "columns", &format!("{SMALL}{SWEEP}"));
    let (full, out) = (dir.join("full"), dir.join("killed"));
    let args = ["run", &sc, "--trials", "300", "--threads", "1", "--out"];
    calbench_ok(&[&args[..], &[path_arg(&full)]].concat());
    kill_once_checkpointed(&[&args[..], &[path_arg(&out)]].concat(), &out, 120);
    assert!(
        !out.join("trials.csv").exists(),
        "the run ended before it was killed"
    );
    calbench_ok(&["run", "--resume", path_arg(&out)]);
    for f in ["trials.csv", "summary.json"] {
        assert_eq!(read(&full.join(f)), read(&out.join(f)), "{f}");
    }
}

/// A method label holding a comma and a quote is one quoted cell of `trials.csv`, which
/// `check` reads back trial by trial.
#[test]
fn a_method_label_with_a_comma_is_one_cell() {
    let dir = tmp_dir("sweeps-label");
    let label = "rob, \\\"k\\\"";
    let sc = write_small(
        &dir,
        "label",
        &SMALL.replace("label = \"rob\"", &format!("label = \"{label}\"")),
    );
    let out = dir.join("out");
    calbench_ok(&["run", &sc, "--out", path_arg(&out)]);
    let text = read(&out.join("trials.csv"));
    let mut rows = csv::Reader::from_reader(text.as_bytes());
    let labels: Vec<String> = rows.records().map(|r| r.unwrap()[1].to_string()).collect();
    assert!(labels.contains(&"rob, \"k\"".to_string()), "{labels:?}");
    let base = dir.join("base.json");
    calbench_ok(&["baseline", path_arg(&out), "--out", path_arg(&base)]);
    let summary = out.join("summary.json");
    let o = calbench_ok(&["check", path_arg(&summary), "--baseline", path_arg(&base)]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(said.contains("paired"), "{said}");
}

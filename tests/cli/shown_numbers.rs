//! Numbers beyond 1e16 are shown in exponent form (docs/formats.md § 8.1): in `record`'s
//! refusal of a figure outside its interval, and in `history.csv`, where ordinary values keep
//! the digits they had.

use crate::common::{calbench, calbench_ok, load_json, one_line_naming, path_arg, read, tmp_dir};
use crate::impossible::{copy_with_summary, good_run};

#[test]
fn a_huge_figure_is_written_in_exponent_form_by_record_and_history() {
    let dir = tmp_dir("cli-shown-numbers");
    let good = good_run(&dir);
    let doc = load_json(&good.join("summary.json"));
    let ordinary = doc["results"][0]["validation_after_mm"]["mean"]
        .as_f64()
        .unwrap();
    let db = dir.join("x.sqlite");
    let mut d = doc.clone();
    d["results"][0]["validation_after_mm"]["mean"] = 1e300.into();
    let edited = copy_with_summary(&good, &dir.join("edited"), &d.to_string());
    let o = calbench(&["record", path_arg(&edited), "--db", path_arg(&db)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    let want = ["validation_after_mm.mean: is 1e300 outside its own 95 % interval"];
    one_line_naming(&err, &edited.join("summary.json"), &want);
    // A mean is at most its RMS and maximum: all three huge, each inside its interval.
    for stat in ["mean", "rms", "max"] {
        d["results"][0]["validation_after_mm"][stat] = 1e300.into();
        d["results"][0]["validation_after_mm"][format!("{stat}_ci95")] =
            serde_json::json!([0.0, 1e301]);
    }
    let widened = copy_with_summary(&good, &dir.join("widened"), &d.to_string());
    for (folder, label) in [(&good, "v1"), (&widened, "v2")] {
        calbench_ok(&[
            "record",
            path_arg(folder),
            "--db",
            path_arg(&db),
            "--label",
            label,
        ]);
    }
    let out = dir.join("history");
    let args = [
        "--metric",
        "validation_after_mm.mean",
        "--out",
        path_arg(&out),
    ];
    calbench_ok(&[&["history", "--db", path_arg(&db)][..], &args].concat());
    let csv = read(&out.join("history.csv"));
    let rows: Vec<&str> = csv.lines().filter(|l| l.contains("ls / random")).collect();
    assert_eq!(rows.len(), 2, "{csv}");
    assert!(rows[0].contains(",v1,") && rows[0].contains(&format!(",{ordinary},")));
    assert!(
        rows[1].contains(",v2,") && rows[1].contains(",1e300,0,1e301,"),
        "{csv}"
    );
    assert!(csv.lines().all(|l| l.len() < 400), "{csv}");
}

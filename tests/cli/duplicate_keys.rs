//! A key written twice in one object of a JSON file calbench reads (a summary, a baseline, a
//! run folder's `summary.json`, `identified.json`) is refused naming the file, the line of its
//! second writing and the key path, as a TOML file's is (docs/formats.md § 8.1); the last
//! value had been used without a word.

use crate::common::{calbench, path_arg, read, refused, tmp_dir};
use crate::impossible::{copy_with_summary, good_run};

/// `text` with `line` inserted after the first line that holds `after`, which follows
/// `"results"`; and the 1-based number of the inserted line.
fn with_line_after(text: &str, after: &str, line: &str) -> (String, usize) {
    let from = text.find("\"results\"").unwrap();
    let at = from + text[from..].find(after).unwrap();
    let end = at + text[at..].find('\n').unwrap() + 1;
    let n = text[..end].matches('\n').count() + 1;
    (format!("{}{line}\n{}", &text[..end], &text[end..]), n)
}

#[test]
fn a_key_written_twice_in_a_summary_is_refused_by_check_and_record_naming_its_line() {
    let dir = tmp_dir("cli-duplicate-keys");
    let good = good_run(&dir);
    let summary = good.join("summary.json");
    let text = read(&summary);
    let (twice, line) =
        with_line_after(&text, "\"eta_mean_pct\": ", "      \"eta_mean_pct\": 1.0,");
    let bad = dir.join("twice.json");
    std::fs::write(&bad, &twice).unwrap();
    let place = format!("{}: line {line}, results[0].eta_mean_pct: ", bad.display());
    for (s, b) in [(&bad, &summary), (&summary, &bad)] {
        let o = calbench(&["check", path_arg(s), "--baseline", path_arg(b)]);
        refused(&o, &[&place, "duplicate key `eta_mean_pct`"]);
    }
    // A second `scenario` in the baseline is the baseline's fault, not the summary's.
    let scenario = format!("  \"scenario\": \"other\",\n{}", &text[2..]);
    let base = dir.join("scenario-twice.json");
    std::fs::write(&base, format!("{{\n{scenario}")).unwrap();
    let o = calbench(&["check", path_arg(&summary), "--baseline", path_arg(&base)]);
    let err = refused(
        &o,
        &[
            &format!("{}: line ", base.display()),
            "duplicate key `scenario`",
        ],
    );
    assert!(!err.contains(&summary.display().to_string()), "{err}");
    // record refuses it, and stores nothing.
    let folder = copy_with_summary(&good, &dir.join("copy"), &twice);
    let db = dir.join("x.sqlite");
    let o = calbench(&["record", path_arg(&folder), "--db", path_arg(&db)]);
    let place = format!("{}: line {line}, ", folder.join("summary.json").display());
    refused(&o, &[&place, "results[0].eta_mean_pct", "duplicate key"]);
}

#[test]
fn a_summary_saved_with_a_byte_order_mark_reads_as_without() {
    // An editor that saves UTF-8 with a byte-order mark; TOML, CSV and URDF files read so.
    let dir = tmp_dir("cli-json-bom");
    let good = good_run(&dir);
    let summary = good.join("summary.json");
    let marked = format!("\u{feff}{}", read(&summary));
    let folder = copy_with_summary(&good, &dir.join("copy"), &marked);
    let copy = folder.join("summary.json");
    let plain = calbench(&[
        "check",
        path_arg(&summary),
        "--baseline",
        path_arg(&summary),
    ]);
    assert!(plain.status.success());
    for (s, b) in [(&copy, &summary), (&summary, &copy)] {
        let o = calbench(&["check", path_arg(s), "--baseline", path_arg(b)]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(o.stdout, plain.stdout);
    }
    let db = dir.join("x.sqlite");
    let o = calbench(&["record", path_arg(&folder), "--db", path_arg(&db)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn a_number_below_the_smallest_double_in_a_summary_is_refused_naming_its_line() {
    // serde_json reads `1e-400` as 0: check had reported a regression of η to 0, compare and
    // record had taken it.
    let dir = tmp_dir("cli-json-underflow");
    let good = good_run(&dir);
    let summary = good.join("summary.json");
    let text = read(&summary);
    let from = text.find("\"results\"").unwrap();
    let at = from + text[from..].find("\"eta_mean_pct\": ").unwrap() + "\"eta_mean_pct\": ".len();
    let end = at + text[at..].find([',', '\n']).unwrap();
    let line = text[..at].matches('\n').count() + 1;
    let tiny = format!("{}1e-400{}", &text[..at], &text[end..]);
    let folder = copy_with_summary(&good, &dir.join("copy"), &tiny);
    let bad = folder.join("summary.json");
    let place = format!("{}: line {line}, results[0].eta_mean_pct: ", bad.display());
    let words = "\"1e-400\" is below the smallest 64-bit number";
    for (s, b) in [(&bad, &summary), (&summary, &bad)] {
        let o = calbench(&["check", path_arg(s), "--baseline", path_arg(b)]);
        refused(&o, &[&place, words]);
    }
    let out = dir.join("compared");
    let o = calbench(&[
        "compare",
        path_arg(&good),
        path_arg(&folder),
        "--out",
        path_arg(&out),
    ]);
    refused(&o, &[&place, words]);
    assert!(!out.exists());
    let db = dir.join("x.sqlite");
    let o = calbench(&["record", path_arg(&folder), "--db", path_arg(&db)]);
    refused(&o, &[&place, words]);
}

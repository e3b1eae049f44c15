//! Report plots: every plot writes a real PNG and SVG, deterministically, and survives empty
//! and non-finite data.

use std::path::Path;

use calbench::report::plots::{
    before_after, box_plot, box_stats, grouped_bars, sweep, traces, BoxStats, PLOT_SIZE,
};
use calbench::Error;

use crate::common::tmp_dir;

const PNG_MAGIC: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];

/// Checks `<stem>.png` (magic, IHDR size) and `<stem>.svg` (an `<svg` document holding the
/// title); returns the SVG text.
fn check_outputs(stem: &Path, title_in_svg: &str) -> String {
    let png = std::fs::read(stem.with_extension("png")).expect("png written");
    assert_eq!(png[..8], PNG_MAGIC, "PNG signature");
    assert_eq!(&png[12..16], b"IHDR", "first chunk is IHDR");
    let w = u32::from_be_bytes([png[16], png[17], png[18], png[19]]);
    let h = u32::from_be_bytes([png[20], png[21], png[22], png[23]]);
    assert_eq!((w, h), PLOT_SIZE, "PNG dimensions");
    // A blank 960×600 white image compresses to well under 3 kB; text and lines add more.
    assert!(png.len() > 5_000, "PNG too small: {} bytes", png.len());
    assert_eq!(
        &png[png.len() - 8..png.len() - 4],
        b"IEND",
        "PNG ends with IEND"
    );

    let svg = std::fs::read_to_string(stem.with_extension("svg")).expect("svg written");
    assert!(svg.starts_with("<svg"), "SVG starts with <svg");
    assert!(svg.trim_end().ends_with("</svg>"), "SVG is closed");
    assert!(
        svg.contains(&format!("width=\"{}\"", PLOT_SIZE.0)),
        "SVG width"
    );
    assert!(svg.contains(title_in_svg), "SVG holds the title");
    svg
}

fn names(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn grouped_bars_writes_png_and_svg() {
    let dir = tmp_dir("report-bars");
    let cats = names(&["a2", "d3", "alpha2", "beta2", "tool.x"]);
    let series = vec![
        ("ls".to_string(), vec![92.0, 80.5, 99.0, 75.0, 60.0]),
        ("ridge".to_string(), vec![95.0, 85.0, 99.5, 70.0, 65.0]),
        ("igg3".to_string(), vec![96.0, 88.0, 98.0, 72.0, 61.0]),
    ];
    let stem = dir.join("eta");
    grouped_bars(&stem, "η per parameter", "η (%)", &cats, &series).unwrap();
    let svg = check_outputs(&stem, "η per parameter");
    // Every category and series name is drawn as text.
    for s in ["a2", "alpha2", "tool.x", "ls", "ridge", "igg3", "η (%)"] {
        assert!(svg.contains(&format!(">\n{s}\n</text>")), "{s}");
    }
    // 15 bars + 3 legend swatches, each a filled <rect>, plus the background.
    let rects = svg.matches("<rect").count();
    assert!(rects >= 18, "bars drawn: {rects} rects");
}

#[test]
fn grouped_bars_many_categories_rotated_labels() {
    let dir = tmp_dir("report-bars-many");
    let cats: Vec<String> = (1..=30).map(|i| format!("theta{i}")).collect();
    let series = vec![("ls".to_string(), (0..30).map(|i| i as f64).collect())];
    let stem = dir.join("eta");
    grouped_bars(&stem, "Thirty parameters", "η (%)", &cats, &series).unwrap();
    let svg = check_outputs(&stem, "Thirty parameters");
    assert!(svg.contains("rotate(90"), "long category lists are rotated");
    assert!(svg.contains("theta30"));
}

#[test]
fn before_after_writes_png_and_svg() {
    let dir = tmp_dir("report-before-after");
    let before: Vec<f64> = (0..40)
        .map(|i| 1.0 + 0.3 * ((i as f64) * 0.7).sin())
        .collect();
    let after: Vec<f64> = (0..40)
        .map(|i| 0.05 + 0.02 * ((i as f64) * 1.3).cos())
        .collect();
    let stem = dir.join("validation");
    before_after(&stem, "Validation error", &before, &after).unwrap();
    let svg = check_outputs(&stem, "Validation error");
    assert!(svg.contains("before (rms"));
    assert!(svg.contains("after (rms"));
    // 80 markers + 2 legend markers.
    assert!(svg.matches("<circle").count() >= 82);
}

#[test]
fn box_plot_writes_png_and_svg() {
    let dir = tmp_dir("report-box");
    let groups = vec![
        ("ls".to_string(), vec![0.10, 0.12, 0.11, 0.13, 0.09, 0.50]),
        ("lm".to_string(), vec![0.05, 0.06, 0.055, 0.07, 0.065]),
        ("bas-pso".to_string(), vec![0.2]),
    ];
    let stem = dir.join("rms");
    box_plot(&stem, "Validation RMS over trials", "RMS (mm)", &groups).unwrap();
    let svg = check_outputs(&stem, "Validation RMS over trials");
    // The 0.50 outlier of `ls` is the only value beyond its whiskers.
    assert_eq!(svg.matches("<circle").count(), 1, "one outlier marker");
}

#[test]
fn traces_linear_and_log() {
    let dir = tmp_dir("report-traces");
    let series = vec![
        (
            "pso".to_string(),
            (0..200)
                .map(|i| 10.0 * (-(i as f64) / 30.0).exp())
                .collect(),
        ),
        (
            "bas-pso".to_string(),
            (0..150).map(|i| 8.0 * (-(i as f64) / 20.0).exp()).collect(),
        ),
    ];
    for log_y in [false, true] {
        let stem = dir.join(format!("fitness-{log_y}"));
        traces(
            &stem,
            "Fitness per iteration",
            "iteration",
            "fitness",
            &series,
            log_y,
        )
        .unwrap();
        let svg = check_outputs(&stem, "Fitness per iteration");
        assert!(svg.contains("<polyline"), "lines drawn");
    }
    // Linear and log renders differ.
    let a = std::fs::read(dir.join("fitness-false.svg")).unwrap();
    let b = std::fs::read(dir.join("fitness-true.svg")).unwrap();
    assert_ne!(a, b);
}

#[test]
fn sweep_writes_png_and_svg() {
    let dir = tmp_dir("report-sweep");
    let series = vec![
        (
            "detmax".to_string(),
            vec![(10.0, 0.30, 0.05), (20.0, 0.15, 0.02), (40.0, 0.08, 0.01)],
        ),
        (
            "random".to_string(),
            vec![(40.0, 0.12, 0.02), (10.0, 0.50, 0.10), (20.0, 0.25, 0.04)],
        ),
    ];
    let stem = dir.join("poses");
    sweep(&stem, "RMS vs pose count", "poses", "RMS (mm)", &series).unwrap();
    let svg = check_outputs(&stem, "RMS vs pose count");
    assert!(svg.matches("<polyline").count() >= 2);
}

#[test]
fn empty_data_draws_titled_empty_charts() {
    let dir = tmp_dir("report-empty");
    let d = |s: &str| dir.join(s);
    grouped_bars(&d("bars"), "Empty bars", "η", &[], &[]).unwrap();
    check_outputs(&d("bars"), "Empty bars");
    before_after(&d("ba"), "Empty before after", &[], &[]).unwrap();
    check_outputs(&d("ba"), "Empty before after");
    box_plot(&d("box"), "Empty box", "mm", &[]).unwrap();
    check_outputs(&d("box"), "Empty box");
    box_plot(&d("box2"), "Empty groups", "mm", &[("ls".into(), vec![])]).unwrap();
    check_outputs(&d("box2"), "Empty groups");
    traces(&d("tr"), "Empty traces", "it", "f", &[], false).unwrap();
    check_outputs(&d("tr"), "Empty traces");
    traces(&d("trl"), "Empty log traces", "it", "f", &[], true).unwrap();
    check_outputs(&d("trl"), "Empty log traces");
    sweep(&d("sw"), "Empty sweep", "x", "y", &[]).unwrap();
    check_outputs(&d("sw"), "Empty sweep");
}

#[test]
fn non_finite_data_is_skipped() {
    let dir = tmp_dir("report-nan");
    let d = |s: &str| dir.join(s);
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    let cats = names(&["a1", "a2", "a3"]);
    grouped_bars(
        &d("bars"),
        "NaN bars",
        "η",
        &cats,
        &[
            ("ls".into(), vec![nan, 3.0, inf]),
            ("lm".into(), vec![nan; 3]),
        ],
    )
    .unwrap();
    check_outputs(&d("bars"), "NaN bars");
    before_after(&d("ba"), "NaN before after", &[nan, 1.0, inf], &[nan, nan]).unwrap();
    check_outputs(&d("ba"), "NaN before after");
    box_plot(
        &d("box"),
        "NaN box",
        "mm",
        &[
            ("ls".into(), vec![nan, inf, -inf]),
            ("lm".into(), vec![1.0, nan, 2.0]),
        ],
    )
    .unwrap();
    check_outputs(&d("box"), "NaN box");
    // Log scale with zeros, negatives and NaN only: an empty log chart.
    traces(
        &d("tr"),
        "NaN traces",
        "it",
        "f",
        &[("a".into(), vec![nan, 0.0, -1.0, inf])],
        true,
    )
    .unwrap();
    check_outputs(&d("tr"), "NaN traces");
    // A constant series (zero-width range) and a single point.
    traces(
        &d("tr1"),
        "Flat trace",
        "it",
        "f",
        &[("a".into(), vec![2.0; 5])],
        false,
    )
    .unwrap();
    check_outputs(&d("tr1"), "Flat trace");
    sweep(
        &d("sw"),
        "NaN sweep",
        "x",
        "y",
        &[(
            "a".into(),
            vec![
                (nan, 1.0, 0.1),
                (1.0, nan, 0.1),
                (2.0, 1.0, nan),
                (3.0, 1.5, inf),
            ],
        )],
    )
    .unwrap();
    check_outputs(&d("sw"), "NaN sweep");
}

#[test]
fn renders_are_byte_identical() {
    let dir = tmp_dir("report-determinism");
    let cats = names(&["a1", "theta2", "beta3"]);
    let series = vec![
        ("ls".to_string(), vec![1.0, 2.0, 3.0]),
        ("igg3".to_string(), vec![1.5, 2.5, 0.5]),
    ];
    grouped_bars(&dir.join("one"), "Same", "η", &cats, &series).unwrap();
    grouped_bars(&dir.join("two"), "Same", "η", &cats, &series).unwrap();
    for ext in ["svg", "png"] {
        let a = std::fs::read(dir.join(format!("one.{ext}"))).unwrap();
        let b = std::fs::read(dir.join(format!("two.{ext}"))).unwrap();
        assert_eq!(a, b, "{ext} differs between renders");
    }
}

#[test]
fn title_is_escaped_in_svg() {
    let dir = tmp_dir("report-escape");
    let stem = dir.join("t");
    before_after(&stem, "LS & ridge <fig. 3>", &[1.0], &[0.5]).unwrap();
    let svg = check_outputs(&stem, "LS &amp; ridge &lt;fig. 3&gt;");
    assert!(!svg.contains("LS & ridge"));
}

#[test]
fn stem_keeps_its_dots() {
    let dir = tmp_dir("report-dots");
    let stem = dir.join("eta.v2");
    traces(
        &stem,
        "Dots",
        "i",
        "f",
        &[("a".into(), vec![1.0, 0.5])],
        false,
    )
    .unwrap();
    assert!(dir.join("eta.v2.png").is_file());
    assert!(dir.join("eta.v2.svg").is_file());
}

#[test]
fn missing_folder_is_an_io_error() {
    let dir = tmp_dir("report-missing");
    let stem = dir.join("no-such-folder").join("plot");
    let err = traces(&stem, "T", "i", "f", &[], false).unwrap_err();
    match err {
        Error::Io { path, .. } => assert_eq!(path, stem.with_extension("svg")),
        other => panic!("expected an I/O error, got {other}"),
    }
}

#[test]
fn box_stats_hand_checked() {
    // Sorted 1..=9 plus an outlier 100: n = 10, positions p·9.
    let v = [5.0, 1.0, 9.0, 2.0, 8.0, 3.0, 7.0, 4.0, 6.0, 100.0, f64::NAN];
    let b = box_stats(&v).unwrap();
    // q1 at 2.25 → 3 + 0.25·1 = 3.25; median at 4.5 → 5.5; q3 at 6.75 → 7.75.
    assert!((b.q1 - 3.25).abs() < 1e-12);
    assert!((b.median - 5.5).abs() < 1e-12);
    assert!((b.q3 - 7.75).abs() < 1e-12);
    // Fences 3.25 − 6.75 = −3.5 and 7.75 + 6.75 = 14.5: whiskers at 1 and 9, 100 is beyond.
    assert_eq!(b.lo, 1.0);
    assert_eq!(b.hi, 9.0);

    let one = box_stats(&[4.0]).unwrap();
    assert_eq!(
        one,
        BoxStats {
            q1: 4.0,
            median: 4.0,
            q3: 4.0,
            lo: 4.0,
            hi: 4.0
        }
    );
    // Even count: median is the mean of the middle two.
    let b = box_stats(&[1.0, 2.0, 3.0, 4.0]).unwrap();
    assert!((b.median - 2.5).abs() < 1e-12);
    assert!((b.q1 - 1.75).abs() < 1e-12);
    assert!((b.q3 - 3.25).abs() < 1e-12);
    assert!(box_stats(&[]).is_none());
    assert!(box_stats(&[f64::NAN, f64::INFINITY]).is_none());
}

//! The `[unmodelled]` section (docs/formats.md § 4.7.1): joint harmonics and backlash on the
//! true arm, run the way a user runs a study.

use std::path::Path;

use crate::common::{
    calbench_ok, load_json, path_arg, read, sharded_and_merged, tmp_dir, write_scenario,
    SMALL_STUDY,
};

fn run(sc: &str, out: &Path, extra: &[&str]) {
    let mut args = vec!["run", sc];
    args.extend_from_slice(extra);
    args.extend(["--out", path_arg(out)]);
    calbench_ok(&args);
}

fn rms_after(out: &Path) -> f64 {
    let s = load_json(&out.join("summary.json"));
    let v = &s["results"][0]["validation_after_mm"]["rms"];
    v.as_f64().unwrap_or_else(|| panic!("{s}"))
}

#[test]
fn zero_spreads_are_the_run_without_the_section_byte_for_byte() {
    let dir = tmp_dir("unmodelled-zero");
    let plain = write_scenario(&dir, "plain", SMALL_STUDY);
    let zero = write_scenario(
        &dir,
        "zero",
        &format!(
            "{SMALL_STUDY}\n[unmodelled]\nharmonic1_rad = 0.0\nharmonic2_rad = 0.0\nbacklash_rad = 0.0\n"
        ),
    );
    let (a, b) = (dir.join("a"), dir.join("b"));
    run(path_arg(&plain), &a, &[]);
    run(path_arg(&zero), &b, &[]);
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&a.join(f)), read(&b.join(f)), "{f}");
    }
}

#[test]
fn unmodelled_error_remains_after_calibration_and_is_seeded_per_trial() {
    let dir = tmp_dir("unmodelled-seeded");
    let plain = write_scenario(&dir, "plain", SMALL_STUDY);
    let text = format!(
        "{SMALL_STUDY}\n[unmodelled]\nharmonic1_rad = 2e-4\nharmonic2_rad = 1e-4\nbacklash_rad = 1e-4\n"
    );
    let sc = write_scenario(&dir, "unmod", &text);
    let sc = path_arg(&sc);
    let (p, one, two) = (dir.join("p"), dir.join("one"), dir.join("two"));
    run(path_arg(&plain), &p, &[]);
    run(sc, &one, &["--threads", "1"]);
    run(sc, &two, &["--threads", "2"]);
    // What no kinematic parameter represents stays after calibration: far above the
    // noise-only residual of the pure kinematic arm.
    let (rp, ru) = (rms_after(&p), rms_after(&one));
    assert!(ru > 5.0 * rp && ru > 0.02, "{ru} against {rp}");
    // The same bytes whatever the thread count or the shard split.
    let merged = sharded_and_merged(sc, &dir, 2, &[]);
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&one.join(f)), read(&two.join(f)), "{f}, threads");
        assert_eq!(read(&one.join(f)), read(&merged.join(f)), "{f}, shards");
    }
    // The trial's other draws do not move: the injected errors and the poses are the same, so
    // the nominal robot's error at the validation poses changes only by the unmodelled part.
    let t = |d: &Path| read(&d.join("trials.csv"));
    assert_ne!(t(&p), t(&one));
}

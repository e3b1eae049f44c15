//! Refusals of a study's scenario file (a registration study, an instruments study) as a
//! user meets them: `run` and `simulate` on a copy of a committed scenario with one key
//! edited, the message naming the file, the line and the key, and nothing written.

use crate::common::{calbench, path_arg as path, refused};

/// A fresh folder for one test.
fn tmp(name: &str) -> crate::common::TmpDir {
    crate::common::tmp_dir(&format!("study-files-{name}"))
}

/// A registration study's claim that names another metric is refused naming the scenario,
/// the line and the claim's key, as a calibration scenario's claims are.
#[test]
fn a_registration_study_claim_is_refused_at_its_line() {
    let d = tmp("registration-claim");
    let text = std::fs::read_to_string(crate::common::root().join("scenarios/ban-fig3.toml"))
        .expect("scenarios/ban-fig3.toml");
    let at = text
        .find("metric = \"registration_error_mm\"")
        .expect("a claim's metric");
    let line = text[..at].lines().count() + 1;
    let bad = d.join("ban-fig3.toml");
    let edited = text.replacen(
        "metric = \"registration_error_mm\"",
        "metric = \"validation_after_mm\"",
        1,
    );
    std::fs::write(&bad, edited).unwrap();
    refused(
        &calbench(&["run", path(&bad), "--out", path(&d.join("out"))]),
        &[
            &format!("ban-fig3.toml: line {line}, claims[0].metric"),
            "validation_after_mm",
        ],
    );
}

/// A pose or instrument count too large to allocate (`9223372036854775807`) is refused when
/// the scenario is read, naming the file, the line and the key, where `run` and `simulate`
/// panicked with "capacity overflow"; nothing is written.
#[test]
fn a_pose_count_too_large_is_refused_naming_file_line_and_key() {
    let d = tmp("huge-count");
    let root = crate::common::root();
    let huge = "9223372036854775807";
    let cases = [
        (
            "scenarios/ci-guard.toml",
            "count = 40",
            "line 26, setting: setting `calibration.count`: must be at most 10000000 poses",
        ),
        (
            "scenarios/ci-guard.toml",
            "count = 30",
            "line 30, setting: setting `validation.count`: must be at most 10000000 poses",
        ),
        (
            "scenarios/instruments.toml",
            "candidates = 600",
            "line 26, instruments_study.candidates: must be at most 10000000 poses",
        ),
        (
            "scenarios/instruments.toml",
            "planes = 3",
            "line 80, measurement[3].planes: must be at most 1000",
        ),
    ];
    for (i, (file, line, expected)) in cases.into_iter().enumerate() {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        assert!(text.contains(line), "{line}");
        let key = line.split(" = ").next().unwrap();
        let p = d.join(format!("huge{i}.toml"));
        std::fs::write(&p, text.replacen(line, &format!("{key} = {huge}"), 1)).unwrap();
        let out = d.join(format!("out{i}"));
        let o = calbench(&["simulate", path(&p), "--out", path(&out)]);
        refused(&o, &[&format!("huge{i}.toml: {expected}"), huge]);
        assert!(!out.exists());
    }
}

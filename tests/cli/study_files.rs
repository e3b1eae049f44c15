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
            "line 26, calibration.count: must be at most 10000000 poses",
        ),
        (
            "scenarios/ci-guard.toml",
            "count = 30",
            "line 30, validation.count: must be at most 10000000 poses",
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

/// A value given twice in a study's grid (a registration study's `outlier_counts` or
/// `magnitude_mm`, an instruments study's `poses`, `strategies`, or one `[[measurement]]`
/// entry twice) is refused naming the file, the line
/// and the key, as a sweep's value given twice is; it ran two cells of one name. Nothing is
/// written.
#[test]
fn a_value_given_twice_in_a_study_s_grid_is_refused_at_its_key() {
    let d = tmp("grid-twice");
    let root = crate::common::root();
    let position = "\n[[measurement]]\nkind = \"position\"\nnoise_um = 7.5\nscale_um_per_m = 3.0\n";
    let instruments = std::fs::read_to_string(root.join("scenarios/instruments.toml")).unwrap();
    let entries = instruments.lines().count() + 2;
    let cases = [
        (
            "scenarios/ban-fig3.toml",
            "outlier_counts = [2, 4, 6, 8, 10, 12, 14, 16]",
            "outlier_counts = [2, 4, 2]",
            "line 16, registration_study.outlier_counts[2]: 2 is given twice: two cells would be one"
                .to_string(),
        ),
        (
            "scenarios/ban-fig3.toml",
            "magnitude_mm = [0.2, 0.4, 0.6, 0.8, 1.0]",
            "magnitude_mm = [0.2, 0.20]",
            "line 17, registration_study.magnitude_mm[1]: 0.2 is given twice: two cells would be one"
                .to_string(),
        ),
        (
            "scenarios/instruments.toml",
            "poses = [50, 200]",
            "poses = [50, 50]",
            "line 24, instruments_study.poses[1]: 50 is given twice: two cells would be one"
                .to_string(),
        ),
        (
            "scenarios/instruments.toml",
            "strategies = [\"random\", \"detmax-ide\"]",
            "strategies = [\"random\", \"detmax-ide\", \"random\"]",
            "line 25, instruments_study.strategies[2]: \"random\" is given twice: two cells would \
             be one"
                .to_string(),
        ),
        (
            "scenarios/instruments.toml",
            "socket_distance_mm = 50.0\n",
            &format!("socket_distance_mm = 50.0\n{position}"),
            format!(
                "line {entries}, measurement[6]: the instrument of measurement[0] is given \
                 twice (every key the same): two cells would be one"
            ),
        ),
    ];
    for (i, (file, line, twice, expected)) in cases.into_iter().enumerate() {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        assert!(text.contains(line), "{line}");
        let p = d.join(format!("twice{i}.toml"));
        std::fs::write(&p, text.replacen(line, twice, 1)).unwrap();
        let out = d.join(format!("out{i}"));
        let o = calbench(&["run", path(&p), "--out", path(&out)]);
        refused(&o, &[&format!("twice{i}.toml: {expected}")]);
        assert!(!out.exists());
    }
}

/// A claim's `value` that is a table, a `family` that can be no claim's id, a `paper_point`
/// given without a sweep or not among the sweep's points, and `parameters` the robot lacks or
/// given with an ordering are refused when the
/// scenario is read, naming the file, the line and the claim's key; so are a `~` without its
/// `tolerance` (at the claim's line), a `tolerance` that is not a table and an `about` that is
/// neither mean nor median (at their own); nothing is written.
#[test]
fn a_claim_with_a_malformed_value_family_or_paper_point_is_refused_at_its_line() {
    let d = tmp("claim-keys");
    let text = std::fs::read_to_string(crate::common::root().join("scenarios/ci-guard.toml"))
        .expect("scenarios/ci-guard.toml");
    let claim = |extra: &str| {
        format!(
            "\n[[claims]]\nid = \"ls-rms\"\nstatement = \"LS reaches 0.1 mm\"\npaper = \"none\"\n\
             value = \"0.1 mm\"\nmetric = \"validation_after_mm.rms\"\n\
             relation = '\"ls\" ~ 0.1'\ntolerance = {{ relative = 0.25 }}\n{extra}\n"
        )
    };
    let sweep = "\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 1]\n";
    let cases = [
        (
            "value-table",
            claim("").replace("value = \"0.1 mm\"", "value = { a = 1 }"),
            "value = {",
            "claims[0].value",
            "give a string, a number or an array",
        ),
        (
            "family-words",
            claim("family = \"two words\""),
            "family = ",
            "claims[0].family",
            "\"two words\"",
        ),
        (
            "point-no-sweep",
            claim("paper_point = 1"),
            "paper_point",
            "claims[0].paper_point",
            "the scenario has no sweep",
        ),
        (
            "point-not-swept",
            format!("{sweep}{}", claim("paper_point = 2")),
            "paper_point",
            "claims[0].paper_point",
            "no point of the sweep (its points: 0, 1)",
        ),
        // A `~` without its band: at the claim's [[claims]] line, the key it lacks named.
        (
            "near-no-band",
            claim("").replace("tolerance = { relative = 0.25 }\n", ""),
            "[[claims]]",
            "claims[0].tolerance",
            "a point value (`~`) needs its band",
        ),
        // A band that is not a table: what it should be is said (serde said "expected
        // struct Margin").
        (
            "band-number",
            claim("").replace("tolerance = { relative = 0.25 }", "tolerance = 0.25"),
            "tolerance = ",
            "claims[0].tolerance",
            "expected a table of `relative` (a fraction, 0.01 for 1 %) or `absolute`",
        ),
        // A claim's `parameters` must be the robot's (irb2600 has six joints).
        (
            "parameters-unknown",
            claim("parameters = [\"alpha4\", \"d7\"]")
                .replace("validation_after_mm.rms", "eta")
                .replace("'\"ls\" ~ 0.1'", "'\"lm\" > \"ls\" for every parameter'")
                .replace("tolerance = { relative = 0.25 }\n", ""),
            "parameters = ",
            "claims[0].parameters",
            "\"d7\" is not a parameter of robot \"irb2600\"",
        ),
        // … with an η possible: an injected error (irb2600's identifiable set leaves out θ6 on
        // position data), not the base's.
        (
            "parameters-no-error",
            claim("parameters = [\"alpha4\", \"theta6\"]")
                .replace("validation_after_mm.rms", "eta")
                .replace("'\"ls\" ~ 0.1'", "'\"lm\" > \"ls\" for every parameter'")
                .replace("tolerance = { relative = 0.25 }\n", ""),
            "parameters = ",
            "claims[0].parameters",
            "\"theta6\" has no injected error (`errors`), so no trial gives it an η",
        ),
        (
            "parameters-base",
            claim("parameters = [\"base.x\"]")
                .replace("validation_after_mm.rms", "eta")
                .replace("'\"ls\" ~ 0.1'", "'\"lm\" > \"ls\" for every parameter'")
                .replace("tolerance = { relative = 0.25 }\n", ""),
            "parameters = ",
            "claims[0].parameters",
            "\"base.x\" is a base parameter, which η leaves out",
        ),
        // … and given with "for every parameter" only.
        (
            "parameters-ordering",
            claim("parameters = [\"alpha4\"]")
                .replace("'\"ls\" ~ 0.1'", "'\"lm\" < \"ls\"'")
                .replace("tolerance = { relative = 0.25 }\n", ""),
            "parameters = ",
            "claims[0].parameters",
            "`parameters` names the parameters of a relation ending \"for every parameter\"",
        ),
        // A value serde refuses: at its own line (it was placed at the [[claims]] line).
        (
            "about-mode",
            claim("about = \"mode\""),
            "about = ",
            "claims[0].about",
            "mode",
        ),
    ];
    for (name, added, at, key, why) in cases {
        let file = format!("{name}.toml");
        let edited = format!("{text}{added}");
        let line = edited[..edited.rfind(at).expect(at)].lines().count() + 1;
        let bad = d.join(&file);
        std::fs::write(&bad, &edited).unwrap();
        let out = d.join(format!("out-{name}"));
        refused(
            &calbench(&["run", path(&bad), "--out", path(&out)]),
            &[&format!("{file}: line {line}, {key}"), why],
        );
        assert!(!out.exists(), "{name}: nothing is written");
    }
    // The same claim at a point of the sweep is accepted: the file reads.
    let good = d.join("point-swept.toml");
    std::fs::write(&good, format!("{text}{sweep}{}", claim("paper_point = 1"))).unwrap();
    let o = calbench(&[
        "run",
        path(&good),
        "--trials",
        "1",
        "--out",
        path(&d.join("out-good")),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A registration study whose box has no extent in two directions draws collinear points,
/// which determine no registration: refused naming the file, the line and `size_mm`, where the
/// run failed with "registration: the points are (nearly) collinear" and no setting to blame;
/// nothing is written.
#[test]
fn a_registration_box_that_draws_collinear_points_is_refused_at_its_key() {
    let d = tmp("grid-flat-box");
    let root = crate::common::root();
    let text = std::fs::read_to_string(root.join("scenarios/ban-fig3.toml")).unwrap();
    let size = "size_mm = [800.0, 800.0, 800.0]";
    assert!(text.contains(size));
    let line = text.lines().position(|l| l == size).unwrap() + 1;
    let p = d.join("flat.toml");
    std::fs::write(
        &p,
        text.replacen(size, "size_mm = [800.0, 1e-12, 1e-12]", 1),
    )
    .unwrap();
    let out = d.join("out");
    let o = calbench(&["run", path(&p), "--trials", "2", "--out", path(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    // The study says what it runs first; the refusal is the last line.
    let last = err.trim_end().lines().last().unwrap_or("");
    let at = format!("flat.toml: line {line}, registration_study.size_mm: the points drawn");
    assert!(last.starts_with("error: ") && last.contains(&at), "{err}");
    assert!(last.contains("do not determine the registration"), "{err}");
    assert!(!out.exists());
}

/// More outliers than a pose list's rows had been refused only as the trials ran, as the
/// setting `outliers.count` of no file or line; it is refused as the study is planned (before
/// any trial, after the line saying the run starts), naming the scenario's file and the line
/// of `outliers.count`, and nothing is written. As many outliers as rows run.
#[test]
fn more_outliers_than_a_pose_list_s_rows_are_refused_at_the_scenario_s_line() {
    let d = tmp("outliers-pose-list");
    let root = crate::common::root();
    let rows: Vec<String> = (0..39)
        .map(|i| {
            let q: Vec<String> = (0..6)
                .map(|j| format!("{}", ((i * 7 + j * 13) % 80) as f64 - 40.0))
                .collect();
            q.join(",")
        })
        .collect();
    std::fs::write(
        d.join("poses39.csv"),
        format!("q1,q2,q3,q4,q5,q6\n{}\n", rows.join("\n")),
    )
    .unwrap();
    let text = std::fs::read_to_string(root.join("scenarios/ci-guard.toml")).unwrap();
    let text = text.replace(
        "strategies = [\"random\"]",
        "strategies = [\"file\"]\nposes_file = \"poses39.csv\"",
    );
    let line = 1 + text.lines().position(|l| l == "count = 2").unwrap();
    for (n, ok) in [(40, false), (39, true)] {
        let sc = d.join(format!("out{n}.toml"));
        std::fs::write(&sc, text.replace("count = 2\n", &format!("count = {n}\n"))).unwrap();
        let out = d.join(format!("o{n}"));
        let o = calbench(&["run", path(&sc), "--trials", "1", "--out", path(&out)]);
        if ok {
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            continue;
        }
        // Refused as the study is planned, after the line that says the run starts.
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && o.status.code() != Some(101), "{err}");
        let said = format!(
            "error: {}: line {line}, outliers.count: 40 outliers but the pose list ",
            sc.display()
        );
        assert!(err.contains(&said), "{err}");
        assert!(err.contains("gives only 39 calibration poses"), "{err}");
        assert!(!out.exists());
    }
}

/// A scenario's calibration pose list of fewer than three distinct poses had been accepted,
/// and every trial then failed with exit 0; one in radians for a robot in degrees had every
/// trial "converged" on a robot made worse. Both are refused before any trial: the first at
/// the pose list's line, as a measurement CSV is, the second at the scenario's line of
/// `calibration.poses_file`, with the cause `identify` names. Nothing is written.
#[test]
fn a_pose_list_of_one_pose_or_in_radians_is_refused_before_any_trial() {
    let d = tmp("pose-list-distinct");
    let root = crate::common::root();
    let text = std::fs::read_to_string(root.join("scenarios/ci-guard.toml")).unwrap();
    let text = text.replace(
        "strategies = [\"random\"]",
        "strategies = [\"file\"]\nposes_file = \"poses.csv\"",
    );
    let line = 1 + text
        .lines()
        .position(|l| l.starts_with("poses_file"))
        .unwrap();
    let sc = d.join("s.toml");
    std::fs::write(&sc, &text).unwrap();
    // The same pose 40 times; then 40 distinct poses, each within a degree of zero.
    let same = "10,20,30,40,50,60\n".repeat(40);
    let radians: String = (0..40)
        .map(|i| {
            let q: Vec<String> = (0..6)
                .map(|j| format!("{:.4}", 0.02 * (((i * 7 + j * 13) % 50) as f64 - 25.0)))
                .collect();
            q.join(",") + "\n"
        })
        .collect();
    for (rows, said) in [
        (
            same,
            "poses.csv: line 2: all 40 rows (lines 2 to 41) are the same pose".to_string(),
        ),
        (
            radians,
            format!(
                "{}: line {line}, calibration.poses_file: {}: every revolute joint value lies \
                 within",
                sc.display(),
                d.join("poses.csv").display()
            ),
        ),
    ] {
        std::fs::write(d.join("poses.csv"), format!("q1,q2,q3,q4,q5,q6\n{rows}")).unwrap();
        let out = d.join("o");
        let o = calbench(&["run", path(&sc), "--trials", "1", "--out", path(&out)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && o.status.code() != Some(101), "{err}");
        assert!(err.contains(&said), "{err} lacks {said}");
        assert!(!out.exists());
    }
}

/// A pose list `calibration.poses_file` without the strategy `file`, and an optimiser's
/// setting without an optimised strategy, had been read and ignored without a word. The run
/// goes on (the example scenario of docs/formats.md keeps such a key), and says which keys it
/// does not use; with the strategies that read them it says nothing of them.
#[test]
fn calibration_keys_no_strategy_reads_are_named_in_a_warning() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tmp("unused_keys");
    let rows: Vec<String> = (0..12)
        .map(|i| format!("{},{},{},0,{},0", 5 * i, -30 + 4 * i, 20 + 3 * i, 10 + i))
        .collect();
    let list = format!("q1,q2,q3,q4,q5,q6\n{}\n", rows.join("\n"));
    std::fs::write(d.join("poses.csv"), list).unwrap();
    let text = std::fs::read_to_string(root.join("scenarios/ci-guard.toml")).unwrap();
    let unused = "poses_file = \"poses.csv\"\ncandidates = 300\nseparate = true";
    for (strategies, warned) in [
        (
            "[\"random\"]",
            &["poses_file", "candidates", "separate"][..],
        ),
        ("[\"file\", \"detmax\"]", &[]),
    ] {
        let sc = d.join("s.toml");
        let with = format!("strategies = {strategies}\n{unused}");
        std::fs::write(&sc, text.replace("strategies = [\"random\"]", &with)).unwrap();
        let err = warnings_of_a_run(&sc, &d.join("o"));
        for key in ["poses_file", "candidates", "separate"] {
            let said = format!("warning: calibration.{key} is not used: no strategy of ");
            assert_eq!(
                err.contains(&said),
                warned.contains(&key),
                "{strategies}: {err}"
            );
        }
    }
    // A sweep of the strategies reads the pose list at its points of `file`: no warning.
    let swept = "poses_file = \"poses.csv\"";
    let with = format!("strategies = [\"random\"]\n{swept}");
    let sweep =
        "\n[sweep]\nkey = \"calibration.strategies\"\nvalues = [[\"random\"], [\"file\"]]\n";
    let sc = d.join("s.toml");
    let text = text.replace("strategies = [\"random\"]", &with) + sweep;
    std::fs::write(&sc, text).unwrap();
    let err = warnings_of_a_run(&sc, &d.join("o"));
    assert!(!err.contains("is not used"), "{err}");
}

/// The standard error of a one-trial `calbench run` of the scenario `sc` into `out`, which
/// must succeed (the folder is removed again).
fn warnings_of_a_run(sc: &std::path::Path, out: &std::path::Path) -> String {
    let o = calbench(&["run", path(sc), "--trials", "1", "--out", path(out)]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    std::fs::remove_dir_all(out).unwrap();
    err
}

/// `[errors]` sizes the kind does not read (`length_mm`, `angle_rad` with `none` or `values`,
/// `params` with `none`) had been ignored without a word: a run with `kind = "none"` and
/// `length_mm = 0.3` simulated a perfect robot. The run goes on and names each such key; a
/// kind that reads them, or a sweep of the kind, says nothing of them.
#[test]
fn error_sizes_the_kind_does_not_read_are_named_in_a_warning() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tmp("unused_errors");
    let text = std::fs::read_to_string(root.join("scenarios/ci-guard.toml")).unwrap();
    assert!(text.contains("\nkind = \"paper\"\n"));
    let sizes = "length_mm = 0.3\nangle_rad = 0.01\nparams = \"all\"";
    let sweep = "\n[sweep]\nkey = \"errors.kind\"\nvalues = [\"none\", \"paper\"]\n";
    for (kind, swept, warned) in [
        ("none", false, &["length_mm", "angle_rad", "params"][..]),
        ("paper", false, &[]),
        ("none", true, &[]),
    ] {
        let sc = d.join("s.toml");
        let with = format!("\nkind = \"{kind}\"\n{sizes}\n");
        let edited = text.replace("\nkind = \"paper\"\n", &with);
        std::fs::write(&sc, if swept { edited + sweep } else { edited }).unwrap();
        let err = warnings_of_a_run(&sc, &d.join("o"));
        for key in ["length_mm", "angle_rad", "params"] {
            let said = format!("warning: errors.{key} is not used: errors.kind is \"{kind}\"");
            assert_eq!(err.contains(&said), warned.contains(&key), "{kind}: {err}");
        }
        assert!(!err.contains("draws angle errors"), "{kind}: {err}");
    }
    // An angle error of 3 rad (degrees meant) is named: the run had printed η of -34873 %
    // without a word.
    let sc = d.join("s.toml");
    let degrees = text.replace(
        "\nkind = \"paper\"\n",
        "\nkind = \"paper\"\nangle_rad = 3.0\n",
    );
    std::fs::write(&sc, degrees).unwrap();
    let err = warnings_of_a_run(&sc, &d.join("o"));
    let said = "warning: errors.angle_rad = 3 rad (171.9°) draws angle errors beyond the 5° a \
                calibration moves: is it in degrees?";
    assert!(err.contains(said), "{err}");
}

/// An instruments study's `robot` that is neither built in nor a file had been refused as the
/// bare setting `robot`, naming neither the scenario nor its line, where a Monte-Carlo
/// scenario's robot is refused at its file, line and key.
#[test]
fn an_instruments_study_s_unknown_robot_is_refused_at_its_line() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tmp("instruments_robot");
    let text = std::fs::read_to_string(root.join("scenarios/instruments.toml")).unwrap();
    let line = 1 + text
        .lines()
        .position(|l| l.starts_with("robot = "))
        .unwrap();
    for robot in ["nosuch", "nope/x.toml"] {
        let sc = d.join("i.toml");
        let edited = text.replace("robot = \"irb2600\"", &format!("robot = \"{robot}\""));
        std::fs::write(&sc, edited).unwrap();
        for cmd in ["run", "simulate"] {
            let out = d.join("o");
            let o = calbench(&[cmd, path(&sc), "--out", path(&out)]);
            let err = String::from_utf8_lossy(&o.stderr);
            let said = format!("{}: line {line}, robot: \"", sc.display());
            assert!(!o.status.success() && err.contains(&said), "{cmd}: {err}");
            assert!(err.contains("is neither a built-in robot"), "{err}");
            assert!(!out.exists());
        }
    }
}

/// A robot file in metres declared in millimetres (`length_unit = "mm"`, `a = -0.612`) is a
/// robot 1000 times too small; a study of it ran without a word, its 0.5 mm errors a third of
/// the arm. The run goes on and says so, with the arm's size; so it does of a robot in degrees
/// whose limits are written in radians. The robots the repository ships (each built-in, and
/// each robot file) say nothing.
#[test]
fn a_robot_too_small_for_its_length_unit_is_named_in_a_warning() {
    let root = crate::common::root();
    let d = tmp("small-robot");
    let scenario = |robot: &str| {
        let sc = d.join("s.toml");
        let text = format!("name = \"s\"\n[robot]\n{robot}\n[[methods]]\nname = \"lm\"\n");
        std::fs::write(&sc, text).unwrap();
        warnings_of_a_run(&sc, &d.join("o"))
    };
    let ur10 = std::fs::read_to_string(root.join("examples/ipa-ur10/ur10.toml")).unwrap();
    let mut in_m = String::new();
    for line in ur10.lines() {
        let metres = |v: &str| format!("{}", v.parse::<f64>().unwrap() / 1000.0);
        in_m += &match line.split_once(" = ") {
            Some((k @ ("a" | "d"), v)) => format!("{k} = {}", metres(v)),
            _ => line.to_string(),
        };
        in_m.push('\n');
    }
    assert!(in_m.contains("a = -0.612\n"), "{in_m}");
    let small = d.join("ur10-m.toml");
    std::fs::write(&small, in_m).unwrap();
    let err = scenario(&format!("file = {:?}", path(&small)));
    assert!(
        err.contains(
            "warning: robot \"ur10\": its joints' lengths, offsets and travels add up to 1.683 \
             mm (its tool's 109.0 mm not counted): are its lengths in its length_unit (\"mm\")?"
        ),
        "{err}"
    );
    // `simulate` and `poses` of that scenario say so too (they had said nothing).
    let sc = d.join("s.toml");
    for command in ["simulate", "poses"] {
        let out = d.join(command);
        let mut args = vec![command, path(&sc), "--out", path(&out)];
        if command == "poses" {
            args.extend(["--strategy", "random"]);
        }
        let said = String::from_utf8_lossy(&calbench(&args).stderr).to_string();
        assert!(said.contains("add up to 1.683 mm"), "{command}: {said}");
    }
    // Limits written in radians in a robot in degrees: poses drawn within ±6.28° barely move
    // the arm, and the study had run without a word.
    let in_rad = ur10.replace("limits = [-360.0, 360.0]", "limits = [-6.2832, 6.2832]");
    assert!(!in_rad.contains("360.0"), "{in_rad}");
    let rad = d.join("ur10-rad.toml");
    std::fs::write(&rad, in_rad).unwrap();
    let err = scenario(&format!("file = {:?}", path(&rad)));
    assert!(
        err.contains(
            "warning: robot \"ur10\": every revolute joint's limits lie within ±6.35° (2π and \
             1 %): are they written in radians?"
        ),
        "{err}"
    );
    let robots = String::from_utf8(crate::common::calbench_ok(&["robots"]).stdout).unwrap();
    let builtins = robots.lines().filter_map(|l| l.split_whitespace().next());
    let shipped = [
        "examples/ipa-ur10/ur10.toml",
        "examples/barrett-wam/wam.toml",
    ];
    let files = (shipped.into_iter().chain(["robots/ban-irb2600.toml"]))
        .map(|f| format!("file = {:?}", path(&root.join(f))));
    for robot in builtins.map(|b| format!("builtin = {b:?}")).chain(files) {
        let err = scenario(&robot);
        assert!(!err.contains("warning"), "{robot}: {err}");
    }
}

/// A robot whose tool point never moves (every length and offset zero): a study runs, every
/// identification fails, and the terminal says why; a failed trial's largest validation error
/// is an empty cell, as its mean and RMS are, not 0 (a perfect result).
#[test]
fn a_study_whose_identifications_all_fail_says_how_they_ended() {
    let d = tmp("dot");
    let joint = "[[joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 0.0\nd = 0.0\ntheta = 0.0\n\
                 limits = [-180.0, 180.0]\n\n";
    let robot = format!(
        "name = \"dot\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n\n{}",
        joint.repeat(6)
    );
    std::fs::write(d.join("dot.toml"), robot).unwrap();
    std::fs::write(
        d.join("s.toml"),
        "name = \"dot\"\nseed = 3\ntrials = 3\n[robot]\nfile = \"dot.toml\"\n[errors]\n\
         kind = \"normal\"\nlength_mm = 0.3\nangle_rad = 0.003\n[calibration]\ncount = 40\n\
         strategies = [\"random\"]\n[validation]\ncount = 20\n[[methods]]\nname = \"lm\"\n",
    )
    .unwrap();
    let out = d.join("r");
    let o = calbench(&["run", path(&d.join("s.toml")), "--out", path(&out)]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}");
    assert!(
        text.contains("lm / random: 3 of 3 identifications failed (ended: invalid-input 3)"),
        "{text}"
    );
    let trials = crate::common::read(&out.join("trials.csv"));
    let mut rows = csv::Reader::from_reader(trials.as_bytes());
    let header = rows.headers().unwrap().clone();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for row in rows.records().map(Result::unwrap) {
        assert_eq!(&row[col("termination")], "invalid-input");
        assert_eq!(&row[col("after_max_mm")], "", "{row:?}");
        assert!(row[col("before_max_mm")].parse::<f64>().unwrap() > 0.0);
    }
}

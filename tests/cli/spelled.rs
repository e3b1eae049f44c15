//! The library names no front end's flag: a refusal carries the option it names by type
//! (`calbench::error::Opt`), and the command line spells it (`--allow-worse`) as Python does
//! its own way (`allow_worse=True`, python/tests/test_api.py). A refusal the data cause
//! (points that do not determine the registration) names the data file.

use std::path::Path;

use calbench::error::{Error, Opt, Said};

use crate::common::{calbench, import_ur10_sample, path_arg, positions_only, root, tmp_dir};

/// The library's folders whose messages reach a user through a front end.
const LIBRARY: [&str; 7] = [
    "src/calibrate",
    "src/identify",
    "src/study",
    "src/robot",
    "src/measurement",
    "src/sim",
    "src/report",
];

/// Every `.rs` file under `dir`.
fn sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// No line of the library's code (comments apart) spells a flag (`--` and a lowercase
/// letter): the option is an `Opt`, which each front end spells.
#[test]
fn the_library_spells_no_flag() {
    let mut files = Vec::new();
    for d in LIBRARY {
        sources(&root().join(d), &mut files);
    }
    assert!(files.len() > 50, "{} files", files.len());
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (i, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("//") {
                continue;
            }
            let b = line.as_bytes();
            let flag = (0..b.len().saturating_sub(2))
                .any(|k| b[k] == b'-' && b[k + 1] == b'-' && b[k + 2].is_ascii_lowercase());
            if flag {
                found.push(format!("{}:{}: {line}", f.display(), i + 1));
            }
        }
    }
    assert!(
        found.is_empty(),
        "flags spelled in the library:\n{}",
        found.join("\n")
    );
}

/// A tracker's file whose points lie on a line does not determine the registration: refused
/// naming the file (and the cause), and the command line names its options as flags
/// (`--fix`) where a refusal names one.
#[test]
fn refusals_name_the_file_and_the_flags() {
    let d = tmp_dir("spelled");
    let full = d.join("ur.csv");
    import_ur10_sample(&crate::common::ur10_example("mapping.toml"), &full);
    let pos = d.join("pos.csv");
    positions_only(&full, &pos);
    let text: String = std::fs::read_to_string(&pos)
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut c: Vec<&str> = l.split(',').collect();
            if i > 0 {
                c[7] = "0";
                c[8] = "0";
            }
            c.join(",") + "\n"
        })
        .collect();
    let line = d.join("line.csv");
    std::fs::write(&line, text).unwrap();
    let robot = crate::common::ur10_example("ur10.toml");
    let out = d.join("out");
    let identify = |data: &Path, extra: &[&str]| {
        let mut a = vec!["identify", "--robot", &robot, "--data", path_arg(data)];
        a.extend_from_slice(&["--method", "ls", "--out", path_arg(&out)]);
        a.extend_from_slice(extra);
        calbench(&a)
    };
    let o = identify(&line, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains(&format!("{}: data:", line.display())), "{err}");
    assert!(err.contains("collinear"), "{err}");
    assert!(!out.exists());
    let o = identify(&pos, &["--fix", "a2,a2"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("error: setting `--fix`: `a2` is given twice"),
        "{err}"
    );
}

/// An option named in a refusal is spelled by each front end its own way; the library's
/// own text names it in backquotes.
#[test]
fn options_are_spelled_by_the_front_end() {
    let cli = |o: Opt, _: bool| format!("--{}", o.name().replace('_', "-"));
    let py = |o: Opt, on: bool| {
        if on {
            format!("{}=True", o.name())
        } else {
            o.name().to_string()
        }
    };
    let msg = Said::from("leave it out of ")
        .name(Opt::Params)
        .text(", or pass ");
    let e = Error::file("d.csv", "data", msg.on(Opt::AllowRankDeficient));
    assert_eq!(
        e.spelled(cli),
        "d.csv: data: leave it out of --params, or pass --allow-rank-deficient"
    );
    assert_eq!(
        e.spelled(py),
        "d.csv: data: leave it out of params, or pass allow_rank_deficient=True"
    );
    assert_eq!(
        e.to_string(),
        "d.csv: data: leave it out of `params`, or pass `allow_rank_deficient`"
    );
    let e = Error::option(Opt::Fix, "`a2` is given twice");
    assert_eq!(e.spelled(cli), "setting `--fix`: `a2` is given twice");
    assert_eq!(e.spelled(py), "setting `fix`: `a2` is given twice");
    assert_eq!(e.key(), Some("fix"));
    let e = Error::setting("tracker.coverage", "bad");
    assert_eq!(e.spelled(cli), e.to_string());
}

//! The command line as a user meets it: options with a fixed set of values are refused by the
//! argument parser with the allowed values listed (the same names as in files and reports),
//! `--help` lists them, and `--out` is checked before any work: a file where a folder goes,
//! a folder where a file goes, or an output file whose name is taken by a folder is refused,
//! naming it, and nothing is written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use strum::IntoEnumIterator as _;

fn tmp(name: &str) -> crate::common::TmpDir {
    crate::common::tmp_dir(&format!("typed-{name}"))
}

fn calbench<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_calbench"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn root(path: &str) -> String {
    crate::common::root().join(path).display().to_string()
}

/// Fails unless `o` is a refusal (exit status `code`, no panic) whose stderr has every `words`.
fn refused(o: &Output, code: i32, words: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(code), "{err}");
    for w in words {
        assert!(err.contains(w), "`{w}` missing from: {err}");
    }
}

/// The files and folders under `dir`, with each file's bytes: to show that a refused command
/// left a folder as it was.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Option<Vec<u8>>)> {
    let mut v = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p.clone());
                v.push((p, None));
            } else {
                let bytes = std::fs::read(&p).unwrap();
                v.push((p, Some(bytes)));
            }
        }
    }
    v.sort();
    v
}

const STRATEGIES: [&str; 7] = [
    "random",
    "detmax",
    "ide",
    "detmax-ide",
    "detmax-full",
    "ide-full",
    "detmax-ide-full",
];

#[test]
fn unknown_values_are_refused_listing_the_allowed_ones() {
    let out = tmp("values").join("out");
    let o = out.to_str().unwrap();
    let scenario = root("scenarios/ci-guard.toml");
    let identify = |extra: &[&str]| {
        let mut args = vec!["identify", "--robot", "irb2600", "--data", "x.csv"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", o]);
        calbench(&args)
    };
    let cases: Vec<(Output, &str, Vec<&str>)> = vec![
        (
            calbench(&["poses", &scenario, "--strategy", "detmax-fast", "--out", o]),
            "detmax-fast",
            STRATEGIES.to_vec(),
        ),
        (
            calbench(&[
                "identifiability",
                "--robot",
                "irb2600",
                "--measure",
                "angle",
            ]),
            "angle",
            vec!["position", "pose"],
        ),
        (
            identify(&["--method", "gauss"]),
            "gauss",
            calbench::identify::METHODS.iter().map(|m| m.name).collect(),
        ),
        (
            identify(&["--method", "lm", "--registration", "best"]),
            "best",
            vec!["svd", "wsvd", "identify", "known"],
        ),
        (
            identify(&["--method", "lm", "--export", "zip"]),
            "zip",
            vec!["urdf", "toml"],
        ),
        (
            calbench(&["robots", "ur5"]),
            "ur5",
            calbench::robot::builtin::BUILTINS
                .iter()
                .map(|b| b.name)
                .collect(),
        ),
    ];
    for (o, bad, allowed) in &cases {
        let mut words = vec![*bad, "possible values"];
        words.extend(allowed);
        refused(o, 2, &words);
    }
    assert!(!out.exists());
}

#[test]
fn help_lists_the_allowed_values() {
    let help = |cmd: &str| String::from_utf8(calbench(&[cmd, "--help"]).stdout).unwrap();
    let poses = help("poses");
    for s in STRATEGIES {
        assert!(poses.contains(s), "poses --help lacks {s}:\n{poses}");
    }
    let identify = help("identify");
    for m in calbench::identify::METHODS {
        assert!(
            identify.contains(m.name),
            "identify --help lacks {}",
            m.name
        );
    }
    for r in ["svd", "wsvd", "identify", "known", "urdf", "toml"] {
        assert!(identify.contains(r), "identify --help lacks {r}");
    }
    assert!(help("identifiability").contains("position, pose"));
}

/// The numbers of `--q` and `--curve` are comma-separated; a negative first joint value is a
/// value, not an option; `--q` is given once.
#[test]
fn number_lists_take_negative_values_and_refuse_what_is_not_a_number() {
    let fk = |q: &[&str]| {
        let mut args = vec!["fk", "--robot", "irb2600"];
        args.extend_from_slice(q);
        calbench(&args)
    };
    let a = fk(&["--q", "-10,20,30,0,45,0", "--json"]);
    let b = fk(&["--q=-10, 20,30,0,45,0", "--json"]);
    assert!(a.status.success(), "{}", stderr(&a));
    assert_eq!(a.stdout, b.stdout);
    refused(&fk(&["--q", "1,2,3"]), 1, &["--q", "3 joint values"]);
    refused(
        &fk(&["--q", "1,2,x,4,5,6"]),
        2,
        &["'x'", "not a finite number"],
    );
    refused(&fk(&["--q", "1,2,3,4,5,inf"]), 2, &["'inf'", "finite"]);
    refused(
        &fk(&["--q", "1,2,3,4,5,6", "--q", "1,2,3,4,5,6"]),
        2,
        &["--q"],
    );
    let out = tmp("curve").join("out");
    let scenario = root("scenarios/ci-guard.toml");
    let poses = |curve: &str| {
        calbench(&[
            "poses",
            &scenario,
            "--strategy",
            "random",
            "--curve",
            curve,
            "--out",
            out.to_str().unwrap(),
        ])
    };
    refused(&poses("20,x"), 2, &["'x'", "--curve"]);
    refused(&poses("20,0"), 1, &["--curve", "\"0\"", "1..="]);
    // A count given twice would print one point twice.
    refused(&poses("10,20,10"), 1, &["--curve", "10 is given twice"]);
    // Too few poses for the parameters: the refusal names `--count`, which gave the count,
    // not the scenario's `calibration.count`.
    let few = calbench(&[
        "poses",
        &scenario,
        "--strategy",
        "detmax",
        "--count",
        "5",
        "--out",
        out.to_str().unwrap(),
    ]);
    refused(&few, 1, &["setting `--count`: 5 poses give fewer rows"]);
    assert!(!out.exists());
}

/// `--out` naming an existing file, for every command that writes a folder, and naming an
/// existing folder, for the commands that write one file: refused before any work, naming
/// it, and the file or folder is left as it was.
#[test]
fn out_in_the_way_is_refused_naming_it_for_every_command() {
    let dir = tmp("out");
    let file = dir.join("taken.txt");
    std::fs::write(&file, "mine\n").unwrap();
    let f = file.to_str().unwrap();
    let d = dir.to_str().unwrap();
    let scenario = root("scenarios/ci-guard.toml");
    let shard = dir.join("shard");
    std::fs::create_dir(&shard).unwrap();
    let s = shard.to_str().unwrap();
    let folder_commands: Vec<Vec<&str>> = vec![
        vec!["run", &scenario, "--trials", "2"],
        vec!["merge", s],
        vec!["simulate", &scenario],
        vec![
            "identify", "--robot", "irb2600", "--data", "x.csv", "--method", "lm",
        ],
        vec!["poses", &scenario, "--strategy", "random"],
    ];
    for mut args in folder_commands {
        args.extend_from_slice(&["--out", f]);
        refused(&calbench(&args), 1, &["--out", f, "not a folder"]);
    }
    let raw = root("examples/ipa-ur10/sample-200.csv");
    let mapping = root("examples/ipa-ur10/mapping.toml");
    let file_commands: Vec<Vec<&str>> = vec![
        vec!["import", &raw, "--mapping", &mapping],
        vec![
            "compensate",
            "--robot",
            "irb2600",
            "--identified",
            "irb2600",
            "--joints",
            "x.csv",
        ],
    ];
    let before = snapshot(&dir);
    for mut args in file_commands {
        args.extend_from_slice(&["--out", d]);
        refused(&calbench(&args), 1, &["--out", d, "is a folder"]);
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine\n");
    assert_eq!(snapshot(&dir), before);
}

/// `import` and `compensate` replace an existing file (`--out` names the file to write).
#[test]
fn import_replaces_an_existing_file() {
    let dir = tmp("replace");
    let csv = dir.join("ur10.csv");
    std::fs::write(&csv, "old\n").unwrap();
    let o = calbench(&[
        "import",
        &root("examples/ipa-ur10/sample-200.csv"),
        "--mapping",
        &root("examples/ipa-ur10/mapping.toml"),
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("q1,q2,q3,q4,q5,q6,x,y,z"), "{text}");
}

/// A folder where `run` writes a file — `trials.csv`, `report.md` — is refused before the run,
/// naming it, and the output folder is left as it was: no summary.json, no partial folder.
#[test]
fn run_into_a_folder_holding_a_folder_named_like_an_output_writes_nothing() {
    let scenario = root("scenarios/ci-guard.toml");
    for name in ["trials.csv", "report.md"] {
        let dir = tmp(&format!("blocked-{name}"));
        let out = dir.join("out");
        std::fs::create_dir_all(out.join(name)).unwrap();
        std::fs::write(out.join(name).join("inside.txt"), "x").unwrap();
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        let before = snapshot(&dir);
        let o = calbench(&[
            "run",
            &scenario,
            "--trials",
            "2",
            "--out",
            out.to_str().unwrap(),
        ]);
        let blocked = out.join(name);
        refused(&o, 1, &["--out", blocked.to_str().unwrap(), "is a folder"]);
        assert_eq!(snapshot(&dir), before, "{name}");
    }
}

/// A folder named like an output that is not checked before the work (a plot of the run) is
/// found before any file is moved into the output folder: the run fails naming it and the
/// folder is left as it was.
#[test]
fn run_checks_every_output_before_moving_any() {
    let dir = tmp("blocked-plot");
    let out = dir.join("out");
    std::fs::create_dir_all(out.join("eta.png")).unwrap();
    std::fs::write(out.join("summary.json"), "old").unwrap();
    let before = snapshot(&dir);
    let o = calbench(&[
        "run",
        &root("scenarios/ci-guard.toml"),
        "--trials",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let blocked = out.join("eta.png");
    refused(&o, 1, &[blocked.to_str().unwrap(), "is a folder"]);
    assert_eq!(snapshot(&dir), before);
}

/// The same for `simulate`, `identify` and `poses`: their output folders are checked the
/// same way before any work.
#[test]
fn every_folder_command_refuses_a_folder_named_like_an_output() {
    let scenario = root("scenarios/ci-guard.toml");
    let dir = tmp("blocked-others");
    let cases: [(&str, Vec<&str>); 3] = [
        ("truth.json", vec!["simulate", &scenario]),
        (
            "identified.json",
            vec![
                "identify", "--robot", "irb2600", "--data", "x.csv", "--method", "lm",
            ],
        ),
        (
            "scores.json",
            vec!["poses", &scenario, "--strategy", "random"],
        ),
    ];
    for (name, mut args) in cases {
        let out = dir.join(name.replace('.', "-"));
        std::fs::create_dir_all(out.join(name)).unwrap();
        let before = snapshot(&dir);
        let o = out.to_str().unwrap().to_string();
        args.extend_from_slice(&["--out", &o]);
        let blocked = out.join(name);
        refused(
            &calbench(&args),
            1,
            &["--out", blocked.to_str().unwrap(), "is a folder"],
        );
        assert_eq!(snapshot(&dir), before, "{name}");
    }
}

/// `poses --strategy X-full` optimises over the full model, as the scenario strategy does,
/// and names itself so in scores.json.
#[test]
fn poses_takes_the_full_model_strategies() {
    let dir = tmp("full");
    let scenario = dir.join("small.toml");
    let text = std::fs::read_to_string(root("scenarios/ci-guard.toml"))
        .unwrap()
        .replace("count = 40\n", "count = 40\ncandidates = 60\n");
    std::fs::write(&scenario, text).unwrap();
    let out = dir.join("out");
    let o = calbench(&[
        "poses",
        scenario.to_str().unwrap(),
        "--strategy",
        "detmax-full",
        "--count",
        "12",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("by detmax-full"));
    let scores: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("scores.json")).unwrap()).unwrap();
    assert_eq!(scores["strategy"], "detmax-full");
    assert_eq!(scores["count"], 12);
}

/// The names an enum gives on the command line and in messages (its `strum` derive) are the
/// names of files and reports (its serde derive), variant by variant.
#[test]
fn command_line_names_are_the_file_names() {
    fn agree<T>()
    where
        T: strum::IntoEnumIterator
            + strum::VariantNames
            + Into<&'static str>
            + serde::de::DeserializeOwned
            + PartialEq
            + std::fmt::Debug
            + Copy,
    {
        let names: Vec<&'static str> = T::iter().map(Into::into).collect();
        assert_eq!(names, T::VARIANTS);
        for v in T::iter() {
            let name: &'static str = v.into();
            let read: T = calbench::robot::names::parse("name", name).unwrap();
            assert_eq!(read, v, "{name}");
        }
    }
    fn written<T: strum::IntoEnumIterator + Into<&'static str> + serde::Serialize + Copy>() {
        for v in T::iter() {
            let name: &'static str = v.into();
            assert_eq!(serde_json::to_value(v).unwrap(), name);
        }
    }
    use calbench::calibrate::{Registration, RoundsEnd};
    use calbench::identify::qiao::error_models::ErrorModel;
    use calbench::identify::Termination;
    use calbench::poses::{Objective, Strategy};
    use calbench::robot::{AngleUnit, Convention, JointType, LengthUnit};
    use calbench::sim::settings::MeasureSetting;
    use calbench::study::scenario::StrategyName;
    agree::<Registration>();
    agree::<RoundsEnd>();
    agree::<ErrorModel>();
    agree::<Termination>();
    agree::<Objective>();
    agree::<Strategy>();
    agree::<Convention>();
    agree::<JointType>();
    agree::<LengthUnit>();
    agree::<AngleUnit>();
    agree::<MeasureSetting>();
    agree::<StrategyName>();
    written::<Registration>();
    written::<RoundsEnd>();
    written::<ErrorModel>();
    written::<Termination>();
    written::<Objective>();
    written::<Strategy>();
    written::<Convention>();
    written::<JointType>();
    written::<LengthUnit>();
    written::<AngleUnit>();
    written::<StrategyName>();
    let names: Vec<&str> = StrategyName::iter().map(Into::into).collect();
    for s in ["detmax-full", "ide-full", "detmax-ide-full"] {
        assert!(names.contains(&s), "{names:?}");
    }
}

/// A scenario naming an unknown pose strategy is refused with every strategy listed, the
/// full-model ones included.
#[test]
fn an_unknown_scenario_strategy_lists_every_strategy() {
    let dir = tmp("scenario-strategy");
    let path = dir.join("s.toml");
    let text = std::fs::read_to_string(root("scenarios/ci-guard.toml"))
        .unwrap()
        .replace(
            "strategies = [\"random\"]",
            "strategies = [\"detmax-fast\"]",
        );
    std::fs::write(&path, text).unwrap();
    let out = dir.join("out");
    let o = calbench(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let mut words = vec![
        "calibration.strategies[0]",
        "detmax-fast",
        "box",
        "grid",
        "file",
    ];
    words.extend(STRATEGIES);
    refused(&o, 1, &words);
}

/// The pose strategies are one table: every optimiser has a name on the separated and on the
/// full model, each name maps back to its optimiser, `Strategy`'s own names are the table's,
/// and no source file under `src/` or `python/src/` spells a full-model name out beside the
/// table (outside its tests).
#[test]
fn the_pose_strategies_are_declared_once() {
    use calbench::poses::Strategy;
    use calbench::study::scenario::StrategyName;
    use strum::IntoEnumIterator as _;
    for o in Strategy::iter() {
        for full in [false, true] {
            let name = StrategyName::of(o, full);
            let model = if o == Strategy::Random { false } else { full };
            assert_eq!(name.selection(), Some((o, model)), "{}", name.as_str());
        }
        assert_eq!(o.as_str(), StrategyName::of(o, false).as_str());
    }
    let mut hits = Vec::new();
    let top = crate::common::root();
    let mut stack = vec![top.join("src"), top.join("python/src")];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs")
                && p.file_name().unwrap() != "tests.rs"
            {
                let text = std::fs::read_to_string(&p).unwrap();
                // The file's own tests start at its `#[cfg(test)]` module.
                let code = text.split("#[cfg(test)]\nmod tests").next().unwrap();
                hits.extend(
                    code.matches("detmax-ide-full")
                        .map(|_| p.display().to_string()),
                );
            }
        }
    }
    assert!(hits.len() <= 1, "{hits:?}");
}

//! The corpora of the fuzz tests ([`super`]): the built-in robots as `calbench robots NAME`
//! prints them, the shipped scenarios (and a robot file beside one, and a sweep), the CSVs
//! `calbench simulate` writes, the shipped URDFs; and the keys the TOML mutations rename to.

use std::path::PathBuf;
use std::sync::OnceLock;

use calbench::robot::{builtin, robot_to_toml, Robot};

use super::scratch;
use crate::common::{calbench_ok, path_arg, root, tmp_dir, write_scenario};

/// The keys and table headers of the files in `corpus` (TOML).
fn keys_of(corpus: &[Vec<u8>]) -> Vec<String> {
    let mut keys: Vec<String> = Vec::new();
    for f in corpus {
        for l in String::from_utf8_lossy(f).lines() {
            let l = l.trim();
            let k = if l.starts_with('[') {
                l.to_string()
            } else if let Some((k, _)) = l.split_once('=') {
                k.trim().to_string()
            } else {
                continue;
            };
            if !k.is_empty() && !k.starts_with('#') && !keys.contains(&k) {
                keys.push(k);
            }
        }
    }
    keys.sort();
    keys
}

/// The built-in robots as `calbench robots NAME` prints them.
pub(super) fn robot_corpus() -> &'static [Vec<u8>] {
    static C: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    C.get_or_init(|| {
        builtin::BUILTINS
            .iter()
            .map(|b| format!("# {}\n{}", b.summary, robot_to_toml(&(b.build)())).into_bytes())
            .collect()
    })
}

pub(super) fn robot_keys() -> &'static [String] {
    static K: OnceLock<Vec<String>> = OnceLock::new();
    K.get_or_init(|| {
        let mut k = keys_of(robot_corpus());
        k.extend(
            [
                "beta",
                "base",
                "tool",
                "[coupling]",
                "kind",
                "l1",
                "xyz",
                "rpy",
            ]
            .map(String::from),
        );
        k
    })
}

/// The shipped scenarios.
pub(super) fn scenario_corpus() -> &'static [Vec<u8>] {
    static C: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    C.get_or_init(|| {
        let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("scenarios"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        assert!(files.len() >= 3, "scenarios/*.toml not found");
        // Registration studies (`[registration_study]`, Ban fig. 3) and instruments studies
        // (`[[measurement]]`) are other formats, not read by `Scenario::parse`.
        // A shipped scenario's robot file (`file = "../robots/…"`, resolved against the
        // scenario's folder) is named by its absolute path, as the corpus is parsed elsewhere.
        let robots = format!("file = \"{}/", root().display());
        let mut corpus: Vec<Vec<u8>> = files
            .iter()
            .map(|p| std::fs::read_to_string(p).unwrap())
            .filter(|f| !f.contains("[registration_study]") && !f.contains("[[measurement]]"))
            .map(|f| f.replace("file = \"../", &robots).into_bytes())
            .collect();
        // A robot file beside the scenario ([`SCENARIO_ROBOT`]) and a sweep, which no shipped
        // scenario has.
        let guard = std::fs::read_to_string(root().join("scenarios/ci-guard.toml")).unwrap();
        // A robot file carries no stiffness: its sag model names one per joint.
        let file = guard
            .replace(
                "builtin = \"irb2600\"",
                &format!("file = \"{SCENARIO_ROBOT}\""),
            )
            .replace(
                "model = \"linear\"",
                "model = \"linear\"\nstiffness_nm_per_rad = [4e6, 3.5e6, 2.5e6, 4e5, 4e5, 2e5]",
            );
        assert_ne!(file, guard);
        corpus.push(file.into_bytes());
        corpus.push(
            format!("{guard}\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 2]\n").into_bytes(),
        );
        corpus
    })
}

/// The robot file the scenario corpus refers to, written beside each case's scenario.
pub(super) const SCENARIO_ROBOT: &str = "fuzz-robot.toml";

/// Writes [`SCENARIO_ROBOT`] into the calling thread's scratch folder.
pub(super) fn write_scenario_robot() -> PathBuf {
    let p = scratch().join(SCENARIO_ROBOT);
    std::fs::write(&p, robot_to_toml(&builtin::irb2600())).unwrap();
    p
}

pub(super) fn scenario_keys() -> &'static [String] {
    static K: OnceLock<Vec<String>> = OnceLock::new();
    K.get_or_init(|| {
        let mut k = keys_of(scenario_corpus());
        // Keys no shipped scenario uses.
        k.extend(
            [
                "[sweep]",
                "key",
                "values",
                "file",
                "poses_file",
                "robot.file",
                "sweep.key",
            ]
            .map(String::from),
        );
        k
    })
}

/// Measurement CSVs written by `calbench simulate` (position-only and full-pose) and the
/// robot each belongs to.
pub(super) fn csv_corpus() -> &'static (Vec<Vec<u8>>, Vec<Robot>) {
    static C: OnceLock<(Vec<Vec<u8>>, Vec<Robot>)> = OnceLock::new();
    C.get_or_init(|| {
        let mut files = Vec::new();
        let mut robots = Vec::new();
        let studies = [
            ("position", "irb2600", "position"),
            ("pose", "tx60", "pose"),
        ];
        for (tag, robot, measure) in studies {
            let scenario = format!(
                "name = \"fuzz-{tag}\"\nseed = 7\ntrials = 1\n\
                 [robot]\nbuiltin = \"{robot}\"\n[errors]\nkind = \"paper\"\n\
                 [tracker]\nmeasure = \"{measure}\"\n\
                 [calibration]\ncount = 12\nstrategies = [\"random\"]\n\
                 [validation]\ncount = 4\n[[methods]]\nname = \"ls\"\n"
            );
            let dir = tmp_dir(&format!("fuzz-simulate-{tag}"));
            let path = write_scenario(&dir, "scenario", &scenario);
            calbench_ok(&["simulate", path_arg(&path), "--out", path_arg(&dir)]);
            for f in ["measurements.csv", "validation.csv"] {
                files.push(std::fs::read(dir.join(f)).unwrap());
                robots.push(builtin::load(robot).unwrap());
            }
            std::fs::remove_dir_all(&dir).unwrap();
        }
        (files, robots)
    })
}

/// The shipped URDFs, each with the tip link its chain ends at (`None`: the only leaf).
pub(super) const URDFS: [(&str, Option<&str>); 3] = [
    ("examples/ipa-ur10/ur10.urdf", None),
    ("data/mukca/kuka_14/iiwa14.urdf", None),
    ("data/mukca/panda.urdf", Some("ball_link")),
];

/// The texts of [`URDFS`].
pub(super) fn urdf_corpus() -> &'static [Vec<u8>] {
    static C: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    C.get_or_init(|| {
        URDFS
            .iter()
            .map(|(f, _)| std::fs::read(root().join(f)).unwrap())
            .collect()
    })
}

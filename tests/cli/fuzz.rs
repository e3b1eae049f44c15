//! Fuzz and property tests of the input parsers: robot files, scenario files and measurement
//! CSVs get random bytes and structured mutations of valid files (the built-in robots as
//! `calbench robots NAME` prints them, the shipped `scenarios/*.toml`, CSVs written by
//! `calbench simulate`), URDFs structured mutations of the shipped ones. Properties: nothing panics, every error names the file, and what is
//! accepted is usable (finite, in range, within the joint limits).
//!
//! Each parser gets [`CASES`] cases per property in the normal run, from a fixed seed so the
//! run is repeatable. The `#[ignore]`d `*_long` tests run [`LONG_CASES`] cases from a random
//! seed: `cargo test --test cli -- --ignored _long` (`CALBENCH_FUZZ_CASES` and
//! `CALBENCH_FUZZ_SEED` override the count and the seed; `CALBENCH_FUZZ_COLLECT=1` prints
//! every message without the file and goes on, to list them all in one run).
//!
//! The mutations are in `fuzz/mutate.rs`, the corpora of valid files in `fuzz/corpus.rs`.
//!
//! Gaps the fuzzing found are pinned by tests with the exact input that showed them (a sweep
//! that overflowed the stack, an unknown `robot.builtin` or an unreadable `robot.file` refused
//! without the scenario file).

mod corpus;
mod mutate;

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};

use calbench::measurement::csv::read_measurements;
use calbench::robot::urdf::{UrdfChain, UrdfRobot};
use calbench::robot::{parse_robot_file, read_robot_file, robot_to_toml, Robot};
use calbench::study::scenario::Scenario;

use crate::common::{calbench, path_arg, root, tmp_dir, write_scenario};
use corpus::{
    csv_corpus, robot_corpus, robot_keys, scenario_corpus, scenario_keys, urdf_corpus,
    write_scenario_robot, URDFS,
};
use mutate::{csv_mutation, mutated, random_bytes, toml_mutation, urdf_mutation};

/// Cases per property in the normal run.
const CASES: u32 = 10_000;
/// Cases per property in the `#[ignore]`d long run.
const LONG_CASES: u32 = 500_000;
/// The seed of the normal run.
const SEED: u64 = 0x00ca_1be4_c4f0_2200;

// ---------------------------------------------------------------------------------------------
// Running

/// Runs `test` on `cases` values of `strategy`, from `seed` (random when `None`), and fails
/// with the smallest failing input proptest finds.
fn fuzz<S: Strategy>(
    cases: u32,
    seed: Option<u64>,
    strategy: S,
    test: impl Fn(S::Value) -> Result<(), TestCaseError>,
) where
    S::Value: std::fmt::Debug,
{
    let seed = seed.unwrap_or_else(|| {
        use std::hash::{BuildHasher, RandomState};
        RandomState::new().hash_one(std::time::SystemTime::now())
    });
    let config = Config {
        cases,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(seed),
        max_shrink_iters: 4096,
        ..Config::default()
    };
    let mut runner = TestRunner::new(config);
    let result = runner.run(&strategy, test);
    let _ = std::fs::remove_dir_all(scratch());
    if let Err(e) = result {
        panic!("seed {seed:#x}: {e}");
    }
}

/// Cases and seed of a long run: [`LONG_CASES`] from a random seed unless the environment
/// says otherwise.
fn long_run() -> (u32, Option<u64>) {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let cases = env("CALBENCH_FUZZ_CASES").map_or(LONG_CASES, |c| c as u32);
    (cases, env("CALBENCH_FUZZ_SEED"))
}

/// A scratch folder for the calling thread (one test): in memory (`/dev/shm`) where there is
/// one, since every case writes a file, else the temporary folder. [`fuzz`] removes it.
fn scratch() -> PathBuf {
    let shm = Path::new("/dev/shm");
    let base = if shm.is_dir() {
        shm.to_path_buf()
    } else {
        std::env::temp_dir()
    };
    let thread = std::thread::current();
    let name = thread.name().unwrap_or("main").replace("::", "-");
    let d = base
        .join("calbench-fuzz")
        .join(format!("{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A file for the cases of one property.
fn case_file(tag: &str, ext: &str) -> PathBuf {
    scratch().join(format!("{tag}.{ext}"))
}

/// Fails unless the error message names `path`.
fn names_file(msg: &str, path: &Path) -> Result<(), TestCaseError> {
    let shown = path.display().to_string();
    if std::env::var("CALBENCH_FUZZ_COLLECT").is_ok() && !msg.contains(&shown) {
        eprintln!("GAP: {msg}");
        return Ok(());
    }
    prop_assert!(
        msg.contains(&shown),
        "the message does not name the file {shown}: {msg}"
    );
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Properties

/// What is accepted is a usable robot: every value checked, forward kinematics finite over
/// the joint range, and the robot written back reads back the same.
fn robot_is_usable(r: &Robot) -> Result<(), TestCaseError> {
    prop_assert_eq!(r.check(), Ok(()));
    for t in [0.0, 0.5, 1.0] {
        let q: Vec<f64> = r
            .joints
            .iter()
            .map(|j| j.limits.0 + t * (j.limits.1 - j.limits.0))
            .collect();
        let f = r.fk(&q);
        prop_assert!(
            f.pos.iter().chain(f.rot.iter()).all(|v| v.is_finite()),
            "forward kinematics not finite at {:?}",
            q
        );
    }
    let text = robot_to_toml(r);
    let back = parse_robot_file(&text, Path::new("written.toml"))
        .map_err(|e| TestCaseError::fail(format!("written robot refused: {e}\n{text}")))?;
    prop_assert_eq!(&back.name, &r.name);
    prop_assert_eq!(back.dof(), r.dof());
    for (a, b) in back.values.iter().zip(&r.values) {
        prop_assert!((a - b).abs() <= 1e-9 * a.abs().max(1.0), "{} vs {}", a, b);
    }
    Ok(())
}

/// The robot parser on `bytes`: from text, and from a file.
fn robot_property(bytes: &[u8]) -> Result<(), TestCaseError> {
    let path = case_file("robot", "toml");
    let text = String::from_utf8_lossy(bytes);
    match parse_robot_file(&text, &path) {
        Ok(r) => robot_is_usable(&r)?,
        Err(e) => names_file(&e.to_string(), &path)?,
    }
    std::fs::write(&path, bytes).unwrap();
    match read_robot_file(&path) {
        Ok(r) => robot_is_usable(&r)?,
        Err(e) => names_file(&e.to_string(), &path)?,
    }
    Ok(())
}

/// The scenario parser on `bytes`, beside [`corpus::SCENARIO_ROBOT`]. An error inside a robot file
/// the scenario refers to may name that file instead of the scenario.
fn scenario_property(bytes: &[u8]) -> Result<(), TestCaseError> {
    let path = case_file("scenario", "toml");
    let text = String::from_utf8_lossy(bytes);
    if let Err(e) = Scenario::parse(&text, Some(&path)) {
        let msg = e.to_string();
        // An error inside a file the scenario refers to (its robot file) names that file.
        let named = msg.split_once(": ").map(|(p, _)| Path::new(p));
        let referenced = named.is_some_and(|p| p != path && p.exists());
        if referenced {
            return Ok(());
        }
        names_file(&msg, &path)?;
    }
    Ok(())
}

/// The measurement reader on `bytes` for `robot`: what is read is finite and within the
/// joint limits.
fn csv_property(bytes: &[u8], robot: &Robot) -> Result<(), TestCaseError> {
    let path = case_file("measurements", "csv");
    std::fs::write(&path, bytes).unwrap();
    match read_measurements(&path, robot) {
        Ok(d) => {
            for q in &d.qs {
                prop_assert!(robot.within_limits(q), "{:?} outside the limits", q);
            }
            prop_assert!(d.points.iter().all(|p| p.iter().all(|v| v.is_finite())));
            for q in d.quats.iter().flatten() {
                let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
                prop_assert!((norm - 1.0).abs() < 1e-9, "quaternion {:?}", q);
            }
        }
        Err(e) => names_file(&e.to_string(), &path)?,
    }
    Ok(())
}

/// The URDF reader on `bytes`, the chain ending at `tip`: what is read is a usable robot, and
/// the URDF written back from it (`identify`'s robot.urdf) reads back as the same robot.
fn urdf_property(bytes: &[u8], tip: Option<&str>) -> Result<(), TestCaseError> {
    let path = case_file("robot", "urdf");
    std::fs::write(&path, bytes).unwrap();
    let chain = UrdfChain {
        base: None,
        tip: tip.map(str::to_string),
    };
    let u = match UrdfRobot::load_chain(&path, &chain) {
        Ok(u) => u,
        Err(e) => return names_file(&e.to_string(), &path),
    };
    robot_is_usable(&u.robot)?;
    let written = u
        .write(&u.robot)
        .map_err(|e| TestCaseError::fail(format!("not written back: {e}")))?;
    let again = case_file("written", "urdf");
    std::fs::write(&again, &written).unwrap();
    let back = UrdfRobot::load_chain(&again, &chain)
        .map_err(|e| TestCaseError::fail(format!("written URDF refused: {e}\n{written}")))?;
    prop_assert_eq!(back.robot.dof(), u.robot.dof());
    let q: Vec<f64> = u
        .robot
        .joints
        .iter()
        .map(|j| 0.5 * (j.limits.0 + j.limits.1))
        .collect();
    let (a, b) = (u.robot.fk(&q), back.robot.fk(&q));
    prop_assert!(
        (a.pos - b.pos).norm() < 1e-6,
        "{:?} written back as {:?}",
        a.pos,
        b.pos
    );
    Ok(())
}

fn run_robot_bytes(cases: u32, seed: Option<u64>) {
    fuzz(cases, seed, random_bytes(), |b| robot_property(&b.0));
}

fn run_robot_mutations(cases: u32, seed: Option<u64>) {
    let s = mutated(robot_corpus(), toml_mutation(robot_keys()), false);
    fuzz(cases, seed, s, |(_, b, _)| robot_property(&b.0));
}

fn run_scenario_bytes(cases: u32, seed: Option<u64>) {
    write_scenario_robot();
    fuzz(cases, seed, random_bytes(), |b| scenario_property(&b.0));
}

fn run_scenario_mutations(cases: u32, seed: Option<u64>) {
    write_scenario_robot();
    let s = mutated(scenario_corpus(), toml_mutation(scenario_keys()), false);
    fuzz(cases, seed, s, |(_, b, _)| scenario_property(&b.0));
}

fn run_csv_bytes(cases: u32, seed: Option<u64>) {
    let robot = &csv_corpus().1[0];
    fuzz(cases, seed, random_bytes(), |b| csv_property(&b.0, robot));
}

fn run_csv_mutations(cases: u32, seed: Option<u64>) {
    let (files, robots) = csv_corpus();
    let s = mutated(files, csv_mutation(), true);
    fuzz(cases, seed, s, |(i, b, _)| csv_property(&b.0, &robots[i]));
}

fn run_urdf_mutations(cases: u32, seed: Option<u64>) {
    let s = mutated(urdf_corpus(), urdf_mutation(), false);
    fuzz(cases, seed, s, |(i, b, _)| urdf_property(&b.0, URDFS[i].1));
}

// ---------------------------------------------------------------------------------------------
// The tests

#[test]
fn corpora_are_valid() {
    for f in robot_corpus() {
        robot_property(f).unwrap();
        parse_robot_file(&String::from_utf8_lossy(f), Path::new("r.toml")).unwrap();
    }
    for (f, (name, tip)) in urdf_corpus().iter().zip(URDFS) {
        urdf_property(f, tip).unwrap();
        let chain = UrdfChain {
            base: None,
            tip: tip.map(str::to_string),
        };
        UrdfRobot::load_chain(&root().join(name), &chain).unwrap();
    }
    let beside = write_scenario_robot().with_file_name("s.toml");
    for f in scenario_corpus() {
        Scenario::parse(&String::from_utf8_lossy(f), Some(&beside)).unwrap();
    }
    let (files, robots) = csv_corpus();
    for (f, r) in files.iter().zip(robots) {
        let path = case_file("valid", "csv");
        std::fs::write(&path, f).unwrap();
        let d = read_measurements(&path, r).unwrap();
        assert!(!d.qs.is_empty());
    }
    std::fs::remove_dir_all(scratch()).unwrap();
}

#[test]
fn urdf_mutations() {
    run_urdf_mutations(CASES, Some(SEED));
}

#[test]
#[ignore = "long fuzz run: cargo test --test cli -- --ignored _long"]
fn urdf_long() {
    let (cases, seed) = long_run();
    run_urdf_mutations(cases, seed);
}

#[test]
fn robot_file_random_bytes() {
    run_robot_bytes(CASES, Some(SEED));
}

#[test]
fn robot_file_mutations() {
    run_robot_mutations(CASES, Some(SEED));
}

#[test]
fn scenario_random_bytes() {
    run_scenario_bytes(CASES, Some(SEED));
}

#[test]
fn scenario_mutations() {
    run_scenario_mutations(CASES, Some(SEED));
}

#[test]
fn csv_random_bytes() {
    run_csv_bytes(CASES, Some(SEED));
}

#[test]
fn csv_mutations() {
    run_csv_mutations(CASES, Some(SEED));
}

#[test]
#[ignore = "long fuzz run: cargo test --test cli -- --ignored _long"]
fn robot_file_long() {
    let (cases, seed) = long_run();
    run_robot_bytes(cases, seed);
    run_robot_mutations(cases, seed);
}

#[test]
#[ignore = "long fuzz run: cargo test --test cli -- --ignored _long"]
fn scenario_long() {
    let (cases, seed) = long_run();
    run_scenario_bytes(cases, seed);
    run_scenario_mutations(cases, seed);
}

#[test]
#[ignore = "long fuzz run: cargo test --test cli -- --ignored _long"]
fn csv_long() {
    let (cases, seed) = long_run();
    run_csv_bytes(cases, seed);
    run_csv_mutations(cases, seed);
}

/// Found by `scenario_mutations`: the shipped `scenarios/guo2024-3t2r.toml` with
/// `builtin = "guo-0t2r"` is refused with `setting `robot.builtin`: no built-in robot
/// "guo-0t2r"; built-ins: irb2600, irb2600-mdh, tx60, guo-3t2r` — without the scenario file.
#[test]
fn scenario_unknown_builtin_names_the_file() {
    let text = std::fs::read_to_string(root().join("scenarios/guo2024-3t2r.toml"))
        .unwrap()
        .replace("builtin = \"guo-3t2r\"", "builtin = \"guo-0t2r\"");
    let path = Path::new("scenarios/guo2024-3t2r.toml");
    let e = Scenario::parse(&text, Some(path)).unwrap_err().to_string();
    assert!(
        e.contains("scenarios/guo2024-3t2r.toml") && e.contains("robot.builtin"),
        "{e}"
    );
}

/// Deep nesting, which a recursive parser could overflow the stack on, is refused like any
/// other TOML error.
#[test]
fn deep_nesting_is_refused_naming_the_file() {
    let path = Path::new("dir/deep.toml");
    for depth in [100, 100_000] {
        for (open, close) in [("[", "]"), ("{a=", "}")] {
            let text = format!("x = {}1{}\n", open.repeat(depth), close.repeat(depth));
            let e = parse_robot_file(&text, path).unwrap_err().to_string();
            assert!(e.starts_with("dir/deep.toml: line 1: "), "{e:.100}");
            let e = Scenario::parse(&text, Some(path)).unwrap_err().to_string();
            assert!(e.starts_with("dir/deep.toml: line 1: "), "{e:.100}");
        }
    }
}

/// Found by `scenario_mutations` with a sweep in its corpus: `scenarios/ci-guard.toml` with
/// `[sweep]`, `key = "outliers.count"`, `values = [0, 2]` appended makes `Scenario::parse`
/// overflow its stack (`thread 'main' has overflowed its stack`, SIGABRT): each swept value
/// is checked through `with_override`, which parses the table again, sweep included. Run in a
/// child process, since a stack overflow aborts the process.
#[test]
fn scenario_with_a_sweep_parses() {
    let dir = tmp_dir("fuzz-sweep");
    let guard = std::fs::read_to_string(root().join("scenarios/ci-guard.toml")).unwrap();
    let path = write_scenario(
        &dir,
        "sweep",
        &format!("{guard}\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 2]\n"),
    );
    let o = calbench(&[
        "simulate",
        path_arg(&path),
        "--out",
        path_arg(&dir.join("out")),
    ]);
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(
        o.status.success(),
        "{:?}: {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Found by `scenario_mutations`: `scenarios/ci-guard.toml` with `builtin = "irb2600"`
/// replaced by `file = "fu.toml"` (no such file beside it) is refused with
/// `<dir>/fu.toml: No such file or directory (os error 2)` — naming neither the scenario file
/// nor the key `robot.file` (the command line prints the cause twice:
/// `error: fu.toml: No such file or directory (os error 2): No such file or directory (os
/// error 2)`). `file = "\u0000"` likewise gives `<dir>/\0: file name contained an unexpected
/// NUL byte`.
#[test]
fn scenario_missing_robot_file_names_the_scenario() {
    let text = std::fs::read_to_string(root().join("scenarios/ci-guard.toml"))
        .unwrap()
        .replace("builtin = \"irb2600\"", "file = \"fu.toml\"");
    let path = std::env::temp_dir().join("calbench-fuzz-no-robot/ci-guard.toml");
    let e = Scenario::parse(&text, Some(&path)).unwrap_err().to_string();
    assert!(
        e.contains(&path.display().to_string()) && e.contains("robot.file"),
        "{e}"
    );
}

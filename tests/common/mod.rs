//! Helpers shared by the test crates. Each group's `tests/<group>/main.rs` includes this file
//! as `#[path = "../common/mod.rs"] mod common;` and uses a part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use calbench::identify::qiao::poses_in_cube;
use calbench::numeric::rng::Rng;
use calbench::numeric::{Real, Vec3};
use calbench::robot::{Param, Robot};

/// A small study: LS and IGG3 on random poses, no sag (fast).
pub const SMALL_STUDY: &str = r#"
name = "small"
seed = 9
trials = 5
[robot]
builtin = "irb2600"
[errors]
kind = "paper"
[tracker]
pose = [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]
[outliers]
count = 0
magnitude_mm = [0.5, 1.0]
[compliance]
model = "none"
[calibration]
count = 25
strategies = ["random"]
[validation]
count = 10
[[methods]]
name = "ls"
[[methods]]
name = "igg3"
label = "rob"
"#;

/// The crate's folder, which holds the shipped files (`scenarios/`, `examples/`, `results/`).
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh, empty folder `calbench-NAME-PID` in the temporary folder. `NAME` starts with the
/// test file's name (`cli-…`, `sweeps-…`), as the tests of one crate share a process.
/// The folder is removed when the value is dropped, unless the test is failing: then it stays
/// for a look at what the run wrote.
pub fn tmp_dir(name: &str) -> TmpDir {
    let d = std::env::temp_dir().join(format!("calbench-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
    TmpDir(d)
}

/// A folder of [`tmp_dir`]'s, used as a `Path`.
pub struct TmpDir(PathBuf);

impl std::ops::Deref for TmpDir {
    type Target = PathBuf;
    fn deref(&self) -> &PathBuf {
        &self.0
    }
}

impl AsRef<Path> for TmpDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for TmpDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for TmpDir {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// The `calbench` binary of this build, to be given arguments, a folder or an environment.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_calbench"))
}

/// Runs `calbench ARGS` and returns its output, whether it succeeded or not.
pub fn calbench(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

/// The message of a refusal (non-zero exit, no panic, nothing on stdout), which must hold
/// every one of `words`.
pub fn refused(o: &Output, words: &[&str]) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(!o.status.success(), "accepted: {out}{err}");
    assert_ne!(o.status.code(), Some(101), "panicked: {err}");
    assert!(err.starts_with("error: "), "{err}");
    for w in words {
        assert!(err.contains(w), "`{w}` missing from: {err}");
    }
    err
}

/// Runs `calbench ARGS` and fails, with its standard error, unless it succeeds.
pub fn calbench_ok(args: &[&str]) -> Output {
    let o = calbench(args);
    assert!(
        o.status.success(),
        "calbench {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Runs the scenario `sc` as `n` shards (`dir/s0` …, each with the arguments `extra`) and
/// merges them into `dir/merged`, which it returns.
pub fn sharded_and_merged(sc: &str, dir: &Path, n: usize, extra: &[&str]) -> PathBuf {
    let shards: Vec<PathBuf> = (0..n).map(|i| dir.join(format!("s{i}"))).collect();
    for (i, d) in shards.iter().enumerate() {
        let share = format!("{i}/{n}");
        let args = ["run", sc, "--shard", &share, "--out", path_arg(d)];
        calbench_ok(&[&args[..], extra].concat());
    }
    let merged = dir.join("merged");
    let mut args = vec!["merge"];
    args.extend(shards.iter().map(|d| path_arg(d)));
    args.extend(["--out", path_arg(&merged)]);
    calbench_ok(&args);
    merged
}

/// A path as a command-line argument.
pub fn path_arg(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Writes the measurement file `file` of `robot` at the joint values `qs`, each pose's point
/// `point(q)`.
pub fn write_points(
    file: &Path,
    robot: &Robot,
    qs: Vec<Vec<Real>>,
    point: impl FnMut(&Vec<Real>) -> Vec3,
) {
    let points = qs.iter().map(point).collect();
    let data = calbench::measurement::Measurements {
        points,
        qs,
        ..Default::default()
    };
    calbench::measurement::csv::write_measurements(file, robot, &data).unwrap();
}

/// `calbench merge SHARDS… --out OUT`, which must succeed.
pub fn merge(shards: &[&Path], out: &Path) -> Output {
    let mut args = vec!["merge"];
    args.extend(shards.iter().map(|s| path_arg(s)));
    args.extend(["--out", path_arg(out)]);
    calbench_ok(&args)
}

/// The names of the files in `dir`, sorted.
pub fn files_in(dir: &Path) -> std::collections::BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

/// The text of a file; a failure names the file.
pub fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The JSON document of a file (`summary.json`, `identified.json`, `truth.json`, …). An
/// `identified.json` is also read through its type ([`identified_round_trip`]).
pub fn load_json(p: &Path) -> serde_json::Value {
    let text = read(p);
    if p.file_name() == Some("identified.json".as_ref()) {
        identified_round_trip(p, &text);
    }
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `identified.json`'s `text` (at `p`) read as `calbench::calibrate::record::IdentifiedRecord`
/// and written again as `identify` writes it: the same bytes (format 1 has no `format` key,
/// docs/formats.md § 7.6).
pub fn identified_round_trip(p: &Path, text: &str) {
    use calbench::calibrate::record::IdentifiedRecord;
    let r = IdentifiedRecord::from_json(text, p).unwrap_or_else(|e| panic!("{e}"));
    let again = serde_json::to_string_pretty(&r).unwrap() + "\n";
    assert!(
        again == text,
        "{}: read and written again:\n{again}",
        p.display()
    );
}

/// Writes a scenario as `DIR/NAME.toml` and returns its path.
/// Runs `scenario` three ways under `dir`, as a user spreads one run: at one thread
/// (`one/`), at two threads (`two/`), and as two shards merged (`s0/`, `s1/`, `merged/`).
/// Returns the three output folders, `[one, two, merged]`, whose results must agree.
pub fn threads_and_merged_shards(dir: &Path, scenario: &Path) -> [PathBuf; 3] {
    let run = |out: &Path, extra: &[&str]| {
        let args = [
            &["run", path_arg(scenario), "--out", path_arg(out)][..],
            extra,
        ]
        .concat();
        calbench_ok(&args);
    };
    let (one, two) = (dir.join("one"), dir.join("two"));
    run(&one, &["--threads", "1"]);
    run(&two, &["--threads", "2"]);
    let (s0, s1, merged) = (dir.join("s0"), dir.join("s1"), dir.join("merged"));
    run(&s0, &["--shard", "0/2"]);
    run(&s1, &["--shard", "1/2"]);
    merge(&[&s0, &s1], &merged);
    [one, two, merged]
}

/// Makes the run in `out` stand for a run of the baseline's scenario by another version of the
/// program: a test that plants a change of the results by editing the scenario removes the
/// edited run's `scenario.toml`, since `check` refuses a run of another scenario than the
/// baseline's (docs/formats.md § 2.4) and compares only when a side does not say what it ran.
pub fn as_another_version(out: &Path) {
    let p = out.join("scenario.toml");
    std::fs::remove_file(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
}

pub fn write_scenario(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    p
}

/// Errors of `len` mm on the lengths and `ang` rad on the angles of `params`, scaled 1, −0.6,
/// 0.8, −1, 0.4 in turn.
pub fn alternating_errors(params: &[Param], len: Real, ang: Real) -> Vec<(Param, Real)> {
    params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let s = [1.0, -0.6, 0.8, -1.0, 0.4][i % 5];
            (*p, s * if p.is_length() { len } else { ang })
        })
        .collect()
}

/// `n` poses of `robot` whose tool point lies in Qiao 2021's measurement cube for the TX60
/// (1 m edge, centred at (550, 0, 550) mm).
pub fn qiao_cube_poses(robot: &Robot, n: usize, rng: &mut Rng) -> Vec<Vec<Real>> {
    poses_in_cube(robot, n, [550.0, 0.0, 550.0], 1000.0, 200_000, rng).unwrap()
}

/// The path of `examples/ipa-ur10/FILE`, as a command-line argument.
pub fn ur10_example(file: &str) -> String {
    root()
        .join("examples/ipa-ur10")
        .join(file)
        .display()
        .to_string()
}

/// `calbench import` of the shipped UR10 sample (`examples/ipa-ur10/sample-200.csv`) with the
/// mapping file `mapping` into the measurement CSV `out`.
pub fn import_ur10_sample(mapping: &str, out: &Path) {
    let sample = ur10_example("sample-200.csv");
    calbench_ok(&[
        "import",
        &sample,
        "--mapping",
        mapping,
        "--out",
        path_arg(out),
    ]);
}

/// The measurement CSV `csv` cut to its position columns (the first nine: six joints and x, y,
/// z), written to `out`.
pub fn positions_only(csv: &Path, out: &Path) {
    let text: String = read(csv)
        .lines()
        .map(|l| l.split(',').take(9).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    std::fs::write(out, text).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
}

/// The first 200 rows of the UR10 export, positions only, as a measurement CSV in `d`
/// (`pos.csv`, beside the full import `all.csv`): its path.
pub fn ur10_positions(d: &Path) -> std::path::PathBuf {
    let all = d.join("all.csv");
    import_ur10_sample(&ur10_example("mapping.toml"), &all);
    let pos = d.join("pos.csv");
    positions_only(&all, &pos);
    pos
}

/// The file-name prefixes of the scenarios named after a paper.
pub const PAPER_SCENARIOS: [&str; 4] = ["li2018-", "ban-", "guo2024-", "qiao2021-"];

/// The claims a scenario file states, each with its metric's name: a Monte-Carlo study's
/// (`calbench::study::metric::Metric`) or a registration study's (Ban fig. 3, `registration_error_mm`).
pub fn scenario_claims(path: &Path) -> Vec<(calbench::study::claims::Claim, String)> {
    use calbench::study::kind::AnyScenario;
    use calbench::study::registration_study::METRIC;
    let sc = match AnyScenario::load(path) {
        Ok(AnyScenario::Registration(sc)) => {
            return sc.claims.into_iter().map(|c| (c, METRIC.key())).collect()
        }
        Ok(AnyScenario::MonteCarlo(sc)) => sc,
        Ok(AnyScenario::Instruments(_)) => panic!("{}: an instruments study", path.display()),
        Err(e) => panic!("{}: {e}", path.display()),
    };
    sc.claims
        .into_iter()
        .map(|c| {
            let m = c.metric.key();
            (c, m)
        })
        .collect()
}

/// Starts `calbench ARGS` (a run writing to `out`), waits until its checkpoint holds a
/// finished trial (at most `limit_s` seconds), kills it (SIGKILL) and returns the path of the
/// checkpoint's `checkpoint.json`. A run that ends before, or outlives the limit, fails the
/// test at once, naming which.
pub fn kill_once_checkpointed(args: &[&str], out: &Path, limit_s: u64) -> PathBuf {
    let name = out.file_name().unwrap().to_str().unwrap();
    let meta = out
        .parent()
        .unwrap()
        .join(format!(".{name}.checkpoint/checkpoint.json"));
    let mut child = bin()
        .args(args)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while !std::fs::read_to_string(&meta).is_ok_and(|t| !t.contains("\"done\": 0,")) {
        if let Some(status) = child.try_wait().unwrap() {
            panic!(
                "the run ended ({status}) before a checkpoint with a trial done was seen at {}",
                meta.display()
            );
        }
        if t0.elapsed().as_secs() >= limit_s {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("no checkpoint after {limit_s} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    meta
}

/// `err` is one line of under 1 kB naming `path`, and holding each of `want`.
pub fn one_line_naming(err: &str, path: &Path, want: &[&str]) {
    let err = err.trim_end();
    assert!(err.len() < 1024 && !err.contains('\n'), "{err:?}");
    assert!(err.contains(&path.display().to_string()), "{err}");
    for w in want {
        assert!(err.contains(w), "{err}: no \"{w}\"");
    }
}

/// A record line of `records.txt` with one digit of its trial's numbers changed (the first
/// digit after `truth:[`, its checksum kept).
pub fn another_digit(line: &str) -> String {
    let from = line.find("truth:[").expect("a record line") + "truth:[".len();
    let at = from + line[from..].find(|c: char| c.is_ascii_digit()).unwrap();
    let other = if &line[at..=at] == "7" { "8" } else { "7" };
    format!("{}{other}{}", &line[..at], &line[at + 1..])
}

/// The checksum of `body` at sweep point `point` and trial `trial` of the run of `settings`
/// and `seed` (docs/formats.md § 7.3), computed apart from calbench's code.
fn run_checksum(settings: &str, seed: u64, point: u64, trial: u64, body: &str) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    h.update(Sha256::digest(settings.as_bytes()));
    h.update(seed.to_le_bytes());
    h.update(point.to_le_bytes());
    h.update(trial.to_le_bytes());
    h.update(body.as_bytes());
    h.finalize()[..16]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The `position_mm` of `calbench fk --robot ROBOT --q Q --json` (Q in the robot's units).
pub fn fk_point(robot: &Path, q: &[f64]) -> Vec<f64> {
    let q: Vec<String> = q.iter().map(|v| format!("{v:?}")).collect();
    let args = [
        "fk",
        "--robot",
        path_arg(robot),
        "--q",
        &q.join(","),
        "--json",
    ];
    let j: serde_json::Value = serde_json::from_slice(&calbench_ok(&args).stdout).unwrap();
    let p = j["position_mm"].as_array().unwrap();
    p.iter().map(|v| v.as_f64().unwrap()).collect()
}

/// `line`, a record of `records.txt` of the run of `settings` and `seed`, with its checksum
/// computed again for its text (docs/formats.md § 7.3): a record edited and its sum made to
/// match, which only reading the record can refuse.
pub fn resummed(line: &str, settings: &str, seed: u64) -> String {
    let body = line.rsplit_once(" #").map_or(line, |(b, _)| b);
    let field = |key: &str| -> u64 {
        let from = body.find(key).expect("a record line") + key.len();
        let digits = &body[from..];
        let end = digits.find(|c: char| !c.is_ascii_digit()).unwrap();
        digits[..end].parse().unwrap()
    };
    let sum = run_checksum(settings, seed, field("(point:"), field(",trial:"), body);
    format!("{body} #{sum}")
}

/// `text`, a `shard.json`, with each block's checksum computed again for its content
/// (docs/formats.md § 7.3: the compact JSON of `[info, trial0]`, keys sorted, at the trial
/// index 2⁶⁴ − 1): blocks edited and their sums made to match, which only reading the blocks
/// against the records can refuse.
pub fn reblocked(text: &str) -> String {
    let mut v: serde_json::Value = serde_json::from_str(text).unwrap();
    let settings = v["settings"].as_str().unwrap().to_string();
    let seed = v["seed"].as_u64().unwrap();
    for b in v["blocks"].as_array_mut().unwrap() {
        let body = serde_json::json!([b["info"], b["trial0"]]).to_string();
        let point = b["info"]["index"].as_u64().unwrap();
        b["sum"] = run_checksum(&settings, seed, point, u64::MAX, &body).into();
    }
    serde_json::to_string_pretty(&v).unwrap()
}

//! Fuzz and property tests of the input parsers: robot files, scenario files and measurement
//! CSVs get random bytes and structured mutations of valid files (the built-in robots as
//! `calbench robots NAME` prints them, the shipped `scenarios/*.toml`, CSVs written by
//! `calbench simulate`). Properties: nothing panics, every error names the file, and what is
//! accepted is usable (finite, in range, within the joint limits).
//!
//! Each parser gets [`CASES`] cases per property in the normal run, from a fixed seed so the
//! run is repeatable. The `#[ignore]`d `*_long` tests run [`LONG_CASES`] cases from a random
//! seed: `cargo test --test cli -- --ignored _long` (`CALBENCH_FUZZ_CASES` and
//! `CALBENCH_FUZZ_SEED` override the count and the seed; `CALBENCH_FUZZ_COLLECT=1` prints
//! every message without the file and goes on, to list them all in one run).
//!
//! Gaps the fuzzing found are pinned by tests with the exact input that showed them (a sweep
//! that overflowed the stack, an unknown `robot.builtin` or an unreadable `robot.file` refused
//! without the scenario file).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};

use calbench::measurement::csv::read_measurements;
use calbench::robot::builtin;
use calbench::robot::{parse_robot_file, read_robot_file, robot_to_toml, Robot};
use calbench::study::scenario::Scenario;

use crate::common::{calbench, calbench_ok, path_arg, root, tmp_dir, write_scenario};

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

/// File contents, shown as an escaped byte string when a case fails.
#[derive(Clone)]
struct Bytes(Vec<u8>);

impl std::fmt::Debug for Bytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "b\"{}\"", self.0.escape_ascii())
    }
}

// ---------------------------------------------------------------------------------------------
// Mutations

/// One edit of a file. Positions are [`Index`]es, so a mutation applies to any text.
#[derive(Clone, Debug)]
enum Mutation {
    /// Removes a line.
    DeleteLine(Index),
    /// Repeats a line.
    DuplicateLine(Index),
    /// Exchanges two lines.
    SwapLines(Index, Index),
    /// Replaces the value of a `key = value` line (TOML) or a cell (CSV).
    ReplaceValue(Index, Index, String),
    /// Replaces a number anywhere in the text.
    ReplaceNumber(Index, String),
    /// Renames the key of a `key = value` line (TOML) or a header column (CSV).
    RenameKey(Index, Index, String),
    /// Inserts a line.
    InsertLine(Index, String),
    /// Cuts the text short.
    Truncate(Index),
    /// Inserts random bytes.
    InsertBytes(Index, Vec<u8>),
    /// Removes a run of bytes.
    DeleteBytes(Index, u8),
    /// Replaces one byte.
    ReplaceByte(Index, u8),
    /// Removes a cell of a CSV row (or the value of a TOML line).
    DeleteCell(Index, Index),
    /// Adds a cell to a CSV row.
    AddCell(Index, String),
    /// Turns every line end into CR LF.
    CrLf,
    /// Puts a UTF-8 byte-order mark in front.
    Bom,
}

fn lines(text: &[u8]) -> Vec<Vec<u8>> {
    text.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect()
}

fn join(lines: &[Vec<u8>]) -> Vec<u8> {
    lines.join(&b'\n')
}

/// The byte ranges of the numbers in `text`.
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts = text[i].is_ascii_digit()
            || (matches!(text[i], b'-' | b'+') && text.get(i + 1).is_some_and(u8::is_ascii_digit));
        let word_before = i > 0 && (text[i - 1].is_ascii_alphanumeric() || text[i - 1] == b'_');
        if starts && !word_before {
            let mut j = i + 1;
            while j < text.len()
                && (text[j].is_ascii_digit()
                    || matches!(text[j], b'.' | b'e' | b'E' | b'_')
                    || (matches!(text[j], b'-' | b'+') && matches!(text[j - 1], b'e' | b'E')))
            {
                j += 1;
            }
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// Splits a CSV or TOML line into its value cells: for CSV the comma-separated fields, for
/// TOML (a line with `=`) the key and the value.
fn cells(line: &[u8], csv: bool) -> Vec<Vec<u8>> {
    if csv {
        line.split(|&b| b == b',').map(<[u8]>::to_vec).collect()
    } else {
        match line.iter().position(|&b| b == b'=') {
            Some(p) => vec![line[..p].to_vec(), line[p + 1..].to_vec()],
            None => vec![line.to_vec()],
        }
    }
}

fn uncells(cells: &[Vec<u8>], csv: bool) -> Vec<u8> {
    if csv {
        cells.join(&b',')
    } else {
        cells.join(&b'=')
    }
}

/// Applies `m` to `text`; `csv` selects comma-separated cells instead of `key = value`.
fn apply(text: &mut Vec<u8>, m: &Mutation, csv: bool) {
    let mut ls = lines(text);
    let n = ls.len();
    match m {
        Mutation::DeleteLine(i) => {
            ls.remove(i.index(n));
            *text = join(&ls);
        }
        Mutation::DuplicateLine(i) => {
            let k = i.index(n);
            let l = ls[k].clone();
            ls.insert(k, l);
            *text = join(&ls);
        }
        Mutation::SwapLines(i, j) => {
            ls.swap(i.index(n), j.index(n));
            *text = join(&ls);
        }
        Mutation::ReplaceValue(i, c, v) => {
            // TOML: a line with a value; CSV: a cell of a data row (or the header).
            let candidates: Vec<usize> = (0..n).filter(|&k| csv || ls[k].contains(&b'=')).collect();
            if candidates.is_empty() {
                return;
            }
            let k = candidates[i.index(candidates.len())];
            let mut cs = cells(&ls[k], csv);
            let c = if csv { c.index(cs.len()) } else { cs.len() - 1 };
            cs[c] = if csv {
                v.as_bytes().to_vec()
            } else {
                format!(" {v}").into_bytes()
            };
            ls[k] = uncells(&cs, csv);
            *text = join(&ls);
        }
        Mutation::ReplaceNumber(i, v) => {
            let nums = numbers(text);
            if nums.is_empty() {
                return;
            }
            let (a, b) = nums[i.index(nums.len())];
            text.splice(a..b, v.bytes());
        }
        Mutation::RenameKey(i, c, k) => {
            let candidates: Vec<usize> = if csv {
                vec![0]
            } else {
                (0..n).filter(|&k| ls[k].contains(&b'=')).collect()
            };
            if candidates.is_empty() {
                return;
            }
            let line = candidates[i.index(candidates.len())];
            let mut cs = cells(&ls[line], csv);
            let c = if csv { c.index(cs.len()) } else { 0 };
            cs[c] = if csv {
                k.as_bytes().to_vec()
            } else {
                format!("{k} ").into_bytes()
            };
            ls[line] = uncells(&cs, csv);
            *text = join(&ls);
        }
        Mutation::InsertLine(i, l) => {
            ls.insert(i.index(n + 1), l.as_bytes().to_vec());
            *text = join(&ls);
        }
        Mutation::Truncate(i) => {
            let k = i.index(text.len() + 1);
            text.truncate(k);
        }
        Mutation::InsertBytes(i, b) => {
            let k = i.index(text.len() + 1);
            text.splice(k..k, b.iter().copied());
        }
        Mutation::DeleteBytes(i, len) => {
            if text.is_empty() {
                return;
            }
            let k = i.index(text.len());
            let e = (k + *len as usize).min(text.len());
            text.drain(k..e);
        }
        Mutation::ReplaceByte(i, b) => {
            if text.is_empty() {
                return;
            }
            let k = i.index(text.len());
            text[k] = *b;
        }
        Mutation::DeleteCell(i, c) => {
            let k = i.index(n);
            let mut cs = cells(&ls[k], csv);
            cs.remove(c.index(cs.len()));
            ls[k] = uncells(&cs, csv);
            *text = join(&ls);
        }
        Mutation::AddCell(i, v) => {
            let k = i.index(n);
            let mut cs = cells(&ls[k], csv);
            cs.push(v.as_bytes().to_vec());
            ls[k] = uncells(&cs, csv);
            *text = join(&ls);
        }
        Mutation::CrLf => {
            *text = ls.join(&b"\r\n"[..]);
        }
        Mutation::Bom => {
            text.splice(0..0, [0xEF, 0xBB, 0xBF]);
        }
    }
}

/// Numbers that probe ranges, overflow after unit conversion, rounding and number syntax.
const NUMBERS: &[&str] = &[
    "0",
    "-0.0",
    "0.0",
    "1",
    "-1",
    "2",
    "0.5",
    "3",
    "40",
    "360",
    "-360.0",
    "360.0000001",
    "3600",
    "-3600.5",
    "1000",
    "1e6",
    "1000000.000001",
    "-1e6",
    "1e300",
    "1e306",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "1e309",
    "5e-324",
    "1e-320",
    "1e-9",
    "nan",
    "-nan",
    "inf",
    "+inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "9223372036854775808",
    "99999999999999999999",
    "1000000000000",
    "4294967296",
    "0x7fffffff",
    "0o17",
    "0b101",
    "1_000",
    "1__0",
    "01",
    "1.",
    ".5",
    "1e",
    "1e+",
    "--1",
    "1.0.0",
];

/// TOML values of other types and shapes.
const TOML_VALUES: &[&str] = &[
    "\"\"",
    "\"x\"",
    "\"irb2600\"",
    "\"irb9999\"",
    "\"tx60\"",
    "\"guo-3t2r\"",
    "\"lm\"",
    "\"ls\"",
    "\"igg3\"",
    "\"ridge\"",
    "\"pso\"",
    "\"detmax\"",
    "\"random\"",
    "\"m\"",
    "\"mm\"",
    "\"rad\"",
    "\"deg\"",
    "\"dh\"",
    "\"mdh\"",
    "\"dh_beta\"",
    "\"revolute\"",
    "\"prismatic\"",
    "\"differential\"",
    "\"pose\"",
    "\"position\"",
    "\"svd\"",
    "\"identify\"",
    "\"linear\"",
    "\"paper\"",
    "\"../nowhere.toml\"",
    "\"methods\"",
    "\"trials\"",
    "\"name.x\"",
    "\".\"",
    "\"outliers.count\"",
    "\"calibration.count\"",
    "[0, 2]",
    "\"/dev/null\"",
    "\"\\u0000\"",
    "\"\\n\"",
    "'lit'",
    "\"\"\"multi\nline\"\"\"",
    "true",
    "false",
    "[]",
    "[1.0]",
    "[0.0, 0.0]",
    "[1.0, -1.0]",
    "[-1e308, 1e308]",
    "[1.0, 2.0, 3.0]",
    "[0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
    "[1e308, 0.0, 0.0, 0.0, 0.0, 0.0]",
    "[\"a\"]",
    "[\"random\", \"detmax\"]",
    "[[1.0]]",
    "{}",
    "{ a = 1 }",
    "1979-05-27T07:32:00Z",
    "07:32:00",
    "1979-05-27",
];

/// CSV cells.
const CELLS: &[&str] = &[
    "",
    " ",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "infinity",
    "1e308",
    "-1e308",
    "1e306",
    "1e-320",
    "5e-324",
    "abc",
    "0x10",
    " 7 ",
    "1e",
    "--1",
    "+1",
    "1.0.0",
    "\"1\"",
    "\"",
    "\"a,b\"",
    "#",
    "999999",
    "-999999",
    "1e30",
    "0",
    "-0",
    "1",
    "0.7071",
    "2",
    "100",
    "-100",
    "180",
    "400",
    "1.0000001",
    "q1",
    "x",
];

/// CSV header names.
const COLUMNS: &[&str] = &[
    "", "q0", "q1", "q2", "q6", "q7", "q16", "x", "y", "z", "qw", "qx", "qy", "qz", "Q1", " q1",
    "X", "w", "q1 ", "\"q1\"", "#x",
];

/// A TOML line from the corpus' keys and headers and the value lists.
fn toml_line(keys: &'static [String]) -> impl Strategy<Value = String> {
    let value = prop_oneof![
        prop::sample::select(NUMBERS).prop_map(str::to_string),
        prop::sample::select(TOML_VALUES).prop_map(str::to_string),
    ];
    prop_oneof![
        (prop::sample::select(keys), value).prop_map(|(k, v)| {
            if k.starts_with('[') {
                k.clone()
            } else {
                format!("{k} = {v}")
            }
        }),
        "[a-z_.\\[\\] =\"0-9]{0,24}",
    ]
}

fn toml_mutation(keys: &'static [String]) -> impl Strategy<Value = Mutation> {
    let value = prop_oneof![
        3 => prop::sample::select(NUMBERS).prop_map(str::to_string),
        2 => prop::sample::select(TOML_VALUES).prop_map(str::to_string),
        1 => "[ -~]{0,12}",
    ];
    let key = prop_oneof![
        prop::sample::select(keys).prop_filter("a key", |k| !k.starts_with('[')),
        "[a-z_.]{1,12}",
    ];
    prop_oneof![
        2 => any::<Index>().prop_map(Mutation::DeleteLine),
        2 => any::<Index>().prop_map(Mutation::DuplicateLine),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        6 => (any::<Index>(), any::<Index>(), value).prop_map(|(a, b, v)| Mutation::ReplaceValue(a, b, v)),
        6 => (any::<Index>(), prop::sample::select(NUMBERS))
            .prop_map(|(a, v)| Mutation::ReplaceNumber(a, v.to_string())),
        2 => (any::<Index>(), any::<Index>(), key).prop_map(|(a, b, k)| Mutation::RenameKey(a, b, k)),
        3 => (any::<Index>(), toml_line(keys)).prop_map(|(a, l)| Mutation::InsertLine(a, l)),
        1 => any::<Index>().prop_map(Mutation::Truncate),
        1 => (any::<Index>(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(a, b)| Mutation::InsertBytes(a, b)),
        1 => (any::<Index>(), 1..16u8).prop_map(|(a, n)| Mutation::DeleteBytes(a, n)),
        1 => (any::<Index>(), any::<u8>()).prop_map(|(a, b)| Mutation::ReplaceByte(a, b)),
        1 => Just(Mutation::CrLf),
        1 => Just(Mutation::Bom),
    ]
}

fn csv_mutation() -> impl Strategy<Value = Mutation> {
    let cell = prop_oneof![
        4 => prop::sample::select(CELLS).prop_map(str::to_string),
        1 => "[ -~]{0,10}",
    ];
    prop_oneof![
        2 => any::<Index>().prop_map(Mutation::DeleteLine),
        2 => any::<Index>().prop_map(Mutation::DuplicateLine),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        8 => (any::<Index>(), any::<Index>(), cell.clone())
            .prop_map(|(a, b, v)| Mutation::ReplaceValue(a, b, v)),
        3 => (any::<Index>(), prop::sample::select(NUMBERS))
            .prop_map(|(a, v)| Mutation::ReplaceNumber(a, v.to_string())),
        3 => (any::<Index>(), any::<Index>(), prop::sample::select(COLUMNS))
            .prop_map(|(a, b, k)| Mutation::RenameKey(a, b, k.to_string())),
        2 => (any::<Index>(), prop_oneof![
                Just(String::new()),
                Just("# comment".to_string()),
                Just(",,,".to_string()),
                "[ -~]{0,40}",
            ]).prop_map(|(a, l)| Mutation::InsertLine(a, l)),
        1 => any::<Index>().prop_map(Mutation::Truncate),
        1 => (any::<Index>(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(a, b)| Mutation::InsertBytes(a, b)),
        1 => (any::<Index>(), 1..16u8).prop_map(|(a, n)| Mutation::DeleteBytes(a, n)),
        1 => (any::<Index>(), any::<u8>()).prop_map(|(a, b)| Mutation::ReplaceByte(a, b)),
        2 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::DeleteCell(a, b)),
        2 => (any::<Index>(), cell).prop_map(|(a, v)| Mutation::AddCell(a, v)),
        1 => Just(Mutation::CrLf),
        1 => Just(Mutation::Bom),
    ]
}

/// A valid file of `corpus` and one to four mutations of it.
fn mutated(
    corpus: &'static [Vec<u8>],
    mutation: impl Strategy<Value = Mutation>,
    csv: bool,
) -> impl Strategy<Value = (usize, Bytes, Vec<Mutation>)> {
    (0..corpus.len(), prop::collection::vec(mutation, 1..5)).prop_map(move |(i, ms)| {
        let mut text = corpus[i].clone();
        for m in &ms {
            apply(&mut text, m, csv);
        }
        (i, Bytes(text), ms)
    })
}

/// Random bytes: arbitrary, or printable text with TOML/CSV punctuation.
fn random_bytes() -> impl Strategy<Value = Bytes> {
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..512).prop_map(Bytes),
        "[\\[\\]{}=,.\"'#a-z0-9 \n_+-]{0,512}".prop_map(|s| Bytes(s.into_bytes())),
    ]
}

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

// ---------------------------------------------------------------------------------------------
// Corpora

/// The built-in robots as `calbench robots NAME` prints them.
fn robot_corpus() -> &'static [Vec<u8>] {
    static C: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    C.get_or_init(|| {
        builtin::BUILTINS
            .iter()
            .map(|b| format!("# {}\n{}", b.summary, robot_to_toml(&(b.build)())).into_bytes())
            .collect()
    })
}

fn robot_keys() -> &'static [String] {
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
fn scenario_corpus() -> &'static [Vec<u8>] {
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
        let file = guard.replace(
            "builtin = \"irb2600\"",
            &format!("file = \"{SCENARIO_ROBOT}\""),
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
const SCENARIO_ROBOT: &str = "fuzz-robot.toml";

/// Writes [`SCENARIO_ROBOT`] into the calling thread's scratch folder.
fn write_scenario_robot() -> PathBuf {
    let p = scratch().join(SCENARIO_ROBOT);
    std::fs::write(&p, robot_to_toml(&builtin::irb2600())).unwrap();
    p
}

fn scenario_keys() -> &'static [String] {
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
fn csv_corpus() -> &'static (Vec<Vec<u8>>, Vec<Robot>) {
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

/// The scenario parser on `bytes`, beside [`SCENARIO_ROBOT`]. An error inside a robot file
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

// ---------------------------------------------------------------------------------------------
// The tests

#[test]
fn corpora_are_valid() {
    for f in robot_corpus() {
        robot_property(f).unwrap();
        parse_robot_file(&String::from_utf8_lossy(f), Path::new("r.toml")).unwrap();
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
            assert!(e.starts_with("dir/deep.toml: TOML"), "{}", &e[..100]);
            let e = Scenario::parse(&text, Some(path)).unwrap_err().to_string();
            assert!(e.starts_with("dir/deep.toml: TOML"), "{}", &e[..100]);
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

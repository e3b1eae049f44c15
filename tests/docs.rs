//! The documentation's examples run from the repository alone, as a user would run them.
//!
//! Every fenced block of `README.md` and of each `docs/*.md` is looked at by its language:
//!
//! - ```` ```toml ```` with `[[methods]]` is a scenario: `calbench run FILE --trials 2 --out DIR`
//!   must succeed (the file written at the root of a copy of the repository, so that paths in it
//!   resolve as in a clone), and a sweep must show in `summary.json`.
//! - ```` ```toml ```` with `[[joints]]` is a robot file: `calbench fk --robot FILE --q 0,…,0`
//!   (one zero per `[[joints]]`) must succeed.
//! - Other ```` ```toml ```` blocks are fragments of a larger file and are not run.
//! - ```` ```sh ```` and ```` ```bash ```` blocks run as `bash -euo pipefail -c BLOCK` in a fresh
//!   temporary copy of the repository's tracked data (`scenarios`, `robots`, `examples`, `data`,
//!   `benches`, `results/baselines`), with the folder of this build's `calbench` first on `PATH`.
//!   They run as written: nothing is substituted, so a long study in the docs must be written
//!   with small settings (`--trials 2`, a small scenario).
//! - Any block whose line before the opening fence is `<!-- not run: REASON -->` is not run:
//!   the set-up block (the build and this test suite itself) and blocks that need a cluster or a
//!   tool outside the repository (Slurm, Ceres, a Python with scipy). The test prints each with
//!   its reason and counts them.
//!
//! `README.md`, `docs/formats.md`, `docs/architecture.md` and `docs/performance.md` must exist.
//! With `CI=true` a missing document or tool (`bash`) fails the test; elsewhere it is reported
//! and skipped. The head-to-head scripts of `docs/performance.md` need Python with scipy or
//! Ceres, which no test may need: they are run here as on a machine without them and must stop
//! with status 2, naming what is missing.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};

#[path = "common/mod.rs"]
mod common;

#[path = "docs/anchors.rs"]
mod anchors;

#[path = "docs/tasks.rs"]
mod tasks;

/// The documents that must exist: every one the repository has, so that a document lost
/// takes its examples out of these tests with a failure, not in silence.
const REQUIRED: [&str; 10] = [
    "README.md",
    "REPRODUCTION.md",
    "docs/formats.md",
    "docs/architecture.md",
    "docs/guard.md",
    "docs/instruments.md",
    "docs/performance.md",
    "docs/python.md",
    "docs/references.md",
    "docs/results.md",
];

/// The languages a fenced block of the documents may have, each with what runs it: a block of
/// another (`console`, `shell`, none) would be passed over by every test without a word.
const LANGUAGES: [(&str, &str); 7] = [
    ("sh", "shell_examples_run"),
    ("bash", "shell_examples_run"),
    ("toml", "toml_examples_run"),
    ("python", "python/tests/test_docs.py (docs/python.md only)"),
    ("rust", "the doctest of README.md (src/lib.rs)"),
    ("text", "nothing: output, synopses and messages shown"),
    ("json", "nothing: output shown"),
];

/// What a shell example may read: the tracked folders a user's clone has.
const COPIED: [&str; 7] = [
    "scenarios",
    "tasks",
    "robots",
    "examples",
    "data",
    "benches",
    "results/baselines",
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}

/// A missing document or tool: a failure under CI, a printed skip elsewhere.
fn missing(what: &str) {
    if ci() {
        panic!("{what} (CI=true: a missing file or tool is a failure)");
    }
    eprintln!("SKIP: {what} (set CI=true to make this a failure)");
}

/// README.md and every docs/*.md that exists, in a fixed order.
fn documents() -> Vec<PathBuf> {
    let mut docs = vec![root().join("README.md")];
    let mut more: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .map(|d| {
            d.map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|x| x == "md"))
                .collect()
        })
        .unwrap_or_default();
    more.sort();
    docs.extend(more);
    docs
}

/// One fenced block of a Markdown file.
struct Block {
    doc: String,
    line: usize,
    lang: String,
    body: String,
    /// The reason of a `<!-- not run: REASON -->` marker on the line before the fence.
    not_run: Option<String>,
}

impl Block {
    fn name(&self) -> String {
        format!("{}:{} ({})", self.doc, self.line, self.lang)
    }
}

fn blocks(path: &Path) -> Vec<Block> {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = path
        .strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string();
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let Some(info) = lines[i].strip_prefix("```") else {
            i += 1;
            continue;
        };
        let lang = info.split_whitespace().next().unwrap_or("").to_string();
        let not_run = i
            .checked_sub(1)
            .map(|j| lines[j].trim())
            .and_then(|l| l.strip_prefix("<!-- not run"))
            .map(|rest| {
                let reason = rest
                    .strip_prefix(':')
                    .and_then(|r| r.strip_suffix("-->"))
                    .map(str::trim)
                    .unwrap_or("");
                assert!(
                    !reason.is_empty(),
                    "{doc}:{}: a not-run marker is `<!-- not run: REASON -->`",
                    i
                );
                reason.to_string()
            });
        let start = i + 1;
        let end = (start..lines.len())
            .find(|&j| lines[j].trim() == "```")
            .unwrap_or_else(|| panic!("{doc}:{}: unclosed code block", i + 1));
        let mut body = lines[start..end].join("\n");
        body.push('\n');
        out.push(Block {
            doc: doc.clone(),
            line: i + 1,
            lang,
            body,
            not_run,
        });
        i = end + 1;
    }
    out
}

fn scratch(tag: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "calbench-docs-{tag}-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}

/// A temporary folder holding the repository's tracked data, as a clone has it.
fn repo_copy(tag: &str) -> PathBuf {
    let dir = scratch(tag);
    for d in COPIED {
        let from = root().join(d);
        if from.is_dir() {
            copy_dir(&from, &dir.join(d));
        }
    }
    dir
}

fn calbench(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_calbench"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Counts of one kind of check over the documents.
#[derive(Default)]
struct Tally {
    run: usize,
    not_run: Vec<String>,
}

impl Tally {
    fn skip(&mut self, b: &Block, reason: &str) {
        let line = format!("{}: {reason}", b.name());
        eprintln!("not run: {line}");
        self.not_run.push(line);
    }

    fn print(&self, what: &str) {
        eprintln!(
            "{what}: {} run, {} not run{}",
            self.run,
            self.not_run.len(),
            self.not_run
                .iter()
                .map(|l| format!("\n  {l}"))
                .collect::<String>()
        );
    }
}

fn run_scenario(b: &Block, dir: &Path, i: usize) {
    let file = format!("example{i}.toml");
    std::fs::write(dir.join(&file), &b.body).unwrap();
    let out = format!("out{i}");
    let o = calbench(&["run", &file, "--trials", "2", "--out", &out], dir);
    assert!(o.status.success(), "{} failed:\n{}", b.name(), text(&o));
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(&out).join("summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["trials"], 2, "{}", b.name());
    let results = summary["results"].as_array().expect("no results");
    if b.body.contains("[[sweep]]") {
        let keys = summary["sweep_keys"]
            .as_array()
            .expect("no sweep_keys")
            .len();
        assert!(
            results
                .iter()
                .all(|e| e["sweep"].as_object().is_some_and(|m| m.len() == keys)),
            "{}: an entry without its sweep point",
            b.name()
        );
    } else if b.body.contains("[sweep]") {
        assert!(
            summary["sweep_key"].is_string(),
            "{}: no sweep_key",
            b.name()
        );
        assert!(
            results.iter().all(|e| !e["sweep_value"].is_null()),
            "{}: an entry without its sweep value",
            b.name()
        );
    }
}

fn load_robot(b: &Block, dir: &Path, i: usize) {
    let file = format!("robot{i}.toml");
    std::fs::write(dir.join(&file), &b.body).unwrap();
    let joints = b.body.matches("[[joints]]").count();
    let q = vec!["0"; joints].join(",");
    let o = calbench(&["fk", "--robot", &file, "--q", &q], dir);
    assert!(
        o.status.success(),
        "{} does not load as a robot file:\n{}",
        b.name(),
        text(&o)
    );
}

/// Scenarios run with `--trials 2`, robot files load; the README has at least one scenario.
#[test]
fn toml_examples_run() {
    let mut scenarios = Tally::default();
    let mut robots = Tally::default();
    let mut readme_scenarios = 0;
    for doc in documents() {
        let dir = repo_copy("toml");
        for (i, b) in blocks(&doc).iter().enumerate() {
            if b.lang != "toml" {
                continue;
            }
            let (tally, scenario) = if b.body.contains("[[methods]]") {
                (&mut scenarios, true)
            } else if b.body.contains("[[joints]]") {
                (&mut robots, false)
            } else {
                continue;
            };
            if let Some(reason) = &b.not_run {
                tally.skip(b, reason);
                continue;
            }
            if scenario {
                run_scenario(b, &dir, i);
                if b.doc == "README.md" {
                    readme_scenarios += 1;
                }
            } else {
                load_robot(b, &dir, i);
            }
            tally.run += 1;
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
    scenarios.print("scenario examples");
    robots.print("robot-file examples");
    assert!(
        readme_scenarios >= 1,
        "README.md shows no scenario that runs"
    );
}

/// Every shell block runs in a copy of the repository with `calbench` on the path, unless
/// marked; the README's real-data example is among those run.
#[test]
fn shell_examples_run() {
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_calbench")).parent().unwrap();
    let path = std::env::join_paths(std::iter::once(bin_dir.to_path_buf()).chain(
        std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default()),
    ))
    .unwrap();
    let mut tally = Tally::default();
    let mut real_data = false;
    for doc in documents() {
        for b in blocks(&doc) {
            if b.lang != "sh" && b.lang != "bash" {
                continue;
            }
            if let Some(reason) = &b.not_run {
                tally.skip(&b, reason);
                continue;
            }
            let dir = repo_copy("sh");
            let o = match Command::new("bash")
                .args(["-euo", "pipefail", "-c", &b.body])
                .current_dir(&dir)
                .env("PATH", &path)
                .output()
            {
                Ok(o) => o,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    missing("bash is not on this machine: the shell examples cannot run");
                    return;
                }
                Err(e) => panic!("bash: {e}"),
            };
            assert!(
                o.status.success(),
                "{} failed ({}):\n{}\n--- output ---\n{}",
                b.name(),
                o.status,
                b.body,
                text(&o)
            );
            std::fs::remove_dir_all(&dir).unwrap();
            real_data |= b.doc == "README.md" && b.body.contains("calbench import");
            tally.run += 1;
        }
    }
    tally.print("shell examples");
    assert!(
        real_data,
        "the README's real-data example (`calbench import …`) did not run"
    );
}

/// Every fenced block names one of [`LANGUAGES`], and the blocks of a language that one file's
/// test runs stand in that file: a Python block elsewhere than docs/python.md, or Rust
/// elsewhere than README.md, would be shown and never run.
#[test]
fn every_block_is_of_a_language_a_test_runs_or_shows() {
    let mut wrong = Vec::new();
    for doc in documents() {
        for b in blocks(&doc) {
            let known = LANGUAGES.iter().any(|(l, _)| *l == b.lang);
            let placed = match b.lang.as_str() {
                "python" => b.doc == "docs/python.md",
                "rust" => b.doc == "README.md",
                _ => true,
            };
            if !known || !placed {
                wrong.push(b.name());
            }
        }
    }
    let known: Vec<String> = LANGUAGES
        .iter()
        .map(|(l, by)| format!("{l} ({by})"))
        .collect();
    assert!(
        wrong.is_empty(),
        "blocks no test runs or knows: {wrong:?}; the languages are {}",
        known.join(", ")
    );
}

#[test]
fn required_documents_exist() {
    for doc in REQUIRED {
        if !root().join(doc).is_file() {
            missing(&format!("{doc} does not exist"));
        }
    }
}

/// The head-to-head scripts need a Python with scipy and, for the second, Ceres and an
/// external Ceres program, which no test may need: run as a user would on a machine without
/// them, they must stop before any work with status 2 and a message naming what is missing.
#[test]
fn head_to_head_scripts_name_what_is_missing() {
    let run = |script: &str, args: &[&Path], python_env: Option<&str>| -> (Option<i32>, String) {
        let mut c = Command::new("bash");
        c.arg(root().join("benches").join(script)).args(args);
        match python_env {
            Some(p) => c.env("PYTHON", p),
            None => c.env_remove("PYTHON"),
        };
        let o = match c.output() {
            Ok(o) => o,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                missing("bash is not on this machine: the head-to-head scripts cannot run");
                return (Some(2), "bash missing".into());
            }
            Err(e) => panic!("bash: {e}"),
        };
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let expect = |(code, err): (Option<i32>, String), words: &[&str], what: &str| {
        if err == "bash missing" {
            return;
        }
        assert_eq!(code, Some(2), "{what}: {err}");
        for w in words {
            assert!(err.contains(w), "{what}: `{w}` not in: {err}");
        }
    };
    let none = Path::new("/nonexistent/calbench-python3");
    let no_scipy = Path::new("/bin/false");

    // scipy_ratio.sh [PYTHON]: the in-repository reference needs only the Python.
    expect(
        run("scipy_ratio.sh", &[none], None),
        &["not found", "/nonexistent/calbench-python3"],
        "scipy_ratio.sh, no such Python",
    );
    expect(
        run("scipy_ratio.sh", &[no_scipy], None),
        &["lacks numpy/scipy"],
        "scipy_ratio.sh, a Python without scipy",
    );
    expect(
        run("scipy_ratio.sh", &[], Some("/bin/false")),
        &["lacks numpy/scipy"],
        "scipy_ratio.sh, $PYTHON without scipy",
    );

    // ceres_sitting.sh PEER_DIR [PYTHON]: the peer folder is required.
    expect(
        run("ceres_sitting.sh", &[], None),
        &["missing PEER_DIR"],
        "ceres_sitting.sh without PEER_DIR",
    );
    let peer = scratch("peer-stub");
    expect(
        run("ceres_sitting.sh", &[&peer.join("absent")], None),
        &["absent", "not a folder"],
        "ceres_sitting.sh, PEER_DIR absent",
    );
    expect(
        run("ceres_sitting.sh", &[&peer], None),
        &["lacks", "ceres/sitting.sh", "h2h.toml", "scipy_ref.py"],
        "ceres_sitting.sh, an empty PEER_DIR",
    );
    std::fs::create_dir_all(peer.join("ceres")).unwrap();
    for f in ["h2h.toml", "scipy_ref.py", "ceres/summarize.py"] {
        std::fs::write(peer.join(f), "").unwrap();
    }
    let sitting = peer.join("ceres/sitting.sh");
    std::fs::write(&sitting, "#!/bin/sh\nexit 1\n").unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&sitting, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    expect(
        run("ceres_sitting.sh", &[&peer, no_scipy], None),
        &["lacks numpy/scipy"],
        "ceres_sitting.sh, a Python without scipy",
    );
    std::fs::remove_dir_all(&peer).unwrap();
}

/// The `rust-version` that Cargo.toml declares is one the crate and every locked dependency
/// build with: no package of `cargo metadata` asks for a newer compiler. (Clippy's
/// `incompatible_msrv` lint, run with `-D warnings` by scripts/test.sh, checks the crate's own
/// use of the standard library against the same number.)
#[test]
fn declared_rust_version_covers_every_dependency() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let o = Command::new(cargo)
        .args(["metadata", "--format-version", "1", "--locked"])
        .current_dir(root())
        .output()
        .expect("cargo metadata runs");
    assert!(o.status.success(), "cargo metadata: {}", text(&o));
    let meta: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let version = |s: &str| -> Vec<u64> {
        let mut v: Vec<u64> = s.split('.').map(|p| p.parse().unwrap()).collect();
        v.resize(3, 0);
        v
    };
    let packages = meta["packages"].as_array().unwrap();
    let ours = packages
        .iter()
        .find(|p| p["name"] == "calbench")
        .and_then(|p| p["rust_version"].as_str())
        .expect("Cargo.toml declares rust-version");
    let newer: Vec<String> = packages
        .iter()
        .filter_map(|p| {
            let need = p["rust_version"].as_str()?;
            (version(need) > version(ours))
                .then(|| format!("{} {} needs {need}", p["name"], p["version"]))
        })
        .collect();
    assert!(
        newer.is_empty(),
        "rust-version {ours} is below what these need: {newer:?}"
    );
}

#[path = "docs/numbers.rs"]
mod numbers;

#[path = "docs/options.rs"]
mod options;

#[path = "docs/verdicts.rs"]
mod verdicts;

//! Every scenario example in README.md, in docs/formats.md (`../shared/FORMATS.md`, the
//! user-facing contract, when it is beside the project) and in FORMATS-additions.md (what
//! calbench adds to it) runs as a user would run it: `calbench run EXAMPLE --trials 2`, sweep
//! included; and README's head-to-head scripts stop with a clear message where their peers
//! (Python with scipy, Ceres) are missing.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The ```toml blocks of a Markdown file that are scenarios (they have `[[methods]]`).
fn scenario_blocks(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut out = Vec::new();
    let mut rest = text.as_str();
    while let Some(i) = rest.find("```toml\n") {
        let body = &rest[i + 8..];
        let end = body.find("```").expect("unclosed code block");
        if body[..end].contains("[[methods]]") {
            out.push(body[..end].to_string());
        }
        rest = &body[end + 3..];
    }
    out
}

fn run_examples(doc: &Path) -> usize {
    let blocks = scenario_blocks(doc);
    let dir = std::env::temp_dir().join(format!(
        "calbench-docs-{}-{}",
        doc.file_stem().unwrap().to_string_lossy(),
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    for (i, b) in blocks.iter().enumerate() {
        let file = dir.join(format!("example{i}.toml"));
        std::fs::write(&file, b).unwrap();
        let out = dir.join(format!("out{i}"));
        let o = Command::new(env!("CARGO_BIN_EXE_calbench"))
            .arg("run")
            .arg(&file)
            .args(["--trials", "2", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{} example {i} failed: {}",
            doc.display(),
            String::from_utf8_lossy(&o.stderr)
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        if b.contains("[[sweep]]") {
            let keys = summary["sweep_keys"]
                .as_array()
                .expect("no sweep_keys")
                .len();
            assert!(summary["results"]
                .as_array()
                .unwrap()
                .iter()
                .all(|e| e["sweep"].as_object().is_some_and(|m| m.len() == keys)));
        } else if b.contains("[sweep]") {
            assert!(
                summary["sweep_key"].is_string(),
                "example {i}: no sweep_key"
            );
            assert!(summary["results"]
                .as_array()
                .unwrap()
                .iter()
                .all(|e| !e["sweep_value"].is_null()));
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
    blocks.len()
}

#[test]
fn readme_scenario_examples_run() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    assert!(run_examples(&root.join("README.md")) >= 1);
}

#[test]
fn formats_scenario_examples_run() {
    let formats = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/FORMATS.md");
    if !formats.exists() {
        eprintln!("{} is not beside the project; skipped", formats.display());
        return;
    }
    assert!(run_examples(&formats) >= 1);
}

#[test]
fn formats_additions_examples_run() {
    let doc = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("FORMATS-additions.md");
    assert!(run_examples(&doc) >= 1);
}

/// The head-to-head scripts of README.md (`benches/scipy_ratio.sh`, `benches/ceres_sitting.sh`)
/// need a Python with scipy and, for the second, Ceres, which no test may need: here they are
/// run as a user would on a machine without them, and must stop before any work with status 2
/// and a message naming what is missing.
#[test]
fn head_to_head_scripts_name_what_is_missing() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let peer = std::env::temp_dir().join(format!("calbench-peer-stub-{}", std::process::id()));
    std::fs::create_dir_all(peer.join("ceres")).unwrap();
    for f in ["h2h.toml", "scipy_ref.py"] {
        std::fs::write(peer.join(f), "").unwrap();
    }
    let sitting = peer.join("ceres/sitting.sh");
    std::fs::write(&sitting, "#!/bin/sh\nexit 1\n").unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&sitting, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let run = |script: &str, peer: &Path, python: &str| {
        let o = Command::new("bash")
            .arg(root.join("benches").join(script))
            .arg(peer)
            .arg(python)
            .output()
            .unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    for script in ["scipy_ratio.sh", "ceres_sitting.sh"] {
        let (code, err) = run(script, &peer.join("absent"), "python3");
        assert_eq!(code, Some(2), "{script}: {err}");
        assert!(err.contains("h2h.toml"), "{script}: {err}");
        let (code, err) = run(script, &peer, "/bin/false");
        assert_eq!(code, Some(2), "{script}: {err}");
        assert!(err.contains("lacks numpy/scipy"), "{script}: {err}");
    }
    std::fs::remove_dir_all(&peer).unwrap();
}

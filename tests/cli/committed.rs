//! The committed outputs (every file in the folders of `results/` that `.gitignore` keeps:
//! the papers' run summaries, the CI guard's baseline, the README's and REPRODUCTION.md's
//! figures and tables) are listed with
//! their SHA-256 in `results/SHA256SUMS` (the `sha256sum` format), so that a committed output
//! changes only on purpose: with the list, in the same commit, named in CHANGELOG.md. Beside
//! the list, `results/REGENERATE.toml` gives the command that writes each of them
//! (`regenerate.rs`).

use std::collections::BTreeMap;
use std::path::Path;

use crate::common::root;
use crate::regenerate::sha256;

/// Every file under `dir`, as its path relative to `base` (with `/`) and its bytes' SHA-256.
fn hashes(base: &Path, dir: &Path, out: &mut BTreeMap<String, String>) {
    for e in std::fs::read_dir(dir).expect("results/") {
        let p = e.expect("entry").path();
        if p.is_dir() {
            hashes(base, &p, out);
        } else {
            let rel = p
                .strip_prefix(base)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let bytes = std::fs::read(&p).expect("a committed output");
            out.insert(rel, sha256(&bytes));
        }
    }
}

#[test]
fn every_committed_output_has_the_sha256_its_list_gives() {
    let results = root().join("results");
    let listed = std::fs::read_to_string(results.join("SHA256SUMS")).expect("results/SHA256SUMS");
    // The committed folders are those `.gitignore` keeps (`!/results/NAME`): a run's own
    // output (`cargo run --release` writes results/default/) is not a committed output.
    let ignore = std::fs::read_to_string(root().join(".gitignore")).expect(".gitignore");
    let kept: Vec<&str> = ignore
        .lines()
        .filter_map(|l| l.trim().strip_prefix("!/results/"))
        .filter(|name| !matches!(*name, "SHA256SUMS" | "REGENERATE.toml"))
        .collect();
    assert!(kept.contains(&"reproduction"), "{kept:?}");
    let mut got = BTreeMap::new();
    for name in kept {
        hashes(&results, &results.join(name), &mut got);
    }
    let want: String = got
        .iter()
        .map(|(path, hex)| format!("{hex}  {path}\n"))
        .collect();
    assert!(got.len() >= 30, "only {} files under results/", got.len());
    assert_eq!(
        listed, want,
        "results/ differs from results/SHA256SUMS: a committed output changed, appeared or \
         went. If on purpose, name it in CHANGELOG.md and write results/SHA256SUMS as:\n{want}"
    );
}

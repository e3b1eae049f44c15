//! The layers of docs/architecture.md hold in the code: each top-level module of the library
//! imports (`crate::MODULE`) only modules listed below it in the document's table of layers
//! (so no two of them import each other: no cycle), and `report/` runs no study.

use std::collections::BTreeSet;
use std::path::Path;

use crate::common::{read, root};

/// The library's modules in the order docs/architecture.md lists them, bottom-up: the rows of
/// its table whose layer is a folder or file of `src/` other than the binary.
fn layers() -> Vec<String> {
    let doc = read(&root().join("docs/architecture.md"));
    let table = doc.split("## Layers").nth(1).expect("a Layers section");
    table
        .lines()
        .take_while(|l| !l.starts_with("## "))
        .filter_map(|l| l.strip_prefix("| `src/"))
        .map(|l| {
            let name = l.split(['/', '`', '.']).next().unwrap_or_default();
            name.to_string()
        })
        .filter(|n| n != "main")
        .collect()
}

/// The code of every source file under `dir` but its tests (`tests` folders, `tests.rs`, and
/// the `#[cfg(test)]` module at a file's end), as (path, code without comment lines).
pub(crate) fn code_under(dir: &Path) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = if d.is_dir() {
            std::fs::read_dir(&d)
                .unwrap()
                .map(|e| e.unwrap().path())
                .collect()
        } else {
            vec![d.clone()]
        };
        for p in entries {
            if p.is_dir() {
                if p.file_name().unwrap() != "tests" {
                    stack.push(p);
                }
            } else if p.extension().is_some_and(|x| x == "rs")
                && p.file_name().unwrap() != "tests.rs"
            {
                let text = read(&p);
                let code: String = text
                    .split("#[cfg(test)]")
                    .next()
                    .unwrap()
                    .lines()
                    .filter(|l| !l.trim_start().starts_with("//"))
                    .map(|l| l.to_string() + "\n")
                    .collect();
                out.push((p.display().to_string(), code));
            }
        }
    }
    out
}

/// The modules of the crate that `code` names: `crate::NAME` and `crate::{NAME, …}`.
fn named(code: &str, modules: &[String]) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    for part in code.split("crate::").skip(1) {
        let items: Vec<&str> = match part.strip_prefix('{') {
            Some(group) => group.split('}').next().unwrap().split(',').collect(),
            None => vec![part],
        };
        for item in items {
            let name: String = item
                .trim()
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if modules.contains(&name) {
                names.insert(name);
            }
        }
    }
    names
}

#[test]
fn each_module_imports_only_the_layers_below_it() {
    let layers = layers();
    for m in [
        "error",
        "numeric",
        "calibrate",
        "study",
        "report",
        "runner",
        "results",
    ] {
        assert!(layers.iter().any(|l| l == m), "{m} not in {layers:?}");
    }
    // Every module of the library is in the table.
    let lib = read(&root().join("src/lib.rs"));
    for m in lib.lines().filter_map(|l| l.strip_prefix("pub mod ")) {
        let m = m.trim_end_matches(';');
        assert!(layers.iter().any(|l| l == m), "{m} not in {layers:?}");
    }
    // Imports that run up a layer, each named with why it is still there: none.
    let known: [(&str, &str); 0] = [];
    let mut upward = Vec::new();
    for (rank, module) in layers.iter().enumerate() {
        let folder = root().join("src").join(module);
        let place = if folder.is_dir() {
            folder
        } else {
            root().join("src").join(format!("{module}.rs"))
        };
        for (path, code) in code_under(&place) {
            let rel = path
                .strip_prefix(&root().display().to_string())
                .unwrap_or(&path)
                .trim_start_matches('/')
                .to_string();
            for other in named(&code, &layers) {
                let up = layers.iter().position(|l| *l == other).unwrap() >= rank;
                if up && other != *module {
                    upward.push((rel.clone(), other));
                }
            }
        }
    }
    let known: Vec<(String, String)> = known
        .iter()
        .map(|(p, m)| (p.to_string(), m.to_string()))
        .collect();
    upward.sort();
    assert_eq!(
        upward, known,
        "imports of a module at or above the importing one (docs/architecture.md)"
    );
    // The report writes what is computed: it runs no trial, study or identification.
    for (path, code) in code_under(&root().join("src/report")) {
        for call in ["run_trial(", "Study::new(", "run_study("] {
            assert!(!code.contains(call), "{path} calls {call}");
        }
    }
}

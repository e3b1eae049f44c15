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

/// Whether `code` names the item or module `path` (`a::b::c`): written out, or imported in a
/// group (`a::b::{x, c}`).
fn names_path(code: &str, path: &str) -> bool {
    if code.contains(path) {
        return true;
    }
    let Some((parent, last)) = path.rsplit_once("::") else {
        return false;
    };
    code.split(&format!("{parent}::{{")).skip(1).any(|group| {
        let group = group.split('}').next().unwrap_or_default();
        group.split(',').any(|item| item.trim() == last)
    })
}

/// The modules and items `report/` must not import, as docs/architecture.md lists them (the
/// rule that begins "The report renders what the analysis decided").
fn forbidden_in_report() -> Vec<String> {
    let doc = read(&root().join("docs/architecture.md"));
    let rule = doc
        .split("- The report renders what the analysis decided")
        .nth(1)
        .expect("the rule of what the report imports");
    let rule = rule
        .split("\n- ")
        .next()
        .unwrap()
        .split("(tests/cli/layers.rs")
        .next()
        .unwrap();
    let names: Vec<String> = rule
        .split('`')
        .skip(1)
        .step_by(2)
        .filter(|n| n.contains("::"))
        .skip(2) // the Summary and analyse named first, as what the report renders
        .map(String::from)
        .collect();
    names
}

/// `report/` renders a `Summary`: it imports nothing that computes a statistic, a test, a
/// claim's verdict or an identifiability (docs/architecture.md); `check`'s regression rule
/// lives in `analysis::regression`.
#[test]
fn the_report_imports_no_statistics() {
    let forbidden = forbidden_in_report();
    for must in [
        "numeric::dist",
        "study::stats::paired",
        "study::verdict::evaluate",
        "robot::identifiability",
    ] {
        assert!(
            forbidden.iter().any(|f| f == must),
            "{must} not in {forbidden:?}"
        );
    }
    let known: [(&str, &str); 0] = [];
    let mut found = Vec::new();
    for (path, code) in code_under(&root().join("src/report")) {
        let rel = path
            .strip_prefix(&root().display().to_string())
            .unwrap_or(&path)
            .trim_start_matches('/')
            .to_string();
        for f in &forbidden {
            if names_path(&code, f) {
                found.push((rel.clone(), f.clone()));
            }
        }
    }
    found.sort();
    let known: Vec<(String, String)> = known
        .iter()
        .map(|(p, m)| (p.to_string(), m.to_string()))
        .collect();
    assert_eq!(found, known, "report/ imports what computes a statistic");
    // The check has teeth: a report that named one would be caught.
    assert!(names_path(
        "use crate::study::claims::{Claim, evaluate};",
        "study::claims::evaluate"
    ));
}

/// Each metric's key in `summary.json` (for example `validation_after_mm`, `eta_mean_pct`,
/// `param_rmse`, `failures`) and its `trials.csv` column (`after_rms_mm`) is written as a
/// string literal in at most one place of the library's and the Python module's code: where
/// the metric is declared (`study::metric`, or the validation keys it names); the report's
/// tables, the results database and `check` name the metric. The word `iterations` is left
/// out: the searches' option of that name (`--set iterations=N`) is a key of its own.
#[test]
fn each_metric_key_is_written_once() {
    use calbench::study::metric::Metric;
    let mut code = code_under(&root().join("src"));
    code.extend(code_under(&root().join("python/src")));
    let keys: BTreeSet<&str> = Metric::ALL
        .iter()
        .flat_map(|m| [Some(m.spec().field), m.column()])
        .flatten()
        .filter(|k| *k != "iterations")
        .collect();
    assert!(keys.len() >= 24, "{keys:?}");
    for key in keys {
        let quoted = format!("\"{key}");
        let places: Vec<&str> = code
            .iter()
            .flat_map(|(path, text)| {
                text.match_indices(&quoted)
                    .filter(|(i, _)| {
                        let next = text[i + quoted.len()..].chars().next();
                        matches!(next, Some('"' | '.'))
                    })
                    .map(move |_| path.as_str())
            })
            .collect();
        assert_eq!(places.len(), 1, "\"{key}\" written in {places:?}");
    }
}

/// The sibling modules (files of the same folder, `mod.rs` aside) that `code` names after
/// `prefix` (`super::` or `crate::PATH::`): `prefix NAME` and `prefix {NAME, …}`.
fn siblings_named(code: &str, prefix: &str, siblings: &BTreeSet<String>) -> BTreeSet<String> {
    let ident = |s: &str| -> String {
        s.trim()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut names = BTreeSet::new();
    for part in code.split(prefix).skip(1) {
        let items: Vec<String> = match part.strip_prefix('{') {
            Some(group) => {
                // The top-level items of the group (a nested `a::{b, c}` names `a`).
                let (mut depth, mut item, mut items) = (0, String::new(), Vec::new());
                for c in group.chars() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => break,
                        '}' => depth -= 1,
                        ',' if depth == 0 => items.push(std::mem::take(&mut item)),
                        c if depth == 0 => item.push(c),
                        _ => {}
                    }
                }
                items.push(item);
                items.iter().map(|i| ident(i)).collect()
            }
            None => vec![ident(part)],
        };
        names.extend(items.into_iter().filter(|n| siblings.contains(n)));
    }
    names
}

/// No two files of one module import each other, directly or through others (a circle
/// `run` → `shard` → `whole` → `run` makes three files one): every edge `super::NAME` or
/// `crate::MODULE::NAME` between the files of a folder points one way.
#[test]
fn the_files_of_a_module_import_each_other_in_no_circle() {
    use std::collections::BTreeMap;
    let src = root().join("src");
    let mut folders: BTreeMap<std::path::PathBuf, Vec<(String, String)>> = BTreeMap::new();
    for (path, code) in code_under(&src) {
        let p = Path::new(&path);
        let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
        if stem != "mod" && stem != "lib" && stem != "main" {
            let folder = p.parent().unwrap().to_path_buf();
            folders.entry(folder).or_default().push((stem, code));
        }
    }
    let mut circles = Vec::new();
    for (folder, files) in &folders {
        let module = folder
            .strip_prefix(&src)
            .unwrap()
            .to_string_lossy()
            .replace('/', "::");
        let siblings: BTreeSet<String> = files.iter().map(|f| f.0.clone()).collect();
        let edges: BTreeMap<&str, BTreeSet<String>> = files
            .iter()
            .map(|(stem, code)| {
                let mut to = siblings_named(code, "super::", &siblings);
                if !module.is_empty() {
                    to.extend(siblings_named(
                        code,
                        &format!("crate::{module}::"),
                        &siblings,
                    ));
                }
                to.remove(stem);
                (stem.as_str(), to)
            })
            .collect();
        // A circle through `start`: a path of edges back to it.
        for start in edges.keys() {
            let mut stack = vec![(start.to_string(), vec![start.to_string()])];
            let mut seen = BTreeSet::new();
            while let Some((at, path)) = stack.pop() {
                for next in &edges[at.as_str()] {
                    if next == start {
                        let circle = path.join(" → ") + " → " + start;
                        circles.push(format!("{}: {circle}", folder.display()));
                    } else if seen.insert(next.clone()) {
                        let mut p = path.clone();
                        p.push(next.clone());
                        stack.push((next.clone(), p));
                    }
                }
            }
        }
    }
    assert!(
        circles.is_empty(),
        "files that import each other in a circle:\n{}",
        circles.join("\n")
    );
}

/// Issue "one results model": no source file of the library, the binary or the Python
/// module's crate over 700 lines, its tests included (a file that grows past it is split by
/// what it does, as `error::serde_words` was).
#[test]
fn no_source_file_is_over_700_lines() {
    let mut stack = vec![root().join("src"), root().join("python/src")];
    let mut long = Vec::new();
    let mut files = 0;
    while let Some(d) = stack.pop() {
        for p in std::fs::read_dir(&d).unwrap().map(|e| e.unwrap().path()) {
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files += 1;
                let lines = read(&p).lines().count();
                if lines > 700 {
                    long.push(format!("{} ({lines} lines)", p.display()));
                }
            }
        }
    }
    assert!(files > 200, "{files} source files found");
    assert!(long.is_empty(), "over 700 lines: {long:?}");
}

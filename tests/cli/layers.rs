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

/// `a::{b, c::{d, e}}` written out: `a::b`, `a::c::d`, `a::c::e`.
fn expand_group(path: &str) -> Vec<String> {
    let Some(open) = path.find('{') else {
        return vec![path.to_string()];
    };
    let (head, rest) = (&path[..open], &path[open + 1..]);
    let (mut depth, mut item, mut items) = (0, String::new(), Vec::new());
    for c in rest.chars() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(std::mem::take(&mut item));
                continue;
            }
            _ => {}
        }
        item.push(c);
    }
    items.push(item);
    items
        .iter()
        .filter(|i| !i.trim().is_empty())
        .flat_map(|i| expand_group(&format!("{head}{}", i.trim())))
        .collect()
}

/// A source file as the import graph sees it: its module path (`["study", "scenario"]` for
/// `src/study/scenario/mod.rs`), whether it is a folder's `mod.rs` (or the crate root), and
/// its code without tests and comment lines.
struct SourceFile {
    module: Vec<String>,
    folder: bool,
    code: String,
}

/// The places of `word` in `code` that begin a word (no letter, digit, `_` or `:` before).
fn word_starts<'a>(code: &'a str, word: &'a str) -> impl Iterator<Item = usize> + 'a {
    code.match_indices(word).map(|(k, _)| k).filter(move |&k| {
        let before = code[..k].chars().next_back();
        !before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':')
    })
}

/// Which files each file imports: every path of a `use` (its groups written out) and every
/// `crate::`, `super::` or `self::` path written inline, taken to the deepest file it reaches.
/// A folder's `mod.rs` naming its own files declares or re-exports them, which is no import.
fn file_imports(files: &[SourceFile]) -> Vec<BTreeSet<usize>> {
    let at = |m: &[String]| files.iter().position(|f| f.module == m);
    let path_char = |c: &char| c.is_alphanumeric() || *c == '_' || *c == ':';
    let mut edges = Vec::new();
    for (i, f) in files.iter().enumerate() {
        let code = f.code.replace(char::is_whitespace, " ");
        let mut paths: Vec<String> = word_starts(&code, "use ")
            .filter_map(|k| code[k + 4..].split_once(';'))
            .flat_map(|(u, _)| expand_group(&u.replace(' ', "")))
            .collect();
        for root in ["crate::", "super::", "self::"] {
            paths.extend(
                word_starts(&code, root).map(|k| code[k..].chars().take_while(path_char).collect()),
            );
        }
        let mut to = BTreeSet::new();
        for path in paths {
            let segs: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
            let ups = segs
                .iter()
                .take_while(|s| **s == "super" || **s == "self")
                .count();
            let mut full = match segs.first() {
                Some(&"crate") => Vec::new(),
                Some(_) if ups > 0 => {
                    let supers = segs[..ups].iter().filter(|s| **s == "super").count();
                    f.module[..f.module.len().saturating_sub(supers)].to_vec()
                }
                _ => continue,
            };
            full.extend(segs[ups.max(1)..].iter().map(|s| s.to_string()));
            let Some(t) = (0..=full.len()).rev().find_map(|k| at(&full[..k])) else {
                continue;
            };
            if t != i && !(f.folder && files[t].module.starts_with(&f.module)) {
                to.insert(t);
            }
        }
        edges.push(to);
    }
    edges
}

/// The sets of two or more files that import one another, directly or through others: each
/// file with every other it reaches that reaches it back.
fn circles(edges: &[BTreeSet<usize>]) -> BTreeSet<BTreeSet<usize>> {
    let reach: Vec<BTreeSet<usize>> = (0..edges.len())
        .map(|start| {
            let (mut seen, mut stack) = (BTreeSet::new(), vec![start]);
            while let Some(at) = stack.pop() {
                stack.extend(edges[at].iter().filter(|&&n| seen.insert(n)));
            }
            seen
        })
        .collect();
    (0..edges.len())
        .filter(|&v| reach[v].contains(&v))
        .map(|v| {
            reach[v]
                .iter()
                .copied()
                .filter(|&u| reach[u].contains(&v))
                .collect()
        })
        .collect()
}

/// The library's and the binary's source files (tests aside), as the import graph sees them.
fn source_files() -> Vec<SourceFile> {
    let src = root().join("src");
    code_under(&src)
        .into_iter()
        .map(|(path, code)| {
            let rel = Path::new(&path)
                .strip_prefix(&src)
                .unwrap()
                .with_extension("");
            let mut module: Vec<String> = rel
                .iter()
                .map(|s| s.to_string_lossy().into_owned())
                .collect();
            let folder = matches!(
                module.last().map(String::as_str),
                Some("mod" | "lib" | "main")
            );
            if folder {
                module.pop();
            }
            SourceFile {
                module,
                folder,
                code,
            }
        })
        .collect()
}

/// No source files import each other, directly or through others (a circle makes them one
/// file: `study/scenario/mod.rs` naming a constant of `study/registration_study.rs`, which
/// reads scenarios, was one).
#[test]
fn no_source_files_import_each_other_in_a_circle() {
    let files = source_files();
    assert!(files.len() > 200, "{} source files found", files.len());
    let edges = file_imports(&files);
    assert!(edges.iter().map(BTreeSet::len).sum::<usize>() > 500);
    let found: Vec<String> = circles(&edges)
        .iter()
        .map(|c| {
            let names: Vec<String> = c.iter().map(|&i| files[i].module.join("::")).collect();
            names.join(" ⇄ ")
        })
        .collect();
    assert!(
        found.is_empty(),
        "source files in a circle of imports:\n{}",
        found.join("\n")
    );
    // The check has teeth: the circle it was written for is found.
    let file = |module: &str, folder: bool, code: &str| SourceFile {
        module: module.split("::").map(String::from).collect(),
        folder,
        code: code.to_string(),
    };
    let circle = [
        file(
            "study::scenario",
            true,
            "use crate::study::registration_study::KEY;",
        ),
        file(
            "study::registration_study",
            false,
            "let s = super::scenario::read(p);",
        ),
        file(
            "study::scenario::parse",
            false,
            "use super::{Scenario, super::kind};",
        ),
        file("study::kind", false, ""),
    ];
    let edges = file_imports(&circle);
    assert_eq!(
        circles(&edges),
        BTreeSet::from([BTreeSet::from([0, 1])]),
        "{edges:?}"
    );
    assert_eq!(edges[2], BTreeSet::from([0, 3]));
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

//! docs/architecture.md's list of the math library's functions that remain in the library's
//! code (the invariant "The joint angles' sines and cosines are calbench's") is complete: each
//! call of a transcendental function of the standard library outside the tests is in a file
//! or folder that the table names, with the function among those its row names; and each row
//! still names a call, so the table cannot go stale either.

use std::collections::BTreeSet;

use crate::common::{read, root};
use crate::layers::code_under;

/// The standard library's floating-point functions that call the math library (the ones that
/// are not correctly rounded IEEE operations: `sqrt`, `mul_add` and `powi` are left out).
const LIBRARY: [&str; 25] = [
    "sin", "cos", "sin_cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh",
    "asinh", "acosh", "atanh", "exp", "exp2", "exp_m1", "ln", "ln_1p", "log", "log2", "log10",
    "powf", "cbrt", "hypot",
];

/// The table's rows: the files and folders of `src/` each names (`robot/chain.rs`,
/// `report/plots/`) and the functions it lists.
fn allowed() -> Vec<(Vec<String>, BTreeSet<String>)> {
    let doc = read(&root().join("docs/architecture.md"));
    let table = doc
        .split("| where | calls | why safe |")
        .nth(1)
        .expect("docs/architecture.md: the table of the math library's remaining functions");
    let ticked = |cell: &str| -> Vec<String> {
        cell.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    };
    table
        .lines()
        .skip(2)
        .map_while(|l| l.trim().strip_prefix('|'))
        .map(|row| {
            let cells: Vec<&str> = row.split('|').collect();
            let paths = ticked(cells[0]).into_iter().filter(|p| p.contains('/'));
            let calls = ticked(cells[1]).into_iter();
            (paths.collect(), calls.collect())
        })
        .collect()
}

/// The math-library calls of `code` (`x.sin()`, `Real::sin(x)`), as (function, line).
fn calls(code: &str) -> Vec<(&'static str, String)> {
    let mut out = Vec::new();
    for line in code.lines() {
        for f in LIBRARY {
            let forms = [format!(".{f}("), format!("::{f}(")];
            let method = line.contains(&forms[0]);
            let path = ["f64", "f32", "Real"]
                .iter()
                .any(|t| line.contains(&format!("{t}{}", forms[1])));
            if method || path {
                out.push((f, line.trim().to_string()));
            }
        }
    }
    out
}

#[test]
fn every_math_library_call_is_in_the_determinism_table() {
    let rows = allowed();
    assert!(rows.len() >= 10, "the table's rows: {rows:?}");
    let src = root().join("src");
    let files = code_under(&src);
    let relative = |p: &str| {
        p.strip_prefix(&format!("{}/", src.display()))
            .unwrap_or(p)
            .to_string()
    };
    let covers = |path: &String, file: &str| {
        path == file || (path.ends_with('/') && file.starts_with(path.as_str()))
    };
    let mut unlisted = Vec::new();
    let mut used = vec![false; rows.len()];
    for (path, code) in &files {
        let file = relative(path);
        for (f, line) in calls(code) {
            let row = rows
                .iter()
                .position(|(paths, fs)| fs.contains(f) && paths.iter().any(|p| covers(p, &file)));
            match row {
                Some(r) => used[r] = true,
                None => unlisted.push(format!("src/{file}: `{f}` in `{line}`")),
            }
        }
    }
    assert!(
        unlisted.is_empty(),
        "math-library calls that docs/architecture.md's table of remaining functions does not \
         list (move them onto numeric::sin_cos, or add a row saying why each is safe):\n{}",
        unlisted.join("\n")
    );
    let stale: Vec<_> = rows
        .iter()
        .zip(&used)
        .filter(|(r, used)| !r.0.is_empty() && !**used)
        .map(|(r, _)| format!("{:?}: {:?}", r.0, r.1))
        .collect();
    assert!(
        stale.is_empty(),
        "rows of docs/architecture.md's table that name no call any more:\n{}",
        stale.join("\n")
    );
}

/// The scan finds what it looks for: both call forms, not a function whose name only starts
/// like one, and not calbench's own `numeric::sin_cos`.
#[test]
fn the_scan_sees_both_call_forms() {
    let code = "let a = x.sin();\nlet b = Real::ln(y);\nlet c = numeric::sin_cos(t);\n\
                let d = v.sinh_like();\nlet e = q.powi(2);";
    let found: Vec<&str> = calls(code).into_iter().map(|(f, _)| f).collect();
    assert_eq!(found, ["sin", "ln"]);
}

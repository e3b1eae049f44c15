//! Every number REPRODUCTION.md quotes has a source, and the ones that come from a committed
//! output are recomputed from it at the precision quoted.
//!
//! The sources are in `docs/reproduction-numbers.toml`: one `[[line]]` per line of
//! REPRODUCTION.md that quotes a number, in the document's order, each with `has` (a text the
//! line contains, so that a table row or a sentence is found again after an edit) and `n`, one
//! source per number of the line, in the line's order. A source is one of:
//!
//! - an expression, recomputed and compared with the number at the digits quoted: `{FILE#PATH}`
//!   reads a committed output or a scenario (a `.json`, `.toml` or `.csv` file; `{PATH}` reads
//!   the line's `file`), `PATH` a `/`-separated list of keys, indices and `[label]` (the element
//!   of an array whose `method`, `label`, `id` or `name` is `label`; `[key=value]` the one whose
//!   `key` is `value`; `[key]` also a key holding `/`); `$k` is the k-th number of the same line as quoted (a delta, a ratio);
//!   `+ - * /`, parentheses, numbers, `deg` (180/π), `sqrt(x)`, `abs(x)`, `min(x, y)`,
//!   `max(x, y)`, `len({…})`, `count({…}, a < b)` (the rows of a `.csv`, or the elements of an
//!   array, whose field `a` is below field `b`; `>` too); over the rows of a `trials.csv`,
//!   `mean({…}, c, M)` and `median({…}, c, M)` (column `c` of method `M`'s rows) and
//!   `paired({…}, c, A < B)` (the trials at which method `A`'s `c` is below `B`'s; `>` too),
//!   each taking a last argument `key=value` that keeps the rows whose column `key` is `value`
//!   (a sweep point), `M` optional in `mean` and `median`. The tolerance is half the last digit quoted,
//!   plus what the rounding of each `$k` used can move the expression;
//! - `paper: SOURCE` (or `paper` in a table whose column names the paper): a paper's figure;
//! - `const: SOURCE`: a constant of calbench's definition or of a formula, with where it is
//!   defined;
//! - `unchecked: REASON`: a figure of a run whose output is not committed; these are counted
//!   and printed, and their number may not grow (`UNCHECKED_AT_MOST`).
//!
//! A number is a decimal (`1 000` grouping, `−` or `-` sign, `e-5` exponent) outside code
//! spans, comments, link targets, fenced blocks and the generated verdict table (checked by
//! `verdicts.rs`); section, equation, table, figure, reference, model, joint, trial, step and
//! series numbers and the papers' years are references, not numbers quoted.
//!
//! When a committed summary is regenerated, the test names every line whose number moved and
//! what the output now gives: the number is updated in REPRODUCTION.md, the sidecar stays.

use super::root;
use std::collections::HashMap;

#[path = "numbers_expr.rs"]
mod expr;
use expr::{eval, refs, Files};

/// The figures whose run is not committed may not grow in number.
const UNCHECKED_AT_MOST: usize = 0;

/// A number of the document: its line, its text, its value and half its last digit.
struct Quoted {
    line: usize,
    text: String,
    value: f64,
    half: f64,
}

fn is_word(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// `s` with code spans, HTML comments and link targets blanked (one space per character).
fn blank(line: &str) -> Vec<char> {
    let mut s: Vec<char> = line.chars().collect();
    let cut = |open: &str, close: &str, s: &mut Vec<char>| {
        let (o, c): (Vec<char>, Vec<char>) = (open.chars().collect(), close.chars().collect());
        let mut i = 0;
        while i + o.len() <= s.len() {
            if s[i..i + o.len()] == o[..] {
                let from = i + o.len();
                let end = (from..=s.len().saturating_sub(c.len()))
                    .find(|&j| j + c.len() <= s.len() && s[j..j + c.len()] == c[..]);
                if let Some(j) = end {
                    s[i..j + c.len()].iter_mut().for_each(|x| *x = ' ');
                    i = j + c.len();
                    continue;
                }
            }
            i += 1;
        }
    };
    cut("`", "`", &mut s);
    cut("<!--", "-->", &mut s);
    cut("](", ")", &mut s);
    s
}

/// Whether the text before a number makes it a reference (`§ 4.1`, `eq. 17`, `table 2`,
/// `Li 2018` …) rather than a figure.
fn is_reference(before: &[char]) -> bool {
    let text: String = before.iter().collect();
    let t = text.trim_end();
    let spaced = t.len() < text.len();
    if t.ends_with('§') {
        return true;
    }
    // A heading's `Table 2` or `Eq. 17` is a reference too: the first letter in either case.
    let word_end = |w: &str| {
        let lower = t.to_lowercase();
        let w = w.to_lowercase();
        lower.len() == t.len()
            && lower
                .strip_suffix(&w)
                .is_some_and(|rest| !rest.chars().last().is_some_and(is_word))
    };
    let dotted = ["eq.", "eqs.", "fig.", "figs.", "ref."];
    let spaced_words = [
        "table",
        "tables",
        "model",
        "models",
        "joint",
        "joints",
        "trial",
        "conclusion",
        "step",
        "Li",
        "Guo",
        "Qiao",
        "Ban",
        "Series",
    ];
    dotted.iter().any(|w| word_end(w)) || (spaced && spaced_words.iter().any(|w| word_end(w)))
}

/// The continuation of a list of references: `4 and 5`, `12–15`, `5/6`, `2, 3`.
fn continues_reference(before: &[char]) -> bool {
    let text: String = before.iter().collect();
    let t = text.trim_end();
    let t = t.strip_suffix('§').unwrap_or(t).trim_end();
    ["and", "–", "/", ","].iter().any(|sep| {
        t.strip_suffix(sep).is_some_and(|r| {
            r.trim_end()
                .chars()
                .last()
                .is_some_and(|c| c.is_ascii_digit())
        })
    })
}

/// The numbers of one line (already blanked).
fn numbers_of(s: &[char], line: usize, out: &mut Vec<Quoted>) {
    let sign = |c: char| c == '-' || c == '−' || c == '+';
    let excluded = |c: char| is_word(c) || c == '.' || c == '/' || sign(c);
    let mut prev_ref = false;
    let mut i = 0;
    while i < s.len() {
        let start = i;
        let signed = sign(s[i]) && s.get(i + 1).is_some_and(|c| c.is_ascii_digit());
        if !(s[i].is_ascii_digit() || signed) || (i > 0 && excluded(s[i - 1])) {
            i += 1;
            continue;
        }
        let mut j = if signed { i + 1 } else { i };
        let mut digits = String::new();
        while j < s.len() && s[j].is_ascii_digit() {
            digits.push(s[j]);
            j += 1;
        }
        while j + 3 < s.len() + 1
            && (s[j] == ' ' || s[j] == '\u{a0}')
            && s[j + 1..]
                .iter()
                .take(3)
                .filter(|c| c.is_ascii_digit())
                .count()
                == 3
            && !s.get(j + 4).is_some_and(|c| c.is_ascii_digit())
        {
            digits.extend(&s[j + 1..j + 4]);
            j += 4;
        }
        let mut decimals = 0i32;
        if s.get(j) == Some(&'.') && s.get(j + 1).is_some_and(|c| c.is_ascii_digit()) {
            digits.push('.');
            j += 1;
            while j < s.len() && s[j].is_ascii_digit() {
                digits.push(s[j]);
                decimals += 1;
                j += 1;
            }
        }
        let mut exponent = 0i32;
        if s.get(j) == Some(&'e') {
            let mut k = j + 1;
            let negative = s.get(k).is_some_and(|&c| c == '-' || c == '−');
            if s.get(k).is_some_and(|&c| sign(c)) {
                k += 1;
            }
            let e0 = k;
            while k < s.len() && s[k].is_ascii_digit() {
                k += 1;
            }
            if k > e0 {
                let e: i32 = s[e0..k].iter().collect::<String>().parse().unwrap();
                exponent = if negative { -e } else { e };
                j = k;
            }
        }
        // Not a number when letters, `_` or `/` follow in the same word (`2.4c`, `tx60-floor`).
        let mut k = j;
        let mut word = false;
        while k < s.len() && (is_word(s[k]) || s[k] == '.') {
            word |= s[k].is_ascii_alphabetic() || s[k] == '_';
            k += 1;
        }
        word |= s.get(k) == Some(&'/');
        if word {
            i = j.max(i + 1);
            continue;
        }
        i = j;
        if is_reference(&s[..start]) || (prev_ref && continues_reference(&s[..start])) {
            prev_ref = true;
            continue;
        }
        prev_ref = false;
        let magnitude: f64 = format!("{digits}e{exponent}").parse().unwrap();
        let negative = signed && s[start] != '+';
        out.push(Quoted {
            line,
            text: s[start..j].iter().collect(),
            value: if negative { -magnitude } else { magnitude },
            half: 0.5 * 10f64.powi(exponent - decimals),
        });
    }
}

/// Every number REPRODUCTION.md quotes outside the generated verdict table.
fn quoted(text: &str) -> Vec<Quoted> {
    let mut out = Vec::new();
    let (mut fence, mut verdicts, mut seen_table) = (false, false, false);
    for (i, line) in text.lines().enumerate() {
        if line.starts_with("```") {
            fence = !fence;
            continue;
        }
        if fence {
            continue;
        }
        if line.starts_with("<!-- verdicts") {
            (verdicts, seen_table) = (true, false);
            continue;
        }
        if verdicts {
            if line.starts_with('|') {
                seen_table = true;
                continue;
            }
            if !seen_table {
                continue;
            }
            verdicts = false;
        }
        numbers_of(&blank(line), i + 1, &mut out);
    }
    out
}

#[test]
fn every_number_reproduction_md_quotes_has_a_checked_source() {
    let doc = std::fs::read_to_string(root().join("REPRODUCTION.md")).expect("REPRODUCTION.md");
    let side_path = "docs/reproduction-numbers.toml";
    let side: toml::Value =
        toml::from_str(&std::fs::read_to_string(root().join(side_path)).expect(side_path))
            .unwrap_or_else(|e| panic!("{side_path}: {e}"));
    let entries = side["line"].as_array().expect("[[line]] entries");
    let numbers = quoted(&doc);
    let mut lines: Vec<(usize, Vec<&Quoted>)> = Vec::new();
    for q in &numbers {
        match lines.last_mut() {
            Some((l, v)) if *l == q.line => v.push(q),
            _ => lines.push((q.line, vec![q])),
        }
    }
    let text: Vec<&str> = doc.lines().collect();
    let mut files = Files::default();
    let (mut errors, mut unchecked) = (Vec::new(), Vec::new());
    let mut counts: HashMap<&str, usize> = HashMap::new();
    for (k, (line, qs)) in lines.iter().enumerate() {
        let at = format!("REPRODUCTION.md:{line}");
        let Some(entry) = entries.get(k) else {
            errors.push(format!(
                "{at}: {} numbers with no [[line]] in {side_path}",
                qs.len()
            ));
            break;
        };
        let has = entry["has"].as_str().unwrap_or("");
        if has.is_empty() || !text[line - 1].contains(has) {
            errors.push(format!(
                "{at}: [[line]] {} of {side_path} is for a line containing {has:?}; this line \
                 quotes {:?} (a line added or removed?)",
                k + 1,
                qs.iter().map(|q| q.text.as_str()).collect::<Vec<_>>()
            ));
            break;
        }
        let n: Vec<&str> = entry["n"].as_array().map_or(vec![], |a| {
            a.iter().map(|v| v.as_str().unwrap_or("")).collect()
        });
        if n.len() != qs.len() {
            errors.push(format!(
                "{at}: {} numbers {:?}, {} sources in {side_path}",
                qs.len(),
                qs.iter().map(|q| q.text.as_str()).collect::<Vec<_>>(),
                n.len()
            ));
            continue;
        }
        let file = entry.get("file").and_then(|f| f.as_str());
        let values: Vec<f64> = qs.iter().map(|q| q.value).collect();
        for (q, src) in qs.iter().zip(&n) {
            let kind = ["paper", "const", "unchecked"].into_iter().find(|k| {
                src.strip_prefix(k)
                    .is_some_and(|r| r.is_empty() || r.starts_with(':'))
            });
            if let Some(kind) = kind {
                *counts.entry(kind).or_default() += 1;
                if kind == "unchecked" {
                    unchecked.push(format!("{at}: {} ({src})", q.text));
                }
                continue;
            }
            *counts.entry("recomputed").or_default() += 1;
            let got = eval(src, &values, file, &mut files);
            let mut slack = q.half * (1.0 + 1e-9);
            for r in refs(src) {
                let (Some(v), Some(h)) = (values.get(r - 1), qs.get(r - 1).map(|q| q.half)) else {
                    continue;
                };
                let mut moved = values.clone();
                let mut worst: f64 = 0.0;
                for x in [v - h, v + h] {
                    moved[r - 1] = x;
                    if let (Ok(a), Ok(b)) = (eval(src, &moved, file, &mut files), &got) {
                        worst = worst.max((a - b).abs());
                    }
                }
                slack += worst * (1.0 + 1e-9);
            }
            match got {
                Err(e) => errors.push(format!("{at}: {} from `{src}`: {e}", q.text)),
                Ok(v) if (v - q.value).abs() > slack || !v.is_finite() => errors.push(format!(
                    "{at}: quotes {} but `{src}` gives {v} (to the digits quoted: within {:.1e})",
                    q.text, q.half
                )),
                Ok(_) => {}
            }
        }
    }
    if errors.is_empty() && entries.len() > lines.len() {
        errors.push(format!(
            "{side_path} has {} [[line]] entries, REPRODUCTION.md {} lines with numbers",
            entries.len(),
            lines.len()
        ));
    }
    eprintln!(
        "REPRODUCTION.md: {} numbers on {} lines: {counts:?}",
        numbers.len(),
        lines.len()
    );
    for u in &unchecked {
        eprintln!("unchecked: {u}");
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
    // Not `len <= UNCHECKED_AT_MOST`: at 0 clippy calls that comparison absurd.
    assert!(
        unchecked.len().saturating_sub(UNCHECKED_AT_MOST) == 0,
        "{} unchecked numbers, at most {UNCHECKED_AT_MOST}",
        unchecked.len()
    );
    assert!(
        counts.get("recomputed").copied().unwrap_or(0) >= 800,
        "{counts:?}"
    );
}

/// The number reader on the forms REPRODUCTION.md uses: signs, grouping, exponents, references.
#[test]
fn numbers_are_read_as_quoted_and_references_are_not_numbers() {
    let mut out = Vec::new();
    let line = "(§4.1, eqs. 12–15, table 2) −0.101 and +0.055, 60 000 of 1.3297e14, \
                Li 2018 at 2.4c k0 tx60-floor 4.6e-3 rad `1.5` 8.7 %";
    numbers_of(&blank(line), 1, &mut out);
    let got: Vec<(&str, f64)> = out.iter().map(|q| (q.text.as_str(), q.value)).collect();
    assert_eq!(
        got,
        vec![
            ("−0.101", -0.101),
            ("+0.055", 0.055),
            ("60 000", 60000.0),
            ("1.3297e14", 1.3297e14),
            ("4.6e-3", 4.6e-3),
            ("8.7", 8.7)
        ]
    );
    assert_eq!(out[0].half, 0.0005);
    assert!((out[3].half - 0.00005e14).abs() < 1.0);
}

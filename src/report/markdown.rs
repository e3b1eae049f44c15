//! Markdown helpers for `report.md` (docs/formats.md, `run` outputs): GitHub tables and compact
//! number formatting.

use crate::numeric::Real;

/// The placeholder written for a missing or non-finite number.
pub const MISSING: &str = "—";

/// Formats `v` with `sig` significant digits (at least 1, at most 17), compactly:
///
/// - non-finite values (NaN, ±∞) give [`MISSING`] (`—`);
/// - zero (either sign) gives `0`;
/// - when the decimal exponent of the rounded value lies in −4 ..= 5, fixed notation with
///   `sig` significant digits, every integer digit kept (`12345.6` → `12346` at 3 digits);
/// - otherwise scientific notation `1.23e-5` (no `+`, no leading zeros in the exponent);
/// - trailing zeros after the decimal point, and a bare point, are dropped (`2.50` → `2.5`).
///
/// ```
/// use calbench::report::markdown::fmt_num;
/// assert_eq!(fmt_num(4.56789, 3), "4.57");
/// assert_eq!(fmt_num(1.23456e-5, 3), "1.23e-5");
/// assert_eq!(fmt_num(f64::NAN, 3), "—");
/// ```
pub fn fmt_num(v: Real, sig: usize) -> String {
    if !v.is_finite() {
        return MISSING.to_string();
    }
    if v == 0.0 {
        return "0".to_string();
    }
    let sig = sig.clamp(1, 17);
    // The exponent after rounding to `sig` digits (9.996 → 1.00e1 at 3 digits).
    let sci = format!("{:.*e}", sig - 1, v);
    let (mantissa, exp) = match sci.split_once('e') {
        Some((m, e)) => (m, e.parse::<i32>().unwrap_or(0)),
        None => (sci.as_str(), 0),
    };
    if (-4..=5).contains(&exp) {
        let decimals = (sig as i32 - 1 - exp).max(0) as usize;
        let fixed = format!("{:.*}", decimals, v);
        let fixed = trim_zeros(&fixed);
        if fixed == "-0" {
            "0".to_string()
        } else {
            fixed
        }
    } else {
        format!("{}e{}", trim_zeros(mantissa), exp)
    }
}

/// Drops trailing zeros after a decimal point, and then the point itself.
fn trim_zeros(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

/// Whether a cell reads as a number: a float (optionally with a trailing `%`), or a
/// placeholder for a missing number (`—`, `-`, `NaN`, `inf`).
fn numeric_kind(cell: &str) -> Option<bool> {
    let c = cell.trim();
    if c.is_empty() || c == MISSING || c == "-" {
        return Some(false); // a placeholder: compatible with a numeric column
    }
    let c = c.strip_suffix('%').unwrap_or(c).trim_end();
    if c.parse::<f64>().is_ok() {
        Some(true)
    } else {
        None
    }
}

/// A name (a robot's, a scenario's, a file's) as Markdown text that reads as written: each
/// character Markdown would take for emphasis, code, a link, HTML or a table cell (`\`, `` ` ``,
/// `*`, `_`, `~`, `[`, `]`, `<`, `>`, `|`, `#`) escaped with a backslash, line breaks as spaces.
///
/// ```
/// use calbench::report::markdown::inline;
/// assert_eq!(inline("arm_*2*"), "arm\\_\\*2\\*");
/// ```
pub fn inline(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\\' | '`' | '*' | '_' | '~' | '[' | ']' | '<' | '>' | '|' | '#' => {
                out.push('\\');
                out.push(c);
            }
            '\r' | '\n' => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// Escapes a cell for a GitHub table: `|` becomes `\|`, line breaks become spaces.
fn escape(cell: &str) -> String {
    cell.replace('|', "\\|").replace(['\r', '\n'], " ")
}

/// A GitHub-flavoured Markdown table.
///
/// A column is right-aligned (`---:`) when every cell of it is a number (optionally with a
/// trailing `%`) or a placeholder for one (`—`, `-`, empty), and at least one is a number;
/// other columns are left-aligned. Cells are padded to the column width (in characters) so
/// the raw text lines up. Rows shorter than the header are filled with empty cells; a row
/// longer than the header adds columns with an empty heading (no data is dropped). `|` in a
/// cell is escaped and line breaks become spaces. The result ends with a newline.
///
/// ```
/// use calbench::report::markdown::table;
/// let t = table(&["method", "rms"], &[vec!["ls".into(), "0.12".into()]]);
/// assert_eq!(t, "| method |  rms |\n| ------ | ---: |\n| ls     | 0.12 |\n");
/// ```
pub fn table(headers: &[&str], rows: &[Vec<String>]) -> String {
    let ncol = rows
        .iter()
        .map(Vec::len)
        .max()
        .unwrap_or(0)
        .max(headers.len());
    if ncol == 0 {
        return String::new();
    }
    let head: Vec<String> = (0..ncol)
        .map(|j| escape(headers.get(j).copied().unwrap_or("")))
        .collect();
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            (0..ncol)
                .map(|j| escape(r.get(j).map(String::as_str).unwrap_or("")))
                .collect()
        })
        .collect();
    let right: Vec<bool> = (0..ncol)
        .map(|j| {
            let mut any_number = false;
            for r in &body {
                match numeric_kind(&r[j]) {
                    Some(true) => any_number = true,
                    Some(false) => {}
                    None => return false,
                }
            }
            any_number
        })
        .collect();
    // Width in characters, at least 3 so the delimiter row is valid.
    let width: Vec<usize> = (0..ncol)
        .map(|j| {
            body.iter()
                .map(|r| r[j].chars().count())
                .chain(std::iter::once(head[j].chars().count()))
                .max()
                .unwrap_or(0)
                .max(3)
        })
        .collect();

    let mut out = String::new();
    let push_row = |cells: &[String], out: &mut String| {
        out.push('|');
        for (j, c) in cells.iter().enumerate() {
            let pad = width[j].saturating_sub(c.chars().count());
            out.push(' ');
            if right[j] {
                out.extend(std::iter::repeat_n(' ', pad));
                out.push_str(c);
            } else {
                out.push_str(c);
                out.extend(std::iter::repeat_n(' ', pad));
            }
            out.push_str(" |");
        }
        out.push('\n');
    };
    push_row(&head, &mut out);
    out.push('|');
    for j in 0..ncol {
        out.push(' ');
        if right[j] {
            out.extend(std::iter::repeat_n('-', width[j] - 1));
            out.push(':');
        } else {
            out.extend(std::iter::repeat_n('-', width[j]));
        }
        out.push_str(" |");
    }
    out.push('\n');
    for r in &body {
        push_row(r, &mut out);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fmt_num_hand_checked() {
        // (value, significant digits, text)
        for (v, digits, text) in [
            (4.56789, 3, "4.57"),
            (-0.5, 2, "-0.5"),
            (2.5, 3, "2.5"),
            (1.0, 3, "1"),
            (100.0, 2, "100"),
            (12345.6, 3, "12346"),
            (0.000123456, 3, "0.000123"),
            (0.0001, 3, "0.0001"),
            (1.23456e-5, 3, "1.23e-5"),
            (-1.0e-5, 3, "-1e-5"),
            (2.5e7, 2, "2.5e7"),
            (1.5e6, 4, "1.5e6"),
            (999_999.0, 4, "1e6"),
            (9.996, 3, "10"),
            (0.099996, 3, "0.1"),
            (0.0, 3, "0"),
            (-0.0, 3, "0"),
            (-0.0001, 1, "-0.0001"),
            (0.123, 0, "0.1"),
            (Real::NAN, 3, "—"),
            (Real::INFINITY, 3, "—"),
            (Real::NEG_INFINITY, 3, "—"),
        ] {
            assert_eq!(fmt_num(v, digits), text, "fmt_num({v}, {digits})");
        }
    }

    #[test]
    fn fmt_num_round_trips_to_sig_digits() {
        for &v in &[1.234567e-9, 0.0314159, 5.55555555, 6022.14, 1.380649e23] {
            let s = fmt_num(v, 4);
            let back: f64 = s.parse().expect("parsable");
            assert!(((back - v) / v).abs() < 5e-4, "{v} -> {s}");
        }
    }

    #[test]
    fn table_hand_checked() {
        let rows = vec![
            vec!["ls".to_string(), "0.125".to_string(), "12%".to_string()],
            vec![
                "ridge|igg3".to_string(),
                "—".to_string(),
                "3.5 %".to_string(),
            ],
        ];
        let t = table(&["method", "rms (mm)", "η"], &rows);
        let expected = "\
| method      | rms (mm) |     η |
| ----------- | -------: | ----: |
| ls          |    0.125 |   12% |
| ridge\\|igg3 |        — | 3.5 % |
";
        assert_eq!(t, expected);
    }

    #[test]
    fn table_text_and_ragged_rows() {
        let rows = vec![
            vec!["a".to_string()],
            vec!["b".to_string(), "x".to_string(), "7".to_string()],
        ];
        let t = table(&["k", "v"], &rows);
        let expected = "\
| k   | v   |     |
| --- | --- | --: |
| a   |     |     |
| b   | x   |   7 |
";
        assert_eq!(t, expected);
        // An all-placeholder column is not numeric.
        let t = table(&["n"], &[vec!["—".to_string()]]);
        assert_eq!(t, "| n   |\n| --- |\n| —   |\n");
        assert_eq!(table(&[], &[]), "");
    }
}

//! A task's split file (docs/formats.md § 9.2): which rows of one data file calibrate and
//! which validate, written out row by row so that every entry is scored on the same rows.

use std::path::Path;

use crate::error::{read_text, Error, Result};

/// The rows of a data file that calibrate and those that validate (0-based, in file order).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Split {
    /// The number of data rows the split is written for.
    pub rows: usize,
    /// The calibration rows, ascending.
    pub calibration: Vec<usize>,
    /// The validation rows, ascending.
    pub validation: Vec<usize>,
}

impl Split {
    /// Reads and checks a split file: a `rows N` line, then `calibration A[-B]` and
    /// `validation A[-B]` lines; `#` comments and blank lines are skipped. Each row below N
    /// lies in exactly one part and each part holds a row. A refusal names the file and line.
    pub fn load(path: &Path) -> Result<Split> {
        let text = read_text(path)?;
        Split::parse(path, &text)
    }

    fn parse(path: &Path, text: &str) -> Result<Split> {
        let at = |line: usize, msg: String| Error::file(path, format!("line {line}"), msg);
        let mut rows: Option<usize> = None;
        // The line that put each row in a part, and the part (true: calibration).
        let mut owner: Vec<Option<(usize, bool)>> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let body = raw.split('#').next().unwrap_or("").trim();
            if body.is_empty() {
                continue;
            }
            let mut words = body.split_whitespace();
            let (word, arg) = (words.next().unwrap_or(""), words.next());
            if words.next().is_some() || arg.is_none() {
                return Err(at(
                    line,
                    format!(
                        "`{body}`: expected `rows N`, `calibration A[-B]` or `validation A[-B]`"
                    ),
                ));
            }
            let arg = arg.unwrap_or("");
            let number = |s: &str| {
                s.parse::<usize>().map_err(|_| {
                    let what = if word == "rows" {
                        "a number of rows"
                    } else {
                        "a row number or a range A-B of row numbers"
                    };
                    at(line, format!("`{arg}` is not {what}"))
                })
            };
            match word {
                "rows" => {
                    if rows.is_some() {
                        return Err(at(line, "`rows` is given twice".into()));
                    }
                    let n = number(arg)?;
                    if n < 2 {
                        return Err(at(
                            line,
                            format!("`rows {n}`: a split needs 2 rows or more (one calibrates, one validates)"),
                        ));
                    }
                    rows = Some(n);
                    owner = vec![None; n];
                }
                "calibration" | "validation" => {
                    let n = rows.ok_or_else(|| {
                        at(line, "the `rows N` line must come before the rows".into())
                    })?;
                    let (a, b) = match arg.split_once('-') {
                        Some((a, b)) => (number(a)?, number(b)?),
                        None => (number(arg)?, number(arg)?),
                    };
                    if a > b {
                        return Err(at(line, format!("range {a}-{b} runs backwards")));
                    }
                    if b >= n {
                        return Err(at(
                            line,
                            format!(
                                "row {b} is out of range: the split is of {n} rows (0 to {})",
                                n.saturating_sub(1)
                            ),
                        ));
                    }
                    for (r, o) in owner.iter_mut().enumerate().take(b + 1).skip(a) {
                        if let Some((first, part)) = *o {
                            let part = if part { "calibration" } else { "validation" };
                            return Err(at(
                                line,
                                format!("row {r} is already in {part} (line {first}): a row lies in one part"),
                            ));
                        }
                        *o = Some((line, word == "calibration"));
                    }
                }
                other => {
                    return Err(at(
                        line,
                        format!(
                        "unknown word `{other}`: expected `rows`, `calibration` or `validation`"
                    ),
                    ))
                }
            }
        }
        let rows = rows.ok_or_else(|| Error::file(path, "rows", "no `rows N` line"))?;
        if let Some(r) = owner.iter().position(Option::is_none) {
            return Err(Error::file(
                path,
                "rows",
                format!(
                    "row {r} is in neither part: every row of the {rows} calibrates or validates"
                ),
            ));
        }
        let (cal, val): (Vec<usize>, Vec<usize>) =
            (0..rows).partition(|&r| owner[r].is_some_and(|(_, c)| c));
        for (part, v) in [("calibration", &cal), ("validation", &val)] {
            if v.is_empty() {
                return Err(Error::file(path, part, "holds no row"));
            }
        }
        Ok(Split {
            rows,
            calibration: cal,
            validation: val,
        })
    }

    /// Refuses the split when the data file `data` does not have its number of rows.
    pub fn check_rows(&self, path: &Path, data: &Path, n: usize) -> Result<()> {
        if n == self.rows {
            return Ok(());
        }
        Err(Error::file(
            path,
            "rows",
            format!(
                "the split is of {} rows, and {} has {n}: it was written for other data",
                self.rows,
                data.display()
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Split> {
        Split::parse(Path::new("t.split"), text)
    }

    #[test]
    fn reads_ranges_and_refuses_overlap_gaps_and_range() {
        let s =
            parse("# c\nrows 5\ncalibration 0-2\nvalidation 3 # last two\nvalidation 4\n").unwrap();
        assert_eq!(s.calibration, vec![0, 1, 2]);
        assert_eq!(s.validation, vec![3, 4]);
        for (text, says) in [
            (
                "rows 5\ncalibration 0-3\nvalidation 3-4\n",
                &[
                    "t.split: line 3",
                    "row 3 is already in calibration (line 2)",
                ][..],
            ),
            (
                "rows 5\ncalibration 0-2\nvalidation 3-5\n",
                &["line 3", "row 5 is out of range"],
            ),
            (
                "rows 5\ncalibration 0-2\nvalidation 4\n",
                &["row 3 is in neither part"],
            ),
            ("rows 3\ncalibration 0-2\n", &["validation: holds no row"]),
            (
                "rows 3\ncalibrate 0-2\n",
                &["line 2", "unknown word `calibrate`"],
            ),
            (
                "rows 5\ncalibration -1-3\n",
                &["line 2", "`-1-3` is not a row number or a range A-B"],
            ),
            ("rows x\n", &["line 1", "`x` is not a number of rows"]),
            (
                "rows 0\ncalibration 0\n",
                &["line 1", "`rows 0`: a split needs 2 rows"],
            ),
        ] {
            let e = parse(text).unwrap_err().to_string();
            assert!(says.iter().all(|s| e.contains(s)), "{text:?}: {e}");
        }
        // An editor's byte-order mark is not a word (`read_text` drops it).
        let file = crate::test_dir("split-bom").join("t.split");
        std::fs::write(&file, "\u{feff}rows 3\ncalibration 0-1\nvalidation 2\n").unwrap();
        let bom = Split::load(&file).unwrap();
        assert_eq!((bom.calibration, bom.validation), (vec![0, 1], vec![2]));
        let s = parse("rows 3\ncalibration 0-1\nvalidation 2\n").unwrap();
        let e = s
            .check_rows(Path::new("t.split"), Path::new("d.csv"), 4)
            .unwrap_err()
            .to_string();
        assert!(e.contains("the split is of 3 rows, and d.csv has 4"), "{e}");
    }
}

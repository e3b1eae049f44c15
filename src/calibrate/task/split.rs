//! A task's split file (docs/formats.md § 9.2): which rows of one data file calibrate and
//! which validate, written out row by row so that every entry is scored on the same rows.

use std::collections::BTreeMap;
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
    ///
    /// The rows are listed only when the data file `data` is long enough to hold them (a row
    /// takes two bytes at the least), so that a `rows N` written for other data is refused
    /// before N rows are listed.
    pub fn load(path: &Path, data: &Path) -> Result<Split> {
        let text = read_text(path)?;
        let bytes = std::fs::metadata(data)
            .map_err(|e| Error::io(data, e))?
            .len();
        Split::parse(path, &text, Some((data, bytes)))
    }

    fn parse(path: &Path, text: &str, data: Option<(&Path, u64)>) -> Result<Split> {
        let at = |line: usize, msg: String| Error::file(path, format!("line {line}"), msg);
        let mut rows: Option<(usize, usize)> = None;
        // The ranges given so far, disjoint, by first row: (last row, line, calibration).
        // Ranges, not a slot per row: `rows N` may be any number a file can write.
        let mut owner: BTreeMap<usize, (usize, usize, bool)> = BTreeMap::new();
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
                // Digits alone: Rust would read `+0` as 0.
                let digits = !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
                (s.parse::<usize>().ok().filter(|_| digits)).ok_or_else(|| {
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
                    rows = Some((n, line));
                }
                "calibration" | "validation" => {
                    let (n, _) = rows.ok_or_else(|| {
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
                    // The first row of a..=b that an earlier range holds: a itself, in the
                    // range starting at or before it, or the first range starting after it.
                    let before = owner.range(..=a).next_back().filter(|(_, e)| e.0 >= a);
                    let after = owner.range(a..=b).next();
                    if let Some((&start, &(_, first, part))) = before.or(after) {
                        let part = if part { "calibration" } else { "validation" };
                        return Err(at(
                            line,
                            format!(
                                "row {} is already in {part} (line {first}): a row lies in one part",
                                start.max(a)
                            ),
                        ));
                    }
                    owner.insert(a, (b, line, word == "calibration"));
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
        let (rows, rows_line) =
            rows.ok_or_else(|| Error::file(path, "rows", "no `rows N` line"))?;
        // The ranges are disjoint: they cover every row when each starts where the last ended.
        let mut next = 0;
        let (mut cal, mut val) = (0, 0);
        for (&a, &(b, _, c)) in &owner {
            if a != next {
                break;
            }
            next = b + 1;
            *(if c { &mut cal } else { &mut val }) += b + 1 - a;
        }
        if next != rows {
            // Every range ends before `next`: the parts stop short of `rows N`, not a gap.
            let short = owner.range(next..).next().is_none();
            let missing = match next + 1 == rows {
                true => format!("row {next} is"),
                false => format!("rows {next} to {} are", rows - 1),
            };
            let why = match short {
                true => format!(
                    "`rows {rows}`, but the parts end at row {}: {missing} in neither part \
                     (is {rows} the data file's number of rows?)",
                    next.saturating_sub(1),
                ),
                false => format!(
                    "row {next} is in neither part: every row of the {rows} calibrates or \
                     validates"
                ),
            };
            return Err(at(rows_line, why));
        }
        if let Some((data, bytes)) = data.filter(|&(_, b)| rows as u64 > b / 2) {
            let msg = format!(
                "`rows {rows}`: {} is {bytes} bytes, too short for that many rows: the split \
                 was written for other data",
                data.display()
            );
            return Err(at(rows_line, msg));
        }
        let held = |n: usize| {
            let mut v: Vec<usize> = Vec::new();
            v.try_reserve_exact(n).map(|()| v).map_err(|_| {
                Error::file(
                    path,
                    "rows",
                    format!("`rows {rows}`: more rows than this machine's memory can list"),
                )
            })
        };
        let (mut cal, mut val) = (held(cal)?, held(val)?);
        for (&a, &(b, _, c)) in &owner {
            (if c { &mut cal } else { &mut val }).extend(a..=b);
        }
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
        Split::parse(Path::new("t.split"), text, None)
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
                &["line 1", "row 3 is in neither part: every row"],
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
            (
                "rows 5\ncalibration 2-3\nvalidation 0-4\n",
                &["line 3", "row 2 is already in calibration (line 2)"],
            ),
            // A number of rows no data file has is refused as any gap, with no slot per row.
            (
                "rows 18446744073709551615\ncalibration 0\nvalidation 1\n",
                &[
                    "line 1",
                    "rows 2 to 18446744073709551614 are in neither part",
                ],
            ),
            // Parts that stop short of `rows N`: the count, at its line, not a gap.
            (
                "# c\nrows 6\ncalibration 0-2\nvalidation 3-4\n",
                &[
                    "line 2",
                    "`rows 6`, but the parts end at row 4: row 5 is in neither",
                ],
            ),
            (
                "rows 18446744073709551615\ncalibration 0-18446744073709551613\n\
                 validation 18446744073709551614\n",
                &["rows: `rows 18446744073709551615`: more rows than this machine's memory"],
            ),
            ("rows x\n", &["line 1", "`x` is not a number of rows"]),
            ("rows +5\n", &["line 1", "`+5` is not a number of rows"]),
            (
                "rows 5\ncalibration +0-3\n",
                &["line 2", "`+0-3` is not a row number or a range A-B"],
            ),
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
        let bom = Split::load(&file, &file).unwrap();
        assert_eq!((bom.calibration, bom.validation), (vec![0, 1], vec![2]));
        // A data file of 9 bytes holds 4 rows at the most: 5 are refused at their line.
        let (five, data) = (
            file.with_file_name("t5.split"),
            file.with_file_name("data.csv"),
        );
        std::fs::write(&five, "rows 5\ncalibration 0-3\nvalidation 4\n").unwrap();
        std::fs::write(&data, "1\n2\n3\n4\n\n").unwrap();
        let e = Split::load(&five, &data).unwrap_err().to_string();
        assert!(
            e.contains("t5.split: line 1: `rows 5`: ")
                && e.contains("data.csv is 9 bytes, too short"),
            "{e}"
        );
        let mixed = parse("rows 6\nvalidation 5\ncalibration 2-4\nvalidation 1\ncalibration 0\n");
        let mixed = mixed.unwrap();
        assert_eq!(
            (mixed.calibration, mixed.validation),
            (vec![0, 2, 3, 4], vec![1, 5])
        );
        let s = parse("rows 3\ncalibration 0-1\nvalidation 2\n").unwrap();
        let e = s
            .check_rows(Path::new("t.split"), Path::new("d.csv"), 4)
            .unwrap_err()
            .to_string();
        assert!(e.contains("the split is of 3 rows, and d.csv has 4"), "{e}");
    }
}

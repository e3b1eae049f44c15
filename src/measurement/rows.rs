//! The rows of the measurement CSVs (docs/formats.md § 5) and of the raw exports `import`
//! reads (§ 6): a header of column names, then data rows read a line at a time by the `csv`
//! crate (quoted fields, LF, CRLF or CR line ends, a UTF-8 byte-order mark), `#` comment and
//! blank lines skipped but counted, so that every refusal names the file's own line.

use std::io::BufRead;
use std::path::Path;

use crate::error::{Error, Result};
use crate::numeric::Real;

/// `message` about line `line` of `path`, at `place` (`", column x"` or empty).
pub(crate) fn at_line(path: &Path, line: u64, place: &str, message: String) -> Error {
    Error::file(path, format!("line {line}{place}"), message)
}

pub(crate) use crate::error::quoted;

/// Cell `c` of `rec` as a finite number; a refusal is (place, message), the place naming the
/// column by its header name.
pub(crate) fn number(
    rec: &::csv::StringRecord,
    names: &[String],
    c: usize,
) -> std::result::Result<Real, (String, String)> {
    let t = rec.get(c).unwrap_or("");
    let place = || format!(", column {}", names[c]);
    let v = t
        .parse::<Real>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| (place(), format!("{} is not a finite number", quoted(t))))?;
    match crate::error::underflow(t, v) {
        Some(msg) => Err((place(), msg)),
        None => Ok(v),
    }
}

/// What a CSV file is.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Dialect {
    /// A measurement file (docs/formats.md § 5): comma-separated, lines starting with `#`
    /// comments, UTF-8.
    Measurement,
    /// A raw export `import` reads (§ 6): fields separated by `separator` (one ASCII byte), no
    /// comment lines (a header may start with `#`), bytes that are not UTF-8 (a Latin-1 `°` in
    /// an unmapped column's name) read as U+FFFD.
    Export {
        /// The field separator.
        separator: u8,
    },
}

impl Dialect {
    /// The field separator, an ASCII character.
    fn separator(self) -> char {
        match self {
            Dialect::Measurement => ',',
            Dialect::Export { separator } => char::from(separator),
        }
    }
}

/// The data rows of a CSV file read a line at a time (docs/formats.md § 5): the header's
/// names, then each row that is not blank with its line in the file (`#` comment and blank
/// lines counted), every row of as many fields as the header.
pub(crate) struct Rows {
    rd: ::csv::Reader<Uncommented<Box<dyn std::io::BufRead>>>,
    path: std::path::PathBuf,
    /// The header's column names, trimmed.
    pub names: Vec<String>,
    /// The header's line in the file (0 for a file without one, [`Rows::headerless`]).
    pub header_line: u64,
    /// The field separator.
    separator: char,
}

impl Rows {
    /// Opens the measurement CSV `path` and reads its header; an empty file is refused,
    /// `expected` saying what header it should have had.
    pub fn open(path: &Path, expected: &str) -> Result<Rows> {
        Rows::open_with(path, expected, Dialect::Measurement)
    }

    /// Opens `path`, a file of the `dialect`, and reads its header; an empty file is refused,
    /// `expected` saying what header it should have had.
    pub fn open_with(path: &Path, expected: &str, dialect: Dialect) -> Result<Rows> {
        let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        Rows::read(
            path,
            Box::new(std::io::BufReader::new(file)),
            expected,
            dialect,
        )
    }

    /// The rows of `text`, a measurement CSV held in memory that refusals name `path`.
    pub fn of_text(path: &Path, text: String, expected: &str) -> Result<Rows> {
        let text = Box::new(std::io::Cursor::new(text.into_bytes()));
        Rows::read(path, text, expected, Dialect::Measurement)
    }

    /// The rows of `text`, a measurement CSV held in memory without a header line, whose
    /// columns are `names`, that refusals name `path`: every line is read as a data row and
    /// named by its own line in `text` (a socket task's joint file, docs/formats.md § 9.4).
    /// [`Rows::header_line`] is 0, the line before the first.
    pub fn headerless(path: &Path, text: String, names: Vec<String>) -> Rows {
        let text = Box::new(std::io::Cursor::new(text.into_bytes()));
        Rows {
            rd: reader(text, Dialect::Measurement, false),
            path: path.to_path_buf(),
            names,
            header_line: 0,
            separator: Dialect::Measurement.separator(),
        }
    }

    /// The rows of `input`, read as the `dialect` says, that refusals name `path`.
    fn read(
        path: &Path,
        input: Box<dyn std::io::BufRead>,
        expected: &str,
        dialect: Dialect,
    ) -> Result<Rows> {
        let mut rd = reader(input, dialect, true);
        let header = match rd.headers() {
            Ok(h) => h.clone(),
            Err(e) => {
                let line = e.position().map_or(1, |p| file_line(&rd.get_ref().kept, p));
                let read = (path, line, &[][..]);
                return Err(unreadable(read, &e, ("header", "cannot read the header")));
            }
        };
        let mut rows = Rows {
            rd,
            path: path.to_path_buf(),
            names: header.iter().map(str::to_string).collect(),
            header_line: 1,
            separator: dialect.separator(),
        };
        rows.header_line = header.position().map_or(1, |p| rows.line_of(p));
        if rows.names.iter().all(|n| n.is_empty()) {
            let msg = format!("empty file: expected a header row {expected}");
            return Err(at_line(path, rows.header_line, "", msg));
        }
        Ok(rows)
    }

    fn line_of(&self, p: &::csv::Position) -> u64 {
        file_line(&self.rd.get_ref().kept, p)
    }

    /// Refuses a header column that `known` does not accept (naming its position and what
    /// was `expected`) and a column given twice.
    pub fn check_columns(&self, known: impl Fn(&str) -> bool, expected: &str) -> Result<()> {
        let names = &self.names;
        for (i, n) in names.iter().enumerate() {
            if !known(n) {
                return Err(self.bad(
                    self.header_line,
                    &format!(", column {}", i + 1),
                    format!("unknown column {} (expected {expected})", quoted(n)),
                ));
            }
            if names[..i].contains(n) {
                return Err(self.bad(
                    self.header_line,
                    &format!(", column {n}"),
                    format!("column \"{n}\" appears twice"),
                ));
            }
        }
        Ok(())
    }

    /// Reads the next data row into `rec` and gives its line; `None` at the end. A row of
    /// another number of fields than the header is refused.
    pub fn next(&mut self, rec: &mut ::csv::StringRecord) -> Result<Option<u64>> {
        loop {
            let more = self.rd.read_record(rec).map_err(|e| self.unreadable(&e))?;
            if !more {
                return Ok(None);
            }
            let line = rec.position().map_or(0, |p| self.line_of(p));
            if rec.len() == 1 && rec.get(0).is_some_and(str::is_empty) {
                continue; // blank line
            }
            if rec.len() != self.names.len() {
                let mut msg = format!(
                    "{} fields, expected {} as in the header",
                    rec.len(),
                    self.names.len()
                );
                // A quote that is not closed where its field ends takes the separators and
                // line breaks after it into the field, which is then all that was counted.
                let runs_on = |f: &str| f.contains(self.separator) || f.contains('\n');
                if let Some(k) = (0..rec.len()).rev().find(|&k| runs_on(&rec[k])) {
                    let name = self.names.get(k).map_or("", String::as_str);
                    msg += &format!(
                        ": field {} (column {}) is quoted and runs on over separators or \
                         lines; a quote that opens a field must close it, and a quote inside a \
                         quoted field is written twice (\"\")",
                        k + 1,
                        quoted(name)
                    );
                }
                return Err(self.bad(line, "", msg));
            }
            return Ok(Some(line));
        }
    }

    /// The refusal of a row the CSV reader could not read ([`unreadable`]).
    fn unreadable(&self, e: &::csv::Error) -> Error {
        let line = e.position().map_or(0, |p| self.line_of(p));
        unreadable(
            (&self.path, line, &self.names),
            e,
            ("rows", "unreadable row"),
        )
    }

    /// `msg` about line `line`, at `place` (`", column x"` or empty).
    pub fn bad(&self, line: u64, place: &str, msg: String) -> Error {
        at_line(&self.path, line, place, msg)
    }
}

/// The CSV reader of `input` as the `dialect` says, its first line read as the header when
/// `header`. `#` comment lines are emptied by [`Uncommented`] (rather than skipped by the
/// reader), and each record's line is the first line that is not empty from the position
/// the reader gives ([`file_line`]).
fn reader(
    input: Box<dyn std::io::BufRead>,
    dialect: Dialect,
    header: bool,
) -> ::csv::Reader<Uncommented<Box<dyn std::io::BufRead>>> {
    let export = matches!(dialect, Dialect::Export { .. });
    ::csv::ReaderBuilder::new()
        .has_headers(header)
        .flexible(true)
        .delimiter(dialect.separator() as u8)
        .trim(::csv::Trim::All)
        .from_reader(Uncommented::new(input, export))
}

/// A file read a line at a time ([`read_line`]) with a UTF-8 byte-order mark at its start
/// dropped, CRLF and CR line ends read as LF, its lines of blanks and (but for an `export`) its `#` comment lines
/// emptied (their line breaks kept), an export's bytes that are not UTF-8 read as U+FFFD,
/// noting the file line number of each line that is not empty (`kept`): the lines keep their
/// line breaks, so that the CSV reader counts the file's lines.
struct Uncommented<R> {
    inner: R,
    export: bool,
    line: Vec<u8>,
    at: usize,
    count: u64,
    kept: Vec<u64>,
}

/// The file line of the record at the reader's position `p`, through the file lines of the
/// lines that are not empty ([`Uncommented`]'s `kept`). The reader counts every line, the
/// emptied ones too, and a record's position is where the reader stood when the record
/// before it ended: before the blank and comment lines ahead of it. The record starts on the
/// first line from there that is not empty.
fn file_line(kept: &[u64], p: &::csv::Position) -> u64 {
    let n = p.line();
    kept.get(kept.partition_point(|&l| l < n))
        .copied()
        .unwrap_or(n)
}

/// The refusal of what the CSV reader could not read at `line` of `path`, the header or a
/// row: a cell or name that is not UTF-8 named by its column (by `names`, or by its number
/// before the header is read), a line too long at the place `part` (`header`, `rows`),
/// anything else with the reader's words after `doing`.
pub(crate) fn unreadable(
    (path, line, names): (&Path, u64, &[String]),
    e: &::csv::Error,
    (part, doing): (&str, &str),
) -> Error {
    match e.kind() {
        ::csv::ErrorKind::Utf8 { err, .. } => {
            let column = names.get(err.field()).map_or_else(
                || format!(", column {}", err.field() + 1),
                |n| format!(", column {n}"),
            );
            at_line(
                path,
                line,
                &column,
                "not UTF-8 text; save the file as UTF-8".into(),
            )
        }
        ::csv::ErrorKind::Io(io) if io.kind() == std::io::ErrorKind::InvalidData => {
            Error::file(path, part, io.to_string())
        }
        // The file could not be read at all (a folder, a device): an I/O error of the path,
        // as every other reader's, not a fault at a line of its text.
        ::csv::ErrorKind::Io(io) => Error::io(path, std::io::Error::new(io.kind(), io.to_string())),
        _ => at_line(path, line, "", format!("{doing}: {e}")),
    }
}

/// The UTF-8 byte-order mark.
const BOM: &[u8] = b"\xEF\xBB\xBF";

/// The longest line read (bytes): a row of a table is short, and a file of one endless line
/// (`/dev/zero`, a binary file) is refused rather than read into memory whole.
const MAX_LINE_BYTES: u64 = 1 << 20;

impl<R: std::io::BufRead> Uncommented<R> {
    fn new(inner: R, export: bool) -> Self {
        Uncommented {
            inner,
            export,
            line: Vec::new(),
            at: 0,
            count: 0,
            kept: Vec::new(),
        }
    }
}

/// Reads one line of `inner` onto `line`, its end included: LF, CRLF or a lone CR (the line
/// end of files saved by old Mac programs), no more than `limit` bytes. The bytes read; 0 at
/// the end of the input.
fn read_line(inner: &mut impl BufRead, line: &mut Vec<u8>, limit: u64) -> std::io::Result<usize> {
    let start = line.len();
    loop {
        let room = usize::try_from(limit).unwrap_or(usize::MAX) - (line.len() - start);
        let buf = inner.fill_buf()?;
        if buf.is_empty() || room == 0 {
            return Ok(line.len() - start);
        }
        let buf = &buf[..buf.len().min(room)];
        match buf.iter().position(|&b| b == b'\n' || b == b'\r') {
            None => {
                let n = buf.len();
                line.extend_from_slice(buf);
                inner.consume(n);
            }
            Some(i) => {
                let cr = buf[i] == b'\r';
                line.extend_from_slice(&buf[..=i]);
                inner.consume(i + 1);
                // A CR followed by LF is one line end, though the LF be in the next block.
                if cr && inner.fill_buf()?.first() == Some(&b'\n') {
                    line.push(b'\n');
                    inner.consume(1);
                }
                return Ok(line.len() - start);
            }
        }
    }
}

impl<R: std::io::BufRead> std::io::Read for Uncommented<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        while self.at == self.line.len() {
            self.line.clear();
            self.at = 0;
            if read_line(&mut self.inner, &mut self.line, MAX_LINE_BYTES + 1)? == 0 {
                return Ok(0);
            }
            self.count += 1;
            if self.line.len() as u64 > MAX_LINE_BYTES {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!(
                        "line {} is longer than {} MiB: not a table of rows",
                        self.count,
                        MAX_LINE_BYTES >> 20
                    ),
                ));
            }
            if self.count == 1 && self.line.starts_with(BOM) {
                self.line.drain(..BOM.len());
            }
            // A CRLF or lone CR line end is read as LF: the reader counts a CRLF row's line
            // from the line before, and a file of CR line ends as one line.
            if self.line.ends_with(b"\r\n") {
                self.line.remove(self.line.len() - 2);
            } else if let Some(end) = self.line.last_mut().filter(|b| **b == b'\r') {
                *end = b'\n';
            }
            if self.export && std::str::from_utf8(&self.line).is_err() {
                self.line = String::from_utf8_lossy(&self.line)
                    .into_owned()
                    .into_bytes();
            }
            let blank = self.line.iter().all(u8::is_ascii_whitespace);
            if blank || (!self.export && self.line.first() == Some(&b'#')) {
                self.line.retain(|&b| b == b'\r' || b == b'\n');
            } else {
                self.kept.push(self.count);
            }
        }
        let n = out.len().min(self.line.len() - self.at);
        out[..n].copy_from_slice(&self.line[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::{quoted, read_line, Rows};
    use std::path::Path;

    /// The lines [`read_line`] reads from `text` through a buffer of `cap` bytes.
    fn lines(text: &[u8], cap: usize) -> Vec<Vec<u8>> {
        let mut r = std::io::BufReader::with_capacity(cap, text);
        let mut out = Vec::new();
        loop {
            let mut line = Vec::new();
            if read_line(&mut r, &mut line, 64).unwrap() == 0 {
                return out;
            }
            out.push(line);
        }
    }

    #[test]
    fn a_line_ends_at_lf_crlf_or_a_lone_cr_whatever_the_buffer() {
        let text = b"a,b\r\n1,2\r3,4\n\r\n5,6\r";
        let want: Vec<&[u8]> = vec![b"a,b\r\n", b"1,2\r", b"3,4\n", b"\r\n", b"5,6\r"];
        // A buffer of 1 to 4 bytes splits a CRLF between two blocks somewhere.
        for cap in [1, 2, 3, 4, 64] {
            assert_eq!(lines(text, cap), want, "buffer of {cap}");
        }
        assert_eq!(lines(b"x\ny", 2), vec![b"x\n".to_vec(), b"y".to_vec()]);
        // No more than the limit: the caller refuses a line that reaches it.
        let long = [b'x'; 100];
        assert_eq!(lines(&long, 8)[0].len(), 64);
    }

    /// Each row is named by its own line, whatever blank and comment lines come before the
    /// header and between the rows (the reader's position of a row is the line after the row
    /// before it).
    #[test]
    fn rows_are_named_by_their_lines_past_blank_and_comment_lines() {
        let cases = [
            ("a,b\n1,2\n3,4\n", vec![1, 2, 3]),
            ("# c\na,b\n1,2\n# c\n3,4\n5,6\n", vec![2, 3, 5, 6]),
            ("\na,b\n1,2\n\n3,4\n5,6\n", vec![2, 3, 5, 6]),
            (
                "# c\n\na,b\n1,2\n\n# c\n\n3,4\r\n# c\r\n5,6\r\n",
                vec![3, 4, 8, 10],
            ),
            ("a,b\n\n\n1,\"2\n2\"\n# c\n3,4\n", vec![1, 4, 7]),
        ];
        for (text, want) in cases {
            let mut r = Rows::of_text(Path::new("t.csv"), text.into(), "a,b").unwrap();
            let mut rec = ::csv::StringRecord::new();
            let mut got = vec![r.header_line];
            while let Some(line) = r.next(&mut rec).unwrap() {
                got.push(line);
            }
            assert_eq!(got, want, "{text:?}");
        }
    }

    #[test]
    fn a_quoted_cell_shows_control_characters_and_is_cut() {
        assert_eq!(quoted("0,25"), "\"0,25\"");
        assert_eq!(quoted("0,0030775\0"), "\"0,0030775\\0\"");
        let long = "x".repeat(10_000);
        let q = quoted(&long);
        assert!(
            q.starts_with(&format!("\"{}", "x".repeat(40))) && q.ends_with("… (10000 bytes)\"")
        );
        assert!(q.len() < 80, "{q}");
    }
}

//! A kind file's rows in a refusal's words: by the line of the file each was read from.

use std::path::Path;

use super::KindFile;

impl KindFile {
    /// The file row `row` was read from, when the rows come from several ([`Self::files`]).
    pub fn file_of(&self, row: usize) -> Option<&Path> {
        let mut end = 0;
        self.files
            .iter()
            .find(|(_, n)| {
                end += n;
                row < end
            })
            .map(|(f, _)| f.as_path())
    }

    /// The line of row `row` in words: `line L of FILE` when the rows come from several files
    /// ([`Self::files`]), else `line L`; `None` for a row the file does not have.
    pub fn line_named(&self, row: usize) -> Option<String> {
        let line = self.lines.get(row)?;
        Some(match self.file_of(row) {
            Some(f) => format!("line {line} of {}", f.display()),
            None => format!("line {line}"),
        })
    }

    /// Row `row` in a refusal's words: by its file's line when the rows come from several
    /// files ([`Self::line_named`]: a 0-based row would count across them), else `row R`
    /// (0-based).
    pub fn row_named(&self, row: usize) -> String {
        match self.files.is_empty() {
            true => None,
            false => self.line_named(row),
        }
        .unwrap_or_else(|| format!("row {row}"))
    }

    /// How [`Self::row_named`] numbers the rows, as a refusal says it.
    pub fn rows_numbered(&self) -> &'static str {
        match self.files.is_empty() {
            true => "0-based rows",
            false => "each by its file's line",
        }
    }
}

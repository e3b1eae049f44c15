//! The mutations of the fuzz tests ([`super`]): edits of valid TOML, CSV and URDF files
//! (lines, keys, values, numbers, cells, bytes, line ends) and random bytes, as proptest
//! strategies.

use proptest::prelude::*;
use proptest::sample::Index;

/// File contents, shown as an escaped byte string when a case fails.
#[derive(Clone)]
pub(super) struct Bytes(pub(super) Vec<u8>);

impl std::fmt::Debug for Bytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "b\"{}\"", self.0.escape_ascii())
    }
}

/// One edit of a file. Positions are [`Index`]es, so a mutation applies to any text.
#[derive(Clone, Debug)]
pub(super) enum Mutation {
    /// Removes a line.
    DeleteLine(Index),
    /// Repeats a line.
    DuplicateLine(Index),
    /// Exchanges two lines.
    SwapLines(Index, Index),
    /// Replaces the value of a `key = value` line (TOML) or a cell (CSV).
    ReplaceValue(Index, Index, String),
    /// Replaces a number anywhere in the text.
    ReplaceNumber(Index, String),
    /// Renames the key of a `key = value` line (TOML) or a header column (CSV).
    RenameKey(Index, Index, String),
    /// Inserts a line.
    InsertLine(Index, String),
    /// Cuts the text short.
    Truncate(Index),
    /// Inserts random bytes.
    InsertBytes(Index, Vec<u8>),
    /// Removes a run of bytes.
    DeleteBytes(Index, u8),
    /// Replaces one byte.
    ReplaceByte(Index, u8),
    /// Removes a cell of a CSV row (or the value of a TOML line).
    DeleteCell(Index, Index),
    /// Adds a cell to a CSV row.
    AddCell(Index, String),
    /// Turns every line end into CR LF.
    CrLf,
    /// Puts a UTF-8 byte-order mark in front.
    Bom,
}

fn lines(text: &[u8]) -> Vec<Vec<u8>> {
    text.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect()
}

fn join(lines: &[Vec<u8>]) -> Vec<u8> {
    lines.join(&b'\n')
}

/// The byte ranges of the numbers in `text`.
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts = text[i].is_ascii_digit()
            || (matches!(text[i], b'-' | b'+') && text.get(i + 1).is_some_and(u8::is_ascii_digit));
        let word_before = i > 0 && (text[i - 1].is_ascii_alphanumeric() || text[i - 1] == b'_');
        if starts && !word_before {
            let mut j = i + 1;
            while j < text.len()
                && (text[j].is_ascii_digit()
                    || matches!(text[j], b'.' | b'e' | b'E' | b'_')
                    || (matches!(text[j], b'-' | b'+') && matches!(text[j - 1], b'e' | b'E')))
            {
                j += 1;
            }
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// Splits a CSV or TOML line into its value cells: for CSV the comma-separated fields, for
/// TOML (a line with `=`) the key and the value.
fn cells(line: &[u8], csv: bool) -> Vec<Vec<u8>> {
    if csv {
        line.split(|&b| b == b',').map(<[u8]>::to_vec).collect()
    } else {
        match line.iter().position(|&b| b == b'=') {
            Some(p) => vec![line[..p].to_vec(), line[p + 1..].to_vec()],
            None => vec![line.to_vec()],
        }
    }
}

fn uncells(cells: &[Vec<u8>], csv: bool) -> Vec<u8> {
    if csv {
        cells.join(&b',')
    } else {
        cells.join(&b'=')
    }
}

/// Applies `m` to `text`; `csv` selects comma-separated cells instead of `key = value`.
fn apply(text: &mut Vec<u8>, m: &Mutation, csv: bool) {
    let mut ls = lines(text);
    let n = ls.len();
    match m {
        Mutation::DeleteLine(i) => {
            ls.remove(i.index(n));
            *text = join(&ls);
        }
        Mutation::DuplicateLine(i) => {
            let k = i.index(n);
            let l = ls[k].clone();
            ls.insert(k, l);
            *text = join(&ls);
        }
        Mutation::SwapLines(i, j) => {
            ls.swap(i.index(n), j.index(n));
            *text = join(&ls);
        }
        Mutation::ReplaceValue(i, c, v) => {
            // TOML: a line with a value; CSV: a cell of a data row (or the header).
            let candidates: Vec<usize> = (0..n).filter(|&k| csv || ls[k].contains(&b'=')).collect();
            if candidates.is_empty() {
                return;
            }
            let k = candidates[i.index(candidates.len())];
            let mut cs = cells(&ls[k], csv);
            let c = if csv { c.index(cs.len()) } else { cs.len() - 1 };
            cs[c] = if csv {
                v.as_bytes().to_vec()
            } else {
                format!(" {v}").into_bytes()
            };
            ls[k] = uncells(&cs, csv);
            *text = join(&ls);
        }
        Mutation::ReplaceNumber(i, v) => {
            let nums = numbers(text);
            if nums.is_empty() {
                return;
            }
            let (a, b) = nums[i.index(nums.len())];
            text.splice(a..b, v.bytes());
        }
        Mutation::RenameKey(i, c, k) => {
            let candidates: Vec<usize> = if csv {
                vec![0]
            } else {
                (0..n).filter(|&k| ls[k].contains(&b'=')).collect()
            };
            if candidates.is_empty() {
                return;
            }
            let line = candidates[i.index(candidates.len())];
            let mut cs = cells(&ls[line], csv);
            let c = if csv { c.index(cs.len()) } else { 0 };
            cs[c] = if csv {
                k.as_bytes().to_vec()
            } else {
                format!("{k} ").into_bytes()
            };
            ls[line] = uncells(&cs, csv);
            *text = join(&ls);
        }
        Mutation::InsertLine(i, l) => {
            ls.insert(i.index(n + 1), l.as_bytes().to_vec());
            *text = join(&ls);
        }
        Mutation::Truncate(i) => {
            let k = i.index(text.len() + 1);
            text.truncate(k);
        }
        Mutation::InsertBytes(i, b) => {
            let k = i.index(text.len() + 1);
            text.splice(k..k, b.iter().copied());
        }
        Mutation::DeleteBytes(i, len) => {
            if text.is_empty() {
                return;
            }
            let k = i.index(text.len());
            let e = (k + *len as usize).min(text.len());
            text.drain(k..e);
        }
        Mutation::ReplaceByte(i, b) => {
            if text.is_empty() {
                return;
            }
            let k = i.index(text.len());
            text[k] = *b;
        }
        Mutation::DeleteCell(i, c) => {
            let k = i.index(n);
            let mut cs = cells(&ls[k], csv);
            cs.remove(c.index(cs.len()));
            ls[k] = uncells(&cs, csv);
            *text = join(&ls);
        }
        Mutation::AddCell(i, v) => {
            let k = i.index(n);
            let mut cs = cells(&ls[k], csv);
            cs.push(v.as_bytes().to_vec());
            ls[k] = uncells(&cs, csv);
            *text = join(&ls);
        }
        Mutation::CrLf => {
            *text = ls.join(&b"\r\n"[..]);
        }
        Mutation::Bom => {
            text.splice(0..0, [0xEF, 0xBB, 0xBF]);
        }
    }
}

/// Numbers that probe ranges, overflow after unit conversion, rounding and number syntax.
const NUMBERS: &[&str] = &[
    "0",
    "-0.0",
    "0.0",
    "1",
    "-1",
    "2",
    "0.5",
    "3",
    "40",
    "360",
    "-360.0",
    "360.0000001",
    "3600",
    "-3600.5",
    "1000",
    "1e6",
    "1000000.000001",
    "-1e6",
    "1e300",
    "1e306",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "1e309",
    "5e-324",
    "1e-320",
    "1e-9",
    "nan",
    "-nan",
    "inf",
    "+inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "9223372036854775808",
    "99999999999999999999",
    "1000000000000",
    "4294967296",
    "0x7fffffff",
    "0o17",
    "0b101",
    "1_000",
    "1__0",
    "01",
    "1.",
    ".5",
    "1e",
    "1e+",
    "--1",
    "1.0.0",
];

/// TOML values of other types and shapes.
const TOML_VALUES: &[&str] = &[
    "\"\"",
    "\"x\"",
    "\"irb2600\"",
    "\"irb9999\"",
    "\"tx60\"",
    "\"guo-3t2r\"",
    "\"lm\"",
    "\"ls\"",
    "\"igg3\"",
    "\"ridge\"",
    "\"pso\"",
    "\"detmax\"",
    "\"random\"",
    "\"m\"",
    "\"mm\"",
    "\"rad\"",
    "\"deg\"",
    "\"dh\"",
    "\"mdh\"",
    "\"dh_beta\"",
    "\"revolute\"",
    "\"prismatic\"",
    "\"differential\"",
    "\"pose\"",
    "\"position\"",
    "\"svd\"",
    "\"identify\"",
    "\"linear\"",
    "\"paper\"",
    "\"../nowhere.toml\"",
    "\"methods\"",
    "\"trials\"",
    "\"name.x\"",
    "\".\"",
    "\"outliers.count\"",
    "\"calibration.count\"",
    "[0, 2]",
    "\"/dev/null\"",
    "\"\\u0000\"",
    "\"\\n\"",
    "'lit'",
    "\"\"\"multi\nline\"\"\"",
    "true",
    "false",
    "[]",
    "[1.0]",
    "[0.0, 0.0]",
    "[1.0, -1.0]",
    "[-1e308, 1e308]",
    "[1.0, 2.0, 3.0]",
    "[0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
    "[1e308, 0.0, 0.0, 0.0, 0.0, 0.0]",
    "[\"a\"]",
    "[\"random\", \"detmax\"]",
    "[[1.0]]",
    "{}",
    "{ a = 1 }",
    "1979-05-27T07:32:00Z",
    "07:32:00",
    "1979-05-27",
];

/// CSV cells.
const CELLS: &[&str] = &[
    "",
    " ",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "infinity",
    "1e308",
    "-1e308",
    "1e306",
    "1e-320",
    "5e-324",
    "abc",
    "0x10",
    " 7 ",
    "1e",
    "--1",
    "+1",
    "1.0.0",
    "\"1\"",
    "\"",
    "\"a,b\"",
    "#",
    "999999",
    "-999999",
    "1e30",
    "0",
    "-0",
    "1",
    "0.7071",
    "2",
    "100",
    "-100",
    "180",
    "400",
    "1.0000001",
    "q1",
    "x",
];

/// CSV header names.
const COLUMNS: &[&str] = &[
    "", "q0", "q1", "q2", "q6", "q7", "q16", "x", "y", "z", "qw", "qx", "qy", "qz", "Q1", " q1",
    "X", "w", "q1 ", "\"q1\"", "#x",
];

/// A TOML line from the corpus' keys and headers and the value lists.
fn toml_line(keys: &'static [String]) -> impl Strategy<Value = String> {
    let value = prop_oneof![
        prop::sample::select(NUMBERS).prop_map(str::to_string),
        prop::sample::select(TOML_VALUES).prop_map(str::to_string),
    ];
    prop_oneof![
        (prop::sample::select(keys), value).prop_map(|(k, v)| {
            if k.starts_with('[') {
                k.clone()
            } else {
                format!("{k} = {v}")
            }
        }),
        "[a-z_.\\[\\] =\"0-9]{0,24}",
    ]
}

pub(super) fn toml_mutation(keys: &'static [String]) -> impl Strategy<Value = Mutation> {
    let value = prop_oneof![
        3 => prop::sample::select(NUMBERS).prop_map(str::to_string),
        2 => prop::sample::select(TOML_VALUES).prop_map(str::to_string),
        1 => "[ -~]{0,12}",
    ];
    let key = prop_oneof![
        prop::sample::select(keys).prop_filter("a key", |k| !k.starts_with('[')),
        "[a-z_.]{1,12}",
    ];
    prop_oneof![
        2 => any::<Index>().prop_map(Mutation::DeleteLine),
        2 => any::<Index>().prop_map(Mutation::DuplicateLine),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        6 => (any::<Index>(), any::<Index>(), value).prop_map(|(a, b, v)| Mutation::ReplaceValue(a, b, v)),
        6 => (any::<Index>(), prop::sample::select(NUMBERS))
            .prop_map(|(a, v)| Mutation::ReplaceNumber(a, v.to_string())),
        2 => (any::<Index>(), any::<Index>(), key).prop_map(|(a, b, k)| Mutation::RenameKey(a, b, k)),
        3 => (any::<Index>(), toml_line(keys)).prop_map(|(a, l)| Mutation::InsertLine(a, l)),
        6 => byte_edits(),
    ]
}

/// The edits of a file's bytes that every kind of file gets, each as likely: cut short, bytes
/// inserted, removed or replaced, CR LF line ends, a byte order mark.
fn byte_edits() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        1 => any::<Index>().prop_map(Mutation::Truncate),
        1 => (any::<Index>(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(a, b)| Mutation::InsertBytes(a, b)),
        1 => (any::<Index>(), 1..16u8).prop_map(|(a, n)| Mutation::DeleteBytes(a, n)),
        1 => (any::<Index>(), any::<u8>()).prop_map(|(a, b)| Mutation::ReplaceByte(a, b)),
        1 => Just(Mutation::CrLf),
        1 => Just(Mutation::Bom),
    ]
}

pub(super) fn csv_mutation() -> impl Strategy<Value = Mutation> {
    let cell = prop_oneof![
        4 => prop::sample::select(CELLS).prop_map(str::to_string),
        1 => "[ -~]{0,10}",
    ];
    prop_oneof![
        2 => any::<Index>().prop_map(Mutation::DeleteLine),
        2 => any::<Index>().prop_map(Mutation::DuplicateLine),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        8 => (any::<Index>(), any::<Index>(), cell.clone())
            .prop_map(|(a, b, v)| Mutation::ReplaceValue(a, b, v)),
        3 => (any::<Index>(), prop::sample::select(NUMBERS))
            .prop_map(|(a, v)| Mutation::ReplaceNumber(a, v.to_string())),
        3 => (any::<Index>(), any::<Index>(), prop::sample::select(COLUMNS))
            .prop_map(|(a, b, k)| Mutation::RenameKey(a, b, k.to_string())),
        2 => (any::<Index>(), prop_oneof![
                Just(String::new()),
                Just("# comment".to_string()),
                Just(",,,".to_string()),
                "[ -~]{0,40}",
            ]).prop_map(|(a, l)| Mutation::InsertLine(a, l)),
        2 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::DeleteCell(a, b)),
        2 => (any::<Index>(), cell).prop_map(|(a, v)| Mutation::AddCell(a, v)),
        6 => byte_edits(),
    ]
}

/// Lines a URDF mutation inserts: elements out of place, comments and sections left open,
/// numbers calbench refuses, characters of several bytes.
const URDF_LINES: &[&str] = &[
    "<joint name=\"j\" type=\"fixed\">",
    "</joint>",
    "<link name=\"link_3\"/>",
    "<joint name=\"x\" type=\"revolute\"><parent link=\"world\"/><child link=\"x\"/></joint>",
    "<origin xyz=\"nan 0 0\" rpy=\"0 0 inf\"/>",
    "<axis xyz=\"0 0 0\"/>",
    "<limit lower=\"1\" upper=\"-1\"/>",
    "<!--",
    "-->",
    "<![CDATA[",
    "]]>",
    "<!-- <joint name=\"c\" type=\"fixed\"> -->",
    "é日本",
    "&amp;&lt;&#x1F4A5;&foo;",
    "</robot>",
    "<robot name=\"r\">",
];

/// Edits of a URDF: its lines, numbers and bytes, and [`URDF_LINES`] inserted.
pub(super) fn urdf_mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        2 => any::<Index>().prop_map(Mutation::DeleteLine),
        2 => any::<Index>().prop_map(Mutation::DuplicateLine),
        2 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        4 => (any::<Index>(), prop::sample::select(NUMBERS))
            .prop_map(|(a, v)| Mutation::ReplaceNumber(a, v.to_string())),
        3 => (any::<Index>(), prop::sample::select(URDF_LINES))
            .prop_map(|(a, l)| Mutation::InsertLine(a, l.to_string())),
        6 => byte_edits(),
    ]
}

/// A valid file of `corpus` and one to four mutations of it.
pub(super) fn mutated(
    corpus: &'static [Vec<u8>],
    mutation: impl Strategy<Value = Mutation>,
    csv: bool,
) -> impl Strategy<Value = (usize, Bytes, Vec<Mutation>)> {
    (0..corpus.len(), prop::collection::vec(mutation, 1..5)).prop_map(move |(i, ms)| {
        let mut text = corpus[i].clone();
        for m in &ms {
            apply(&mut text, m, csv);
        }
        (i, Bytes(text), ms)
    })
}

/// Random bytes: arbitrary, or printable text with TOML/CSV punctuation.
pub(super) fn random_bytes() -> impl Strategy<Value = Bytes> {
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..512).prop_map(Bytes),
        "[\\[\\]{}=,.\"'#a-z0-9 \n_+-]{0,512}".prop_map(|s| Bytes(s.into_bytes())),
    ]
}

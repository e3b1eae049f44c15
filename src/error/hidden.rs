//! Characters a terminal acts on rather than shows, and text quoted with them escaped.

/// Whether a terminal acts on `c` rather than shows it: a control character (an ESC starts a
/// colour or a cursor move) or a bidirectional formatting one (U+061C, U+200E, U+200F, U+202A
/// to U+202E, U+2066 to U+2069), which reorders the text after it. A name refuses such
/// characters (a study's `name`, a method's `label`), and the terminal is shown them escaped.
pub fn is_hidden(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{61c}' | '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}'
        )
        || matches!(c, '\u{2066}'..='\u{2069}')
}

/// A cell as a message quotes it: in double quotes, control characters escaped (a NUL byte
/// shown as `\0`, not as a blank a reader takes for a space the reader trims) and a long cell
/// cut after 40 characters, so that a 10 MB cell is not echoed whole.
pub fn quoted(cell: &str) -> String {
    const SHOWN: usize = 40;
    let head: String = cell.chars().take(SHOWN).collect();
    let mut s = head.escape_debug().to_string();
    if cell.chars().nth(SHOWN).is_some() {
        s.push_str(&format!("… ({} bytes)", cell.len()));
    }
    format!("\"{s}\"")
}

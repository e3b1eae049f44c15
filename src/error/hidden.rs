//! Characters a terminal acts on rather than shows.

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

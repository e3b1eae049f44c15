//! Where a key is written in a file's text: the line of a TOML key path
//! ([`toml_key_line`]) and of a JSON one ([`json_key_line`]), for the places of refusals
//! (`line 12, calibration.count`, docs/formats.md § 8.1).

/// The 1-based line of the byte offset `at` in `text`.
pub fn line_of(text: &str, at: usize) -> usize {
    let end = at.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The 1-based line where the dotted `key` is written in the TOML `text`: a path of table
/// keys and array indices such as `calibration.region`, `joints[1].a` or `methods[0].k1`, a
/// key with a dot in double quotes (`errors.values."tool.z"`).
/// The line of the key itself when the path ends in a key, of the element when it ends in an
/// index (`joints[1]`: the line of that `[[joints]]`). `None` when the text does not parse or
/// does not write the key (a default, a value set on the command line).
pub fn toml_key_line(text: &str, key: &str) -> Option<usize> {
    use toml::de::{DeTable, DeValue};
    let doc = DeTable::parse(text).ok()?;
    let mut table = doc.get_ref();
    let mut value: Option<&toml::Spanned<DeValue>> = None;
    let mut span = None;
    for part in dotted_parts(key) {
        let part = part.as_str();
        let (name, indices) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if let Some(v) = value {
            table = match v.get_ref() {
                DeValue::Table(t) => t,
                _ => return None,
            };
        }
        let (k, v) = table.get_key_value(name)?;
        span = Some(k.span());
        let mut v = v;
        for index in indices.split('[').skip(1) {
            let i: usize = index.strip_suffix(']')?.parse().ok()?;
            v = match v.get_ref() {
                DeValue::Array(a) => a.get(i)?,
                _ => return None,
            };
            span = Some(v.span());
        }
        value = Some(v);
    }
    span.map(|s| line_of(text, s.start))
}

/// The parts of a dotted key path, split at the dots outside double quotes, the quotes
/// dropped: `errors.values."tool.z"` is `errors`, `values`, `tool.z`.
fn dotted_parts(key: &str) -> Vec<String> {
    let (mut parts, mut part, mut quoted) = (Vec::new(), String::new(), false);
    for c in key.chars() {
        match c {
            '"' => quoted = !quoted,
            '.' if !quoted => parts.push(std::mem::take(&mut part)),
            c => part.push(c),
        }
    }
    parts.push(part);
    parts
}

/// The 1-based line where the key path `key` is written in the JSON `text`: keys joined by
/// dots and array indices in brackets, as serde_path_to_error writes them (`results`,
/// `per_trial.format`, `results[2].method`). The line of the key itself when the path ends in
/// a key, of the element's first character when it ends in an index. `None` when the text
/// does not write the key (a missing key) or is not JSON of that shape.
pub fn json_key_line(text: &str, key: &str) -> Option<usize> {
    // Each open object or array: its key path, and for an array the index of its element.
    let mut open: Vec<(String, Option<usize>)> = Vec::new();
    // The key last read in the innermost object: the path of an object or array it opens.
    let mut name = String::new();
    let (mut line, mut element) = (1, false);
    let path = |prefix: &str, name: &str| match prefix {
        "" => name.to_string(),
        p => format!("{p}.{name}"),
    };
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if std::mem::take(&mut element) {
            match (c, open.last()) {
                (' ' | '\t' | '\r' | '\n', _) => element = true,
                (']', _) => {}
                (_, Some((p, Some(i)))) if format!("{p}[{i}]") == key => return Some(line),
                _ => {}
            }
        }
        match c {
            '\n' => line += 1,
            '{' | '[' => {
                let at = match open.last() {
                    None => String::new(),
                    Some((p, Some(i))) => format!("{p}[{i}]"),
                    Some((p, None)) => path(p, &name),
                };
                open.push((at, (c == '[').then_some(0)));
                element = c == '[';
            }
            '}' | ']' => {
                open.pop();
            }
            ',' => {
                if let Some((_, Some(i))) = open.last_mut() {
                    *i += 1;
                    element = true;
                }
            }
            '"' => {
                let (start, mut word, mut escaped) = (line, String::new(), false);
                for c in chars.by_ref() {
                    match c {
                        _ if escaped => escaped = false,
                        '\\' => escaped = true,
                        '"' => break,
                        '\n' => line += 1,
                        _ => {}
                    }
                    if !escaped && c != '\\' {
                        word.push(c);
                    }
                }
                while chars.peek().is_some_and(|c| c.is_whitespace()) {
                    if chars.next() == Some('\n') {
                        line += 1;
                    }
                }
                if let (Some((p, None)), Some(':')) = (open.last(), chars.peek()) {
                    if path(p, &word) == key {
                        return Some(start);
                    }
                    name = word;
                }
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_key_lines_are_found() {
        let text = "{\n  \"a\": {\"results\": 1},\n  \"results\": [\n    {\"method\": \"ls\"},\n    {\n      \
                    \"method\": \"lm\"\n    }\n  ],\n  \"per_trial\": {\n    \"format\": \"x\",\n    \
                    \"entries\": {\"ls / random\": {\"trials\": [0, 1]}}\n  }\n}\n";
        for (key, line) in [
            ("a", 2),
            ("a.results", 2),
            ("results", 3),
            ("results[0]", 4),
            ("results[0].method", 4),
            ("results[1]", 5),
            ("results[1].method", 6),
            ("per_trial", 9),
            ("per_trial.format", 10),
            ("per_trial.entries.ls / random.trials", 11),
            ("per_trial.entries.ls / random.trials[1]", 11),
        ] {
            assert_eq!(json_key_line(text, key), Some(line), "{key}");
        }
        for absent in [
            "format",
            "method",
            "results[2]",
            "a.b",
            "per_trial.format.x",
            "",
        ] {
            assert_eq!(json_key_line(text, absent), None, "{absent}");
        }
    }
}

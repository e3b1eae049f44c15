//! Every intra-document link of README.md and docs/*.md, `](#anchor)` or
//! `](other.md#anchor)`, resolves to a heading of the document it names, by GitHub's rule:
//! the heading's text lower-cased, every character but letters, digits, `_`, `-` and spaces
//! dropped, spaces made `-`; a repeated heading's anchor gets `-1`, `-2`, ….

use std::collections::HashSet;

use super::{documents, root};

/// The anchors of the headings of the Markdown text `text` (fenced blocks passed over).
fn anchors(text: &str) -> HashSet<String> {
    let mut seen: HashSet<String> = HashSet::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        let heading = line.trim_start_matches('#');
        if fenced || heading.len() == line.len() || !heading.starts_with(' ') {
            continue;
        }
        let slug: String = heading
            .trim()
            .to_lowercase()
            .chars()
            .filter(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | ' '))
            .map(|c| if c == ' ' { '-' } else { c })
            .collect();
        let mut anchor = slug.clone();
        let mut n = 0;
        while seen.contains(&anchor) {
            n += 1;
            anchor = format!("{slug}-{n}");
        }
        seen.insert(anchor);
    }
    seen
}

/// The anchor's rule on headings whose anchors GitHub shows.
#[test]
fn the_anchor_rule() {
    let text = "# 5.3 Measurement-kind CSV: distance, `socket`\n## Notes\n```\n# not a heading\n```\n## Notes\n";
    let want = [
        "53-measurement-kind-csv-distance-socket",
        "notes",
        "notes-1",
    ];
    assert_eq!(anchors(text), want.iter().map(|s| s.to_string()).collect());
}

#[test]
fn every_anchor_link_resolves_to_a_heading() {
    let mut broken = Vec::new();
    let mut links = 0;
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        let name = doc
            .strip_prefix(root())
            .unwrap_or(&doc)
            .display()
            .to_string();
        for (i, line) in text.lines().enumerate() {
            for part in line.split("](").skip(1) {
                let Some(target) = part.split(')').next() else {
                    continue;
                };
                let Some((file, anchor)) = target.split_once('#') else {
                    continue;
                };
                if file.contains("://") || !(file.is_empty() || file.ends_with(".md")) {
                    continue;
                }
                let named = if file.is_empty() {
                    doc.clone()
                } else {
                    doc.parent().unwrap().join(file)
                };
                links += 1;
                let target_text = std::fs::read_to_string(&named).unwrap_or_default();
                if !named.is_file() || !anchors(&target_text).contains(anchor) {
                    broken.push(format!("{name}:{}: ]({target})", i + 1));
                }
            }
        }
    }
    assert!(
        links > 100,
        "only {links} anchor links found: is the reader broken?"
    );
    assert!(
        broken.is_empty(),
        "links to no heading:\n{}",
        broken.join("\n")
    );
}

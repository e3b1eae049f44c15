//! docs/formats.md § 9 lists every task of `tasks/`: each `tasks/NAME.toml` is named in the
//! first column of the section's table, in full (`ipa-ur10-series-a`) or as a suffix after a
//! name that shares the rest (`mukca-panda-2`, `-3`).

use std::collections::BTreeSet;

use super::root;

/// The task names of the first column of the table under `## 9 `.
fn listed(formats: &str) -> BTreeSet<String> {
    let section = formats
        .split("\n## 9 ")
        .nth(1)
        .expect("docs/formats.md has a section 9")
        .split("\n### ")
        .next()
        .unwrap();
    let mut names = BTreeSet::new();
    for row in section.lines().filter(|l| l.starts_with("| `")) {
        let first = row.split('|').nth(1).unwrap();
        let mut last = String::new();
        for token in first.split('`').skip(1).step_by(2) {
            let name = match token.strip_prefix('-') {
                Some(suffix) => {
                    let stem = last.rsplit_once('-').expect("a name before a suffix").0;
                    format!("{stem}-{suffix}")
                }
                None => token.to_string(),
            };
            names.insert(name.clone());
            last = name;
        }
    }
    names
}

#[test]
fn section_9_lists_every_task() {
    let formats = std::fs::read_to_string(root().join("docs/formats.md")).unwrap();
    let listed = listed(&formats);
    let tasks: BTreeSet<String> = std::fs::read_dir(root().join("tasks"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|n| !n.ends_with(".mapping"))
        .collect();
    assert!(tasks.len() >= 10, "{tasks:?}");
    let missing: Vec<&String> = tasks.difference(&listed).collect();
    assert!(
        missing.is_empty(),
        "tasks not in docs/formats.md § 9: {missing:?}"
    );
    let unknown: Vec<&String> = listed.difference(&tasks).collect();
    assert!(
        unknown.is_empty(),
        "docs/formats.md § 9 names no such task: {unknown:?}"
    );
}

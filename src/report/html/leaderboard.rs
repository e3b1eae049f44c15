//! `leaderboard.html` and `leaderboard.csv` of `calbench leaderboard` (docs/formats.md): per
//! task, a closed and an open division, each ranking every recorded entry and the authors'
//! published figures (fixed rows) by the task's metric, lower first, rows whose intervals
//! overlap sharing a rank; each entry against the task's published figure; each entrant's
//! score across tasks.

use std::collections::BTreeMap;

use super::history::{ci_cells, csv_text};
use super::Page;
use crate::error::Result;
use crate::numeric::Real;

/// One row of the leaderboard.
#[derive(Clone, Debug)]
pub struct Row {
    /// The task.
    pub task: String,
    /// The hash of the task file's canonical text.
    pub task_hash: String,
    /// The ranking metric.
    pub metric: String,
    /// `closed` or `open`.
    pub division: String,
    /// Whether the row is a published figure rather than a recorded entry.
    pub published: bool,
    /// `entrant: method`, or the published figure's label.
    pub name: String,
    /// The models used (and how they were chosen).
    pub models: String,
    /// The value of the metric.
    pub value: Real,
    /// Its 95 % interval.
    pub ci: Option<[Real; 2]>,
    /// The version label of an entry, the source of a published figure.
    pub source: String,
    /// The machine an entry was recorded on.
    pub machine: String,
    /// When an entry was recorded.
    pub recorded_at: String,
    /// The rank in its task and division, from 1: one more than the rows whose interval lies
    /// wholly below this row's (rows whose intervals overlap share a rank).
    pub rank: usize,
    /// An entry's figure less the task's (lowest) published figure, and the interval of that
    /// difference (the entry's interval shifted by the published point); `None` for a
    /// published row or a task without one.
    pub vs_published: Option<(Real, Option<[Real; 2]>)>,
}

impl Row {
    /// The board the row is ranked on: its task at one version of what the task fixes (its
    /// `task_hash`). Entries of a task whose files changed between records rank apart.
    pub fn board(&self) -> (&str, &str) {
        (&self.task, &self.task_hash)
    }

    /// The board's title among `rows`: the task's name, with the start of its hash when
    /// `rows` hold more than one version of the task.
    pub fn board_title(&self, rows: &[Row]) -> String {
        let several = rows
            .iter()
            .any(|r| r.task == self.task && r.task_hash != self.task_hash);
        match several {
            true => format!("{} (task hash {})", self.task, short(&self.task_hash)),
            false => self.task.clone(),
        }
    }
}

/// The first 12 characters of a hash.
fn short(hash: &str) -> &str {
    hash.char_indices()
        .nth(12)
        .map_or(hash, |(i, _)| &hash[..i])
}

/// An entrant's score across the tasks it entered ([`crate::report::html::leaderboard`]):
/// the geometric mean of its best figure on each task relative to the task's reference.
#[derive(Clone, Debug)]
pub struct Score {
    /// `entrant: method`.
    pub name: String,
    /// The tasks it entered (a task recorded at several versions once per version, by its
    /// board's title).
    pub tasks: Vec<String>,
    /// The geometric mean of figure / reference over those tasks (below 1: better).
    pub score: Real,
}

/// `leaderboard.csv`: one row per ranked row.
pub fn csv(rows: &[Row]) -> Result<String> {
    let header = "task,task_hash,metric,division,rank,row,name,models,value,ci_lo,ci_hi,source,\
                  machine,recorded_at,vs_published,vs_published_lo,vs_published_hi";
    csv_text(
        header,
        rows.iter().map(|r| {
            let [lo, hi] = ci_cells(r.ci);
            let row = if r.published { "published" } else { "entry" };
            let mut cells = vec![r.task.clone(), r.task_hash.clone(), r.metric.clone()];
            cells.extend([r.division.clone(), r.rank.to_string(), row.to_string()]);
            cells.extend([
                r.name.clone(),
                r.models.clone(),
                r.value.to_string(),
                lo,
                hi,
            ]);
            cells.extend([r.source.clone(), r.machine.clone(), r.recorded_at.clone()]);
            let (d, ci) = r
                .vs_published
                .map_or((String::new(), None), |(d, ci)| (d.to_string(), ci));
            cells.push(d);
            cells.extend(ci_cells(ci));
            cells
        }),
    )
}

/// `leaderboard.html`: the tasks, then the entrants' scores across tasks (`scores`).
pub fn page(rows: &[Row], scores: &[Score]) -> String {
    let mut page = Page::new(
        "calbench leaderboard",
        "Per task, every recorded entry ranked by the task's metric (lower is better) beside \
         the figures its data's authors published (shaded rows); rows whose 95 % intervals \
         overlap share a rank. Each entry stands against the task's published figure: the \
         difference and its interval. Closed division: kinematic models only (DH, β, tool, \
         base); open division: any model or method.",
    );
    let mut boards: BTreeMap<(&str, &str), Vec<&Row>> = BTreeMap::new();
    for r in rows {
        boards.entry(r.board()).or_default().push(r);
    }
    if boards.is_empty() {
        page.para("No task entry is recorded (`calbench record DIR` of a `calbench task` folder).");
    }
    for list in boards.values() {
        let title = list[0].board_title(rows);
        page.section(&title);
        page.facts(&[
            ("metric", list[0].metric.clone()),
            ("task hash", list[0].task_hash.clone()),
        ]);
        if title != list[0].task {
            page.para(
                "What this task fixes (its file, data, split, mapping or robot) changed between \
                 the records: each version's entries are ranked apart, against that version's \
                 published figures.",
            );
        }
        for division in ["closed", "open"] {
            let rows: Vec<&&Row> = list.iter().filter(|r| r.division == division).collect();
            if !rows.iter().any(|r| !r.published) {
                let published = if rows.is_empty() {
                    String::new()
                } else {
                    " (only the published figures)".to_string()
                };
                page.para(&format!(
                    "{division} division: no entry recorded{published}."
                ));
                if rows.is_empty() {
                    continue;
                }
            }
            let table: Vec<Vec<String>> = rows
                .iter()
                .map(|r| {
                    let models = if r.published { "published" } else { &r.models };
                    let ci =
                        r.ci.map_or(String::new(), |[a, b]| format!("{a:.4} – {b:.4}"));
                    let vs = r.vs_published.map_or(String::new(), |(d, ci)| {
                        let ci = ci.map_or(String::new(), |[a, b]| format!(" ({a:+.4} – {b:+.4})"));
                        format!("{d:+.4}{ci}")
                    });
                    let mut row = vec![r.rank.to_string(), r.name.clone(), models.to_string()];
                    row.extend([format!("{:.4}", r.value), ci, vs, r.source.clone()]);
                    row.extend([r.machine.clone(), r.recorded_at.clone()]);
                    row
                })
                .collect();
            let shaded: Vec<bool> = rows.iter().map(|r| r.published).collect();
            page.table_with(
                &format!("{division} division"),
                &[
                    "rank",
                    "entry",
                    "models",
                    &list[0].metric,
                    "95 % interval",
                    "vs published (95 % interval)",
                    "version or source",
                    "machine",
                    "recorded",
                ],
                &table,
                |i| shaded[i].then_some("alone"),
            );
        }
    }
    if !scores.is_empty() {
        page.section("Across tasks");
        page.para(
            "Each entrant's best figure on each task it entered, relative to the task's lowest \
             published figure (else the best figure recorded), as a geometric mean: 1 is level \
             with the reference, 0.9 is 10 % below it; a task whose reference is 0 mm is left \
             out. Scores over different sets of tasks compare only roughly.",
        );
        let table: Vec<Vec<String>> = scores
            .iter()
            .map(|s| {
                vec![
                    s.name.clone(),
                    format!("{:.4}", s.score),
                    s.tasks.len().to_string(),
                    s.tasks.join(", "),
                ]
            })
            .collect();
        page.table_with(
            "scores across tasks",
            &["entrant", "score", "tasks", "which"],
            &table,
            |_| None,
        );
    }
    page.finish()
}

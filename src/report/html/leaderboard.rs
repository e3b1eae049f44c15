//! `leaderboard.html` and `leaderboard.csv` of `calbench leaderboard` (docs/formats.md): per
//! task, a closed and an open division, each ranking every recorded entry and the authors'
//! published figures (fixed rows) by the task's metric, lower first.

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
    /// The rank in its task and division, from 1.
    pub rank: usize,
}

/// `leaderboard.csv`: one row per ranked row.
pub fn csv(rows: &[Row]) -> Result<String> {
    let header = "task,task_hash,metric,division,rank,row,name,models,value,ci_lo,ci_hi,source,\
                  machine,recorded_at";
    let header: Vec<&str> = header.split(',').collect();
    csv_text(
        &header,
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
            cells
        }),
    )
}

/// `leaderboard.html`.
pub fn page(rows: &[Row]) -> String {
    let mut page = Page::new(
        "calbench leaderboard",
        "Per task, every recorded entry ranked by the task's metric (lower is better) beside \
         the figures its data's authors published (shaded rows). Closed division: kinematic \
         models only (DH, β, tool, base); open division: any model or method.",
    );
    let mut tasks: BTreeMap<&str, Vec<&Row>> = BTreeMap::new();
    for r in rows {
        tasks.entry(&r.task).or_default().push(r);
    }
    if tasks.is_empty() {
        page.para("No task entry is recorded (`calbench record DIR` of a `calbench task` folder).");
    }
    for (task, list) in &tasks {
        page.section(task);
        page.facts(&[
            ("metric", list[0].metric.clone()),
            ("task hash", list[0].task_hash.clone()),
        ]);
        for division in ["closed", "open"] {
            let rows: Vec<&&Row> = list.iter().filter(|r| r.division == division).collect();
            let table: Vec<Vec<String>> = rows
                .iter()
                .map(|r| {
                    let models = if r.published { "published" } else { &r.models };
                    let ci =
                        r.ci.map_or(String::new(), |[a, b]| format!("{a:.4} – {b:.4}"));
                    let mut row = vec![r.rank.to_string(), r.name.clone(), models.to_string()];
                    row.extend([format!("{:.4}", r.value), ci, r.source.clone()]);
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
                    "version or source",
                    "machine",
                    "recorded",
                ],
                &table,
                |i| shaded[i].then_some("alone"),
            );
        }
    }
    page.finish()
}

//! The leaderboard of the tasks (docs/formats.md, `calbench leaderboard`): per task and
//! division, every recorded entry and the authors' published figures, ranked by the task's
//! metric (lower is better).

use super::Db;
use crate::error::Result;
use crate::report::html::leaderboard::Row;

/// The rows of every task, by task, division (`closed` first) and rank.
pub fn rows(db: &Db) -> Result<Vec<Row>> {
    // Entries, then the published figures, as the same columns: task, hash, metric,
    // division, published, name, models, value, ci_lo, ci_hi, source, machine, date.
    let sql = "SELECT t.task, t.task_hash, t.metric, t.division, 0, t.entrant || ': ' || \
               t.method, t.models || CASE WHEN t.chosen_by = '' THEN '' ELSE ' (' || \
               t.chosen_by || ')' END, t.value, t.ci_lo, t.ci_hi, r.label, r.machine, \
               r.recorded_at FROM tasks t JOIN runs r ON r.id = t.run \
               UNION ALL SELECT DISTINCT p.task, t.task_hash, t.metric, p.division, 1, p.label, \
               '', p.value, NULL, NULL, p.source, '', '' FROM published p \
               JOIN tasks t ON t.run = p.run";
    let all = db.query(sql, [], |r| {
        let (lo, hi): (Option<f64>, Option<f64>) = (r.get(8)?, r.get(9)?);
        Ok(Row {
            task: r.get(0)?,
            task_hash: r.get(1)?,
            metric: r.get(2)?,
            division: r.get(3)?,
            published: r.get::<_, i64>(4)? == 1,
            name: r.get(5)?,
            models: r.get(6)?,
            value: r.get(7)?,
            ci: lo.zip(hi).map(|(l, h)| [l, h]),
            source: r.get(10)?,
            machine: r.get(11)?,
            recorded_at: r.get(12)?,
            rank: 0,
        })
    })?;
    let (mut rows, published): (Vec<Row>, Vec<Row>) = all.into_iter().partition(|r| !r.published);
    // The same published figure copied by several task entries is one row.
    for p in published {
        let dup = rows.iter().any(|r| {
            r.published
                && r.task == p.task
                && r.division == p.division
                && r.name == p.name
                && r.value == p.value
        });
        if !dup {
            rows.push(p);
        }
    }
    rows.sort_by(|a, b| {
        (&a.task, a.division != "closed", &a.division)
            .cmp(&(&b.task, b.division != "closed", &b.division))
            .then(a.value.total_cmp(&b.value))
            .then(b.published.cmp(&a.published))
    });
    let mut rank = 0;
    for i in 0..rows.len() {
        let same =
            i > 0 && rows[i - 1].task == rows[i].task && rows[i - 1].division == rows[i].division;
        rank = if same { rank + 1 } else { 1 };
        rows[i].rank = rank;
    }
    Ok(rows)
}

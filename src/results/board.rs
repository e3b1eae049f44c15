//! The leaderboard of the tasks (docs/formats.md, `calbench leaderboard`): per task and
//! division, every recorded entry and the authors' published figures, ranked by the task's
//! metric (lower is better) with their intervals: a row's rank is one more than the rows
//! whose interval lies wholly below its own, so rows whose intervals overlap share a rank.
//! Each entry stands against the task's published figure (the difference with its interval);
//! each entrant's figures across tasks make one score ([`scores`]).

use std::collections::BTreeMap;
use std::path::Path;

use super::folder::{Published, TaskResult};
use super::Db;
use crate::calibrate::task::record::{same_figure, shown, TaskRecord};
use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::report::html::leaderboard::{Row, Score};

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
            vs_published: None,
        })
    })?;
    let (mut rows, published): (Vec<Row>, Vec<Row>) = all.into_iter().partition(|r| !r.published);
    // The same published figure copied by several task entries is one row.
    for p in published {
        let dup = rows.iter().any(|r| {
            r.published
                && r.board() == p.board()
                && r.division == p.division
                && r.name == p.name
                && r.value == p.value
        });
        if !dup {
            rows.push(p);
        }
    }
    rows.sort_by(|a, b| {
        (a.board(), a.division != "closed", &a.division)
            .cmp(&(b.board(), b.division != "closed", &b.division))
            .then(a.value.total_cmp(&b.value))
            .then(b.published.cmp(&a.published))
    });
    let bounds = |r: &Row| r.ci.unwrap_or([r.value, r.value]);
    let ranks: Vec<usize> = rows
        .iter()
        .map(|r| {
            let lo = bounds(r)[0];
            let below = rows
                .iter()
                .filter(|o| o.board() == r.board() && o.division == r.division && bounds(o)[1] < lo)
                .count();
            below + 1
        })
        .collect();
    // The board's published figure an entry stands against: the lowest one, of any division;
    // keyed by the board owned, as the rows are changed below.
    let owned = |r: &Row| {
        let (task, hash) = r.board();
        (task.to_string(), hash.to_string())
    };
    let mut published: BTreeMap<(String, String), Real> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.published) {
        let p = published.entry(owned(r)).or_insert(r.value);
        *p = p.min(r.value);
    }
    for (r, rank) in rows.iter_mut().zip(ranks) {
        r.rank = rank;
        if !r.published {
            r.vs_published = published.get(&owned(r)).map(|&p| {
                let ci = r.ci.map(|[lo, hi]| [lo - p, hi - p]);
                (r.value - p, ci)
            });
        }
    }
    Ok(rows)
}

/// Each entrant's score across the tasks it entered (`rows` of [`rows`]): the geometric mean,
/// over those tasks, of its best figure there relative to the task's reference — its lowest
/// published figure, else the best figure recorded (the best known) — so 1 is level with the
/// reference and 0.9 is 10 % below it on average. Sorted by score, lowest first. A task
/// recorded at several versions ([`Row::board`]) counts once per version; one whose
/// reference is 0 mm is left out (a figure relative to it is not defined), and an entrant
/// with no other task has no score.
pub fn scores(rows: &[Row]) -> Vec<Score> {
    let mut reference: BTreeMap<(&str, &str), (bool, Real)> = BTreeMap::new();
    for r in rows {
        let e = reference.entry(r.board()).or_insert((r.published, r.value));
        // A published figure outranks every recorded one as the reference.
        if (r.published, -r.value) > (e.0, -e.1) {
            *e = (r.published, r.value);
        }
    }
    // Per entrant and board: a row of it, and the entrant's best figure there.
    type Board<'r> = (&'r str, &'r str);
    let mut best: BTreeMap<(&str, Board), (&Row, Real)> = BTreeMap::new();
    for r in rows.iter().filter(|r| !r.published) {
        let b = best.entry((&r.name, r.board())).or_insert((r, r.value));
        b.1 = b.1.min(r.value);
    }
    // A figure relative to a reference of 0 mm is not defined: that board is left out.
    let mut by_entrant: BTreeMap<&str, Vec<(&Row, Real)>> = BTreeMap::new();
    for ((name, board), row_value) in best {
        if reference[&board].1 > 0.0 {
            by_entrant.entry(name).or_default().push(row_value);
        }
    }
    let mut out: Vec<Score> = by_entrant
        .into_iter()
        .map(|(name, tasks)| {
            let logs: Real = tasks
                .iter()
                .map(|(r, v)| (v / reference[&r.board()].1).ln())
                .sum::<Real>();
            Score {
                name: name.to_string(),
                tasks: tasks.iter().map(|t| t.0.board_title(rows)).collect(),
                score: (logs / tasks.len() as Real).exp(),
            }
        })
        .collect();
    out.sort_by(|a, b| a.score.total_cmp(&b.score).then(a.name.cmp(&b.name)));
    out
}

/// Refuses the entry recorded as run `id` from `file` where the database ranks it otherwise
/// than its `task.json` (`stated`) says: `kept`, its metric, division, method, models,
/// chosen_by and entrant in the `tasks` table, or its published figures in `published`.
fn check_kept(
    db: &Db,
    (id, file): (i64, &Path),
    kept: &[String; 6],
    stated: &TaskResult,
) -> Result<()> {
    let edited = |key: &str, db: String, doc: String| {
        let msg = format!(
            "the entry recorded as run {id} is ranked with {key} {db}, but its task.json \
             says {doc}: the database was edited"
        );
        Err(Error::file(file, key, msg))
    };
    let keys = [
        "metric",
        "division",
        "method",
        "models",
        "chosen_by",
        "entrant",
    ];
    let doc = [
        &stated.metric,
        &stated.division,
        &stated.method,
        &stated.models,
        &stated.chosen_by,
        &stated.entrant,
    ];
    for ((key, db), doc) in keys.iter().zip(kept).zip(doc) {
        if db != doc {
            return edited(key, format!("{db:?}"), format!("{doc:?}"));
        }
    }
    let sql = "SELECT label, value, source, division FROM published WHERE run = ?1 ORDER BY rowid";
    let published: Vec<Published> = db.query(sql, [id], |r| {
        Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?))
    })?;
    let n = published.len().max(stated.published.len());
    let Some(i) = (0..n).find(|&i| published.get(i) != stated.published.get(i)) else {
        return Ok(());
    };
    match (published.get(i), stated.published.get(i)) {
        (Some(d), Some(t)) => {
            let parts = [
                ("label", format!("{:?}", d.0), format!("{:?}", t.0)),
                ("value", format!("{} mm", d.1), format!("{} mm", t.1)),
                ("source", format!("{:?}", d.2), format!("{:?}", t.2)),
                ("division", format!("{:?}", d.3), format!("{:?}", t.3)),
            ];
            let (key, d, t) = parts
                .into_iter()
                .find(|(_, d, t)| d != t)
                .unwrap_or_default();
            edited(&format!("published[{i}].{key}"), d, t)
        }
        (d, t) => {
            let shown = |p: Option<&Published>| p.map_or("none".into(), |p| format!("{:?}", p.0));
            edited(&format!("published[{i}]"), shown(d), shown(t))
        }
    }
}

/// `leaderboard --verify`: every recorded task entry's figure and interval computed again, by
/// the task's metric, from the per-row validation errors its `task.json` recorded, and compared
/// bit for bit with the figure the database ranks and the one the document states. A mismatch
/// (a figure edited before `record`, a database edited after) or an entry without per-row
/// errors is refused, naming the folder it was recorded from; so is an entry ranked under
/// another task than its `task.json` names, and one whose task hash is recorded under
/// another task's name (an entry filed under a task it did not run), and one whose other
/// ranked values (division, models, published figures…) are not its `task.json`'s
/// (`check_kept`). Returns the entries verified.
pub fn verify(db: &Db) -> Result<usize> {
    let sql = "SELECT r.id, r.source, r.document, t.value, t.ci_lo, t.ci_hi, t.task, \
               t.task_hash, t.metric, t.division, t.method, t.models, t.chosen_by, t.entrant \
               FROM tasks t JOIN runs r ON r.id = t.run ORDER BY r.id";
    let entries = db.query(sql, [], |r| {
        let ci: (Option<f64>, Option<f64>) = (r.get(4)?, r.get(5)?);
        let kept: [String; 6] = [
            r.get(8)?,
            r.get(9)?,
            r.get(10)?,
            r.get(11)?,
            r.get(12)?,
            r.get(13)?,
        ];
        Ok((
            (r.get::<_, i64>(0)?, r.get::<_, String>(1)?),
            r.get::<_, String>(2)?,
            r.get::<_, f64>(3)?,
            ci.0.zip(ci.1).map(|(l, h)| [l, h]),
            (r.get::<_, String>(6)?, r.get::<_, String>(7)?),
            kept,
        ))
    })?;
    // Each task hash with the first task name it is recorded under, and where.
    let mut named: BTreeMap<&str, (&str, i64)> = BTreeMap::new();
    for ((id, source), document, value, ci, (task, hash), kept) in &entries {
        let file = Path::new(source).join("task.json");
        let text: serde_json::Value = serde_json::from_str(document)
            .map_err(|e| Error::file(&file, "task.json", format!("recorded as run {id}: {e}")))?;
        let rec = TaskRecord::from_value(text, &file)?;
        if (rec.task.as_str(), rec.task_hash.as_str()) != (task, hash) {
            let msg = format!(
                "the entry recorded as run {id} is ranked as task `{task}` (task hash {hash}), \
                 but its task.json names `{}` ({}): the database was edited",
                rec.task, rec.task_hash
            );
            return Err(Error::file(&file, "task", msg));
        }
        check_kept(db, (*id, &file), kept, &TaskResult::of(&rec))?;
        // The hash binds the task file's values, so one hash under two names is an entry
        // filed under the name of a task it did not run.
        match named.get(hash.as_str()) {
            Some((other, first)) if other != task => {
                let msg = format!(
                    "the entry recorded as run {id} is of task `{task}`, but its task_hash \
                     {hash} is that of task `{other}` (recorded as run {first}): one task's \
                     hash under two names, an entry filed under a task it did not run"
                );
                return Err(Error::file(&file, "task", msg));
            }
            Some(_) => {}
            None => {
                named.insert(hash, (task, *id));
            }
        }
        let Some((again, again_ci)) = rec.recomputed(&file)? else {
            return Err(Error::file(
                &file,
                "validation_errors_mm",
                format!(
                    "the entry recorded as run {id} holds no per-row validation errors, so its \
                     figure {value} cannot be computed again; run the task again and record it"
                ),
            ));
        };
        let stated = [("recorded", *value, *ci), ("stated", rec.value, rec.ci95)];
        if let Some((what, v, c)) = stated
            .into_iter()
            .find(|(_, v, c)| !same_figure((*v, *c), (again, again_ci)))
        {
            return Err(Error::file(
                &file,
                "value",
                format!(
                    "the entry recorded as run {id} has the figure {}, but its {} \
                     validation errors give {} by {}: the figure {what} is not the one they \
                     give",
                    shown((v, c)),
                    rec.validation_errors_mm.len(),
                    shown((again, again_ci)),
                    rec.metric.as_str()
                ),
            ));
        }
    }
    Ok(entries.len())
}

//! A metric across recorded versions (docs/formats.md, `calbench history`): every figure of
//! the runs recorded, per scenario, machine and entry, each step between consecutive records
//! of a run's scenario on one machine judged by the rule of `calbench check`
//! ([`crate::report::check::compare_with`]: the tolerance, and the Holm-adjusted interval of
//! the change from the summaries' intervals), and the regressions of the latest version.

use std::collections::BTreeMap;

use serde_json::Value;

use super::Db;
use crate::error::Result;
use crate::numeric::Real;
use crate::report::check::{compare_with, Status};
use crate::report::html::history::Point;

/// The metrics shown when none is asked for (a task's ranking metric is always shown).
pub const DEFAULT_METRICS: [&str; 5] = [
    "validation_after_mm.mean",
    "validation_after_mm.rms",
    "validation_after_mm.max",
    "eta_mean_pct",
    "failures",
];

/// One recorded run as history reads it.
struct Run {
    id: i64,
    kind: String,
    scenario: String,
    label: String,
    version: String,
    commit: String,
    machine: String,
    recorded_at: String,
    document: String,
}

/// Up to 12 of `names`, comma-separated (`none` when there is none).
fn listed(names: &[String]) -> String {
    if names.is_empty() {
        return "none".into();
    }
    let more = names.len().saturating_sub(12);
    let shown = names[..names.len() - more].join(", ");
    if more > 0 {
        format!("{shown} and {more} more")
    } else {
        shown
    }
}

/// [`runs`] of `scenario`, refused naming it (and the recorded ones) when it has none.
fn recorded(db: &Db, scenario: Option<&str>) -> Result<Vec<Run>> {
    let found = runs(db, scenario)?;
    if let (Some(name), true) = (scenario, found.is_empty()) {
        let mut known: Vec<String> = runs(db, None)?.into_iter().map(|r| r.scenario).collect();
        known.sort();
        known.dedup();
        return Err(crate::Error::setting(
            "scenario",
            format!(
                "`{name}` has no record in the database (recorded: {})",
                listed(&known)
            ),
        ));
    }
    Ok(found)
}

fn runs(db: &Db, scenario: Option<&str>) -> Result<Vec<Run>> {
    db.query(
        "SELECT id, kind, scenario, label, calbench_version, git_commit, machine, recorded_at, \
         document FROM runs WHERE ?1 IS NULL OR scenario = ?1 ORDER BY id",
        [scenario],
        |r| {
            Ok(Run {
                id: r.get(0)?,
                kind: r.get(1)?,
                scenario: r.get(2)?,
                label: r.get(3)?,
                version: r.get(4)?,
                commit: r.get(5)?,
                machine: r.get(6)?,
                recorded_at: r.get(7)?,
                document: r.get(8)?,
            })
        },
    )
}

fn is_run(r: &Run) -> bool {
    r.kind == "run" || r.kind == "merge"
}

/// The records of each scenario on each machine, in the order recorded.
fn series(runs: &[Run]) -> BTreeMap<(&str, &str), Vec<&Run>> {
    let mut m: BTreeMap<(&str, &str), Vec<&Run>> = BTreeMap::new();
    for r in runs {
        m.entry((&r.scenario, &r.machine)).or_default().push(r);
    }
    m
}

/// Each metric's status from run `a` to run `b` by `check`'s rule, by (entry, metric).
fn steps(a: &Run, b: &Run, tolerance: Real) -> BTreeMap<(String, String), Status> {
    let (Ok(va), Ok(vb)) = (
        serde_json::from_str::<Value>(&a.document),
        serde_json::from_str::<Value>(&b.document),
    ) else {
        return BTreeMap::new();
    };
    compare_with(&vb, &va, tolerance, None)
        .into_iter()
        .map(|c| ((c.metric.entry, c.metric.metric), c.status))
        .collect()
}

/// Every figure of the runs recorded (of `scenario` when given) whose metric is one of
/// `metrics` (a name or its prefix before a `.`; [`DEFAULT_METRICS`] when empty), in the
/// order recorded, each with its step from the record before it in its series.
pub fn points(
    db: &Db,
    scenario: Option<&str>,
    metrics: &[String],
    tolerance: Real,
) -> Result<Vec<Point>> {
    let runs = recorded(db, scenario)?;
    let mut step_of: BTreeMap<i64, BTreeMap<(String, String), Status>> = BTreeMap::new();
    for list in series(&runs).values() {
        for w in list.windows(2) {
            if is_run(w[0]) && is_run(w[1]) {
                step_of.insert(w[1].id, steps(w[0], w[1], tolerance));
            }
        }
    }
    let by_id: BTreeMap<i64, &Run> = runs.iter().map(|r| (r.id, r)).collect();
    let wanted = |metric: &str, kind: &str| {
        if metrics.is_empty() {
            kind == "task" || DEFAULT_METRICS.contains(&metric)
        } else {
            metrics.iter().any(|m| {
                metric == m
                    || metric
                        .strip_prefix(m.as_str())
                        .is_some_and(|r| r.starts_with('.'))
            })
        }
    };
    let figures = db.query(
        "SELECT run, entry, metric, value, ci_lo, ci_hi FROM figures ORDER BY run, entry, metric",
        [],
        |r| {
            Ok((
                r.get::<_, i64>(0)?,
                r.get::<_, String>(1)?,
                r.get::<_, String>(2)?,
                r.get::<_, f64>(3)?,
                r.get::<_, Option<f64>>(4)?,
                r.get::<_, Option<f64>>(5)?,
            ))
        },
    )?;
    let ids: std::collections::BTreeSet<i64> = runs.iter().map(|r| r.id).collect();
    let mut names: Vec<&String> = figures
        .iter()
        .filter(|f| ids.contains(&f.0))
        .map(|f| &f.2)
        .collect();
    names.sort();
    names.dedup();
    let matches =
        |m: &str, n: &str| n == m || n.strip_prefix(m).is_some_and(|r| r.starts_with('.'));
    if let Some(m) = metrics
        .iter()
        .find(|m| !names.iter().any(|n| matches(m, n)))
    {
        let mut heads: Vec<String> = names
            .iter()
            .map(|n| n.split('.').next().unwrap_or(n).to_string())
            .collect();
        heads.dedup();
        return Err(crate::Error::setting(
            "metric",
            format!(
                "`{m}` is no recorded metric nor a prefix of one (recorded: {})",
                listed(&heads)
            ),
        ));
    }
    let mut out = Vec::new();
    for (id, entry, metric, value, lo, hi) in figures {
        let Some(run) = by_id.get(&id) else {
            continue;
        };
        if !wanted(&metric, &run.kind) {
            continue;
        }
        let step = step_of
            .get(&id)
            .and_then(|s| s.get(&(entry.clone(), metric.clone())))
            .map(|s| s.as_str());
        out.push(Point {
            scenario: run.scenario.clone(),
            machine: run.machine.clone(),
            kind: run.kind.clone(),
            entry,
            metric,
            label: run.label.clone(),
            version: run.version.clone(),
            git_commit: run.commit.clone(),
            recorded_at: run.recorded_at.clone(),
            value,
            ci: lo.zip(hi).map(|(l, h)| [l, h]),
            step,
        });
    }
    Ok(out)
}

/// A regression of the latest version of a scenario on a machine against the version
/// before it.
#[derive(Clone, Debug)]
pub struct Regressed {
    /// The scenario.
    pub scenario: String,
    /// The machine.
    pub machine: String,
    /// The version label before.
    pub from: String,
    /// The latest version label.
    pub to: String,
    /// What got worse (`entry: metric got worse: value (baseline b)`), with the interval of
    /// the change.
    pub what: String,
}

/// For each scenario (or `scenario`) and machine with runs of at least two version labels:
/// the latest run against the last run of the label before the latest one, by `check`'s rule;
/// every metric that regressed, and how many such pairs were compared.
pub fn regressions(
    db: &Db,
    scenario: Option<&str>,
    tolerance: Real,
) -> Result<(Vec<Regressed>, usize)> {
    let runs = recorded(db, scenario)?;
    let mut out = Vec::new();
    let mut compared = 0;
    for ((scenario, machine), list) in series(&runs) {
        let list: Vec<&Run> = list.into_iter().filter(|r| is_run(r)).collect();
        let Some(latest) = list.last() else {
            continue;
        };
        let Some(before) = list.iter().rev().find(|r| r.label != latest.label) else {
            continue;
        };
        compared += 1;
        let (Ok(va), Ok(vb)) = (
            serde_json::from_str::<Value>(&before.document),
            serde_json::from_str::<Value>(&latest.document),
        ) else {
            continue;
        };
        for c in compare_with(&vb, &va, tolerance, None) {
            if c.status == Status::Regression {
                let ci = c.diff_ci.map_or(String::new(), |[lo, hi]| {
                    format!(
                        " (change {lo:.4}..{hi:.4}, Holm-adjusted p {:.2e})",
                        c.p_holm
                    )
                });
                out.push(Regressed {
                    scenario: scenario.to_string(),
                    machine: machine.to_string(),
                    from: before.label.clone(),
                    to: latest.label.clone(),
                    what: format!("{}{ci}", c.metric),
                });
            }
        }
    }
    Ok((out, compared))
}

//! A metric across recorded versions (docs/formats.md, `calbench history`): every figure of
//! the runs recorded, per scenario, machine and entry, in the order of the versions — by
//! semantic version ([`VersionKey`]), then by the time of calbench's commit, never by the
//! order of recording — each step between consecutive versions of a run's scenario on one
//! machine judged by the rule of `calbench check`
//! ([`crate::analysis::regression::compare_with`]: the tolerance, and the Holm-adjusted
//! interval of the change from the summaries' intervals); the regressions and the drift of
//! the latest version ([`regressions`]).

use std::cmp::Ordering;
use std::collections::BTreeMap;
use std::path::Path;

use super::Db;
use crate::analysis::regression::{check_summary, compare_with, Compared, Status};
use crate::analysis::summary::Summary;
use crate::error::Result;
use crate::numeric::Real;
use crate::report::html::history::Point;
use crate::report::scenario_file;
use crate::study::metric::Metric;

/// The metrics shown when none is asked for (a task's ranking metric is always shown).
pub const DEFAULT_METRICS: [Metric; 5] = [
    Metric::ValidationAfterMean,
    Metric::ValidationAfterRms,
    Metric::ValidationAfterMax,
    Metric::EtaMean,
    Metric::Failures,
];

/// The step of a version whose scenario differs from the version's before it (other than
/// in `seed` and `trials`): not compared.
pub const SCENARIO_CHANGED: &str = "scenario changed";

/// One recorded run as history reads it (its columns by name).
#[derive(serde::Deserialize)]
struct Run {
    id: i64,
    kind: String,
    scenario: String,
    scenario_text: String,
    label: String,
    version: String,
    git_commit: String,
    commit_time: Option<i64>,
    machine: String,
    recorded_at: String,
    source: String,
    seed: Option<i64>,
    document: String,
}

/// Whether `name` asks for the recorded metric `metric`: its name, or its prefix before a
/// `.`.
fn names_metric(name: &str, metric: &str) -> bool {
    metric == name
        || metric
            .strip_prefix(name)
            .is_some_and(|r| r.starts_with('.'))
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
    db.query_as(
        "SELECT id, kind, scenario, scenario_text, label, calbench_version AS version, \
         git_commit, commit_time, machine, recorded_at, source, seed, document \
         FROM runs WHERE ?1 IS NULL OR scenario = ?1 ORDER BY id",
        [scenario],
    )
}

/// A version label's place among versions: semantic versioning's precedence (semver.org
/// § 11) of `MAJOR[.MINOR[.PATCH]][-PRE][+BUILD]`, a leading `v` allowed, missing numbers
/// taken as 0 and the build metadata ignored; `None` for a label that is not a version.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VersionKey {
    numbers: Vec<u64>,
    pre: Vec<String>,
}

impl VersionKey {
    /// Parses `label`.
    pub fn parse(label: &str) -> Option<VersionKey> {
        let l = label.strip_prefix(['v', 'V']).unwrap_or(label);
        let l = l.split('+').next()?;
        let (core, pre) = match l.split_once('-') {
            Some((c, p)) => (c, p.split('.').map(str::to_string).collect()),
            None => (l, Vec::new()),
        };
        let mut numbers = core
            .split('.')
            .map(|n| n.parse::<u64>().ok())
            .collect::<Option<Vec<u64>>>()?;
        if numbers.is_empty() || numbers.len() > 3 {
            return None;
        }
        numbers.resize(3, 0);
        Some(VersionKey { numbers, pre })
    }

    /// Whether `v` is a version as a calbench writes its own: `MAJOR.MINOR.PATCH[-PRE]` of
    /// semantic versioning (semver.org § 2 and § 9), each number without a leading zero, each
    /// pre-release identifier of ASCII letters, digits and `-` (a number without a leading
    /// zero); no `v`, no build metadata.
    pub fn is_release(v: &str) -> bool {
        let number = |n: &str| {
            !n.is_empty()
                && n.bytes().all(|b| b.is_ascii_digit())
                && (n == "0" || !n.starts_with('0'))
        };
        let (core, pre) = match v.split_once('-') {
            Some((c, p)) => (c, Some(p)),
            None => (v, None),
        };
        let parts: Vec<&str> = core.split('.').collect();
        let identifier = |i: &str| {
            !i.is_empty()
                && i.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'-')
                && (!i.bytes().all(|b| b.is_ascii_digit()) || number(i))
        };
        parts.len() == 3
            && parts.iter().all(|n| number(n))
            && pre.is_none_or(|p| p.split('.').all(identifier))
    }
}

impl Ord for VersionKey {
    fn cmp(&self, o: &Self) -> Ordering {
        self.numbers
            .cmp(&o.numbers)
            .then_with(|| match (self.pre.is_empty(), o.pre.is_empty()) {
                (true, true) => Ordering::Equal,
                (true, false) => Ordering::Greater,
                (false, true) => Ordering::Less,
                (false, false) => {
                    for (a, b) in self.pre.iter().zip(&o.pre) {
                        let c = match (a.parse::<u64>(), b.parse::<u64>()) {
                            (Ok(x), Ok(y)) => x.cmp(&y),
                            (Ok(_), Err(_)) => Ordering::Less,
                            (Err(_), Ok(_)) => Ordering::Greater,
                            _ => a.cmp(b),
                        };
                        if c != Ordering::Equal {
                            return c;
                        }
                    }
                    self.pre.len().cmp(&o.pre.len())
                }
            })
    }
}

impl PartialOrd for VersionKey {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// The order of records: by the version of the label (else of calbench's version), then by
/// the time of calbench's commit (unknown first), then — for records of one version and
/// commit — by the label, the time recorded and the record's number.
fn order(a: &Run, b: &Run) -> Ordering {
    let key = |r: &Run| VersionKey::parse(&r.label).or_else(|| VersionKey::parse(&r.version));
    key(a)
        .cmp(&key(b))
        .then(a.commit_time.cmp(&b.commit_time))
        .then_with(|| a.label.cmp(&b.label))
        .then_with(|| a.recorded_at.cmp(&b.recorded_at))
        .then(a.id.cmp(&b.id))
}

/// The records of each scenario on each machine, in [`order`].
fn series(runs: &[Run]) -> BTreeMap<(&str, &str), Vec<&Run>> {
    let mut m: BTreeMap<(&str, &str), Vec<&Run>> = BTreeMap::new();
    for r in runs {
        m.entry((&r.scenario, &r.machine)).or_default().push(r);
    }
    for list in m.values_mut() {
        list.sort_by(|a, b| order(a, b));
    }
    m
}

/// The versions of a series of runs: each label's records, in order, and the record that
/// stands for the label in comparisons (its last in [`order`]).
fn versions<'r>(list: &[&'r Run]) -> Vec<Vec<&'r Run>> {
    let mut out: Vec<Vec<&Run>> = Vec::new();
    for r in list.iter().filter(|r| super::Kind::is_study(&r.kind)) {
        match out.last_mut() {
            Some(v) if v[0].label == r.label => v.push(r),
            _ => out.push(vec![r]),
        }
    }
    out
}

/// Whether `a` and `b` ran the same scenario, up to the keys that only choose the draws
/// (`seed`, `trials`): records whose scenarios differ otherwise are not compared.
fn same_scenario(a: &Run, b: &Run) -> bool {
    scenario_file::differences(&a.scenario_text, &b.scenario_text).is_empty()
}

/// The summary a record holds (`None` for a record of another kind, whose document is no
/// summary).
fn summary_of(r: &Run) -> Option<Summary> {
    let v = serde_json::from_str(&r.document).ok()?;
    check_summary(v, Path::new(&r.source)).ok()
}

/// Every metric compared from run `a` to run `b` by `check`'s rule (unpaired: the records
/// hold summaries).
fn compared(a: &Run, b: &Run, tolerance: Real) -> Vec<Compared> {
    let (Some(sa), Some(sb)) = (summary_of(a), summary_of(b)) else {
        return Vec::new();
    };
    compare_with(&sb, &sa, tolerance, None)
}

/// Each metric's step from `a` to `b`, by (entry, metric): `check`'s status, or
/// [`SCENARIO_CHANGED`].
fn steps(a: &Run, b: &Run, tolerance: Real) -> BTreeMap<(String, String), &'static str> {
    if !same_scenario(a, b) {
        let Some(doc) = summary_of(b) else {
            return BTreeMap::new();
        };
        return crate::analysis::regression::compare_all(&doc, &doc, 0.0)
            .into_iter()
            .map(|c| ((c.metric.entry, c.metric.metric), SCENARIO_CHANGED))
            .collect();
    }
    compared(a, b, tolerance)
        .into_iter()
        .map(|c| ((c.metric.entry, c.metric.metric), c.status.as_str()))
        .collect()
}

/// Every figure of the runs recorded (of `scenario` when given) whose metric is one of
/// `metrics` (a name or its prefix before a `.`; [`DEFAULT_METRICS`] when empty), series by
/// series in the order of versions (`order`), each with its step from the version before
/// it.
pub fn points(
    db: &Db,
    scenario: Option<&str>,
    metrics: &[String],
    tolerance: Real,
) -> Result<Vec<Point>> {
    let runs = recorded(db, scenario)?;
    let mut step_of: BTreeMap<i64, BTreeMap<(String, String), &'static str>> = BTreeMap::new();
    let series = series(&runs);
    for list in series.values() {
        let v = versions(list);
        for w in v.windows(2) {
            let before = w[0].last().copied();
            for r in &w[1] {
                if let Some(b) = before {
                    step_of.insert(r.id, steps(b, r, tolerance));
                }
            }
        }
    }
    let wanted = |metric: &str, kind: &str| {
        if metrics.is_empty() {
            kind == "task" || Metric::from_key(metric).is_some_and(|m| DEFAULT_METRICS.contains(&m))
        } else {
            metrics.iter().any(|m| names_metric(m, metric))
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
    if let Some(m) = metrics
        .iter()
        .find(|m| !names.iter().any(|n| names_metric(m, n)))
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
    let mut by_run: BTreeMap<i64, Vec<_>> = BTreeMap::new();
    for f in figures {
        by_run.entry(f.0).or_default().push(f);
    }
    let mut out = Vec::new();
    for run in series.values().flatten() {
        for (_, entry, metric, value, lo, hi) in by_run.remove(&run.id).unwrap_or_default() {
            if !wanted(&metric, &run.kind) {
                continue;
            }
            let step = step_of
                .get(&run.id)
                .and_then(|s| s.get(&(entry.clone(), metric.clone())))
                .copied();
            out.push(Point {
                scenario: run.scenario.clone(),
                machine: run.machine.clone(),
                kind: run.kind.clone(),
                entry,
                metric,
                label: run.label.clone(),
                version: run.version.clone(),
                git_commit: run.git_commit.clone(),
                recorded_at: run.recorded_at.clone(),
                value,
                ci: lo.zip(hi).map(|(l, h)| [l, h]),
                step,
                record: run.id,
                seed: run.seed,
                source: run.source.clone(),
            });
        }
    }
    Ok(out)
}

/// What a flagged change of the latest version is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flag {
    /// Worse than the version before it, by `check`'s rule.
    Regression,
    /// Each step since an earlier version within the tolerance (no step a regression),
    /// together a regression by `check`'s rule against that version.
    Drift,
    /// The scenario differs from the version's before it: not compared.
    ScenarioChanged,
}

/// A flagged change of the latest version of a scenario on a machine.
#[derive(Clone, Debug)]
pub struct Regressed {
    /// The scenario.
    pub scenario: String,
    /// The machine.
    pub machine: String,
    /// What it is.
    pub flag: Flag,
    /// The version label compared against: the one before the latest, or for a drift the
    /// earliest from which the metric drifted.
    pub from: String,
    /// The versions between `from` and `to`, exclusive (a drift's path).
    pub through: Vec<String>,
    /// The latest version label.
    pub to: String,
    /// What got worse (`entry: metric got worse: value (baseline b)`), with the interval of
    /// the change; empty for a changed scenario.
    pub what: String,
}

/// The flagged changes of the latest version, for each scenario (or `scenario`) and machine
/// with runs of at least two version labels, versions in `order`:
///
/// - **regression**: the latest version (its last record) against the version before it
///   that ran the same scenario (up to `seed` and `trials`; versions between that ran another
///   are passed over), by `check`'s rule at `tolerance`;
/// - **drift** (a cumulative rule): for each metric that is not a regression of that step,
///   the latest version against every earlier version back to the last step that was a
///   regression of that metric (a regression already flagged), over the versions that ran
///   the latest's scenario; when it is a regression against one of them, the earliest such
///   version is reported: several steps each within the tolerance that together are beyond
///   it;
/// - **scenario changed**: no earlier version ran the latest's scenario (up to `seed` and
///   `trials`): nothing is compared, and no regression is claimed.
///
/// Returns them, how many scenario-machine pairs were compared, and how many were not judged:
/// a registration or instruments study's, whose cells `check`'s rule does not compare.
pub fn regressions(
    db: &Db,
    scenario: Option<&str>,
    tolerance: Real,
) -> Result<(Vec<Regressed>, usize, usize)> {
    let runs = recorded(db, scenario)?;
    let mut out = Vec::new();
    let (mut pairs, mut unjudged) = (0, 0);
    for ((scenario, machine), list) in series(&runs) {
        let every: Vec<&Run> = versions(&list)
            .into_iter()
            .filter_map(|g| g.last().copied())
            .collect();
        let Some((&latest, [.., before])) = every.split_last() else {
            continue;
        };
        if summary_of(latest).is_none() {
            unjudged += 1;
            continue;
        }
        pairs += 1;
        // The versions that ran the latest's scenario (up to seed and trials): one between
        // that ran another is passed over, so that a change of the scenario and back does
        // not hide a regression against the version before the change.
        let v: Vec<&Run> = every
            .iter()
            .copied()
            .filter(|r| same_scenario(r, latest))
            .collect();
        let k = v.len() - 1;
        let flag = |flag, from: &Run, through: &[&Run], what: String| Regressed {
            scenario: scenario.to_string(),
            machine: machine.to_string(),
            flag,
            from: from.label.clone(),
            through: through.iter().map(|r| r.label.clone()).collect(),
            to: v[k].label.clone(),
            what,
        };
        if k == 0 {
            out.push(flag(Flag::ScenarioChanged, before, &[], String::new()));
            continue;
        }
        let describe = |c: &Compared| {
            let ci = c.diff_ci.map_or(String::new(), |[lo, hi]| {
                format!(
                    " (change {}..{}, Holm-adjusted p {:.2e})",
                    crate::report::markdown::fmt_num(lo, 3),
                    crate::report::markdown::fmt_num(hi, 3),
                    c.p_holm
                )
            });
            format!("{}{ci}", c.metric)
        };
        let last = compared(v[k - 1], v[k], tolerance);
        let key = |c: &Compared| (c.metric.entry.clone(), c.metric.metric.clone());
        let mut done: Vec<(String, String)> = Vec::new();
        for c in last.iter().filter(|c| c.status == Status::Regression) {
            out.push(flag(Flag::Regression, v[k - 1], &[], describe(c)));
            done.push(key(c));
        }
        // Drift: walk back, stopping per metric at a step that was a regression, and for
        // every metric at a change of the scenario.
        let mut stopped: Vec<(String, String)> = done.clone();
        let mut drift: BTreeMap<(String, String), (usize, Compared)> = BTreeMap::new();
        for j in (0..k - 1).rev() {
            for c in compared(v[j], v[j + 1], tolerance) {
                if c.status == Status::Regression {
                    stopped.push(key(&c));
                }
            }
            for c in compared(v[j], v[k], tolerance) {
                let id = key(&c);
                if c.status == Status::Regression && !stopped.contains(&id) {
                    drift.insert(id, (j, c));
                }
            }
        }
        let mut drift: Vec<(usize, Compared)> = drift.into_values().collect();
        drift.sort_by_key(|(j, _)| *j);
        for (j, c) in drift {
            out.push(flag(Flag::Drift, v[j], &v[j + 1..k], describe(&c)));
        }
    }
    Ok((out, pairs, unjudged))
}

#[cfg(test)]
mod tests {
    use super::VersionKey;

    #[test]
    fn versions_order_by_semantic_version() {
        let k = |l: &str| VersionKey::parse(l).unwrap();
        assert!(k("v0.9") < k("v1.0"));
        assert!(k("1.0") == k("v1.0.0"));
        assert!(k("v1.10") > k("v1.9"));
        assert!(k("2.0.0-rc.1") < k("2.0.0"));
        assert!(k("2.0.0-alpha") < k("2.0.0-alpha.1"));
        assert!(k("2.0.0-alpha.2") < k("2.0.0-alpha.10"));
        assert!(k("2.0.0-1") < k("2.0.0-alpha"));
        assert!(k("0.1.0+abc") == k("0.1.0+def"));
        assert!(VersionKey::parse("nightly").is_none());
        for v in [
            "0.1.0",
            "1.20.3",
            "2.0.0-rc.1",
            "1.0.0-alpha-2.x",
            "10.0.0-0",
        ] {
            assert!(VersionKey::is_release(v), "{v}");
        }
        for v in [
            "9.9", "01.2.3", "1.2.3.4", "v1.2.3", "1.2.3+b", "1.2.3-", "1.2.3-01", "1..3",
        ] {
            assert!(!VersionKey::is_release(v), "{v}");
        }
        assert!(VersionKey::parse("1.2.3.4").is_none());
    }
}

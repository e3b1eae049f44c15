//! What a baseline carries so that `check` can compare against it trial by trial
//! (docs/formats.md § 8.4): the run's `summary.json` with, under `per_trial`, each entry's
//! trial numbers and the per-trial values of the guarded metrics ([`Trials`]) — those
//! `check` reads from a run folder's `trials.csv`, in a few kilobytes instead of the whole
//! file. A run compared with such a baseline is paired whenever the seed, the sweep and the
//! trials agree; otherwise [`unpaired_because`] says what differs, and so what a paired
//! comparison would take.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::noise::{differs, figure_of, is_rmse, same_figure, trials_key, Trials};
use super::{check_summary, entry_metrics, lookup, read_json};
use crate::analysis::summary::Summary;
use crate::error::shown;
use crate::error::{at_line, Error, Result};
use crate::numeric::Real;
use crate::study::metric::Metric;
use crate::study::stats::Entry;

/// The key of a baseline's per-trial values in its document.
pub const KEY: &str = "per_trial";

/// The `format` of [`PerTrial`].
pub const FORMAT: &str = "calbench-per-trial-1";

/// The per-trial values of a run's guarded metrics, as a baseline file holds them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerTrial {
    /// [`FORMAT`].
    pub format: String,
    /// By entry key ([`super::noise::trials_key`]).
    pub entries: BTreeMap<String, EntryTrials>,
    /// The scenario the run ran, as its folder's `scenario.toml` holds it below the hash
    /// line, when the run's folder has one: `check` refuses a run of another scenario.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenario: Option<String>,
}

/// One entry's trials and values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EntryTrials {
    /// Every trial number of the entry, usable or not, ascending.
    pub trials: Vec<usize>,
    /// By metric key: the value of each trial of `trials`, in its order (`null` where the
    /// trial gave no usable value).
    pub values: BTreeMap<String, Vec<Option<Real>>>,
}

impl From<&Trials> for PerTrial {
    fn from(t: &Trials) -> PerTrial {
        let mut entries = BTreeMap::new();
        for (entry, trials) in &t.trials {
            let trials: Vec<usize> = trials.iter().copied().collect();
            let values = t
                .values
                .iter()
                .filter(|((e, _), _)| e == entry)
                .map(|((_, metric), by_trial)| {
                    let row = trials.iter().map(|i| by_trial.get(i).copied()).collect();
                    (metric.clone(), row)
                })
                .collect();
            entries.insert(entry.clone(), EntryTrials { trials, values });
        }
        PerTrial {
            format: FORMAT.into(),
            entries,
            scenario: None,
        }
    }
}

impl PerTrial {
    /// The per-trial values as `check` compares them; refuses, naming `path` and the key, a
    /// list whose length is not the entry's number of trials, a trial listed twice or out of
    /// order, or a value that is not finite.
    pub fn to_trials(&self, path: &Path) -> Result<Trials> {
        let bad = |key: String, what: String| Error::file(path, key, what);
        if self.format != FORMAT {
            return Err(bad(
                format!("{KEY}.format"),
                format!("is \"{}\", not \"{FORMAT}\"", self.format),
            ));
        }
        let mut t = Trials::default();
        for (entry, e) in &self.entries {
            if e.trials.windows(2).any(|w| w[0] >= w[1]) {
                return Err(bad(
                    format!("{KEY}.entries.{entry}.trials"),
                    "must list each trial once, ascending".into(),
                ));
            }
            t.trials
                .insert(entry.clone(), e.trials.iter().copied().collect());
            for (metric, row) in &e.values {
                let key = format!("{KEY}.entries.{entry}.values.{metric}");
                if row.len() != e.trials.len() {
                    return Err(bad(
                        key,
                        format!(
                            "has {} values for the entry's {} trials",
                            row.len(),
                            e.trials.len()
                        ),
                    ));
                }
                let mut by_trial = BTreeMap::new();
                for (i, v) in e.trials.iter().zip(row) {
                    match v {
                        Some(x) if !x.is_finite() => {
                            return Err(bad(key, format!("trial {i} is not finite")))
                        }
                        Some(x) => {
                            by_trial.insert(*i, *x);
                        }
                        None => {}
                    }
                }
                t.values.insert((entry.clone(), metric.clone()), by_trial);
            }
        }
        Ok(t)
    }
}

/// The baseline document of a run: its `summary` with the per-trial values `trials` (read
/// from its `trials.csv`) and the `scenario` it ran (its canonical text), when known, under
/// [`KEY`].
pub fn baseline_document(
    summary: &Summary,
    trials: &Trials,
    scenario: Option<String>,
) -> Result<Value> {
    let mut doc = summary.to_value()?;
    let per_trial = PerTrial {
        scenario,
        ..PerTrial::from(trials)
    };
    let per_trial = serde_json::to_value(per_trial).map_err(|e| Error::Compute(e.to_string()))?;
    match doc.as_object_mut() {
        Some(m) => {
            m.insert(KEY.into(), per_trial);
            Ok(doc)
        }
        None => Err(Error::Compute("a summary is a JSON object".into())),
    }
}

/// The `trials.csv` beside the summary file `path`.
fn trials_csv(path: &Path) -> PathBuf {
    path.parent().unwrap_or(Path::new(".")).join("trials.csv")
}

/// The per-trial values behind the summary `doc` read from `path`: its own [`KEY`] (a
/// baseline file, with the scenario it names), else the `trials.csv` beside it (a run
/// folder); `None` when it has neither. A refusal of its own names the line of the key
/// refused (`line 80, per_trial.format`).
pub fn trials_of(doc: &Value, path: &Path) -> Result<Option<(Trials, Option<String>)>> {
    if doc.get(KEY).is_some() {
        /// The baseline's own values, read by their full key path (`per_trial.entries.…`).
        #[derive(Deserialize)]
        struct Own {
            per_trial: PerTrial,
        }
        let p = crate::error::read_typed::<Own, _>(doc, path, "baseline");
        return p
            .and_then(|o| {
                let scenario = o.per_trial.scenario.clone();
                if let Some(Err(e)) = scenario.as_deref().map(toml::from_str::<toml::Table>) {
                    let msg = format!(
                        "is not the text of a scenario (TOML: {}): the file was altered; write \
                         the baseline again with `calbench baseline`",
                        e.message()
                    );
                    return Err(Error::file(path, "per_trial.scenario", msg));
                }
                Ok((o.per_trial.to_trials(path)?, scenario))
            })
            .map(Some)
            .map_err(Error::at_json_key_line);
    }
    let csv = trials_csv(path);
    if crate::error::exists(&csv)? {
        Trials::read(&csv).map(|t| Some((t, None)))
    } else {
        Ok(None)
    }
}

/// The refusal of the folder `dir` of a shard (it holds `shard.json`) where a whole run's is
/// taken, `then` saying what to do with the merged folder; `None` for another folder.
pub fn a_shard(dir: &Path, then: &str) -> Option<Error> {
    dir.join("shard.json").is_file().then(|| {
        let why = format!(
            "is a shard of a run (shard.json), a part that holds no results of its own: merge \
             the run's shards first (`calbench merge SHARD… --out DIR`, or `merge --record`) \
             and {then}"
        );
        Error::file(dir, "folder", why)
    })
}

/// One side of a comparison: where its summary was read from, the summary, and its
/// per-trial values ([`trials_of`]).
pub struct Side {
    /// The summary file read.
    pub path: PathBuf,
    /// Its contents.
    pub summary: Summary,
    /// Its per-trial values, when it has them.
    pub trials: Option<Trials>,
    /// The scenario the run ran (canonical text), when a baseline file names it
    /// ([`PerTrial::scenario`]); a run folder's is its `scenario.toml`, which `check` and
    /// `compare` read (`report::scenario_file::ran`, a layer above this one).
    pub scenario: Option<String>,
}

impl Side {
    /// The files [`Side::read`] reads for `path`: the summary (`path`, or its `summary.json`
    /// when `path` is a folder) and the `trials.csv` beside it.
    pub fn files(path: &Path) -> [PathBuf; 2] {
        let file = if path.is_dir() {
            path.join("summary.json")
        } else {
            path.to_path_buf()
        };
        let csv = trials_csv(&file);
        [file, csv]
    }

    /// Reads a run's summary: `path` is the run's folder (its `summary.json` is read), its
    /// `summary.json` or a baseline file. Refuses, naming the file, what is not a calbench
    /// summary, and a missing file.
    pub fn read(path: &Path) -> Result<Side> {
        let [file, _] = Side::files(path);
        if !crate::error::exists(&file)? {
            if let Some(e) = a_shard(path, "give the merged folder") {
                return Err(e);
            }
            return Err(Error::io(
                &file,
                std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "no such file: give a run's folder or its summary.json",
                ),
            ));
        }
        let doc = read_json(&file)?;
        let own = doc.get(KEY).is_some();
        let (trials, scenario) = trials_of(&doc, &file)?.unzip();
        let summary = check_summary(doc, &file)?;
        if let (true, Some(t)) = (own, &trials) {
            own_keys(&summary, t)
                .map_err(|(key, why)| Error::file(&file, key, why).at_json_key_line())?;
        }
        if let Some(t) = &trials {
            let csv = trials_csv(&file);
            if let (false, Some((entry, why))) = (own, unknown_entry(&summary, t)) {
                let line = t.first_line.get(&entry).copied();
                let msg = format!("{entry} {why}: {} is not of this run", csv.display());
                return Err(Error::file(&csv, at_line(line, "column method"), msg));
            }
            whole_run(&summary, t).map_err(|(entry, why)| match own {
                true => Error::file(&file, format!("{KEY}.entries.{entry}.trials"), why)
                    .at_json_key_line(),
                false => Error::file(
                    &csv,
                    "column trial",
                    format!("{why}: {} is not this run's whole file", csv.display()),
                ),
            })?;
            behind(&summary, t).map_err(|(entry, metric, why)| match own {
                true => Error::file(&file, format!("{KEY}.entries.{entry}.values.{metric}"), why)
                    .at_json_key_line(),
                false => {
                    let column = Metric::from_key(&metric).and_then(|m| m.column());
                    Error::file(
                        &csv,
                        format!("column {}", column.unwrap_or(&metric)),
                        format!(
                            "{why}: {} is not of this run (entry {entry})",
                            csv.display()
                        ),
                    )
                }
            })?;
        }
        Ok(Side {
            path: file,
            summary,
            trials,
            scenario: scenario.flatten(),
        })
    }
}

/// The first entry of the per-trial values `t` that `summary` has no result of, and why it is
/// refused: per-trial values (a baseline's own, or a run's `trials.csv`, which `baseline`
/// would carry into its file) are those behind the summary. `None` for a summary of no
/// results, which is refused as such.
fn unknown_entry(summary: &Summary, t: &Trials) -> Option<(String, String)> {
    let names: Vec<String> = summary
        .results
        .iter()
        .map(|e| trials_key(e, summary))
        .collect();
    let entry = t.trials.keys().find(|k| !names.contains(k))?;
    let why = format!(
        "is not an entry of the summary's results ({}): per-trial values are those behind the \
         summary",
        names.join(", ")
    );
    (!names.is_empty()).then(|| (entry.clone(), why))
}

/// Refuses a baseline's own per-trial values `t` (docs/formats.md § 2.4.1) with a key its
/// `summary` cannot be behind: an entry the summary has no result of (an entry one run lacks
/// is compared unpaired, § 8.4, but one the file's own summary lacks is an edited file), or a
/// metric that is not a per-trial metric of the entry. The key and why, where one is.
fn own_keys(summary: &Summary, t: &Trials) -> std::result::Result<(), (String, String)> {
    // A summary of no results is refused as such, by `check` and `compare`.
    if summary.results.is_empty() {
        return Ok(());
    }
    if let Some((entry, why)) = unknown_entry(summary, t) {
        return Err((format!("{KEY}.entries.{entry}"), why));
    }
    let entries: BTreeMap<String, &Entry> = summary
        .results
        .iter()
        .map(|e| (trials_key(e, summary), e))
        .collect();
    // `failures` and `eta_median_pct` are always compared from the summaries (§ 8.4).
    let unpaired = [Metric::EtaMedian.key(), Metric::Failures.key()];
    for (entry, metric) in t.values.keys() {
        let of_entry = entries
            .get(entry)
            .map(|e| entry_metrics(e))
            .unwrap_or_default();
        if unpaired.contains(metric) || !of_entry.iter().any(|(m, _)| m == metric) {
            let why = format!(
                "unknown metric \"{metric}\": the per-trial metrics are eta_mean_pct, \
                 validation_after_mm.mean, .rms, .max, validation_after_deg.mean, .rms and \
                 param_rmse.P of each parameter P of the entry's param_rmse"
            );
            return Err((format!("{KEY}.entries.{entry}.values.{metric}"), why));
        }
    }
    Ok(())
}

/// Whether the per-trial values `t` are those behind `summary`'s figures: for each entry and
/// metric they hold, the summary has the figure; and where it is the mean over trials (the
/// error statistics and the parameters' RMSE, root of the mean square; not `eta_mean_pct`,
/// whose figure is over each parameter's determinable trials), the figure they give
/// ([`figure_of`]) is the summary's. The entry key, the metric and what differs, where one is
/// not (values of another run, or edited).
fn behind(summary: &Summary, t: &Trials) -> std::result::Result<(), (String, String, String)> {
    let over_trials = |metric: &str| {
        Metric::from_key(metric).is_some_and(|m| m.spec().stat.is_some()) || is_rmse(metric)
    };
    for e in &summary.results {
        let entry = trials_key(e, summary);
        for (metric, _) in entry_metrics(e) {
            let Some(values) = t.values.get(&(entry.clone(), metric.clone())) else {
                continue;
            };
            let over = over_trials(&metric);
            let finite = values.values().filter(|v| v.is_finite()).count();
            if values.is_empty() || !over && finite == 0 {
                continue;
            }
            let given = || figure_of(values.values().copied(), &metric);
            // A figure the summary lacks beside values that give it: a key deleted, which
            // would leave the metric unguarded without a word.
            let Some(figure) = lookup(e, &metric) else {
                let why = match over {
                    true => format!(
                        "its {} values give {metric} {}, where the summary has none",
                        values.len(),
                        shown(given())
                    ),
                    false => format!(
                        "its {finite} finite values are behind {metric}, where the summary \
                         has none"
                    ),
                };
                return Err((entry, metric, why));
            };
            if !over {
                continue;
            }
            let given = given();
            if !same_figure(given, figure) {
                let why = format!(
                    "its {} values give {metric} {}, where the summary has {}",
                    values.len(),
                    shown(given),
                    shown(figure)
                );
                return Err((entry, metric, why));
            }
        }
    }
    Ok(())
}

/// Whether the per-trial values `t` are a whole run's: for each entry of `summary`, its
/// trials 0 to N − 1, N the summary's `trials` (each sweep point runs them all). A
/// `trials.csv` cut short (to its header) would otherwise leave the comparison unpaired, and
/// rows of trials the run never drew would pair with another run's. The entry key and why,
/// where one is not.
fn whole_run(summary: &Summary, t: &Trials) -> std::result::Result<(), (String, String)> {
    let Some(n) = summary.trials else {
        return Ok(());
    };
    for e in &summary.results {
        let entry = trials_key(e, summary);
        let held = t.trials.get(&entry);
        let count = held.map_or(0, BTreeSet::len);
        let why = match held.and_then(|h| h.iter().find(|i| **i >= n)) {
            Some(i) => format!(
                "holds trial {i} of {entry}, where the summary ran trials 0 to {}",
                n.saturating_sub(1)
            ),
            None if count != n => {
                format!("holds {count} of the {n} trials of {entry} that the summary ran")
            }
            None => continue,
        };
        return Err((entry, why));
    }
    Ok(())
}

/// Which side of a comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    /// The baseline (A).
    Baseline,
    /// The summary compared with it (B).
    Summary,
}

/// Why a comparison is made from the summaries rather than trial by trial.
#[derive(Clone, Debug, PartialEq)]
pub enum Unpaired {
    /// That side has no per-trial values: a summary alone, without `trials.csv` beside it or
    /// [`KEY`] in it.
    NoTrials(Which),
    /// The two summaries differ in `key` (`scenario`, `seed`, `trials`, `sweep_keys`,
    /// `sweep_values`): the baseline's value, then the summary's, as JSON.
    Differs {
        /// The key.
        key: &'static str,
        /// The baseline's value (`none` when missing).
        baseline: String,
        /// The summary's.
        summary: String,
    },
}

/// Why `summary` cannot be compared with `baseline` trial by trial; `None` when it can
/// (each entry is then paired when it holds the same trials on both sides).
pub fn unpaired_because(baseline: &Side, summary: &Side) -> Option<Unpaired> {
    if baseline.trials.is_none() {
        return Some(Unpaired::NoTrials(Which::Baseline));
    }
    if summary.trials.is_none() {
        return Some(Unpaired::NoTrials(Which::Summary));
    }
    let show = |v: Value| match v {
        Value::Null => "none".to_string(),
        v => v.to_string(),
    };
    differs(&baseline.summary, &summary.summary).map(|(key, a, b)| Unpaired::Differs {
        key,
        baseline: show(a),
        summary: show(b),
    })
}

/// The entries compared from the summaries although the runs pair ([`unpaired_because`] is
/// `None`), each with why: the entry key and the reason. An entry missing on either side is
/// not among them (it is a regression, or not compared).
pub fn unpaired_entries(baseline: &Side, summary: &Side) -> Vec<(String, String)> {
    let (Some(ta), Some(tb)) = (&baseline.trials, &summary.trials) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for b in &baseline.summary.results {
        let Some(e) = summary.summary.results.iter().find(|e| e.same_entry(b)) else {
            continue;
        };
        let (ka, kb) = (
            trials_key(b, &baseline.summary),
            trials_key(e, &summary.summary),
        );
        let why = match (ta.trials.get(&ka), tb.trials.get(&kb)) {
            (None, _) => "the baseline's per-trial values have no such entry".to_string(),
            (_, None) => "this run's per-trial values have no such entry".to_string(),
            (Some(x), Some(y)) if x != y => {
                let only =
                    |x: &BTreeSet<usize>, y: &BTreeSet<usize>| x.difference(y).next().copied();
                let first = only(x, y).into_iter().chain(only(y, x)).min();
                format!(
                    "its trials differ ({} in the baseline, {} in this run; trial {} is in one \
                     only)",
                    x.len(),
                    y.len(),
                    first.map_or("?".into(), |t| t.to_string())
                )
            }
            _ => continue,
        };
        out.push((b.key(), why));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_trial_values_round_trip() {
        let mut t = Trials::default();
        t.trials.insert("ls / random".into(), [0, 1, 2].into());
        let vals: BTreeMap<usize, Real> = [(0, 0.5), (2, 0.25)].into();
        t.values.insert(
            ("ls / random".into(), "validation_after_mm.rms".into()),
            vals,
        );
        let p = PerTrial::from(&t);
        let e = &p.entries["ls / random"];
        assert_eq!(e.trials, [0, 1, 2]);
        assert_eq!(
            e.values["validation_after_mm.rms"],
            [Some(0.5), None, Some(0.25)]
        );
        let back = p.to_trials(Path::new("b.json")).unwrap();
        assert_eq!(back.values, t.values);
        assert_eq!(back.trials, t.trials);
        let text = serde_json::to_string(&p).unwrap();
        let again: PerTrial = serde_json::from_str(&text).unwrap();
        assert_eq!(again, p);
    }

    #[test]
    fn inconsistent_per_trial_values_are_refused_naming_the_key() {
        let mut p = PerTrial {
            format: FORMAT.into(),
            entries: BTreeMap::new(),
            scenario: None,
        };
        p.entries.insert(
            "ls / random".into(),
            EntryTrials {
                trials: vec![0, 1],
                values: [("eta_mean_pct".to_string(), vec![Some(1.0)])].into(),
            },
        );
        let e = p.to_trials(Path::new("b.json")).unwrap_err().to_string();
        assert!(
            e.contains("b.json") && e.contains("eta_mean_pct") && e.contains("1 values"),
            "{e}"
        );
        p.entries.get_mut("ls / random").unwrap().trials = vec![1, 0];
        let e = p.to_trials(Path::new("b.json")).unwrap_err().to_string();
        assert!(e.contains("trials") && e.contains("ascending"), "{e}");
    }
}

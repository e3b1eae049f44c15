//! The figures of a summary: every number of an entry with its 95 % interval, as the results
//! database stores them (docs/formats.md "The results database"), and the refusal of figures
//! no run can have written, which every reader of a summary applies (`check`, `compare`,
//! `baseline`, `record`).

use std::path::Path;

use serde_json::Value;

use super::summary::Summary;
use crate::error::{at_line, json_key_line, shown, Error, Result};
use crate::numeric::Real;
use crate::study::metric::Metric;

/// One figure: a metric of an entry with its 95 % interval.
#[derive(Clone, Debug)]
pub struct Figure {
    /// The entry's name.
    pub entry: String,
    /// The metric's key path, e.g. `validation_after_mm.mean`.
    pub metric: String,
    /// Its value.
    pub value: Real,
    /// Its 95 % interval, where the output gives one.
    pub ci: Option<[Real; 2]>,
}

fn interval(v: Option<&Value>) -> Option<[Real; 2]> {
    let a = v?.as_array()?;
    match (a.first()?.as_f64(), a.get(1)?.as_f64()) {
        (Some(lo), Some(hi)) => Some([lo, hi]),
        _ => None,
    }
}

/// Every number under `m` as a figure `prefix + key` of `entry`, with the interval of its
/// sibling `<key>_ci95` (or of the same key in `cis`, the `_ci95` sibling of `m` itself, as
/// `param_rmse_ci95` is of `param_rmse`); objects are walked, `*_ci95`, strings and lists
/// skipped.
pub fn flatten(
    entry: &str,
    prefix: &str,
    m: &serde_json::Map<String, Value>,
    cis: Option<&Value>,
    out: &mut Vec<Figure>,
) {
    for (k, v) in m {
        if k.ends_with("_ci95") || (prefix.is_empty() && k == "sweep_value") {
            continue;
        }
        let sibling = m.get(&format!("{k}_ci95"));
        match v {
            Value::Number(n) => {
                if let Some(value) = n.as_f64() {
                    out.push(Figure {
                        entry: entry.to_string(),
                        metric: format!("{prefix}{k}"),
                        value,
                        ci: interval(sibling).or_else(|| interval(cis.and_then(|c| c.get(k)))),
                    });
                }
            }
            Value::Object(inner) => flatten(entry, &format!("{prefix}{k}."), inner, sibling, out),
            _ => {}
        }
    }
}

/// Whether a figure can be negative: η (an improvement can be a worsening), a parameter's
/// bias, the improvement in per cent, a signed error along the tool axis and a registration
/// study's difference SVD − weighted SVD; every other figure (an error, an RMSE, a spread, a
/// count, a ratio) is ≥ 0.
fn signed(metric: &str) -> bool {
    metric.starts_with(Metric::Eta.spec().field)
        || metric.starts_with("param_bias.")
        || metric == Metric::Improvement.key()
        || metric.contains("_axis_mm.")
        || metric == "difference_mm"
}

/// Whether a figure is η (%) of the mean or median kind, which no run writes above 100:
/// η = 100 · (1 − |x − x̂| / |x|) is at most 100 in every trial, and so are its means and
/// medians (`eta_mean_pct`, `eta_median_pct`, a parameter's `eta.P.mean` and `eta.P.median`,
/// an instruments study's `eta.P`); its spread (`eta.P.std`) is not bounded. The second: its
/// interval is bounded too, as an interval of order statistics is (the medians'); a t
/// interval of a mean can reach above 100.
fn eta_bounded(metric: &str) -> (bool, bool) {
    let median = Metric::EtaMedian.key();
    let Some(per) = metric
        .strip_prefix(Metric::Eta.spec().field)
        .and_then(|m| m.strip_prefix('.'))
    else {
        return (
            metric == Metric::EtaMean.key() || metric == median,
            metric == median,
        );
    };
    (!per.ends_with(".std"), per.ends_with(".median"))
}

/// Who reads a summary's figures: what [`check_figures`] refuses depends on it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reader {
    /// `check`, `compare` and `baseline`: a figure scaled by hand beyond its interval is
    /// compared (a "what if" of a worse run), since its interval still gives its spread.
    Compare,
    /// `record`: what is stored must be what a run wrote, so such a figure is refused too,
    /// and so are error statistics out of their order (a mean above its RMS).
    Record,
}

/// Refuses, naming the summary `path` and the key, a document that cannot be what a run
/// wrote: `trials` not a positive whole number; a count (`failures`, `terminations.*`) not
/// a whole number ≥ 0, or above `trials`; a figure that must be ≥ 0 below zero (`signed`);
/// η (`eta_bounded`) and the improvement in per cent above 100 %; an interval whose ends are reversed; and, for
/// [`Reader::Record`], a figure outside its own 95 % interval (edited) and a block of error
/// statistics out of order (`ordered_statistics`). `at` gives the key
/// path of an entry by its name (`results[2]`, `cells[0]`), for the line of the refusal; an
/// empty path is the top of the file (an identification's figures), whose figures are named
/// by their key alone.
pub fn check_figures(
    path: &Path,
    trials: Option<usize>,
    figures: &[Figure],
    reader: Reader,
    at: &dyn Fn(&str) -> Option<String>,
) -> Result<()> {
    if trials == Some(0) {
        let line = crate::error::read_text(path)
            .ok()
            .and_then(|text| json_key_line(&text, "trials"));
        return Err(Error::file(
            path,
            at_line(line, "trials"),
            "is 0: the trials of a run are a whole number above 0",
        ));
    }
    // An entry at the top of its file (an identification's) is named by its key.
    let refuse_at = |f: &Figure, msg: String| {
        let entry = at(&f.entry);
        let (key, full) = match entry.as_deref() {
            Some("") => (f.metric.clone(), f.metric.clone()),
            e => (
                format!("results ({}), {}", f.entry, f.metric),
                format!("{}.{}", e.unwrap_or_default(), f.metric),
            ),
        };
        let line = entry.and_then(|_| {
            let text = crate::error::read_text(path).ok()?;
            json_key_line(&text, &full)
        });
        Err(Error::file(path, at_line(line, key), msg))
    };
    for f in figures {
        let refuse = |msg: String| refuse_at(f, msg);
        let count = f.metric == Metric::Failures.key() || f.metric.starts_with("terminations.");
        if count && (f.value < 0.0 || f.value.fract() != 0.0) {
            return refuse(format!(
                "is {}: a count is a whole number ≥ 0",
                shown(f.value)
            ));
        }
        if let Some(n) = trials.filter(|&n| count && f.value > n as Real) {
            return refuse(format!(
                "is {}, more than the {n} trials of the run: a count is of its trials",
                shown(f.value)
            ));
        }
        if !signed(&f.metric) && f.value < 0.0 {
            return refuse(format!(
                "is {}: this figure is never negative",
                shown(f.value)
            ));
        }
        if f.metric == Metric::Improvement.key() && f.value > 100.0 {
            return refuse(format!(
                "is {} %: the improvement 100 · (before − after) / before of errors ≥ 0 is at \
                 most 100 %: no run writes it",
                shown(f.value)
            ));
        }
        let (eta_value, eta_interval) = eta_bounded(&f.metric);
        if eta_value && f.value > 100.0 {
            return refuse(format!(
                "is {} %: η = 100 · (1 − remaining error / injected error) is at most 100 %, \
                 and so are its means and medians: no run writes it",
                shown(f.value)
            ));
        }
        let Some([lo, hi]) = f.ci else { continue };
        let (l, h) = (shown(lo), shown(hi));
        if lo > hi {
            return refuse(format!(
                "has the 95 % interval [{l}, {h}], whose lower end is above its upper: no run \
                 writes it"
            ));
        }
        if eta_interval && hi > 100.0 {
            return refuse(format!(
                "has the 95 % interval [{}, {}], above 100 %: the interval of a median η is \
                 of η values, each at most 100 %: no run writes it",
                l, h
            ));
        }
        let slack = 1e-9 * f.value.abs().max(lo.abs()).max(hi.abs());
        if reader == Reader::Record && (f.value < lo - slack || f.value > hi + slack) {
            return refuse(format!(
                "is {} outside its own 95 % interval [{l}, {h}]: the figures were edited",
                shown(f.value)
            ));
        }
    }
    match reader {
        Reader::Record => ordered_statistics(figures, &refuse_at),
        Reader::Compare => Ok(()),
    }
}

/// Refuses (`refuse`) a block of error statistics whose `mean` is above its `rms`, or, for
/// errors that are never negative, whose `rms` is above its `max`: so it is in every trial's
/// errors, and so in their averages over trials (a summary's figures) too. No run or
/// identification writes such a block; it is refused from what `record` stores, where
/// `check` and `compare` take a figure scaled by hand as a "what if" ([`Reader`]).
fn ordered_statistics(
    figures: &[Figure],
    refuse: &dyn Fn(&Figure, String) -> Result<()>,
) -> Result<()> {
    let by_key: std::collections::HashMap<(&str, &str), &Figure> = figures
        .iter()
        .map(|f| ((f.entry.as_str(), f.metric.as_str()), f))
        .collect();
    for f in figures {
        let Some(block) = f.metric.strip_suffix(".rms") else {
            continue;
        };
        let stat = |name: &str| {
            by_key
                .get(&(f.entry.as_str(), format!("{block}.{name}").as_str()))
                .copied()
        };
        let above = |a: Real, b: Real| a > b + 1e-9 * a.abs().max(b.abs());
        let (first, second, a, b) = match (stat("mean"), stat("max")) {
            (Some(mean), _) if above(mean.value, f.value) => (mean, "RMS", mean.value, f.value),
            (_, Some(max)) if !signed(&f.metric) && above(f.value, max.value) => {
                (f, "maximum", f.value, max.value)
            }
            _ => continue,
        };
        let name = first.metric.rsplit('.').next().unwrap_or_default();
        return refuse(
            first,
            format!(
                "is {}, above the {second} {} of the same errors: their {} is at most their \
                 {second} (in each trial, and so in averages over trials), so no run or \
                 identification writes it",
                shown(a),
                shown(b),
                if name == "rms" { "RMS" } else { name },
            ),
        );
    }
    Ok(())
}

/// Every figure of the entries of `s`, as its `summary.json` writes them.
pub fn of_summary(s: &Summary) -> Result<Vec<Figure>> {
    let mut figures = Vec::new();
    for e in &s.results {
        let written = serde_json::to_value(e).map_err(|e| Error::Compute(e.to_string()))?;
        if let Value::Object(m) = &written {
            flatten(&e.key(), "", m, None, &mut figures);
        }
    }
    Ok(figures)
}

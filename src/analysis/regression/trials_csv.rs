//! A run's `trials.csv` as `check`, `compare` and `baseline` read it for their paired
//! comparisons (docs/formats.md § 2.4 and § 7.1 "trials.csv"): strictly, since a value read
//! wrong would pair the wrong numbers. An empty file, a header without a column the
//! comparison reads, a row of more or fewer cells than the header, a cell that is not a
//! number where one is written, or a trial given twice for an entry is refused, naming the
//! file, the line and the column.

use std::collections::BTreeMap;
use std::path::Path;

use super::noise::Trials;
use crate::error::{at_line, Error, Result};
use crate::numeric::Real;
use crate::study::metric::Metric;

/// The terminations of `trials.csv` whose identification gave no usable result.
const FAILED: [&str; 3] = ["diverged", "singular", "invalid-input"];

/// The columns every run's `trials.csv` has, after `trial` and the sweep's.
fn required() -> [&'static str; 7] {
    let column = |m: Metric| m.column().unwrap_or_default();
    [
        "method",
        "poses",
        column(Metric::EtaMean),
        column(Metric::ValidationAfterMean),
        column(Metric::ValidationAfterRms),
        column(Metric::ValidationAfterMax),
        "termination",
    ]
}

/// The columns that hold text rather than numbers, besides the sweep's.
const TEXT: [&str; 4] = ["method", "poses", "termination", "error"];

/// The parameters of the header's `true_P` and `identified_P` columns: the name and the
/// index of each column. A `true_P` without its `identified_P`, or the reverse, is refused
/// naming the one missing.
fn paired_columns(path: &Path, head: &[String]) -> Result<Vec<(String, usize, usize)>> {
    let col = |name: &str| head.iter().position(|h| h == name);
    let mut params = Vec::new();
    for (i, h) in head.iter().enumerate() {
        let (name, twin) = match (h.strip_prefix("true_"), h.strip_prefix("identified_")) {
            (Some(n), _) => (n, format!("identified_{n}")),
            (_, Some(n)) => (n, format!("true_{n}")),
            _ => continue,
        };
        let Some(j) = col(&twin) else {
            let msg = format!("missing, where the header has `{h}`");
            return Err(Error::file(path, at_line(Some(1), twin), msg));
        };
        if h.starts_with("true_") {
            params.push((name.to_string(), i, j));
        }
    }
    Ok(params)
}

/// The number in `cell` (a missing value is an empty cell: NaN), or the refusal naming the
/// file, `line` and `column`.
fn number(path: &Path, line: u64, column: &str, cell: &str) -> Result<Real> {
    if cell.is_empty() {
        return Ok(Real::NAN);
    }
    match cell.trim().parse::<Real>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(Error::file(
            path,
            at_line(Some(line as usize), column),
            format!("\"{cell}\" is not a number (a missing value is an empty cell)"),
        )),
    }
}

impl Trials {
    /// Reads a run's `trials.csv`, refusing a malformed one (see the module). In a sweep,
    /// the columns between `trial` and `method` hold the sweep point: the rows of the k-th
    /// point in order of appearance (0-based) are entry `method / poses @ k`
    /// ([`super::noise::trials_key`]).
    pub fn read(path: &Path) -> Result<Trials> {
        let mut r = csv::ReaderBuilder::new()
            .flexible(true)
            .from_path(path)
            .map_err(|e| Error::file(path, "CSV", e.to_string()))?;
        let head: Vec<String> = r
            .headers()
            .map_err(|e| Error::file(path, at_line(Some(1), "header"), e.to_string()))?
            .iter()
            .map(String::from)
            .collect();
        let header = at_line(Some(1), "header");
        if head.iter().all(String::is_empty) {
            let msg = "is empty, where a run's trials.csv starts with its header line";
            return Err(Error::file(path, "header", msg));
        }
        if head[0] != "trial" {
            let msg = format!("the first column is `{}`, not `trial`", head[0]);
            return Err(Error::file(path, header, msg));
        }
        for (i, name) in head.iter().enumerate() {
            if let Some(j) = head[..i].iter().position(|h| h == name) {
                let msg = format!(
                    "column \"{name}\" appears twice in the header (columns {} and {}): which \
                     one holds the run's values is not known",
                    j + 1,
                    i + 1
                );
                return Err(Error::file(
                    path,
                    at_line(Some(1), format!("column {name}")),
                    msg,
                ));
            }
        }
        let col = |name: &str| head.iter().position(|h| h == name);
        if let Some(name) = required().into_iter().find(|n| col(n).is_none()) {
            let msg = "missing from the header, which every run's trials.csv has";
            return Err(Error::file(path, at_line(Some(1), name), msg));
        }
        let method_col = col("method").unwrap_or_default();
        let params = paired_columns(path, &head)?;
        let plain = [
            Metric::EtaMean,
            Metric::ValidationAfterMean,
            Metric::ValidationAfterRms,
            Metric::ValidationAfterMax,
            Metric::DegAfterMean,
            Metric::DegAfterRms,
        ]
        .map(|m| (m.key(), m.column().and_then(col)));
        let (mi, pi, termi) = (col("method"), col("poses"), col("termination"));
        let rms = col(Metric::ValidationAfterRms.column().unwrap_or_default());
        let mut points: Vec<Vec<String>> = Vec::new();
        let mut line_of_trial: BTreeMap<(String, usize), u64> = BTreeMap::new();
        let mut t = Trials::default();
        for rec in r.records() {
            let rec = rec.map_err(|e| {
                let line = e.position().map_or(0, |p| p.line());
                let doing = ("rows", "unreadable row");
                crate::measurement::rows::unreadable((path, line, &head), &e, doing)
            })?;
            let line = rec.position().map_or(0, |p| p.line());
            if rec.len() != head.len() {
                let (place, msg) = match head.get(rec.len()) {
                    Some(missing) => (
                        at_line(Some(line as usize), missing),
                        format!(
                            "missing: the row has {} of the header's {} cells",
                            rec.len(),
                            head.len()
                        ),
                    ),
                    None => (
                        format!("line {line}"),
                        format!(
                            "has {} cells, more than the header's {}",
                            rec.len(),
                            head.len()
                        ),
                    ),
                };
                return Err(Error::file(path, place, msg));
            }
            // Every cell that holds a number is one (the sweep's and the text columns aside).
            let mut nums = vec![Real::NAN; head.len()];
            for (i, (h, cell)) in head.iter().zip(rec.iter()).enumerate() {
                if i > 0 && i < method_col || TEXT.contains(&h.as_str()) {
                    continue;
                }
                nums[i] = number(path, line, h, cell)?;
            }
            let get = |i: Option<usize>| i.and_then(|i| rec.get(i)).unwrap_or("");
            let num = |i: Option<usize>| i.map_or(Real::NAN, |i| nums[i]);
            if termi.is_some() && get(termi).parse::<crate::identify::Termination>().is_err() {
                let names = <crate::identify::Termination as strum::VariantNames>::VARIANTS;
                let msg = format!(
                    "is {:?}, which is not a termination of an identification ({})",
                    get(termi),
                    names.join(", ")
                );
                let place = at_line(Some(line as usize), "termination");
                return Err(Error::file(path, place, msg));
            }
            let index: usize = get(Some(0)).parse().map_err(|_| {
                let place = at_line(Some(line as usize), "trial");
                Error::file(path, place, "is not a trial number")
            })?;
            let entry = if method_col > 1 {
                let point: Vec<String> =
                    (1..method_col).map(|i| get(Some(i)).to_string()).collect();
                let k = match points.iter().position(|p| *p == point) {
                    Some(k) => k,
                    None => {
                        points.push(point);
                        points.len() - 1
                    }
                };
                format!("{} / {} @ {k}", get(mi), get(pi))
            } else {
                format!("{} / {}", get(mi), get(pi))
            };
            if let Some(first) = line_of_trial.insert((entry.clone(), index), line) {
                let msg =
                    format!("trial {index} of {entry} is given twice (first on line {first})");
                return Err(Error::file(
                    path,
                    at_line(Some(line as usize), "trial"),
                    msg,
                ));
            }
            t.first_line.entry(entry.clone()).or_insert(line as usize);
            t.trials.entry(entry.clone()).or_default().insert(index);
            let truth: Vec<Real> = params.iter().map(|p| nums[p.1]).collect();
            let found: Vec<Real> = params.iter().map(|p| nums[p.2]).collect();
            // A parameter the row's sweep point does not identify has both cells empty
            // (the header is the union over the points): it does not make the row unusable.
            let usable = !FAILED.contains(&get(termi))
                && num(rms).is_finite()
                && found
                    .iter()
                    .zip(&truth)
                    .all(|(x, t)| x.is_finite() || t.is_nan());
            if !usable {
                continue;
            }
            let mut put = |metric: String, v: Real| {
                if v.is_finite() {
                    t.values
                        .entry((entry.clone(), metric))
                        .or_default()
                        .insert(index, v);
                }
            };
            for (m, c) in &plain {
                if c.is_some() {
                    put(m.clone(), num(*c));
                }
            }
            for (k, (name, _, _)) in params.iter().enumerate() {
                if name.starts_with("base.") {
                    continue;
                }
                put(
                    Metric::ParamRmse.of_parameter(name),
                    (found[k] - truth[k]).powi(2),
                );
            }
        }
        Ok(t)
    }
}

//! `history.html` and `history.csv` of `calbench history` (docs/formats.md): each metric of
//! each scenario against the version labels recorded, per machine and entry, with its 95 %
//! interval, and each step marked that `check`'s rule calls a regression or an improvement.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::{escape, Page};
use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::report::markdown::fmt_num;

/// One recorded figure.
#[derive(Clone, Debug)]
pub struct Point {
    /// The scenario (task, identification).
    pub scenario: String,
    /// The machine it was recorded on.
    pub machine: String,
    /// `run`, `merge`, `identify` or `task`.
    pub kind: String,
    /// The entry.
    pub entry: String,
    /// The metric.
    pub metric: String,
    /// The version label.
    pub label: String,
    /// calbench's version.
    pub version: String,
    /// calbench's git commit.
    pub git_commit: String,
    /// When it was recorded (UTC).
    pub recorded_at: String,
    /// The value.
    pub value: Real,
    /// Its 95 % interval.
    pub ci: Option<[Real; 2]>,
    /// What the step from the version before it in its series did (`check`'s status, or
    /// `scenario changed`), for runs.
    pub step: Option<&'static str>,
    /// The record's number in the database.
    pub record: i64,
    /// The run's master seed, where there is one.
    pub seed: Option<i64>,
    /// The folder recorded.
    pub source: String,
}

/// A CSV text of `header` (its column names joined by commas) and `rows` (quoted where
/// needed).
pub(crate) fn csv_text(header: &str, rows: impl Iterator<Item = Vec<String>>) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header.split(','))
        .map_err(|e| Error::Compute(e.to_string()))?;
    for row in rows {
        w.write_record(&row)
            .map_err(|e| Error::Compute(e.to_string()))?;
    }
    let bytes = w.into_inner().map_err(|e| Error::Compute(e.to_string()))?;
    String::from_utf8(bytes).map_err(|e| Error::Compute(e.to_string()))
}

/// A number as a CSV cell: as `{}` writes it (`0.1668`, `1.8e-5` as `0.000018`), but from
/// 1e16 on in exponent form (`1e300`), as a refusal shows it ([`crate::error::shown`]), where
/// `{}` would write a run of hundreds of digits.
pub(crate) fn number_cell(v: Real) -> String {
    if v.abs() >= 1e16 {
        crate::error::shown(v)
    } else {
        v.to_string()
    }
}

/// An interval as two CSV cells (empty without one).
pub(crate) fn ci_cells(ci: Option<[Real; 2]>) -> [String; 2] {
    ci.map_or([String::new(), String::new()], |[l, h]| {
        [number_cell(l), number_cell(h)]
    })
}

/// `history.csv`: one row per point.
pub fn csv(points: &[Point]) -> Result<String> {
    let header = "scenario,machine,kind,entry,metric,label,calbench_version,git_commit,\
                  recorded_at,value,ci_lo,ci_hi,step";
    csv_text(
        header,
        points.iter().map(|p| {
            let [lo, hi] = ci_cells(p.ci);
            let mut row = vec![p.scenario.clone(), p.machine.clone(), p.kind.clone()];
            row.extend([p.entry.clone(), p.metric.clone(), p.label.clone()]);
            row.extend([
                p.version.clone(),
                p.git_commit.clone(),
                p.recorded_at.clone(),
            ]);
            row.extend([
                number_cell(p.value),
                lo,
                hi,
                p.step.unwrap_or("").to_string(),
            ]);
            row
        }),
    )
}

const COLOURS: [&str; 8] = [
    "#1565c0", "#ef6c00", "#2e7d32", "#6a1b9a", "#00838f", "#ad1457", "#5d4037", "#455a64",
];

/// The SVG drawing of one metric: x the records in order (labelled by version label), one
/// series per machine and entry, a bar for each interval, a red ring on a regression and a
/// green one on an improvement.
fn chart(points: &[&Point]) -> String {
    let (w, h, left, right, top, bottom) = (960.0, 420.0, 80.0, 250.0, 20.0, 70.0);
    // One place per record, in the order of versions: several records under one label are
    // shown apart, each labelled with its number.
    let mut xs: Vec<(i64, String)> = Vec::new();
    for p in points {
        if !xs.iter().any(|(r, _)| *r == p.record) {
            xs.push((p.record, format!("{} #{}", p.label, p.record)));
        }
    }
    let x_of = |p: &Point| {
        let i = xs.iter().position(|(r, _)| *r == p.record).unwrap_or(0);
        left + (i as Real + 0.5) * (w - left - right) / xs.len().max(1) as Real
    };
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for p in points {
        let [a, b] = p.ci.unwrap_or([p.value, p.value]);
        lo = lo.min(a.min(p.value));
        hi = hi.max(b.max(p.value));
    }
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        let pad = lo.abs().max(1.0) * 0.05;
        (lo, hi) = (lo - pad, hi + pad);
    }
    let pad = (hi - lo) * 0.08;
    let (lo, hi) = (lo - pad, hi + pad);
    let y_of = |v: Real| top + (hi - v) / (hi - lo) * (h - top - bottom);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {w} {h}\">\
         <rect width=\"{w}\" height=\"{h}\" fill=\"#fff\"/>\
         <g font-family=\"sans-serif\" font-size=\"12\" fill=\"#333\">"
    );
    for k in 0..=4 {
        let v = lo + (hi - lo) * k as Real / 4.0;
        let y = y_of(v);
        let _ = write!(
            s,
            "<line x1=\"{left}\" x2=\"{}\" y1=\"{y:.1}\" y2=\"{y:.1}\" stroke=\"#e3e3e3\"/>\
             <text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            w - right,
            left - 6.0,
            y + 4.0,
            escape(&fmt_num(v, 4))
        );
    }
    for (i, (_, label)) in xs.iter().enumerate() {
        let x = left + (i as Real + 0.5) * (w - left - right) / xs.len().max(1) as Real;
        let _ = write!(
            s,
            "<text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"end\" transform=\"rotate(-30 {x:.1} {:.1})\">{}</text>",
            h - bottom + 16.0,
            h - bottom + 16.0,
            escape(label)
        );
    }
    let mut series: BTreeMap<(&str, &str), Vec<&Point>> = BTreeMap::new();
    for p in points {
        series.entry((&p.machine, &p.entry)).or_default().push(p);
    }
    for (k, ((machine, entry), list)) in series.iter().enumerate() {
        let c = COLOURS[k % COLOURS.len()];
        let path: Vec<String> = list
            .iter()
            .map(|p| format!("{:.1},{:.1}", x_of(p), y_of(p.value)))
            .collect();
        let _ = write!(
            s,
            "<polyline fill=\"none\" stroke=\"{c}\" stroke-width=\"1.5\" points=\"{}\"/>",
            path.join(" ")
        );
        for p in list {
            let (x, y) = (x_of(p), y_of(p.value));
            if let Some([a, b]) = p.ci {
                let _ = write!(
                    s,
                    "<line x1=\"{x:.1}\" x2=\"{x:.1}\" y1=\"{:.1}\" y2=\"{:.1}\" stroke=\"{c}\"/>",
                    y_of(a),
                    y_of(b)
                );
            }
            let _ = write!(
                s,
                "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"3.5\" fill=\"{c}\"/>"
            );
            let ring = match p.step {
                Some("regression") => Some("#c62828"),
                Some("improved") => Some("#2e7d32"),
                _ => None,
            };
            if let Some(r) = ring {
                let _ = write!(
                    s,
                    "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"8\" fill=\"none\" stroke=\"{r}\" stroke-width=\"2.5\"/>"
                );
            }
        }
        let ly = top + 16.0 * (k as Real + 1.0);
        let _ = write!(
            s,
            "<rect x=\"{}\" y=\"{:.1}\" width=\"12\" height=\"4\" fill=\"{c}\"/>\
             <text x=\"{}\" y=\"{ly:.1}\">{}</text>",
            w - right + 12.0,
            ly - 5.0,
            w - right + 30.0,
            escape(&format!("{entry} ({machine})"))
        );
    }
    s.push_str("</g></svg>");
    s
}

/// One scenario on one machine at the top of `history.html`: its state (`regressed`,
/// `drifting`, `scenario changed`, `unchanged`, or `one version`) and the lines of what was
/// flagged.
pub struct Series {
    /// The scenario.
    pub scenario: String,
    /// The machine.
    pub machine: String,
    /// Its state.
    pub state: String,
    /// The flagged changes of its latest version, one line each.
    pub flags: Vec<String>,
}

/// A value and its interval with the decimals the interval supports: two significant digits
/// of its half-width (at least one of the value when the interval is nil), else four
/// significant digits.
pub fn with_interval(value: Real, ci: Option<[Real; 2]>) -> (String, String) {
    let Some([lo, hi]) = ci.filter(|[l, h]| l.is_finite() && h.is_finite()) else {
        return (fmt_num(value, 4), String::new());
    };
    let half = (hi - lo).abs() / 2.0;
    let scale = if half > 0.0 { half } else { value.abs() };
    if scale == 0.0 || !scale.is_finite() {
        return (
            fmt_num(value, 4),
            format!("{} – {}", fmt_num(lo, 4), fmt_num(hi, 4)),
        );
    }
    let decimals = (1 - scale.log10().floor() as i32).clamp(0, 12) as usize;
    let f = |x: Real| format!("{x:.decimals$}");
    (f(value), format!("{} – {}", f(lo), f(hi)))
}

/// `history.html`: one line per scenario and machine (its state), the flagged changes folded
/// under it; then per scenario a figure per metric and the table of its points.
pub fn page(points: &[Point], series: &[Series]) -> String {
    let mut page = Page::new(
        "calbench history",
        "Each recorded metric against the versions, in version order, per machine and entry, \
         with its 95 % interval; a red ring marks a step that calbench check's rule calls a \
         regression (worse by the tolerance and beyond the noise), a green ring an \
         improvement.",
    );
    page.section("Latest versions");
    if series.is_empty() {
        page.para("No run recorded.");
    } else {
        let rows: Vec<Vec<String>> = series
            .iter()
            .map(|s| {
                vec![
                    s.scenario.clone(),
                    s.machine.clone(),
                    s.state.clone(),
                    s.flags.len().to_string(),
                ]
            })
            .collect();
        let flagged: Vec<bool> = series
            .iter()
            .map(|s| s.state == "regressed" || s.state == "drifting")
            .collect();
        page.table_with(
            "Each scenario on each machine: its latest version against the versions before it",
            &["scenario", "machine", "latest version", "flagged"],
            &rows,
            |i| flagged[i].then_some("regressed"),
        );
        for s in series.iter().filter(|s| !s.flags.is_empty()) {
            page.folded(
                &format!(
                    "{} on {}: {} ({} flagged)",
                    s.scenario,
                    s.machine,
                    s.state,
                    s.flags.len()
                ),
                &s.flags,
            );
        }
    }
    let mut by_scenario: BTreeMap<&str, BTreeMap<&str, Vec<&Point>>> = BTreeMap::new();
    for p in points {
        by_scenario
            .entry(&p.scenario)
            .or_default()
            .entry(&p.metric)
            .or_default()
            .push(p);
    }
    if by_scenario.is_empty() {
        page.para("Nothing recorded matches.");
    }
    for (scenario, metrics) in &by_scenario {
        page.section(scenario);
        page.plots_begin();
        for (metric, list) in metrics {
            page.figure(
                &chart(list),
                &format!("{scenario}: {metric}"),
                &format!("{metric} of {scenario} against the records in version order, one line per machine and entry"),
            );
        }
        page.plots_end();
        for (metric, list) in metrics {
            let rows: Vec<Vec<String>> = list
                .iter()
                .map(|p| {
                    let (value, ci) = with_interval(p.value, p.ci);
                    vec![
                        p.label.clone(),
                        format!("#{}", p.record),
                        p.seed.map_or(String::new(), |s| s.to_string()),
                        p.source.clone(),
                        p.recorded_at.clone(),
                        p.machine.clone(),
                        p.entry.clone(),
                        value,
                        ci,
                        p.step.unwrap_or("").to_string(),
                    ]
                })
                .collect();
            let flagged: Vec<bool> = list.iter().map(|p| p.step == Some("regression")).collect();
            page.table_with(
                metric,
                &[
                    "label",
                    "record",
                    "seed",
                    "source",
                    "recorded",
                    "machine",
                    "entry",
                    "value",
                    "95 % interval",
                    "step",
                ],
                &rows,
                |i| flagged[i].then_some("regressed"),
            );
        }
    }
    page.finish()
}

#[cfg(test)]
mod tests {
    use super::with_interval;

    #[test]
    fn values_have_the_decimals_of_their_interval() {
        assert_eq!(
            with_interval(0.123456789, Some([0.1200001, 0.1269999])),
            ("0.1235".to_string(), "0.1200 – 0.1270".to_string())
        );
        assert_eq!(
            with_interval(12.3456, Some([10.0, 15.0])),
            ("12.3".to_string(), "10.0 – 15.0".to_string())
        );
        // Angles of a few µrad: the interval's digits, not 0.0000.
        let (v, ci) = with_interval(3.2e-6, Some([3.0e-6, 3.4e-6]));
        assert_eq!(
            (v.as_str(), ci.as_str()),
            ("0.00000320", "0.00000300 – 0.00000340")
        );
        assert_eq!(with_interval(0.5, None).0, "0.5");
    }
}

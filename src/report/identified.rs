//! The files of `calbench identify` (docs/formats.md `identify`): `identified.json`,
//! `residuals.csv`, `report.md` and its figures, and the compensated `robot.toml`, each an
//! [`Output`] ([`outputs`]).

use super::markdown::{fmt_num, inline, table};
use super::plots;

use super::output::{Buffered, Figure, Output, Outputs, Text};
use crate::calibrate::pipeline::TrackerOutcome;
use crate::calibrate::record::unconverged_warning;
use crate::calibrate::record::IdentifiedRecord;
pub use crate::calibrate::validation::FileValidation;
pub use crate::calibrate::verdict::registration_warning;
use crate::calibrate::ErrorStats;
use crate::error::Result;
use crate::identify::{standard_error, Termination};
use crate::numeric::Real;
use crate::robot::{robot_to_toml, Param};

/// What an identification on a file is written from: the pipeline's outcome (its fields read
/// through [`std::ops::Deref`]) and the compensated robot as a URDF, if asked for.
pub struct IdentifyRecord<'a> {
    /// The outcome of [`crate::calibrate::request`].
    pub outcome: &'a TrackerOutcome,
    /// The compensated robot as a URDF (written as `robot.urdf`), if asked for.
    pub urdf: Option<String>,
}

impl<'a> IdentifyRecord<'a> {
    /// The record of the pipeline's outcome `o`, with the compensated robot as a URDF
    /// (`urdf`, written as `robot.urdf`) if asked for.
    pub fn of(o: &'a TrackerOutcome, urdf: Option<String>) -> Self {
        IdentifyRecord { outcome: o, urdf }
    }
}

impl std::ops::Deref for IdentifyRecord<'_> {
    type Target = TrackerOutcome;
    fn deref(&self) -> &TrackerOutcome {
        self.outcome
    }
}

/// `identified.json` of any identification, tracker's or kind file's: the record
/// pretty-printed, with a final newline; the one writer of the file.
pub fn identified_json(record: &IdentifiedRecord) -> Buffered<'_> {
    Buffered {
        name: "identified.json",
        body: Box::new(move |w| {
            serde_json::to_writer_pretty(&mut *w, record)?;
            w.write_all(b"\n")
        }),
    }
}

/// `residuals.csv`, written a row at a time: per point, the residual before (the nominal
/// robot in its own registration) and after (the compensated robot in the final
/// registration), and the final weight.
pub fn residuals_csv<'a>(r: &'a IdentifyRecord) -> Result<Buffered<'a>> {
    let (before, after) = (&r.outcome.residuals.0[..], &r.outcome.residuals.1[..]);
    let weights = &r.calibrated.identified.weights;
    Ok(Buffered {
        name: "residuals.csv",
        body: Box::new(move |w| {
            w.write_all(b"row,residual_before_mm,residual_after_mm,weight\n")?;
            for (i, (b, a)) in before.iter().zip(after).enumerate() {
                let wt = weights.get(i).copied().unwrap_or(1.0);
                writeln!(w, "{i},{b},{a},{wt}")?;
            }
            Ok(())
        }),
    })
}

/// What `identify`'s options add to its reports: a section of `report.md` and `report.html`
/// ([`super::practice`]).
#[derive(Default)]
pub struct Additions {
    /// The section's content, in order: one piece serves both pages.
    pub blocks: Vec<Block>,
}

/// A piece of a report section, written as Markdown ([`Additions::markdown`]) or HTML
/// (`report.html`'s identify page).
#[derive(Clone, Debug, PartialEq)]
pub enum Block {
    /// A heading.
    Heading(String),
    /// A paragraph of plain text.
    Para(String),
    /// A table: header row and rows.
    Table(Vec<&'static str>, Vec<Vec<String>>),
}

impl Additions {
    /// The blocks as Markdown, each after a blank line.
    pub fn markdown(&self) -> String {
        let mut md = String::new();
        for b in &self.blocks {
            md.push('\n');
            match b {
                Block::Heading(h) => md += &format!("## {h}\n"),
                Block::Para(t) => md += &format!("{t}\n"),
                Block::Table(headers, rows) => md += &table(headers, rows),
            }
        }
        md
    }
}

/// The files of `calbench identify` but `report.html` and the controller exports
/// ([`super::write_identified_with`] adds them), in the order they are written:
/// `residuals.csv`, `identified.json` ([`identified_json`]), the figures, `report.md` (with
/// the `more` section: cross-validation, priors, diagnostics, [`super::practice`]),
/// `robot.urdf` if asked for and `robot.toml` (the compensated robot, named
/// `<nominal>-calibrated`).
pub fn outputs<'a>(r: &'a IdentifyRecord, more: &'a Additions) -> Result<Outputs<'a>> {
    let mut out: Outputs<'a> = vec![
        Box::new(residuals_csv(r)?),
        Box::new(identified_json(&r.record)),
    ];
    out.extend(
        figures(r)?
            .into_iter()
            .map(|f| Box::new(f) as Box<dyn Output>),
    );
    out.push(Box::new(Text {
        name: "report.md",
        text: report_md(r)? + &more.markdown(),
    }));
    if let Some(u) = &r.urdf {
        out.push(Box::new(Text {
            name: "robot.urdf",
            text: u.clone(),
        }));
    }
    out.push(Box::new(Text {
        name: "robot.toml",
        text: robot_to_toml(&r.compensated()),
    }));
    Ok(out)
}

/// The warnings of an identification, in plain words: data that do not determine every
/// parameter (a result kept with `--allow-rank-deficient`), points a robust method rejected
/// (weight 0) or weighed down, then those `identify` prints ([`TrackerOutcome::warnings`]: a
/// registration that did not settle, a result kept although it makes the robot worse or
/// cannot be physically right, a search that ended on the edge of its box) and a solve that
/// stopped short of convergence ([`unconverged_warning`]), each a sentence.
pub fn warnings(r: &IdentifyRecord) -> Vec<String> {
    let id = &r.calibrated.identified;
    let n = r.params.len();
    let mut w = Vec::new();
    let undetermined = matches!(
        id.termination,
        Termination::RankDeficient | Termination::Singular
    ) || id.rank.is_some_and(|k| k < n);
    if undetermined {
        w.push(format!(
            "the data determine only {} of the {n} parameters (rank deficiency; the \
             identification ended {}). The undetermined directions were filled in by the \
             method's damping or regularisation, not by the data: measure poses that move \
             every joint before trusting these values.",
            id.rank.map_or("some".to_string(), |k| k.to_string()),
            id.termination.as_str()
        ));
    }
    let m = r.data.len();
    let prior = r.data.weights();
    if let Some(rows) = id
        .row_weights
        .as_deref()
        .filter(|w| m > 0 && w.len() % m == 0)
    {
        w.extend(coordinate_warnings(rows, prior.as_deref(), rows.len() / m));
    } else {
        w.extend(point_warnings(&id.weights, prior.as_deref(), m));
    }
    let printed = r.outcome.warnings().into_iter().map(|t| t.to_string());
    w.extend(
        printed
            .chain(unconverged_warning(&r.record))
            .map(|t| t + "."),
    );
    w
}

/// The warnings of a fit that weighed each residual row on its own (IGG3 with
/// `per = "coordinate"`): the rows rejected (weight 0), each as its data row and coordinate,
/// and the number weighed down below their point's `prior` weight ([`lowered`]).
fn coordinate_warnings(rows: &[Real], prior: Option<&[Real]>, per: usize) -> Vec<String> {
    const AXES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];
    let rejected: Vec<String> = rows
        .iter()
        .enumerate()
        .filter(|(_, x)| **x == 0.0)
        .map(|(k, _)| format!("{} {}", k / per, AXES.get(k % per).copied().unwrap_or("?")))
        .collect();
    let lowered = lowered(rows, |k| k / per, prior);
    let mut w = Vec::new();
    if !rejected.is_empty() {
        w.push(format!(
            "{} of the {} coordinates were rejected as outliers (row weight 0; row and \
             coordinate: {}): they do not count in the result, their points' other coordinates \
             do. Check those measurements.",
            rejected.len(),
            rows.len(),
            rejected.join(", ")
        ));
    }
    if lowered > 0 {
        w.push(format!(
            "{lowered} coordinates were weighed down (row weight between 0 and their point's \
             weight before the fit) as suspect."
        ));
    }
    w
}

/// The warnings of a fit that weighed points: those rejected (weight 0) and the number
/// weighed down below its `prior` weight ([`lowered`]), of `m` points.
fn point_warnings(weights: &[Real], prior: Option<&[Real]>, m: usize) -> Vec<String> {
    let mut w = Vec::new();
    let rejected: Vec<String> = weights
        .iter()
        .enumerate()
        .filter(|(_, x)| **x == 0.0)
        .map(|(i, _)| i.to_string())
        .collect();
    let lowered = lowered(weights, |i| i, prior);
    if !rejected.is_empty() {
        w.push(format!(
            "{} of the {} points were rejected as outliers (final weight 0; rows {}): they do \
             not count in the result. Check those measurements.",
            rejected.len(),
            m,
            rejected.join(", ")
        ));
    }
    if lowered > 0 {
        w.push(format!(
            "{lowered} points were weighed down (final weight between 0 and their weight \
             before the fit) as suspect."
        ));
    }
    w
}

/// How many of the final `weights` lie between 0 and the `prior` weight of their point
/// (`point` of a weight's index; [`weighed_down`]).
fn lowered(weights: &[Real], point: impl Fn(usize) -> usize, prior: Option<&[Real]>) -> usize {
    (weights.iter().enumerate())
        .filter(|&(i, x)| *x > 0.0 && weighed_down(*x, prior, point(i)))
        .count()
}

/// Whether a final weight `w` is below the `prior` weight of its point `point` (1/σ², mean 1;
/// 1 without σ): the method weighed the point down. A method that does not reweigh (`ls`,
/// `lm`) ends on the prior weights, which differ from 1 but judge no point; the rounding of
/// the product of prior and robust weight is no weighing down.
pub fn weighed_down(w: Real, prior: Option<&[Real]>, point: usize) -> bool {
    w < prior.and_then(|p| p.get(point)).copied().unwrap_or(1.0) * (1.0 - 1e-9)
}

/// The headers of [`validation_rows`].
pub const VALIDATION_HEADERS: [&str; 5] = ["error", "mean", "rms", "max", "std"];

/// The validation table's rows: mean, RMS, max and standard deviation of the position errors
/// before and after, of the orientation errors on full-pose files, and with `attitude` of
/// Qiao's attitude errors.
pub fn validation_rows(v: &FileValidation, attitude: bool) -> Vec<Vec<String>> {
    let row = |l: &str, e: &ErrorStats| {
        vec![
            l.to_string(),
            fmt_num(e.mean, 4),
            fmt_num(e.rms, 4),
            fmt_num(e.max, 4),
            fmt_num(e.std, 4),
        ]
    };
    let mut rows = vec![
        row("before (mm)", &v.before_mm),
        row("after (mm)", &v.after_mm),
    ];
    if let Some((b, a)) = &v.deg {
        rows.push(row("before (deg)", b));
        rows.push(row("after (deg)", a));
    }
    if let (true, Some((b, a))) = (attitude, &v.attitude_deg) {
        rows.push(row("attitude before (deg)", b));
        rows.push(row("attitude after (deg)", a));
    }
    rows
}

/// Points drawn one by one in the residual plot of `report.md`; more are drawn as the
/// largest of each run ([`largest_of_runs`]).
const PLOT_POINTS: usize = 4096;

/// The largest finite value of each run of `k` consecutive values of `v` (NaN for a run
/// with none).
fn largest_of_runs(v: &[Real], k: usize) -> Vec<Real> {
    v.chunks(k)
        .map(|c| {
            c.iter()
                .copied()
                .filter(|x| x.is_finite())
                .fold(Real::NAN, Real::max)
        })
        .collect()
}

/// Bins of the residual histogram in `report.md`.
const BINS: usize = 12;

/// Counts of each series in [`BINS`] equal bins over `[0, max]` (the largest finite value of
/// all the series, so they share the bins), with the bins' labels; non-finite values are not
/// counted.
fn histogram(series: &[&[Real]]) -> (Vec<String>, Vec<Vec<Real>>) {
    let finite = |v: &[Real]| {
        v.iter()
            .copied()
            .filter(|x| x.is_finite())
            .collect::<Vec<_>>()
    };
    let top = series.iter().flat_map(|v| finite(v)).fold(0.0, Real::max);
    let w = if top > 0.0 { top / BINS as Real } else { 1.0 };
    let counts = series
        .iter()
        .map(|v| {
            let mut h = vec![0.0; BINS];
            for x in finite(v) {
                h[((x / w) as usize).min(BINS - 1)] += 1.0;
            }
            h
        })
        .collect();
    let labels = (0..BINS)
        .map(|b| {
            format!(
                "{}–{}",
                fmt_num(b as Real * w, 2),
                fmt_num((b + 1) as Real * w, 2)
            )
        })
        .collect();
    (labels, counts)
}

/// `report.md` of `identify` on real data, showing its [`figures`]: the [`warnings`] of
/// `report.html` (a section only when there is one), residual per calibration point before and
/// after, their histogram, the identified errors with standard errors (the
/// square roots of the covariance's diagonal), the condition number and the dependent groups of
/// the parameters the robot offers, and, for a robust method (IGG3, Qiao 2021 eq. 15), the final
/// point weights.
pub fn report_md(r: &IdentifyRecord) -> Result<String> {
    use std::fmt::Write as _;
    let c = &r.calibrated;
    let id = &c.identified;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Identification of {} on {}\n",
        inline(&r.nominal.name),
        inline(&r.record.data)
    );
    let _ = writeln!(
        s,
        "{} on {} points ({}), registration {}: {} after {}; condition number \
         (column-scaled) {}, rank {} of {} parameters.\n",
        r.record.method,
        r.data.len(),
        if r.data.quats.is_some() {
            "full pose"
        } else {
            "position"
        },
        r.registration.as_str(),
        id.termination.as_str(),
        crate::error::counted(id.iterations, "iteration", "iterations"),
        fmt_num(id.condition_number(), 4),
        id.rank.map_or("—".to_string(), |k| k.to_string()),
        r.params.len(),
    );
    let w = warnings(r);
    if !w.is_empty() {
        s += "## Warnings\n\n";
        for text in &w {
            let _ = writeln!(s, "- {}", inline(text));
        }
        s.push('\n');
    }
    if let Some(v) = &r.validation {
        s += "## Validation\n\n";
        s += &table(&VALIDATION_HEADERS, &validation_rows(v, false));
        s.push('\n');
    }
    s += "## Residuals\n\n![residual per point](residuals.png)\n\n![histogram](histogram.png)\n\n";
    s += "## Identified errors\n\nmm and rad (joint compliances c<j>: rad/(N·m)); standard error = √ of the \
          covariance's diagonal.\n\n";
    let covariance = id.covariance();
    let rows: Vec<Vec<String>> = r
        .params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let se = standard_error(&covariance, i);
            vec![p.to_string(), fmt_num(id.x[i], 4), fmt_num(se, 3)]
        })
        .collect();
    s += &table(&["parameter", "error", "standard error"], &rows);
    let a = &r.identifiability;
    s += "\n## Identifiability on these poses\n\n";
    let names = |v: &[Param]| {
        v.iter()
            .map(|p| p.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let _ = writeln!(
        s,
        "Of all {} parameters: rank {}, condition number {}; not identifiable together with \
         the rest: {} (one choice among the members of each dependent group below: the \
         identified set above makes its own, tool parameters first, and may keep one of these \
         and leave out a partner of its group).\n",
        a.identifiable.len() + a.unidentifiable.len(),
        a.rank,
        fmt_num(a.condition_number, 4),
        names(&a.unidentifiable)
    );
    for g in &a.groups {
        let _ = writeln!(s, "- dependent group: {}", names(g));
    }
    if igg3_weights(r) {
        let prior = r.data.weights();
        let low: Vec<String> = (id.weights.iter().enumerate())
            .filter(|&(i, w)| weighed_down(*w, prior.as_deref(), i))
            .map(|(i, w)| format!("{i} ({})", fmt_num(*w, 3)))
            .collect();
        let _ = writeln!(
            s,
            "\n## IGG3 final weights\n\n![weights](weights.png)\n\nPoints weighed below their weight before the fit (1/σ², mean 1; 1 without σ) (row, final weight): {}\n",
            if low.is_empty() { "none".to_string() } else { low.join(", ") }
        );
    }
    Ok(s)
}

/// Whether the report shows the final point weights: those of IGG3.
fn igg3_weights(r: &IdentifyRecord) -> bool {
    r.record.method == "igg3" && !r.calibrated.identified.weights.is_empty()
}

/// The figures of `report.md`: the residual per point before and after, their histogram,
/// and IGG3's final weights.
pub fn figures<'a>(r: &'a IdentifyRecord) -> Result<Vec<Figure<'a>>> {
    let (before, after) = (&r.outcome.residuals.0[..], &r.outcome.residuals.1[..]);
    // Beyond PLOT_POINTS points the plot shows the largest of each run of k consecutive
    // points (the outliers stay visible; the figure and its SVG stay small).
    let k = before.len().div_ceil(PLOT_POINTS).max(1);
    let per_point = if k == 1 {
        Figure::new("residuals", "residual per point", move |p| {
            plots::before_after(p, "Residual per calibration point", before, after)
        })
    } else {
        let title = format!("Residual per calibration point (largest of each {k})");
        let (b, a) = (largest_of_runs(before, k), largest_of_runs(after, k));
        Figure::new("residuals", "residual per point", move |p| {
            plots::before_after(p, &title, &b, &a)
        })
    };
    let (labels, counts) = histogram(&[before, after]);
    let series: Vec<(String, Vec<Real>)> = ["before", "after"]
        .into_iter()
        .map(String::from)
        .zip(counts)
        .collect();
    let mut figs = vec![
        per_point,
        Figure::new("histogram", "histogram", move |p| {
            plots::grouped_bars(
                p,
                "Residuals (mm): points per bin",
                "points",
                &labels,
                &series,
            )
        }),
    ];
    if igg3_weights(r) {
        let (labels, mut counts) = histogram(&[&r.calibrated.identified.weights]);
        let series = [("points".to_string(), counts.remove(0))];
        figs.push(Figure::new("weights", "weights", move |p| {
            plots::grouped_bars(p, "IGG3 final point weights", "points", &labels, &series)
        }));
    }
    Ok(figs)
}

//! `report.html` of `calbench identify`: the warnings in plain words, the identified
//! parameters with ±σ from the covariance and the strongly correlated pairs, rank and
//! condition number, validation before and after, residuals per point with their histogram
//! and weights, the registration rounds and, when `identify`'s options ask for them, the
//! cross-validation, model choice, priors and diagnostics ([`crate::report::practice`]).
//!
//! The page is the list [`SECTIONS`]: each entry is a heading and the function that writes
//! its body from a [`View`] of the result, so a new diagnostic is one more function and one
//! more line in the list.

use std::path::Path;

use nalgebra::DMatrix;

use super::Page;
use crate::error::Result;
use crate::identify::standard_error;
use crate::numeric::Real;
use crate::report::identified::{
    validation_rows, warnings, weighed_down, Additions, Block, IdentifyRecord, VALIDATION_HEADERS,
};
use crate::report::markdown::fmt_num;

/// Pairs of parameters whose estimates correlate by more than this (|ρ|) are flagged: the
/// data hardly tell them apart.
pub const STRONG_CORRELATION: Real = 0.8;

/// What the sections are written from: the record, the folder holding its plots, the
/// residual per point before and after, and the covariance of the estimate.
pub struct View<'a> {
    /// The identification.
    pub record: &'a IdentifyRecord<'a>,
    /// The output folder, holding the plots.
    pub dir: &'a Path,
    /// Residual per calibration point of the nominal robot (mm).
    pub before: &'a [Real],
    /// … of the compensated robot (mm).
    pub after: &'a [Real],
    /// The covariance of the identified errors (its entries NaN when the data do not give one).
    pub covariance: DMatrix<Real>,
}

/// A section of the page: heading and body writer.
pub type Section = (&'static str, fn(&mut Page, &View) -> Result<()>);

/// The sections of the page, in order.
pub const SECTIONS: &[Section] = &[
    ("Warnings", warnings_section),
    ("Result", result_section),
    ("Validation before and after", validation_section),
    ("Identified parameters", parameters_section),
    ("Residuals and weights", residuals_section),
    ("Registration", registration_section),
];

/// The page of an identification whose files (and plots) are in `dir`, with what `more`
/// adds (the practice options' section) after [`SECTIONS`].
pub fn page(dir: &Path, r: &IdentifyRecord, more: &Additions) -> Result<Page> {
    let (before, after) = (&r.residuals.0[..], &r.residuals.1[..]);
    let view = View {
        record: r,
        dir,
        before,
        after,
        covariance: r.calibrated.identified.covariance(),
    };
    let mut page = Page::new(
        &format!("Identification of {}", r.nominal.name),
        &format!(
            "{} on {} points of {} ({}), registration {}.",
            r.record.method,
            r.data.len(),
            r.record.data,
            if r.data.quats.is_some() {
                "full pose"
            } else {
                "position"
            },
            r.registration.as_str()
        ),
    );
    for (title, write) in SECTIONS {
        page.section(title);
        write(&mut page, &view)?;
    }
    if !more.blocks.is_empty() {
        page.section("Cross-validation, priors and diagnostics");
        blocks(&mut page, &more.blocks);
    }
    Ok(page)
}

/// Writes `blocks` (the Markdown report's own pieces) on the page; a table takes the heading
/// before it as its caption.
fn blocks(page: &mut Page, blocks: &[Block]) {
    let mut caption = "";
    for b in blocks {
        match b {
            Block::Heading(h) => {
                page.heading(h);
                caption = h;
            }
            Block::Para(t) => page.para(t),
            Block::Table(headers, rows) => page.table(caption, headers, rows),
        }
    }
}

fn warnings_section(page: &mut Page, v: &View) -> Result<()> {
    let w = warnings(v.record);
    if w.is_empty() {
        page.fine(
            "Nothing to warn about: the data determine every parameter, the registration \
             settled and no point was rejected as an outlier.",
        );
    }
    for text in &w {
        page.warning(text);
    }
    Ok(())
}

fn result_section(page: &mut Page, v: &View) -> Result<()> {
    let r = v.record;
    let id = &r.calibrated.identified;
    let n = r.params.len();
    page.facts(&[
        ("method", r.record.method.clone()),
        (
            "termination",
            format!(
                "{} after {} ({} evaluations)",
                id.termination.as_str(),
                crate::error::counted(id.iterations, "iteration", "iterations"),
                id.evaluations
            ),
        ),
        (
            "rank",
            id.rank.map_or_else(
                || format!("not computed ({n} parameters)"),
                |k| format!("{k} of {n} parameters"),
            ),
        ),
        (
            "condition number",
            format!(
                "{} (column-scaled Jacobian)",
                fmt_num(id.condition_number(), 4)
            ),
        ),
        ("σ0", fmt_num(id.sigma0, 4)),
        (
            "RMS residual",
            format!("{} mm", fmt_num(id.rms_residual, 4)),
        ),
    ]);
    Ok(())
}

fn validation_section(page: &mut Page, v: &View) -> Result<()> {
    let Some(val) = &v.record.validation else {
        page.para("No validation was asked for (a validation file or held-out rows).");
        return Ok(());
    };
    page.table(
        "Error at the validation points of the nominal (before) and compensated (after) robot",
        &VALIDATION_HEADERS,
        &validation_rows(val, true),
    );
    let gain = 100.0 * (val.before_mm.mean - val.after_mm.mean) / val.before_mm.mean;
    page.para(&format!(
        "The compensation {} the mean validation error by {} % ({} → {} mm).",
        if gain >= 0.0 { "reduces" } else { "increases" },
        fmt_num(gain.abs(), 3),
        fmt_num(val.before_mm.mean, 4),
        fmt_num(val.after_mm.mean, 4)
    ));
    Ok(())
}

/// The correlation of parameters `i` and `j` from the covariance (NaN without one).
fn correlation(cov: &DMatrix<Real>, i: usize, j: usize) -> Real {
    if cov.nrows() <= i.max(j) {
        return Real::NAN;
    }
    cov[(i, j)] / (cov[(i, i)] * cov[(j, j)]).sqrt()
}

/// The pairs `(i, j, ρ)`, i < j, correlated by more than [`STRONG_CORRELATION`].
pub fn strong_pairs(cov: &DMatrix<Real>) -> Vec<(usize, usize, Real)> {
    let n = cov.nrows();
    (0..n)
        .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
        .map(|(i, j)| (i, j, correlation(cov, i, j)))
        .filter(|(_, _, rho)| rho.abs() > STRONG_CORRELATION)
        .collect()
}

fn parameters_section(page: &mut Page, v: &View) -> Result<()> {
    let r = v.record;
    let id = &r.calibrated.identified;
    let cov = &v.covariance;
    let names: Vec<String> = r.params.iter().map(|p| p.to_string()).collect();
    let pairs = strong_pairs(cov);
    page.para(
        "Errors in mm and rad (joint compliances c<j>: rad/(N·m)); σ is the square root of the \
         covariance's diagonal (σ0² (JᵀPJ)⁻¹).",
    );
    if (0..names.len()).any(|i| standard_error(cov, i).is_nan()) {
        page.para(
            "No covariance: the data do not determine every parameter, leave no redundancy, \
             or the method does not estimate σ0. σ and ρ are not given.",
        );
    }
    let rows: Vec<Vec<String>> = names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let sigma = standard_error(cov, i);
            let partners: Vec<String> = pairs
                .iter()
                .filter(|(a, b, _)| *a == i || *b == i)
                .map(|(a, b, rho)| {
                    let other = if *a == i { *b } else { *a };
                    format!("{} ({})", names[other], fmt_num(*rho, 3))
                })
                .collect();
            vec![
                name.clone(),
                fmt_num(id.x[i], 5),
                format!("± {}", fmt_num(sigma, 3)),
                partners.join(", "),
            ]
        })
        .collect();
    page.table_with(
        &format!(
            "Identified errors ± σ; flagged: correlated with another by |ρ| > {STRONG_CORRELATION}"
        ),
        &["parameter", "error", "± σ", "|ρ| > 0.8 with"],
        &rows,
        |i| (!rows[i][3].is_empty()).then_some("failed"),
    );
    if !pairs.is_empty() {
        let rows: Vec<Vec<String>> = pairs
            .iter()
            .map(|(a, b, rho)| vec![names[*a].clone(), names[*b].clone(), fmt_num(*rho, 4)])
            .collect();
        page.warning(&format!(
            "{} pairs of parameters are correlated by |ρ| > {STRONG_CORRELATION}: the data \
             hardly tell each pair apart, so their individual values are uncertain even where \
             their sum is well determined.",
            pairs.len()
        ));
        page.table(
            "Strongly correlated pairs",
            &["parameter", "parameter", "ρ"],
            &rows,
        );
    }
    Ok(())
}

fn residuals_section(page: &mut Page, v: &View) -> Result<()> {
    let r = v.record;
    let weights = &r.calibrated.identified.weights;
    let prior = r.data.weights();
    let mean = |x: &[Real]| x.iter().sum::<Real>() / x.len().max(1) as Real;
    page.plots_begin();
    page.figure_file(
        v.dir,
        "residuals",
        "Residual per calibration point",
        &format!(
            "Residual of each of the {} calibration points before (nominal robot, mean {} mm) \
             and after (compensated robot, mean {} mm); the table below lists them (the largest when there are more than {TABLE_ROWS}).",
            v.before.len(),
            fmt_num(mean(v.before), 4),
            fmt_num(mean(v.after), 4)
        ),
    )?;
    page.figure_file(
        v.dir,
        "histogram",
        "Residuals: points per bin",
        "Histogram of the residuals before and after, in 12 equal bins from 0 to the largest.",
    )?;
    if v.dir.join("weights.svg").is_file() {
        let rejected = weights.iter().filter(|w| **w == 0.0).count();
        page.figure_file(
            v.dir,
            "weights",
            "Final point weights",
            &format!(
                "Histogram of the robust method's final weights of the {} points; {rejected} \
                 have weight 0 (rejected as outliers).",
                weights.len()
            ),
        )?;
    }
    page.plots_end();
    // Beyond TABLE_ROWS points the table lists the TABLE_ROWS largest residuals after
    // (in row order); residuals.csv holds every point.
    let n = v.before.len();
    let mut shown: Vec<usize> = (0..n).collect();
    if n > TABLE_ROWS {
        shown.sort_by(|&a, &b| v.after[b].total_cmp(&v.after[a]).then(a.cmp(&b)));
        shown.truncate(TABLE_ROWS);
        shown.sort_unstable();
    }
    let rows: Vec<Vec<String>> = shown
        .iter()
        .map(|&i| {
            vec![
                i.to_string(),
                fmt_num(v.before[i], 4),
                fmt_num(v.after[i], 4),
                fmt_num(weights.get(i).copied().unwrap_or(1.0), 3),
            ]
        })
        .collect();
    let caption = if n > TABLE_ROWS {
        format!(
            "Residual per point (mm) and final weight: the {TABLE_ROWS} largest after of {n} \
             points (residuals.csv holds all; rows weighed below their weight before the fit are \
             marked)"
        )
    } else {
        "Residual per point (mm) and final weight (rows weighed below their weight before the \
         fit are marked)"
            .to_string()
    };
    page.table_with(
        &caption,
        &["row", "before mm", "after mm", "weight"],
        &rows,
        |k| {
            let i = shown[k];
            (weights
                .get(i)
                .is_some_and(|w| weighed_down(*w, prior.as_deref(), i)))
            .then_some("low")
        },
    );
    Ok(())
}

/// Rows of the residual table at most: a larger file lists its largest residuals after.
pub const TABLE_ROWS: usize = 4096;

fn registration_section(page: &mut Page, v: &View) -> Result<()> {
    let c = &v.record.calibrated;
    let (xyz, rpy) = c.frame.to_xyz_rpy();
    let f = |v: &[Real]| {
        v.iter()
            .map(|x| fmt_num(*x, 6))
            .collect::<Vec<_>>()
            .join(", ")
    };
    page.facts(&[
        ("method", v.record.registration.as_str().to_string()),
        (
            "rounds",
            format!("{} ({})", c.rounds.rounds, c.rounds.termination.as_str()),
        ),
        (
            "last frame step",
            format!("{} mm", fmt_num(c.rounds.last_step_mm, 3)),
        ),
        ("frame position", format!("{} mm", f(&xyz))),
        ("frame roll, pitch, yaw", format!("{} rad", f(&rpy))),
    ]);
    Ok(())
}

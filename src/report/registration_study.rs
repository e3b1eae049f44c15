//! The files of a registration study (Ban fig. 3, [`crate::study::registration_study`]):
//! `summary.json`, `report.md` with the grid as a table, and the heat map
//! `heatmap_difference.png` / `.svg` of the mean registration-error difference SVD −
//! weighted SVD. Writers only read results that are already computed.

use serde_json::json;
use std::fmt::Write as _;

use super::markdown::{fmt_num, table};
use super::output::{Figure, Outputs, Text};
use super::plots;
use crate::analysis::claims::ClaimResult;
use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::study::claims::Claim;
use crate::study::registration_study::{Cell, RegistrationScenario};
use crate::study::verdict::Evaluation;

/// `values[row][column]` of `f` over the grid: a row per outlier count, a column per
/// magnitude.
fn grid(s: &RegistrationScenario, cells: &[Cell], f: fn(&Cell) -> Real) -> Vec<Vec<Real>> {
    let nm = s.registration_study.magnitude_mm.len();
    cells
        .chunks(nm)
        .map(|r| r.iter().map(f).collect())
        .collect()
}

/// The column names: the magnitude ranges `0–m mm`.
fn magnitude_names(s: &RegistrationScenario) -> Vec<String> {
    s.registration_study
        .magnitude_mm
        .iter()
        .map(|m| format!("0–{} mm", fmt_num(*m, 3)))
        .collect()
}

/// `report.md`: the claims (if any), the settings, the difference grid in µm, and each
/// method's mean error.
pub fn report_md(
    s: &RegistrationScenario,
    cells: &[Cell],
    claims: &[(&Claim, Evaluation)],
    plot: &str,
) -> String {
    let st = &s.registration_study;
    let mut out = String::new();
    let _ = writeln!(out, "# {}\n\n{}\n", s.head.name, s.head.description);
    if !claims.is_empty() {
        use super::run::claims::{headers, row, NOTE};
        let rows: Vec<Vec<String>> = claims
            .iter()
            .map(|(c, e)| row(&ClaimResult::new(c, e, None), None))
            .collect();
        let _ = writeln!(
            out,
            "## Claims\n\n{}\n{NOTE}\n",
            table(&headers(false), &rows)
        );
    }
    let _ = writeln!(
        out,
        "Registration study (Ban fig. 3): {} points in a {} mm box centred at ({}) mm, noise uniform in ±{} mm per coordinate, {} draws per cell from seed {}. Registration error = mean distance of the registered noise-free points from the truth.\n",
        st.points,
        st.size_mm.map(|v| fmt_num(v, 4)).join(" × "),
        st.center_mm.map(|v| fmt_num(v, 4)).join(", "),
        fmt_num(st.noise_mm, 3),
        s.head.trials,
        s.head.seed
    );
    let mut headers = vec!["gross errors"];
    let names = magnitude_names(s);
    headers.extend(names.iter().map(String::as_str));
    let rows_of = |f: fn(&Cell) -> Real, scale: Real| -> Vec<Vec<String>> {
        grid(s, cells, f)
            .iter()
            .zip(&st.outlier_counts)
            .map(|(r, c)| {
                let mut row = vec![c.to_string()];
                row.extend(r.iter().map(|v| fmt_num(v * scale, 4)));
                row
            })
            .collect()
    };
    out += "## Mean registration error, SVD − weighted SVD (µm)\n\n";
    out += &table(&headers, &rows_of(|c| c.difference_mm, 1e3));
    let _ = writeln!(out, "\n![SVD − weighted SVD]({plot})\n");
    out += "## Mean registration error of the SVD (µm)\n\n";
    out += &table(&headers, &rows_of(|c| c.svd_mm, 1e3));
    out += "\n## Mean registration error of the weighted SVD (µm)\n\n";
    out += &table(&headers, &rows_of(|c| c.wsvd_mm, 1e3));
    out += "\n## Share of draws where the weighted SVD is better\n\n";
    out += &table(&headers, &rows_of(|c| c.wsvd_better_fraction, 1.0));
    out
}

/// The study's files, in the order they are written: `summary.json` (with the claims
/// evaluated, [`RegistrationScenario::evaluate_claims`], when the scenario states any), the
/// heat map and `report.md`; and the grid's table as the terminal shows it.
pub fn outputs<'a>(
    s: &'a RegistrationScenario,
    cells: &[Cell],
    claims: &[(&Claim, Evaluation)],
) -> Result<(Outputs<'a>, String)> {
    let settings =
        serde_json::to_value(&s.registration_study).map_err(|e| Error::Compute(e.to_string()))?;
    let mut more = json!({"settings": settings, "cells": cells});
    if !claims.is_empty() {
        let evaluated = claims
            .iter()
            .map(|(c, e)| serde_json::to_value(ClaimResult::new(c, e, None)))
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| Error::Compute(e.to_string()))?;
        more["claims"] = serde_json::Value::Array(evaluated);
    }
    let head = (
        s.head.name.as_str(),
        s.head.description.as_str(),
        "registration_study",
    );
    let summary = super::whole_summary(head, (s.head.trials, s.head.seed), more)?;
    let rows: Vec<String> = s
        .registration_study
        .outlier_counts
        .iter()
        .map(|c| c.to_string())
        .collect();
    // `grid` is by row (outlier count), the plot's values by column (magnitude range).
    let by_row = grid(s, cells, |c| c.difference_mm * 1e3);
    let columns = magnitude_names(s);
    let by_column: Vec<Vec<Real>> = (0..columns.len())
        .map(|j| by_row.iter().map(|row| row[j]).collect())
        .collect();
    let title = "Mean registration error, SVD − weighted SVD (µm)";
    let heatmap = Figure::new("heatmap_difference", title, move |p| {
        plots::heatmap(
            p,
            title,
            ("gross-error magnitude range", &columns),
            ("points with a gross error", &rows),
            &by_column,
        )
    });
    let text = report_md(s, cells, claims, &heatmap.listed().0);
    let table = text
        .lines()
        .skip_while(|l| !l.starts_with("## Mean"))
        .take_while(|l| !l.starts_with("!["))
        .collect::<Vec<_>>()
        .join("\n");
    let report = Text {
        name: "report.md",
        text,
    };
    let outputs: Outputs<'a> = vec![Box::new(summary), Box::new(heatmap), Box::new(report)];
    Ok((outputs, table))
}

//! The files of the instruments study ([`crate::study::instruments`]): `summary.json` (a cell
//! per instrument, pose count and strategy), and `report.md` and `report.html` (the table of
//! what each instrument buys). Writers only read results that are already computed.

use serde_json::json;

use super::html::Page;
use super::markdown::{fmt_num, table};
use super::output::{Outputs, Text};
use crate::error::{Error, Result};
use crate::study::instruments::{Cell, InstrumentsScenario};
use crate::study::metric::Metric;

/// The columns of the cells' table.
const HEADERS: [&str; 10] = [
    "instrument",
    "poses",
    "strategy",
    "σ (µm)",
    "identified",
    "η mean %",
    "before mm",
    "after mm",
    "CRB ratio",
    Metric::Failures.spec().field,
];

/// What `report.md` and `report.html` both show: the settings in a sentence, a row per cell,
/// and per instrument the parameters it cannot see and its own unknowns.
struct Content {
    lead: String,
    rows: Vec<Vec<String>>,
    blind: Vec<Vec<String>>,
}

fn content(s: &InstrumentsScenario, cells: &[Cell]) -> Content {
    let lead = format!(
        "Instruments study on `{}`: {} trials per cell from seed {}, `ls` weighted by 1/σ², \
         validation RMS = position error at {} fresh poses (mm). η: Guo 2024 eq. 29, a \
         parameter the instrument cannot see counts at its nominal value.",
        s.robot, s.head.trials, s.head.seed, s.validation
    );
    let rows = cells
        .iter()
        .map(|c| {
            vec![
                c.kind.clone(),
                c.poses.to_string(),
                c.strategy.clone(),
                format!(
                    "{} + {}/m",
                    fmt_num(c.noise_um, 3),
                    fmt_num(c.scale_um_per_m, 3)
                ),
                c.identified.len().to_string(),
                fmt_num(c.eta_mean_pct, 4),
                fmt_num(c.validation_before_mm, 4),
                fmt_num(c.validation_after_mm, 4),
                fmt_num(c.crb_ratio, 3),
                c.failures.to_string(),
            ]
        })
        .collect();
    let listed = |v: &[String]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(", ")
        }
    };
    let mut blind: Vec<Vec<String>> = Vec::new();
    for c in cells {
        if !blind.iter().any(|b| b[0] == c.kind) {
            let unknowns = listed(&c.instrument_unknowns);
            blind.push(vec![c.kind.clone(), listed(&c.unidentifiable), unknowns]);
        }
    }
    Content { lead, rows, blind }
}

/// `report.md`: the settings, a row per cell, and each instrument's blind parameters.
pub fn report_md(s: &InstrumentsScenario, cells: &[Cell]) -> String {
    let c = content(s, cells);
    let mut out = format!(
        "# {}\n\n{}\n\n{}\n\n",
        s.head.name, s.head.description, c.lead
    );
    out += &table(&HEADERS, &c.rows);
    out += "\n## Parameters each instrument cannot see\n\n";
    for b in &c.blind {
        out += &format!("- **{}**: {} (instrument unknowns: {})\n", b[0], b[1], b[2]);
    }
    out
}

/// `report.html`: the page of [`report_md`], its tables sortable.
pub fn report_html(s: &InstrumentsScenario, cells: &[Cell]) -> Page {
    let c = content(s, cells);
    let mut page = Page::new(
        &format!("Instruments study: {}", s.head.name),
        &s.head.description,
    );
    page.section("What each instrument buys");
    page.para(&c.lead);
    let caption = "a row per instrument, pose count and pose strategy";
    page.table(caption, &HEADERS, &c.rows);
    page.section("Parameters each instrument cannot see");
    let headers = ["instrument", "cannot see", "instrument unknowns"];
    page.table(
        "joint and tool parameters left at their nominal values",
        &headers,
        &c.blind,
    );
    page
}

/// The study's files: `summary.json`, `report.md` and `report.html`; and the cells' table as
/// the terminal shows it.
pub fn outputs<'a>(s: &'a InstrumentsScenario, cells: &[Cell]) -> Result<(Outputs<'a>, String)> {
    let instruments =
        serde_json::to_value(&s.measurement).map_err(|e| Error::Compute(e.to_string()))?;
    let more = json!({"robot": s.robot, "instruments": instruments, "cells": cells});
    let head = (
        s.head.name.as_str(),
        s.head.description.as_str(),
        "instruments",
    );
    let summary = super::whole_summary(head, (s.head.trials, s.head.seed), more)?;
    let report = Text {
        name: "report.md",
        text: report_md(s, cells),
    };
    let page = report_html(s, cells).output("report.html");
    let table = report_md(s, cells);
    let outputs: Outputs<'a> = vec![Box::new(summary), Box::new(report), Box::new(page)];
    Ok((outputs, table))
}

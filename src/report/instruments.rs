//! The files of the instruments study ([`crate::study::instruments`]): `summary.json` (a cell
//! per instrument, pose count and strategy) and `report.md` (the table of what each instrument
//! buys). Writers only read results that are already computed.

use std::path::Path;

use serde_json::json;

use super::markdown::{fmt_num, table};
use crate::error::{Error, Result};
use crate::study::instruments::{Cell, InstrumentsScenario};

/// `report.md`: the settings, a row per cell, and each instrument's blind parameters.
pub fn report_md(s: &InstrumentsScenario, cells: &[Cell]) -> String {
    let mut out = format!("# {}\n\n{}\n\n", s.head.name, s.head.description);
    out += &format!(
        "Instruments study on `{}`: {} trials per cell from seed {}, `ls` weighted by 1/σ², \
         validation RMS = position error at {} fresh poses (mm). η: Guo 2024 eq. 29, a \
         parameter the instrument cannot see counts at its nominal value.\n\n",
        s.robot, s.head.trials, s.head.seed, s.validation
    );
    let rows: Vec<Vec<String>> = cells
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
    out += &table(
        &[
            "instrument",
            "poses",
            "strategy",
            "σ (µm)",
            "identified",
            "η mean %",
            "before mm",
            "after mm",
            "CRB ratio",
            "failures",
        ],
        &rows,
    );
    out += "\n## Parameters each instrument cannot see\n\n";
    let mut seen = Vec::new();
    for c in cells {
        if seen.contains(&c.kind) {
            continue;
        }
        seen.push(c.kind.clone());
        out += &format!(
            "- **{}**: {} (instrument unknowns: {})\n",
            c.kind,
            if c.unidentifiable.is_empty() {
                "none".into()
            } else {
                c.unidentifiable.join(", ")
            },
            if c.instrument_unknowns.is_empty() {
                "none".into()
            } else {
                c.instrument_unknowns.join(", ")
            },
        );
    }
    out
}

/// Writes `summary.json` and `report.md` into `out` as a whole ([`super::atomically`]).
pub fn write_all(s: &InstrumentsScenario, cells: &[Cell], out: &Path) -> Result<()> {
    super::atomically(out, |dir| {
        let instruments =
            serde_json::to_value(s.instruments()).map_err(|e| Error::Compute(e.to_string()))?;
        let more = json!({"robot": s.robot, "instruments": instruments, "cells": cells});
        let head = (
            s.head.name.as_str(),
            s.head.description.as_str(),
            "instruments",
        );
        super::write_whole_summary(dir, head, (s.head.trials, s.head.seed), more)?;
        let path = dir.join("report.md");
        std::fs::write(&path, report_md(s, cells)).map_err(|e| Error::io(&path, e))
    })
}

//! `report.html` of `calbench run` and `calbench merge`: the verdicts first (the paper's
//! claims, the paired comparisons, the headline figures with their intervals), then the
//! scenario's settings, the results per method × poses (× sweep point), validation before
//! and after, η per parameter, the CRB ratio, the sweep plots and heat maps, the plots of
//! trial 0, and the terminations and failures, with every plot of the run inlined.

use std::collections::BTreeSet;
use std::path::Path;

use super::Page;
use crate::analysis::summary::Summary;
use crate::error::Result;
use crate::report::markdown::fmt_num;
use crate::report::run::{
    claims, columns::*, comparisons, entry_table, entry_table_by, eta_table, not_determinable,
    searches, validation_columns, Column, INTERVAL_COLUMNS, INTERVAL_NOTE, METRIC_NOTES,
};
use crate::study::metric::Metric;
use crate::study::RunResult;

/// The section a plot of the run belongs to, by its file stem.
fn section_of(stem: &str) -> &'static str {
    if stem == "headline_rms" {
        "Headline figures"
    } else if stem == Metric::Eta.spec().field {
        "η per parameter"
    } else if stem.starts_with("validation") {
        "Validation before and after"
    } else if stem.starts_with("sweep_") || stem.starts_with("heatmap_") {
        "Sweep"
    } else if stem.starts_with("paired_") {
        "Paired comparisons"
    } else if stem == "search_ecdf" || stem == "fixed_budget" {
        "Searches compared"
    } else if stem.ends_with("_trace") {
        "Convergence"
    } else {
        "Other plots"
    }
}

/// Inlines the plots (file name `<stem>.png`, caption) of `plots` that belong to `section`.
fn figures(page: &mut Page, dir: &Path, plots: &[(String, String)], section: &str) -> Result<()> {
    let mine: Vec<&(String, String)> = plots
        .iter()
        .filter(|(f, _)| section_of(stem(f)) == section)
        .collect();
    if mine.is_empty() {
        return Ok(());
    }
    page.plots_begin();
    for (file, caption) in mine {
        let title = capitalised(caption);
        let alt = format!(
            "Plot: {caption}. The numbers it shows are in the tables of this page and in \
             summary.json; the same plot is {file}."
        );
        page.figure_file(dir, stem(file), &title, &alt)?;
    }
    page.plots_end();
    Ok(())
}

/// The verdict tables' sections: `[section, note, caption]` ([`noted_table`]).
const CLAIMS: [&str; 3] = [
    "The paper's claims",
    claims::NOTE,
    "Claims and their verdicts",
];
const PAIRED: [&str; 3] = [
    "Paired verdicts",
    comparisons::NOTE,
    "Paired comparisons on the shared trials",
];
const SEARCHES: [&str; 3] = [
    "Searches compared",
    searches::NOTE,
    "Targets reached and fitness at the full budget",
];

/// The table `(headers, rows)` in a section of its own, its note above it:
/// `[section, note, caption]`; nothing, and `false`, when it has no rows.
fn noted_table(
    page: &mut Page,
    [section, note, caption]: [&str; 3],
    (headers, rows): (Vec<impl AsRef<str>>, Vec<Vec<String>>),
) -> bool {
    if rows.is_empty() {
        return false;
    }
    page.section(section);
    page.para(note);
    page.table(caption, &headers, &rows);
    true
}

fn stem(file: &str) -> &str {
    file.rsplit_once('.').map_or(file, |(s, _)| s)
}

fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map(|f| f.to_uppercase().chain(c).collect())
        .unwrap_or_default()
}

/// A table of one row per results entry with `cols`.
fn entries(page: &mut Page, r: &RunResult, caption: &str, cols: &[Column]) {
    let (h, rows) = entry_table(r, cols);
    page.table(caption, &h, &rows);
}

/// The page of run `r` whose plots (`plots`: file name, caption, as `report.md` lists them)
/// are in `dir`.
pub fn page(
    r: &RunResult,
    summary: &Summary,
    plots: &[(String, String)],
    dir: &Path,
) -> Result<Page> {
    let sc = &r.scenario;
    let first = &r.blocks[0].info;
    let pose = first.full_pose;
    let per_trial: usize = r.blocks.iter().map(|b| b.entries.len()).sum();
    let mut page = Page::new(
        &sc.name,
        &format!(
            "{} — {} trials of each method and pose strategy{}, robot {}.",
            sc.description,
            sc.trials,
            if r.blocks.len() > 1 {
                format!(" at each of {} sweep points", r.blocks.len())
            } else {
                String::new()
            },
            first.robot
        ),
    );

    if let Some(w) = summary.stopping.as_ref().and_then(|st| st.shortfall()) {
        page.warning(&format!("{w}."));
    }
    // The verdicts first: the paper's claims, the paired comparisons, the headline figures
    // with their intervals; then how they were obtained.
    noted_table(&mut page, CLAIMS, claims::table(summary));
    if noted_table(&mut page, PAIRED, comparisons::table(summary)) {
        figures(&mut page, dir, plots, "Paired comparisons")?;
    }
    page.section("Headline figures");
    page.para(INTERVAL_NOTE);
    entries(
        &mut page,
        r,
        "Headline figures with their 95 % intervals over trials",
        &INTERVAL_COLUMNS,
    );
    figures(&mut page, dir, plots, "Headline figures")?;

    page.section("Settings");
    page.facts(&[
        ("robot", first.robot.clone()),
        ("trials", format!("{} (seed {})", sc.trials, sc.seed)),
        (
            "measurement",
            if pose { "full pose" } else { "position" }.into(),
        ),
        ("registration", sc.registration.as_str().into()),
        (
            "poses",
            format!(
                "{} calibration, {} validation per trial",
                sc.calibration.count, sc.validation.count
            ),
        ),
        ("identified parameters", first.params.join(" ")),
        (
            "identifications",
            format!(
                "{} ({} per trial{})",
                sc.trials * per_trial,
                per_trial / r.blocks.len(),
                if r.blocks.len() > 1 {
                    " and sweep point"
                } else {
                    ""
                }
            ),
        ),
    ]);
    page.pre(
        "The scenario as run (TOML)",
        &toml::to_string(sc.table()).unwrap_or_default(),
    );

    page.section("Results");
    page.para(
        "Each statistic is averaged over trials. Validation errors are against the true \
         (sagging) arm at fresh poses, free of tracker noise.",
    );
    entries(
        &mut page,
        r,
        "Results per method and pose strategy",
        &[
            ETA_MEAN,
            ETA_MEDIAN,
            AFTER_RMS,
            IMPROVEMENT,
            CRB_RATIO,
            FAILURES,
            EVALUATIONS,
            MS_PER_IDENTIFICATION,
        ],
    );

    if noted_table(&mut page, SEARCHES, searches::table(r)) {
        figures(&mut page, dir, plots, "Searches compared")?;
    }

    page.section("Validation before and after");
    entries(
        &mut page,
        r,
        "Validation error of the nominal (before) and compensated (after) robot",
        &validation_columns(pose),
    );
    figures(&mut page, dir, plots, "Validation before and after")?;

    page.section("η per parameter");
    page.para(
        "Mean η over trials per parameter with an injected error (Guo 2024 eq. 29); 100 % is \
         exact recovery.",
    );
    let (h, rows) = eta_table(&r.blocks[0]);
    let which = if r.blocks.len() > 1 {
        " (the first sweep point)"
    } else {
        ""
    };
    page.table(&format!("η per parameter (mean %){which}"), &h, &rows);
    if let Some((text, lines)) = not_determinable(&r.blocks[0]) {
        page.para(&text);
        for l in lines {
            page.para(&l);
        }
    }
    figures(&mut page, dir, plots, "η per parameter")?;

    page.section("CRB ratio");
    page.para(METRIC_NOTES[3].1.trim_start_matches([':', ' ']));
    entries(
        &mut page,
        r,
        "Covariance over the Cramér–Rao bound",
        &[CRB_RATIO, ETA_MEDIAN],
    );

    if let Some(sw) = &sc.sweep {
        page.section("Sweep");
        page.para(&format!(
            "Swept: {}{}.",
            sw.keys().join(", "),
            if sw.zip { " (paired)" } else { "" }
        ));
        entries(
            &mut page,
            r,
            "Headline metrics per sweep point",
            &[AFTER_RMS, ETA_MEDIAN, CRB_RATIO, MS_PER_IDENTIFICATION],
        );
        figures(&mut page, dir, plots, "Sweep")?;
    }
    if plots
        .iter()
        .any(|(f, _)| section_of(stem(f)) == "Convergence")
    {
        page.section("Convergence");
        figures(&mut page, dir, plots, "Convergence")?;
    }
    if plots
        .iter()
        .any(|(f, _)| section_of(stem(f)) == "Other plots")
    {
        page.section("Other plots");
        figures(&mut page, dir, plots, "Other plots")?;
    }

    page.section("Terminations and failures");
    let reasons: BTreeSet<String> = r
        .blocks
        .iter()
        .flat_map(|b| {
            b.entries
                .iter()
                .flat_map(|e| e.terminations.keys().cloned())
        })
        .collect();
    let failed: usize = r
        .blocks
        .iter()
        .flat_map(|b| b.entries.iter().map(|e| e.failures))
        .sum();
    if failed == 0 {
        page.fine("No identification failed.");
    } else {
        page.warning(&format!(
            "{failed} identifications gave no usable result (diverged, singular, invalid or \
             non-finite); their trials are left out of the statistics of their entry."
        ));
    }
    let (h, rows) = entry_table_by(
        r,
        reasons
            .iter()
            .cloned()
            .chain([Metric::Failures.key(), Metric::Iterations.key()]),
        |e| {
            reasons
                .iter()
                .map(|k| e.terminations.get(k).copied().unwrap_or(0).to_string())
                .chain([e.failures.to_string(), fmt_num(e.iterations_mean, 4)])
                .collect()
        },
    );
    page.table_with(
        "How the identifications ended (count per termination; mean iterations)",
        &h,
        &rows,
        |i| {
            rows[i]
                .get(h.len() - 2)
                .filter(|f| f.as_str() != "0")
                .map(|_| "failed")
        },
    );

    page.section("What the metrics mean");
    for (term, text) in METRIC_NOTES {
        page.para(&format!("{term}{text}"));
    }
    Ok(page)
}

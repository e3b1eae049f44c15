//! `trials.csv` (docs/formats.md `run`): one row per trial × strategy × method, streamed as
//! the trials finish ([`crate::report::output::Stream`]).

use std::fmt::Write as _;
use std::path::Path;

use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::report::output::{Bytes, Output, Stream};
use crate::study::metric::Metric;
use crate::study::scenario::Sweep;
use crate::study::stats::trial_eta_mean;
use crate::study::{BlockInfo, TrialResult, TrialSink};

/// Appends `,` and `v` (empty where it is not finite) to the row `out`.
fn num(out: &mut String, v: Real) {
    out.push(',');
    if v.is_finite() {
        // Writing into a String cannot fail.
        let _ = write!(out, "{v}");
    }
}

/// The name of the file.
pub const NAME: &str = "trials.csv";

/// `trials.csv`, written as trials finish: one row per trial × strategy × method (× sweep
/// point), in trial order. One axis adds the column `sweep_value`, a grid one column per
/// swept key. It streams into an output folder ([`TrialsCsv::create`], a [`Stream`] whose
/// memory does not grow with the trials) or, for a run held in memory, to bytes
/// ([`TrialsCsv::in_memory`]): the same bytes.
///
/// The header is the first block's, and every row is written in its block's columns. Where
/// the blocks of a sweep differ in their columns (a point that identifies more parameters,
/// measures full pose or runs a search), the finished file is rewritten once in the union of
/// every block's columns (`Layout::widen`), the cells a block does not have left empty:
/// a file of one layout is never read back.
pub struct TrialsCsv {
    out: Rows,
    sweep_columns: Vec<String>,
    /// The runs of consecutive blocks of one layout: the layout and its number of rows.
    segments: Vec<(Layout, usize)>,
}

/// Where the rows go.
enum Rows {
    Stream(Stream),
    Memory(Vec<u8>),
}

/// What a block's columns depend on.
#[derive(Clone, Debug, PartialEq)]
struct Layout {
    full_pose: bool,
    searches: bool,
    external: bool,
    params: Vec<String>,
}

impl Layout {
    fn of(info: &BlockInfo) -> Layout {
        Layout {
            full_pose: info.full_pose,
            searches: info.searches,
            external: info.external,
            params: info.params.clone(),
        }
    }

    /// Whether the rows of `info` are written in this layout.
    fn holds(&self, info: &BlockInfo) -> bool {
        self.full_pose == info.full_pose
            && self.searches == info.searches
            && self.external == info.external
            && self.params == info.params
    }

    /// Adds the columns of `other` that this layout lacks; new parameters follow the
    /// known ones in `other`'s order.
    fn widen(&mut self, other: &Layout) {
        self.full_pose |= other.full_pose;
        self.searches |= other.searches;
        self.external |= other.external;
        for p in &other.params {
            if !self.params.contains(p) {
                self.params.push(p.clone());
            }
        }
    }

    /// The header's columns, after `trial` and `sweep_columns`.
    fn header(&self, sweep_columns: &[String]) -> Vec<String> {
        let mut head = vec!["trial".to_string()];
        head.extend(sweep_columns.iter().cloned());
        head.extend(["method", "poses"].map(String::from));
        let column = |m: Metric| m.column().unwrap_or_default().to_string();
        head.extend(
            [
                Metric::EtaMean,
                Metric::ValidationBeforeMean,
                Metric::ValidationBeforeRms,
            ]
            .map(column),
        );
        head.push("before_max_mm".into());
        head.extend(
            [
                Metric::ValidationAfterMean,
                Metric::ValidationAfterRms,
                Metric::ValidationAfterMax,
            ]
            .map(column),
        );
        if self.full_pose {
            head.extend(["before_mean_deg", "before_rms_deg"].map(String::from));
            head.extend([Metric::DegAfterMean, Metric::DegAfterRms].map(column));
        }
        head.push(column(Metric::Iterations));
        if self.searches {
            head.push(column(Metric::FinalFitness));
        }
        head.push("termination".into());
        head.extend(self.params.iter().map(|n| format!("true_{n}")));
        head.extend(self.params.iter().map(|n| format!("identified_{n}")));
        if self.external {
            head.push("error".into());
        }
        head
    }
}

impl TrialsCsv {
    /// Starts `trials.csv` in the output folder `dir` for the trials of a run of a scenario
    /// with `sweep`.
    pub fn create(dir: &Path, sweep: Option<&Sweep>) -> Result<TrialsCsv> {
        Ok(TrialsCsv::to(
            Rows::Stream(Stream::create(dir, NAME)?),
            sweep,
        ))
    }

    /// `trials.csv` of a run of a scenario with `sweep`, kept in memory.
    pub fn in_memory(sweep: Option<&Sweep>) -> TrialsCsv {
        TrialsCsv::to(Rows::Memory(Vec::new()), sweep)
    }

    /// The bytes written (empty for a file streamed into a folder).
    pub fn into_bytes(self) -> Result<Vec<u8>> {
        let widened = self.widened();
        match self.out {
            Rows::Memory(b) => Widen::bytes(widened, b),
            Rows::Stream(_) => Ok(Vec::new()),
        }
    }

    fn to(out: Rows, sweep: Option<&Sweep>) -> TrialsCsv {
        let sweep_columns = match sweep {
            None => Vec::new(),
            Some(sw) if sw.axes.len() == 1 => vec!["sweep_value".into()],
            Some(sw) => sw.axes.iter().map(|a| a.key.clone()).collect(),
        };
        TrialsCsv {
            out,
            sweep_columns,
            segments: Vec::new(),
        }
    }

    /// The finished file, written under its name with the run's other outputs.
    pub fn finish(self) -> Result<Box<dyn Output>> {
        let widened = self.widened();
        Ok(match self.out {
            Rows::Stream(s) => {
                let done = s.finish()?;
                Box::new(match widened {
                    None => done,
                    Some(plan) => done.rewrite(|from, to| plan.rewrite(from, to))?,
                })
            }
            Rows::Memory(b) => Box::new(Owned {
                bytes: Widen::bytes(widened, b)?,
            }),
        })
    }

    /// How to rewrite the file in the union of its blocks' columns, when they differ.
    fn widened(&self) -> Option<Widen> {
        let (first, _) = self.segments.first()?;
        if self.segments.iter().all(|(l, _)| l == first) {
            return None;
        }
        let mut union = first.clone();
        for (l, _) in &self.segments[1..] {
            union.widen(l);
        }
        let header = union.header(&self.sweep_columns);
        let place = |l: &Layout| -> Vec<usize> {
            let at = |c: &String| header.iter().position(|h| h == c).unwrap_or_default();
            l.header(&self.sweep_columns).iter().map(at).collect()
        };
        Some(Widen {
            segments: self.segments.iter().map(|(l, n)| (place(l), *n)).collect(),
            header,
        })
    }
}

/// The rewrite of a `trials.csv` whose blocks differ in their columns.
struct Widen {
    /// The union's header.
    header: Vec<String>,
    /// Per run of rows of one layout: where each of its columns goes, and its row count.
    segments: Vec<(Vec<usize>, usize)>,
}

impl Widen {
    /// The bytes `b` rewritten by `plan`, if any.
    fn bytes(plan: Option<Widen>, b: Vec<u8>) -> Result<Vec<u8>> {
        let Some(plan) = plan else { return Ok(b) };
        let mut out = Vec::with_capacity(b.len());
        plan.rewrite(&mut b.as_slice(), &mut out)?;
        Ok(out)
    }

    /// Reads the file as written (the first block's header, then every row in its block's
    /// columns) from `from` and writes it in the union's columns to `to`.
    fn rewrite(&self, from: &mut dyn std::io::Read, to: &mut dyn std::io::Write) -> Result<()> {
        let broken = |e: &dyn std::fmt::Display| {
            Error::Compute(format!(
                "{NAME} could not be read back to widen its rows: {e}"
            ))
        };
        let mut rows = csv::ReaderBuilder::new()
            .has_headers(true)
            .flexible(true)
            .from_reader(from)
            .into_records();
        let mut line = self.header.join(",");
        line.push('\n');
        to.write_all(line.as_bytes()).map_err(|e| broken(&e))?;
        let mut cells = vec![String::new(); self.header.len()];
        for (place, n) in &self.segments {
            for _ in 0..*n {
                let row = rows
                    .next()
                    .ok_or_else(|| broken(&"it ended early"))?
                    .map_err(|e| broken(&e))?;
                if row.len() != place.len() {
                    return Err(broken(&format!("a row of {} cells", row.len())));
                }
                cells.iter_mut().for_each(String::clear);
                for (cell, &at) in row.iter().zip(place) {
                    cells[at] = csv_text(cell);
                }
                line.clear();
                line += &cells.join(",");
                line.push('\n');
                to.write_all(line.as_bytes()).map_err(|e| broken(&e))?;
            }
        }
        Ok(())
    }
}

impl TrialSink for TrialsCsv {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        let mut out = String::new();
        match self.segments.last_mut() {
            Some((layout, rows)) if layout.holds(info) => *rows += t.outcomes.len(),
            _ => {
                let layout = Layout::of(info);
                if self.segments.is_empty() {
                    out += &layout.header(&self.sweep_columns).join(",");
                    out.push('\n');
                }
                self.segments.push((layout, t.outcomes.len()));
            }
        }
        // What every row of the trial repeats: its index and sweep point, and the true
        // errors, formatted once.
        let mut lead = t.index.to_string();
        if let Some(p) = &info.point {
            for v in p {
                lead.push(',');
                lead += &v.to_string().replace(',', ";");
            }
        }
        let mut truth = String::new();
        for &v in &t.truth {
            num(&mut truth, v);
        }
        for o in &t.outcomes {
            // As summary.json counts it: without the base's and the undeterminable η.
            let below = t.not_determinable_on(o.strategy);
            let eta_mean = trial_eta_mean(&info.params, (&t.truth, &o.identified), below);
            out += &lead;
            for text in [&info.methods[o.method], &info.strategies[o.strategy]] {
                out.push(',');
                out += &csv_text(text);
            }
            for v in [
                eta_mean,
                o.before_mm.mean,
                o.before_mm.rms,
                o.before_mm.max,
                o.after_mm.mean,
                o.after_mm.rms,
                o.after_mm.max,
            ] {
                num(&mut out, v);
            }
            if info.full_pose {
                let (bd, ad) = (
                    o.optional.validation_before_deg.unwrap_or_default(),
                    o.optional.validation_after_deg.unwrap_or_default(),
                );
                for v in [bd.mean, bd.rms, ad.mean, ad.rms] {
                    num(&mut out, v);
                }
            }
            let _ = write!(out, ",{}", o.iterations);
            if info.searches {
                let fitness = o.search.as_ref().map_or(Real::NAN, |s| s.final_fitness);
                num(&mut out, fitness);
            }
            out.push(',');
            out += o.termination.as_str();
            out += &truth;
            for &v in &o.identified {
                num(&mut out, v);
            }
            if info.external {
                out.push(',');
                out += &csv_text(o.error.as_deref().unwrap_or(""));
            }
            out.push('\n');
        }
        match &mut self.out {
            Rows::Stream(s) => s.append(out.as_bytes()),
            Rows::Memory(b) => {
                b.extend_from_slice(out.as_bytes());
                Ok(())
            }
        }
    }
}

/// `trials.csv` of a run held in memory.
struct Owned {
    bytes: Vec<u8>,
}

impl Output for Owned {
    fn name(&self) -> &str {
        NAME
    }
    fn write(&self, path: &Path) -> Result<()> {
        let bytes = Bytes {
            name: NAME,
            bytes: &self.bytes,
        };
        bytes.write(path)
    }
}

/// `text` as one CSV field: quoted (inner quotes doubled) when it holds a comma, a quote or
/// a line break.
fn csv_text(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

//! `trials.csv` (docs/formats.md `run`): one row per trial × strategy × method, streamed as
//! the trials finish ([`crate::report::output::Stream`]).

use std::fmt::Write as _;
use std::path::Path;

use crate::error::Result;
use crate::numeric::Real;
use crate::report::output::{Bytes, Output, Stream};
use crate::study::metric::Metric;
use crate::study::scenario::Sweep;
use crate::study::stats::eta;
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
/// point), in trial order. The header comes from the first block; one axis adds the column
/// `sweep_value`, a grid one column per swept key. It streams into an output folder
/// ([`TrialsCsv::create`], a [`Stream`] whose memory does not grow with the trials) or, for
/// a run held in memory, to bytes ([`TrialsCsv::in_memory`]): the same bytes.
pub struct TrialsCsv {
    out: Rows,
    sweep_columns: Vec<String>,
    header: bool,
}

/// Where the rows go.
enum Rows {
    Stream(Stream),
    Memory(Vec<u8>),
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
    pub fn into_bytes(self) -> Vec<u8> {
        match self.out {
            Rows::Memory(b) => b,
            Rows::Stream(_) => Vec::new(),
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
            header: false,
        }
    }

    /// The finished file, written under its name with the run's other outputs.
    pub fn finish(self) -> Result<Box<dyn Output>> {
        Ok(match self.out {
            Rows::Stream(s) => Box::new(s.finish()?),
            Rows::Memory(bytes) => Box::new(Owned { bytes }),
        })
    }

    fn header(&self, info: &BlockInfo) -> String {
        let mut head = vec!["trial".to_string()];
        head.extend(self.sweep_columns.iter().cloned());
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
        if info.full_pose {
            head.extend(["before_mean_deg", "before_rms_deg"].map(String::from));
            head.extend([Metric::DegAfterMean, Metric::DegAfterRms].map(column));
        }
        head.push(column(Metric::Iterations));
        if info.searches {
            head.push(column(Metric::FinalFitness));
        }
        head.push("termination".into());
        head.extend(info.params.iter().map(|n| format!("true_{n}")));
        head.extend(info.params.iter().map(|n| format!("identified_{n}")));
        if info.external {
            head.push("error".into());
        }
        head.join(",") + "\n"
    }
}

impl TrialSink for TrialsCsv {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        let mut out = String::new();
        if !self.header {
            out += &self.header(info);
            self.header = true;
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
            let etas: Vec<Real> = t
                .truth
                .iter()
                .zip(&o.identified)
                .filter_map(|(&x, &y)| eta(x, y))
                .collect();
            let eta_mean = if etas.is_empty() {
                Real::NAN
            } else {
                etas.iter().sum::<Real>() / etas.len() as Real
            };
            out += &lead;
            for text in [&info.methods[o.method], &info.strategies[o.strategy]] {
                out.push(',');
                out += text;
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

//! `trials.csv` (docs/formats.md `run`): one row per trial × strategy × method, written as
//! the trials finish.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::study::scenario::Sweep;
use crate::study::stats::eta;
use crate::study::{BlockInfo, TrialResult, TrialSink};

fn num(v: Real) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// `trials.csv`, written as trials finish: one row per trial × strategy × method (× sweep
/// point), in trial order. The header comes from the first block; one axis adds the column
/// `sweep_value`, a grid one column per swept key. It goes to a file ([`TrialsCsv::create`])
/// or, for a run held in memory, to bytes ([`TrialsCsv::in_memory`]): the same bytes.
pub struct TrialsCsv<W: std::io::Write = std::io::BufWriter<std::fs::File>> {
    path: PathBuf,
    out: W,
    sweep_columns: Vec<String>,
    header: bool,
}

impl TrialsCsv {
    /// Creates `path` for the trials of a run of a scenario with `sweep`.
    pub fn create(path: &Path, sweep: Option<&Sweep>) -> Result<TrialsCsv> {
        let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
        Ok(TrialsCsv::to(path, std::io::BufWriter::new(file), sweep))
    }
}

impl TrialsCsv<Vec<u8>> {
    /// `trials.csv` of a run of a scenario with `sweep`, kept in memory.
    pub fn in_memory(sweep: Option<&Sweep>) -> TrialsCsv<Vec<u8>> {
        TrialsCsv::to(Path::new("trials.csv"), Vec::new(), sweep)
    }

    /// The bytes written.
    pub fn into_bytes(self) -> Vec<u8> {
        self.out
    }
}

impl<W: std::io::Write> TrialsCsv<W> {
    fn to(path: &Path, out: W, sweep: Option<&Sweep>) -> TrialsCsv<W> {
        let sweep_columns = match sweep {
            None => Vec::new(),
            Some(sw) if sw.axes.len() == 1 => vec!["sweep_value".into()],
            Some(sw) => sw.axes.iter().map(|a| a.key.clone()).collect(),
        };
        TrialsCsv {
            path: path.to_path_buf(),
            out,
            sweep_columns,
            header: false,
        }
    }

    /// Flushes the file.
    pub fn finish(mut self) -> Result<()> {
        self.out.flush().map_err(|e| Error::io(&self.path, e))
    }

    fn header(&self, info: &BlockInfo) -> String {
        let mut head = vec!["trial".to_string()];
        head.extend(self.sweep_columns.iter().cloned());
        head.extend(
            [
                "method",
                "poses",
                "eta_mean_pct",
                "before_mean_mm",
                "before_rms_mm",
                "before_max_mm",
                "after_mean_mm",
                "after_rms_mm",
                "after_max_mm",
            ]
            .map(String::from),
        );
        if info.full_pose {
            head.extend(
                [
                    "before_mean_deg",
                    "before_rms_deg",
                    "after_mean_deg",
                    "after_rms_deg",
                ]
                .map(String::from),
            );
        }
        head.extend(["iterations", "termination"].map(String::from));
        head.extend(info.params.iter().map(|n| format!("true_{n}")));
        head.extend(info.params.iter().map(|n| format!("identified_{n}")));
        if info.external {
            head.push("error".into());
        }
        head.join(",") + "\n"
    }
}

impl<W: std::io::Write> TrialSink for TrialsCsv<W> {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        let mut out = String::new();
        if !self.header {
            out += &self.header(info);
            self.header = true;
        }
        for o in &t.outcomes {
            let mut row = vec![t.index.to_string()];
            if let Some(p) = &info.point {
                row.extend(p.iter().map(|v| v.to_string().replace(',', ";")));
            }
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
            row.push(info.methods[o.method].clone());
            row.push(info.strategies[o.strategy].clone());
            for v in [
                eta_mean,
                o.before_mm.mean,
                o.before_mm.rms,
                o.before_mm.max,
                o.after_mm.mean,
                o.after_mm.rms,
                o.after_mm.max,
            ] {
                row.push(num(v));
            }
            if info.full_pose {
                let (bd, ad) = (
                    o.optional.validation_before_deg.unwrap_or_default(),
                    o.optional.validation_after_deg.unwrap_or_default(),
                );
                for v in [bd.mean, bd.rms, ad.mean, ad.rms] {
                    row.push(num(v));
                }
            }
            row.push(o.iterations.to_string());
            row.push(o.termination.as_str().into());
            row.extend(t.truth.iter().map(|&v| num(v)));
            row.extend(o.identified.iter().map(|&v| num(v)));
            if info.external {
                row.push(csv_text(o.error.as_deref().unwrap_or("")));
            }
            out += &row.join(",");
            out.push('\n');
        }
        self.out
            .write_all(out.as_bytes())
            .map_err(|e| Error::io(&self.path, e))
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

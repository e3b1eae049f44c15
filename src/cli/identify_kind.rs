//! `calbench identify` on a measurement-kind file (docs/formats.md § 5.3: `length_mm`,
//! `step_mm`, `plane`, `sphere` or `target` readings): the outcome of the pipeline
//! ([`calbench::calibrate::request`]) handed to the report's writers (`identified.json`,
//! `robot.toml`), with the validation table and a summary line.

use std::path::Path;

use anyhow::Result;

use calbench::calibrate::on_kind::KindOutcome;
use calbench::calibrate::ErrorStats;
use calbench::report::write_kind;

/// The files written.
pub const OUTPUTS: [&str; 2] = ["identified.json", "robot.toml"];

/// Writes the output folder of the identification `o` and prints its warning, the
/// validation table (with `--validate`, a tracker's file) and a summary line.
pub fn write(out: &Path, o: &KindOutcome) -> Result<()> {
    for w in o.warnings() {
        eprintln!("warning: {}", w.spell(super::spell));
    }
    if let Some(w) = calbench::calibrate::record::unconverged_warning(&o.record) {
        eprintln!("warning: {w}");
    }
    write_kind(out, &o.record, &o.compensated(), &[])?;
    if let Some((before, after)) = &o.validation {
        print_validation(before, after);
    }
    let kind = o.kind.as_str();
    let unidentifiable = &o.fit.analysis.unidentifiable;
    if !unidentifiable.is_empty() {
        let left = if o.identifiable {
            " (left at their nominal values)"
        } else {
            ""
        };
        let names: Vec<String> = unidentifiable.iter().map(|p| p.to_string()).collect();
        out!(
            "not determined by these {kind} readings{left}: {}",
            names.join(" ")
        );
    }
    let r = &o.fit.identified;
    out!(
        "{} on {} {kind} readings: {} after {}; written to {}",
        o.record.method,
        o.readings,
        r.termination.as_str(),
        calbench::error::counted(r.iterations, "iteration", "iterations"),
        out.display()
    );
    Ok(())
}

/// Prints the validation table: the position errors before and after (mm).
pub(super) fn print_validation(before: &ErrorStats, after: &ErrorStats) {
    out!("validation error (mm)   mean      rms       max       std");
    for (label, s) in [("before", before), ("after", after)] {
        out!(
            "  {label:<8} {:>10.4} {:>9.4} {:>9.4} {:>9.4}",
            s.mean,
            s.rms,
            s.max,
            s.std
        );
    }
}

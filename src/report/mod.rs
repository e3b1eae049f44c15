//! Every writer of calbench's output files (FORMATS.md): [`run`] writes a run's
//! `summary.json`, `trials.csv`, `report.md` and plots; [`identified`] the files of
//! `calbench identify`.
//!
//! The report only reads results that are already computed (DESIGN.md). [`plots`] draws the
//! figures of the source papers — η per parameter per method (Guo 2024, fig. 8), validation
//! error per point before and after calibration (Li 2018, fig. 3; Ban, fig. 7), validation
//! RMS over trials per method, objective or fitness per iteration (Qiao 2021; Guo 2024,
//! DETMAX-IDE) and a metric against a swept setting — each to `<stem>.png` and `<stem>.svg`.
//! [`markdown`] formats tables and numbers for `report.md`.
//!
//! Text is drawn with the bundled DejaVu Sans (`assets/DejaVuSans.ttf`, registered once as
//! family `sans-serif`), so plots render the same on every machine without system font
//! libraries, and the same data gives the same bytes.

pub mod identified;
pub mod markdown;
pub mod plots;
pub mod run;

pub use markdown::{fmt_num, table};
pub use plots::{
    before_after, box_plot, box_stats, grouped_bars, sweep, traces, BoxStats, SweepSeries,
    PLOT_SIZE,
};
pub use run::{columns, entry_table, summary, trials_csv, write_all, Column};

//! Where a running study's progress and warnings go. Nothing in the library prints: a run
//! hands them to the [`Reporter`] its caller supplies — the command line and the Python
//! module pass [`Terminal`] (a progress bar on stderr when it is a terminal, warnings as
//! `warning: …` lines), a test or an embedding program [`Silent`] or its own.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};

/// The receiver of a run's progress and warnings.
pub trait Reporter: Sync {
    /// A warning about the run (not an error: the run goes on).
    fn warning(&self, text: &str);
    /// The progress of a run of `total` trials, advanced as they finish.
    fn progress(&self, total: u64) -> Box<dyn Progress + '_>;
}

/// The progress of one run (shared by its worker threads).
pub trait Progress: Sync {
    /// `n` more trials are done.
    fn inc(&self, n: u64);
    /// What runs now (the sweep point).
    fn message(&self, text: &str);
    /// The run is over: the progress is cleared.
    fn finish(&self);
}

/// A reporter that shows nothing.
pub struct Silent;

/// A progress that shows nothing.
pub struct NoProgress;

impl Progress for NoProgress {
    fn inc(&self, _: u64) {}
    fn message(&self, _: &str) {}
    fn finish(&self) {}
}

impl Reporter for Silent {
    fn warning(&self, _: &str) {}
    fn progress(&self, _: u64) -> Box<dyn Progress + '_> {
        Box::new(NoProgress)
    }
}

/// The terminal's reporter: warnings on stderr (`warning: TEXT`), and a progress bar on
/// stderr when stderr is a terminal.
pub struct Terminal;

impl Progress for ProgressBar {
    fn inc(&self, n: u64) {
        ProgressBar::inc(self, n);
    }
    fn message(&self, text: &str) {
        self.set_message(text.to_string());
    }
    fn finish(&self) {
        self.finish_and_clear();
    }
}

impl Reporter for Terminal {
    fn warning(&self, text: &str) {
        eprintln!("warning: {text}");
    }

    fn progress(&self, total: u64) -> Box<dyn Progress + '_> {
        if !std::io::stderr().is_terminal() {
            return Box::new(NoProgress);
        }
        let b = ProgressBar::new(total);
        if let Ok(style) = ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} trials ({per_sec}, {eta} left) {msg}",
        ) {
            b.set_style(style);
        }
        Box::new(b)
    }
}

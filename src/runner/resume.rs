//! The resume of a killed run (`calbench run --resume DIR`): its checkpoint checked
//! ([`Resumable::open`]) and what continuing it needs ([`Resumable::continued`]), for a
//! Monte-Carlo study and a study of cells alike ([`super::whole::resume`]).

use std::path::{Path, PathBuf};

use super::checkpoint::{self, Checkpoint};
use crate::error::Result;
use crate::study::kind::AnyScenario;
use crate::study::{RunOptions, Shard};

/// The checkpoint of a killed run, checked and ready to continue ([`super::whole::resume`]).
pub struct Resumable {
    pub(super) out: PathBuf,
    pub(super) checkpoint: Checkpoint,
    pub(super) scenario: AnyScenario,
    pub(super) shard: Option<Shard>,
    pub(super) records: checkpoint::Records,
}

impl Resumable {
    /// Opens the checkpoint of the run into `out` that was killed (`calbench run --resume
    /// DIR`, [`checkpoint`]): it must be of this binary's version and, when `given`, of that
    /// scenario, its writer no longer running on this host (unless `force`), and every
    /// record it counts intact. A refused checkpoint is left as it was.
    pub fn open(out: &Path, given: Option<&AnyScenario>, force: bool) -> Result<Resumable> {
        let (checkpoint, scenario, shard, records) = Checkpoint::resume(out, given, force)?;
        Ok(Resumable {
            out: out.to_path_buf(),
            checkpoint,
            scenario,
            shard,
            records,
        })
    }

    /// The trials of the run (per block of a Monte-Carlo study, of every cell of a study of
    /// cells).
    pub fn trials(&self) -> usize {
        self.scenario.trials()
    }

    /// The files the continued run writes into its folder, checked before it continues
    /// ([`crate::report::run::checked_outputs`]): a whole run's or a shard's.
    pub fn outputs(&self) -> &'static [&'static str] {
        let monte_carlo = matches!(self.scenario, AnyScenario::MonteCarlo(_));
        crate::report::run::checked_outputs(monte_carlo, self.shard.is_some())
    }
}

/// What continuing a killed run needs ([`Resumable::continued`]).
pub struct Continued {
    /// Its output folder.
    pub out: PathBuf,
    /// Its options: the folder, shard and precision of the killed run.
    pub opts: RunOptions,
    /// Its checkpoint, which the continued run goes on writing.
    pub checkpoint: Checkpoint,
    /// Its scenario.
    pub scenario: AnyScenario,
    /// The records of the trials it ran, replayed first.
    pub records: checkpoint::Records,
}

impl Resumable {
    /// The killed run ready to continue on `threads` worker threads, with the progress shown.
    pub fn continued(self, threads: Option<usize>) -> Result<Continued> {
        let opts = RunOptions {
            threads,
            out: Some(self.out.clone()),
            progress: true,
            shard: self.shard,
            precision: self.checkpoint.precision()?,
        };
        Ok(Continued {
            out: self.out,
            opts,
            checkpoint: self.checkpoint,
            scenario: self.scenario,
            records: self.records,
        })
    }
}

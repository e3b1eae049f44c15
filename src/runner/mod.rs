//! Running a study: trials in chunks on rayon, in order, into the statistics and the sinks,
//! with the output folder written whole through the report's writers ([`run`]); the
//! checkpoint beside a running study and the resume of a killed one ([`checkpoint`]); a share
//! of the work and the merge of every share ([`shard`]). This layer sits above both
//! [`crate::study`] (the scenario, one trial, the statistics, the record format) and
//! [`crate::report`] (the files), and nothing below it imports it.

mod as_run;
pub mod cells;
pub mod checkpoint;
pub mod resume;
pub mod run;
pub mod shard;
pub mod threads;
pub mod whole;

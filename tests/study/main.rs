//! Monte-Carlo studies: the harness end to end (files, determinism, the CI regression guard),
//! sweeps and sharded runs, and the report's plots.

#[path = "../common/mod.rs"]
mod common;

mod claims;
mod harness;
mod intervals;
mod report;
mod summary;
mod sweeps;
mod unmodelled;

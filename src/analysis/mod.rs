//! The analysis of a run (docs/architecture.md): what its trials say — the entries' figures
//! with their intervals, the paired comparisons, the claims' verdicts, the performance
//! profile — decided once ([`analyse::analyse`]) into a typed [`summary::Summary`], which the
//! report renders and every reader of a run deserialises; and the regression rule of `check`,
//! `compare` and `history` ([`regression`]).

pub mod analyse;
pub mod claims;
pub mod comparisons;
pub mod figures;
pub mod idle;
pub mod regression;
pub mod summary;

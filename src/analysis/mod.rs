//! The analysis of finished results, between the studies that produce them and the reports that render them: the regression rule of `check`, `compare` and `history` ([`regression`]).

pub mod regression;

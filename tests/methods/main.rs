//! Identification methods and pose selection: Qiao 2021's pose-error models and searches
//! (BAS, PSO, BAS-PSO), Guo 2024's full model and parameter separation, and DETMAX/IDE pose
//! selection.

#[path = "../common/mod.rs"]
mod common;

mod errmodel;
mod guo;
mod igg3_coordinate;
mod metaheur;
mod options;
mod poses;

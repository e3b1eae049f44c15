//! The measurement model: forward kinematics and the identification Jacobian, the
//! elasto-geometric (compliance) model, tracker registration alternating with identification,
//! and per-point weights.

#[path = "../common/mod.rs"]
mod common;

mod alloc;
mod compliance;
mod kinematics;
mod registration;
mod weights;

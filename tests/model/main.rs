//! The measurement model: forward kinematics and the identification Jacobian, the
//! elasto-geometric (compliance) model, tracker registration alternating with identification,
//! and per-point weights.

#[path = "../common/mod.rs"]
mod common;

mod alloc;
mod compliance;
mod compliance_payload;
#[cfg(all(target_arch = "x86_64", target_os = "linux", target_env = "gnu"))]
mod fma;
mod kinematics;
mod registration;
mod urdf_chain;
mod weights;

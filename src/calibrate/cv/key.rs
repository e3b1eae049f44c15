//! What a cross-validation is of, as one value: two cross-validations with equal keys are
//! the same computation and give the same figures to the bit, so one that ran may stand for
//! the other ([`super::CvSetup::done`]).

use sha2::{Digest, Sha256};

use super::{CvModel, CvSetup};
use crate::calibrate::Registration;
use crate::measurement::Measurements;
use crate::numeric::Real;
use crate::robot::{Param, Robot};

/// Everything that changes a fold's fit or its held-out errors: the model (its robot, the
/// parameters identified, those the re-check at the identified robot may re-admit, the
/// kernel residual), the method with every setting, its orientation weight and priors, the
/// registration, the method's seed, the folds and their seed, and the rows (joint values,
/// points, orientations, σ and payloads, by their SHA-256). Fixed parameters enter through
/// the parameters and candidates they remove. `None` for a method supplied from outside,
/// whose settings calbench cannot read: its cross-validations are never taken for another.
#[derive(Clone, Debug, PartialEq)]
pub struct CvKey {
    robot: Robot,
    params: Vec<Param>,
    candidates: Vec<Param>,
    kernel: bool,
    /// The method's name, its settings (their `Debug` form: every option, numbers to the
    /// bit), its orientation weight and its priors (to the bit).
    method: (&'static str, String, u64, Vec<(Param, u64)>),
    registration: Registration,
    seed: u64,
    folds: usize,
    fold_seed: u64,
    rows: [u8; 32],
}

impl CvKey {
    /// The key of the `folds`-fold cross-validation of `m` on `data` by `s`.
    pub fn of(m: &CvModel, data: &Measurements, folds: usize, s: &CvSetup) -> Option<CvKey> {
        if s.method.is_external() {
            return None;
        }
        let priors = s.method.priors.iter().map(|&(p, v)| (p, v.to_bits()));
        Some(CvKey {
            robot: m.robot.clone(),
            params: m.params.to_vec(),
            candidates: m.candidates.to_vec(),
            kernel: m.kernel,
            method: (
                s.method.name,
                format!("{:?}", s.method.method),
                s.method.k.to_bits(),
                priors.collect(),
            ),
            registration: s.registration,
            seed: s.seed,
            folds,
            fold_seed: s.fold_seed,
            rows: rows_digest(data),
        })
    }
}

/// The SHA-256 of every row of `m`, by the bits of its numbers (which columns are present
/// included).
fn rows_digest(m: &Measurements) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update((m.len() as u64).to_le_bytes());
    for (q, p) in m.qs.iter().zip(&m.points) {
        h.update((q.len() as u64).to_le_bytes());
        for v in q.iter().chain(p.iter()) {
            h.update(v.to_bits().to_le_bytes());
        }
    }
    column(&mut h, m.quats.as_ref().map(|q| q.iter().flatten()));
    column(&mut h, m.sigma_mm.as_ref().map(|v| v.iter()));
    column(&mut h, m.payload_kg.as_ref().map(|v| v.iter()));
    h.finalize().into()
}

/// An optional column into `h`: a byte for its presence, then its numbers' bits.
fn column<'a>(h: &mut Sha256, c: Option<impl Iterator<Item = &'a Real>>) {
    match c {
        None => h.update([0u8]),
        Some(v) => {
            h.update([1u8]);
            for x in v {
                h.update(x.to_bits().to_le_bytes());
            }
        }
    }
}

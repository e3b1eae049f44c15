//! The one run-time choice of instruction set for every numeric kernel.
//!
//! [`detected`] asks the processor once whether it has AVX2 and FMA and keeps the answer;
//! [`dispatch`] runs a kernel compiled for that [`Isa`] and hands it the `Isa`. A kernel
//! written in plain Rust ignores the argument: inlined into a function built with AVX2 and
//! FMA, its loops over small arrays of lanes become four-wide vector instructions and
//! `mul_add` one instruction. A kernel with explicit vector intrinsics matches on it: the
//! [`Isa::Avx2Fma`] variant carries an [`Avx2Fma`] token that only this module makes, after
//! the check, so holding one is the proof the intrinsics need.
//!
//! The results are the same bits on either path. Rust never fuses a multiplication and an
//! addition on its own (no floating-point contraction), `mul_add` is the correctly rounded
//! IEEE fused multiply-add on every machine (an instruction where the processor has one, a
//! library call where not), and each kernel fixes the order of its operations (lanes, partial
//! sums) independently of the vector width. Every kernel's tests run it on each path that
//! the processor offers ([`available`], and `forced` in tests) and compare the bits.

#[cfg(target_arch = "x86_64")]
use std::sync::atomic::{AtomicU8, Ordering};

/// The instruction set a kernel runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Isa {
    /// Plain Rust for the target the crate was built for.
    Portable,
    /// x86-64 with AVX2 and FMA, with the token that proves the processor has both.
    #[cfg(target_arch = "x86_64")]
    Avx2Fma(Avx2Fma),
}

/// Proof that the processor has AVX2 and FMA: made only by [`detected`] after checking.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Avx2Fma(());

/// [`detected`]'s answer: not asked yet, portable, AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
static DETECTED: AtomicU8 = AtomicU8::new(UNKNOWN);
#[cfg(target_arch = "x86_64")]
const UNKNOWN: u8 = 0;
#[cfg(target_arch = "x86_64")]
const PORTABLE: u8 = 1;
#[cfg(target_arch = "x86_64")]
const AVX2_FMA: u8 = 2;

/// The environment variable that chooses the instruction set: `scalar` forces the portable
/// path, `auto` (or unset, or empty) takes the best one the processor has (docs/formats.md).
pub const SIMD_VARIABLE: &str = "CALBENCH_SIMD";

/// Whether [`SIMD_VARIABLE`] forces the portable path: `Ok(true)` for `scalar`, `Ok(false)`
/// for `auto`, empty or unset, and an error naming the variable and its allowed values
/// otherwise. Programs call it once at start to refuse a misspelt value; the kernels read
/// the same answer.
pub fn simd_forced_scalar() -> Result<bool, String> {
    match std::env::var(SIMD_VARIABLE) {
        Err(std::env::VarError::NotPresent) => Ok(false),
        Ok(v) if v.is_empty() || v == "auto" => Ok(false),
        Ok(v) if v == "scalar" => Ok(true),
        Ok(v) => Err(format!(
            "environment variable {SIMD_VARIABLE}=\"{v}\": allowed values are \"scalar\" \
             (the portable path) and \"auto\" (the best path of this processor)"
        )),
        Err(e) => Err(format!("environment variable {SIMD_VARIABLE}: {e}")),
    }
}

/// The best instruction set of this processor, checked on the first call and kept; the
/// portable one if [`SIMD_VARIABLE`] is `scalar`.
///
/// # Panics
/// If [`SIMD_VARIABLE`] holds another value than those of [`simd_forced_scalar`] (the
/// command line refuses it before any kernel runs).
#[inline]
pub(crate) fn detected() -> Isa {
    #[cfg(target_arch = "x86_64")]
    {
        let mut v = DETECTED.load(Ordering::Relaxed);
        if v == UNKNOWN {
            let scalar = simd_forced_scalar().unwrap_or_else(|e| panic!("{e}"));
            let both = std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma");
            v = if both && !scalar { AVX2_FMA } else { PORTABLE };
            DETECTED.store(v, Ordering::Relaxed);
        }
        if v == AVX2_FMA {
            return Isa::Avx2Fma(Avx2Fma(()));
        }
    }
    Isa::Portable
}

/// Every instruction set this processor can run, the portable one first.
#[cfg(test)]
pub(crate) fn available() -> Vec<Isa> {
    let mut all = vec![Isa::Portable];
    if detected() != Isa::Portable {
        all.push(detected());
    }
    all
}

/// `kernel(isa)`, compiled for the instruction set of [`detected`] (or, in tests, the one
/// that `forced` sets): `kernel` and what it calls with `#[inline(always)]` are inlined into
/// a function built with that instruction set's target features.
#[inline(always)]
pub(crate) fn dispatch<R>(kernel: impl FnOnce(Isa) -> R) -> R {
    #[cfg(test)]
    if let Some(isa) = FORCED.get() {
        return run(isa, kernel);
    }
    run(detected(), kernel)
}

/// `kernel` compiled for `isa`, and handed it.
#[inline(always)]
fn run<R>(isa: Isa, kernel: impl FnOnce(Isa) -> R) -> R {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2Fma(token) => {
            /// `kernel(Isa::Avx2Fma(token))` with AVX2 and FMA enabled.
            ///
            /// # Safety
            /// The CPU must support AVX2 and FMA.
            #[target_feature(enable = "avx2,fma")]
            unsafe fn avx2_fma<R>(token: Avx2Fma, kernel: impl FnOnce(Isa) -> R) -> R {
                kernel(Isa::Avx2Fma(token))
            }
            // SAFETY: the token exists, so the processor has AVX2 and FMA.
            unsafe { avx2_fma(token, kernel) }
        }
        Isa::Portable => kernel(Isa::Portable),
    }
}

#[cfg(test)]
thread_local! {
    /// The instruction set [`dispatch`] uses on this thread instead of the detected one.
    static FORCED: std::cell::Cell<Option<Isa>> = const { std::cell::Cell::new(None) };
}

/// `f()` with every kernel on this thread dispatched to `isa` (one of [`available`]).
#[cfg(test)]
pub(crate) fn forced<R>(isa: Isa, f: impl FnOnce() -> R) -> R {
    let before = FORCED.replace(Some(isa));
    let r = f();
    FORCED.set(before);
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dispatch_hands_the_kernel_the_chosen_path() {
        assert_eq!(available()[0], Isa::Portable);
        for isa in available() {
            assert_eq!(forced(isa, || dispatch(|got| got)), isa);
        }
        assert_eq!(dispatch(|got| got), detected());
        assert_eq!(detected(), detected());
    }
}

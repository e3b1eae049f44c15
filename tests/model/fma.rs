//! The chain walk's multiply-adds run as instructions where the processor has FMA
//! (docs/performance.md, "The chain walk's sine"): `mul_add` compiled without the FMA
//! instruction is a call into the math library's software `fma`, several times slower in the
//! walk, and the results are the same bits either way, so only a count shows it.
//!
//! The test crate defines the C function `fma` that such code calls: it counts the calls of
//! the calling thread and forwards each to the math library's own (`dlsym(RTLD_NEXT)`).

use std::cell::Cell;
use std::ffi::{c_char, c_void};
use std::hint::black_box;
use std::sync::OnceLock;

use calbench::numeric::{self, Real};
use calbench::robot::builtin;

thread_local! {
    static FMA_CALLS: Cell<u64> = const { Cell::new(0) };
}

extern "C" {
    fn dlsym(handle: *mut c_void, symbol: *const c_char) -> *mut c_void;
}

/// The math library's `fma`, the next definition after this program's.
fn library_fma() -> extern "C" fn(f64, f64, f64) -> f64 {
    static NEXT: OnceLock<usize> = OnceLock::new();
    let at = *NEXT.get_or_init(|| {
        // SAFETY: `RTLD_NEXT` (-1 in glibc) and a NUL-terminated name.
        let f = unsafe { dlsym(-1isize as *mut c_void, c"fma".as_ptr()) };
        assert!(!f.is_null(), "the math library's fma not found");
        f as usize
    });
    // SAFETY: `at` is the address of the C function `double fma(double, double, double)`.
    unsafe { std::mem::transmute::<usize, extern "C" fn(f64, f64, f64) -> f64>(at) }
}

/// Every `mul_add` of this program compiled without the FMA instruction calls this `fma`.
#[no_mangle]
pub extern "C" fn fma(x: f64, y: f64, z: f64) -> f64 {
    let _ = FMA_CALLS.try_with(|c| c.set(c.get() + 1));
    library_fma()(x, y, z)
}

/// The calls of the software `fma` that `f` makes on this thread.
fn fma_calls<T>(f: impl FnOnce() -> T) -> u64 {
    let before = FMA_CALLS.with(Cell::get);
    black_box(f());
    FMA_CALLS.with(Cell::get) - before
}

#[test]
fn the_chain_walk_calls_no_software_fma() {
    // The count sees a `mul_add` compiled without FMA, and returns the correctly rounded value.
    let (x, y, z) = (
        black_box(1.0 + Real::EPSILON),
        black_box(1.0 - Real::EPSILON),
        -1.0,
    );
    let mut v = 0.0;
    assert_eq!(fma_calls(|| v = x.mul_add(y, black_box(z))), 1);
    assert_eq!(v, -Real::EPSILON * Real::EPSILON);
    let robot = builtin::irb2600();
    let chain = robot.chain();
    let q: [Real; 6] = [0.3, -0.7, 0.9, 1.1, -0.4, 2.0];
    let mut sc = [(0.0, 0.0); 6];
    let walk = fma_calls(|| chain.fk(&q));
    let one = fma_calls(|| numeric::sin_cos(black_box(0.7)));
    let slice = fma_calls(|| numeric::sin_cos_slice(&q, &mut sc));
    let fma_path = std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma")
        && !numeric::simd_forced_scalar().unwrap();
    if fma_path {
        assert_eq!(
            (walk, one, slice),
            (0, 0, 0),
            "software fma calls of the walk, of numeric::sin_cos and of numeric::sin_cos_slice \
             on a processor with FMA: a multiply-add runs outside the FMA-compiled dispatch \
             (numeric/simd.rs)"
        );
    } else {
        // The portable path: the same bits through the software fma.
        assert!(walk > 0 && one > 0 && slice > 0, "{walk} {one} {slice}");
    }
}

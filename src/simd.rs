//! Runtime dispatch to the widest vector instructions this CPU has, for the
//! batch loops: the kernels are written once, as branch-free scalar code
//! without library calls, and the compiler vectorises the loop that calls
//! them when it is compiled for AVX2 + FMA.
//!
//! This module holds the crate's only `unsafe`: calling a function compiled
//! for AVX2 + FMA, which is sound because the CPU was just checked to have
//! both. Results do not depend on the path taken: no floating-point
//! contraction is enabled, so each operation rounds the same way.

/// Runs `f`, compiled for AVX2 + FMA when the CPU has them (x86-64), else
/// for the baseline target. Mark the closure `#[inline(always)]` so that
/// its body is compiled inside the dispatching function.
#[inline(always)]
pub fn dispatch<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        #[allow(unsafe_code)]
        // SAFETY: the CPU supports AVX2 and FMA, checked just above.
        return unsafe { avx2_fma(f) };
    }
    f()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn avx2_fma<R>(f: impl FnOnce() -> R) -> R {
    f()
}

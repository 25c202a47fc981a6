//! Runtime dispatch to the widest vector instructions this CPU has, for the
//! batch loops: the kernels are written once, as branch-free scalar code
//! without library calls, and the compiler vectorises the loop that calls
//! them when it is compiled for AVX-512 or AVX2 + FMA.
//!
//! This module holds the crate's only `unsafe`: calling a function compiled
//! for an instruction set, which is sound because the CPU was just checked
//! to have it. Results do not depend on the path taken: no floating-point
//! contraction is enabled, so each operation rounds the same way.

/// Runs `f` compiled for the widest vector unit this CPU has: AVX-512
/// (F, VL, DQ, BW), else AVX2 + FMA (x86-64), else the baseline target.
/// Mark the closure `#[inline(always)]` so that its body is compiled inside
/// the dispatching function.
#[inline(always)]
pub fn dispatch<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("avx512f") && has!("avx512vl") && has!("avx512dq") && has!("avx512bw") {
            #[allow(unsafe_code)]
            // SAFETY: the CPU supports these AVX-512 subsets, checked just above.
            return unsafe { avx512(f) };
        }
        if has!("avx2") && has!("fma") {
            #[allow(unsafe_code)]
            // SAFETY: the CPU supports AVX2 and FMA, checked just above.
            return unsafe { avx2_fma(f) };
        }
    }
    f()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
fn avx512<R>(f: impl FnOnce() -> R) -> R {
    f()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn avx2_fma<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Rows per block of [`map_rows`].
const BLOCK: usize = 64;

/// `out[i] = kernel(inputs[i])` for every row, compiled for the widest
/// vector unit (see [`dispatch`]); returns whether `valid` holds for every
/// input row. Both closures must be branch-free for the loop to vectorise.
///
/// Rows are interleaved (`[x, y]`, `[x, y, z]`), which the vectoriser
/// handles only at half width; each block of [`BLOCK`] rows is therefore
/// transposed into one array per component, mapped at full width, and
/// transposed back.
#[inline(always)]
pub fn map_rows<F, T, const K: usize, const M: usize>(
    out: &mut [[T; M]],
    inputs: &[[F; K]],
    kernel: &impl Fn([F; K]) -> [T; M],
    valid: impl Fn(&[F; K]) -> bool,
) -> bool
where
    F: Copy + Default,
    T: Copy + Default,
{
    dispatch(
        #[inline(always)]
        || {
            let mut ok = true;
            for (out, inputs) in out.chunks_mut(BLOCK).zip(inputs.chunks(BLOCK)) {
                let mut columns = [[F::default(); BLOCK]; K];
                for (i, u) in inputs.iter().enumerate() {
                    ok &= valid(u);
                    for k in 0..K {
                        columns[k][i] = u[k];
                    }
                }
                let mut results = [[T::default(); BLOCK]; M];
                for i in 0..BLOCK {
                    let r = kernel(std::array::from_fn(|k| columns[k][i]));
                    for m in 0..M {
                        results[m][i] = r[m];
                    }
                }
                for (i, o) in out.iter_mut().enumerate() {
                    *o = std::array::from_fn(|m| results[m][i]);
                }
            }
            ok
        },
    )
}

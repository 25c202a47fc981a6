//! Runtime dispatch to the widest vector instructions this CPU has, for the
//! batch loops: the kernels are written once, as branch-free scalar code
//! without library calls, and the compiler vectorises the loop that calls
//! them when it is compiled for AVX-512 or AVX2 + FMA.
//!
//! This module holds the crate's only `unsafe`: calling a function compiled
//! for an instruction set, which is sound because the CPU was just checked
//! to have it, and the non-temporal stores of large outputs (raw-pointer
//! intrinsics, bounds and alignment argued at each use), and cache prefetch
//! hints. Results do not
//! depend on the path taken: no floating-point contraction is enabled, so
//! each operation rounds the same way.

/// Name of the environment variable that caps the instruction set batch
/// loops use: `avx512`, `avx2` or `baseline` (for tests and debugging;
/// results are the same bits on every path).
pub const SIMD_VAR: &str = "MCSAMPLE_SIMD";

/// The instruction sets [`dispatch`] can use, widest last.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// The target's baseline (SSE2 on x86-64).
    Baseline,
    /// AVX2 and FMA.
    Avx2,
    /// AVX-512 F, VL, DQ and BW.
    Avx512,
}

/// The widest [`Level`] this CPU has, capped by `MCSAMPLE_SIMD` (read once).
pub fn level() -> Level {
    static LEVEL: std::sync::OnceLock<Level> = std::sync::OnceLock::new();
    *LEVEL.get_or_init(|| {
        let cap = match std::env::var(SIMD_VAR).as_deref() {
            Ok("baseline") => Level::Baseline,
            Ok("avx2") => Level::Avx2,
            _ => Level::Avx512,
        };
        detected().min(cap)
    })
}

fn detected() -> Level {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("avx512f") && has!("avx512vl") && has!("avx512dq") && has!("avx512bw") {
            return Level::Avx512;
        }
        if has!("avx2") && has!("fma") {
            return Level::Avx2;
        }
    }
    Level::Baseline
}

/// Runs `f` compiled for the widest vector unit this CPU has ([`level`]):
/// AVX-512 (F, VL, DQ, BW), else AVX2 + FMA (x86-64), else the baseline
/// target. Mark the closure `#[inline(always)]` so that its body is
/// compiled inside the dispatching function.
#[inline(always)]
pub fn dispatch<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    match level() {
        #[allow(unsafe_code)]
        // SAFETY: `level` reports AVX-512 only when the CPU has these subsets.
        Level::Avx512 => return unsafe { avx512(f) },
        #[allow(unsafe_code)]
        // SAFETY: `level` reports AVX2 only when the CPU has AVX2 and FMA.
        Level::Avx2 => return unsafe { avx2_fma(f) },
        Level::Baseline => {}
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

/// Asks the CPU to bring `data[index]` into the caches ahead of its use. A
/// hint: it never faults (an index out of bounds is harmless) and does
/// nothing on targets without the instruction.
#[inline(always)]
pub fn prefetch<T>(data: &[T], index: usize) {
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    // SAFETY: a prefetch reads nothing the program can observe and never
    // faults, whatever the address.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(data.as_ptr().wrapping_add(index).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (data, index);
}

/// Rows per block of [`map_rows`].
const BLOCK: usize = 64;

/// Outputs of at least this many bytes are written with non-temporal
/// stores: they would not stay in the caches anyway, and such stores skip
/// reading each line before writing it, which halves the write traffic.
pub const STREAM_MIN_BYTES: usize = 16 << 20;

/// `out[i] = kernel(inputs[i])` for every row, compiled for the widest
/// vector unit (see [`dispatch`]); returns whether `valid` holds for every
/// input row. Both closures must be branch-free for the loop to vectorise,
/// and `kernel` must be inlined into it: a function marked
/// `#[inline(always)]`, or a closure so marked (the dispatch calls it from
/// one function per instruction set, which LLVM's own heuristics would
/// decline for a large body).
///
/// Rows are interleaved (`[x, y]`, `[x, y, z]`), which the vectoriser
/// handles only at half width inside a kernel loop; each block of [`BLOCK`]
/// rows is therefore transposed into one array per component, mapped at
/// full width, and transposed back. With `stream`, the block is written to
/// `out` with non-temporal stores (for outputs of [`STREAM_MIN_BYTES`] or
/// more).
#[inline(always)]
pub fn map_rows<F, T, const K: usize, const M: usize>(
    out: &mut [[T; M]],
    inputs: &[[F; K]],
    kernel: &impl Fn([F; K]) -> [T; M],
    valid: impl Fn(&[F; K]) -> bool,
    stream: bool,
) -> bool
where
    F: Copy + Default,
    T: Copy + Default,
{
    let ok = dispatch(
        #[inline(always)]
        || {
            // Full blocks straight from the slices; the last, partial block
            // padded with copies of its first row, in its own code path (a
            // shared one would copy every block through the padding).
            let (in_blocks, in_tail) = inputs.as_chunks::<BLOCK>();
            let (out_blocks, out_tail) = out.as_chunks_mut::<BLOCK>();
            let mut ok = true;
            for (o, i) in out_blocks.iter_mut().zip(in_blocks) {
                ok &= map_block(o, i, kernel, &valid, stream);
            }
            if let Some(&first) = in_tail.first() {
                let n = in_tail.len();
                let padded: [[F; K]; BLOCK] =
                    std::array::from_fn(|i| if i < n { in_tail[i] } else { first });
                let mut rows = [[T::default(); M]; BLOCK];
                ok &= map_block(&mut rows, &padded, kernel, &valid, false);
                if stream {
                    stream_copy(out_tail, &rows[..n]);
                } else {
                    out_tail.copy_from_slice(&rows[..n]);
                }
            }
            ok
        },
    );
    if stream {
        store_fence();
    }
    ok
}

/// One block of [`map_rows`]: transpose to columns, map, transpose back
/// (into `out`, or with `stream` through a buffer and non-temporal stores).
/// Every loop runs exactly [`BLOCK`] times.
#[inline(always)]
fn map_block<F, T, const K: usize, const M: usize>(
    out: &mut [[T; M]; BLOCK],
    inputs: &[[F; K]; BLOCK],
    kernel: &impl Fn([F; K]) -> [T; M],
    valid: &impl Fn(&[F; K]) -> bool,
    stream: bool,
) -> bool
where
    F: Copy + Default,
    T: Copy + Default,
{
    let mut columns = [[F::default(); BLOCK]; K];
    for i in 0..BLOCK {
        for k in 0..K {
            columns[k][i] = inputs[i][k];
        }
    }
    let mut ok = true;
    let mut results = [[T::default(); BLOCK]; M];
    for i in 0..BLOCK {
        let x = std::array::from_fn(|k| columns[k][i]);
        ok &= valid(&x);
        let r = kernel(x);
        for m in 0..M {
            results[m][i] = r[m];
        }
    }
    if stream {
        let mut rows = [[T::default(); M]; BLOCK];
        interleave(&results, &mut rows);
        stream_copy(out, &rows);
    } else {
        interleave(&results, out);
    }
    ok
}

/// `rows[i][m] = columns[m][i]`, as one flat loop of constant length,
/// which vectorises where a loop over rows does not.
#[inline(always)]
fn interleave<T: Copy, const M: usize>(columns: &[[T; BLOCK]; M], rows: &mut [[T; M]; BLOCK]) {
    let flat = rows.as_flattened_mut();
    for i in 0..BLOCK {
        for m in 0..M {
            flat[i * M + m] = columns[m][i];
        }
    }
}

/// Copies `src` into `dst` (same length) with non-temporal stores for the
/// 16-byte-aligned part of `dst`.
#[inline(always)]
fn stream_copy<T: Copy>(dst: &mut [T], src: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128i, _mm_loadu_si128, _mm_stream_si128};
        let len = size_of_val(src).min(size_of_val(dst));
        let (d, s) = (dst.as_mut_ptr().cast::<u8>(), src.as_ptr().cast::<u8>());
        let head = d.align_offset(16).min(len);
        let body = (len - head) / 16 * 16;
        #[allow(unsafe_code)]
        // SAFETY: `d` and `s` point to `len` valid bytes of two distinct
        // slices (one borrowed mutably); `T: Copy` has no drop glue, and the
        // bytes copied are those of valid `T` values. The streamed stores go
        // to `d + head + 16·j`, 16-byte aligned and within `len`.
        unsafe {
            std::ptr::copy_nonoverlapping(s, d, head);
            for j in (head..head + body).step_by(16) {
                let v = _mm_loadu_si128(s.add(j).cast::<__m128i>());
                _mm_stream_si128(d.add(j).cast::<__m128i>(), v);
            }
            std::ptr::copy_nonoverlapping(
                s.add(head + body),
                d.add(head + body),
                len - head - body,
            );
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    dst.copy_from_slice(src);
}

/// Orders non-temporal stores before whatever follows (another thread
/// reading the output after the batch joins).
#[inline(always)]
fn store_fence() {
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    // SAFETY: SSE is part of every x86-64 CPU.
    unsafe {
        std::arch::x86_64::_mm_sfence();
    }
}

//! Runtime dispatch to the widest vector instructions this CPU has, for the
//! batch loops: the kernels are written once, as branch-free scalar code
//! without library calls, and the compiler vectorises the loop that calls
//! them when it is compiled for AVX-512 or AVX2 + FMA.
//!
//! This module holds the crate's only `unsafe`: calling a function compiled
//! for an instruction set, which is sound because the CPU was just checked
//! to have it, the non-temporal stores of large outputs and the gathers of
//! table entries (raw-pointer intrinsics, bounds and alignment argued at
//! each use), and cache prefetch hints. Results do not depend on the path taken: no floating-point
//! contraction is enabled, so each operation rounds the same way.

mod gather;
#[cfg(target_arch = "x86_64")]
mod lanes;
mod stream;

pub use gather::{Gathered, gather, gather_columns, gather_runs};
pub(crate) use stream::stream_copy;
pub use stream::{store_fence, stream_copy_rows};

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
/// target. `f` is given that level as a constant of its compiled copy, so
/// that a branch on it costs nothing. Mark the closure `#[inline(always)]`
/// so that its body is compiled inside the dispatching function.
#[inline(always)]
pub fn dispatch<R>(f: impl FnOnce(Level) -> R) -> R {
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
    f(Level::Baseline)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
fn avx512<R>(f: impl FnOnce(Level) -> R) -> R {
    f(Level::Avx512)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn avx2_fma<R>(f: impl FnOnce(Level) -> R) -> R {
    f(Level::Avx2)
}

/// Asks the CPU to bring `data[index]` into the caches ahead of its use. A
/// hint: it never faults (an index out of bounds is harmless) and does
/// nothing on targets without the instruction.
#[inline(always)]
pub fn prefetch<T>(data: &[T], index: usize) {
    prefetch_address(data.as_ptr().wrapping_add(index).cast());
}

/// Asks the CPU to bring every cache line of `data` into the caches ahead
/// of its use: a hint, as [`prefetch`].
#[inline(always)]
pub fn prefetch_lines<T>(data: &[T]) {
    let start = data.as_ptr().cast::<u8>();
    for offset in (0..size_of_val(data)).step_by(LINE) {
        prefetch_address(start.wrapping_add(offset));
    }
}

/// The prefetch hint of [`prefetch`] and [`prefetch_lines`], for any
/// address.
#[inline(always)]
fn prefetch_address(address: *const u8) {
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    // SAFETY: a prefetch reads nothing the program can observe and never
    // faults, whatever the address.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(address.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}

/// Cache line size in bytes (x86-64 and most other targets).
const LINE: usize = 64;

/// Rows per block of [`map_rows`] and [`map_to_columns`].
pub const BLOCK: usize = 64;

/// A value that starts on a cache-line boundary: a block's columns (or
/// rows) on the stack, so that each full-width load and store of them
/// touches one line, not two. (Columns split across lines cost the
/// standard normal warp 13.2 ms against 9.8 on one thread in one build, and
/// nothing in another, as the stack happened to fall.)
#[repr(C, align(64))]
pub(crate) struct OnLines<T>(pub(crate) T);

/// How far ahead of the block it maps [`map_rows`] prefetches its input:
/// the loads of a block come in an order the hardware prefetchers do not
/// follow, and a cheap kernel would otherwise wait on memory for most of
/// them. At least this many blocks, and at least [`PREFETCH_BYTES`].
const PREFETCH_BLOCKS: usize = 4;

/// The least distance of [`map_rows`]'s prefetches, in bytes: four blocks
/// of `f32` pairs (2 KiB) were too close for the cheapest warps (the
/// triangle, the disk and the sphere ran 5–10 % faster at 4 KiB on an
/// AVX-512 Xeon; the `f64` warps, 4 KiB at four blocks, did not move).
const PREFETCH_BYTES: usize = 4 << 10;

/// The blocks of rows of `K` values of `F` that [`map_rows`] prefetches
/// ahead: [`PREFETCH_BYTES`] of them, at least [`PREFETCH_BLOCKS`].
const fn blocks_ahead<F, const K: usize>() -> usize {
    let blocks = PREFETCH_BYTES / size_of::<[[F; K]; BLOCK]>();
    if blocks > PREFETCH_BLOCKS {
        blocks
    } else {
        PREFETCH_BLOCKS
    }
}

/// Outputs of at least this many bytes are written with non-temporal
/// stores: they would not stay in the caches anyway, and such stores skip
/// reading each line before writing it, which cuts the memory traffic of a
/// warp by a third or more.
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
/// handles only at half width inside a kernel loop; each block of `BLOCK`
/// rows is therefore transposed into one array per component, mapped at
/// full width, and transposed back. With `stream` (for outputs of
/// [`STREAM_MIN_BYTES`] or more), whole cache lines of `out` are written
/// with non-temporal stores, as wide as the CPU has.
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
        |level| {
            // Streamed, the rows before the first line boundary of `out` take
            // the tail's path, so that every block covers whole lines (a
            // line left partly written by non-temporal stores is merged in
            // memory, which costs more than the stores save).
            // (`align_offset` may find no such row, or report none.)
            let head = if stream {
                out.as_ptr().align_offset(LINE)
            } else {
                0
            };
            let (head, stream) = if head < BLOCK {
                (head.min(out.len()), stream)
            } else {
                (0, false)
            };
            let (out_head, out) = out.split_at_mut(head);
            let (in_head, inputs) = inputs.split_at(head);
            let mut ok = map_tail(out_head, in_head, kernel, &valid, level);
            let (in_blocks, in_tail) = inputs.as_chunks::<BLOCK>();
            let (out_blocks, out_tail) = out.as_chunks_mut::<BLOCK>();
            let blocks_ahead = const { blocks_ahead::<F, K>() };
            for (b, (o, i)) in out_blocks.iter_mut().zip(in_blocks).enumerate() {
                if let Some(ahead) = in_blocks.get(b + blocks_ahead) {
                    prefetch_lines(ahead);
                }
                ok &= map_block(o, i, kernel, &valid, level, stream);
            }
            ok & map_tail(out_tail, in_tail, kernel, &valid, level)
        },
    );
    if stream {
        store_fence();
    }
    ok
}

/// [`map_block`] for fewer than [`BLOCK`] rows, written with plain stores:
/// the rows padded with copies of the first, in their own code path (a
/// shared one would copy every block through the padding).
#[inline(always)]
fn map_tail<F, T, const K: usize, const M: usize>(
    out: &mut [[T; M]],
    inputs: &[[F; K]],
    kernel: &impl Fn([F; K]) -> [T; M],
    valid: &impl Fn(&[F; K]) -> bool,
    level: Level,
) -> bool
where
    F: Copy + Default,
    T: Copy + Default,
{
    let Some(padded) = padded_block(inputs) else {
        return true;
    };
    let n = inputs.len();
    let OnLines(rows) = &mut OnLines([[T::default(); M]; BLOCK]);
    let ok = map_block(rows, &padded, kernel, valid, level, false);
    out.copy_from_slice(&rows[..n]);
    ok
}

/// One block of [`map_rows`]: transpose to columns, map, transpose back
/// (with `stream`, by non-temporal stores). Every loop runs exactly
/// [`BLOCK`] times. On AVX-512, blocks of four-byte values with two or
/// three components are transposed by permutes in registers and streamed
/// straight from them ([`lanes`]); otherwise by loops the compiler vectorises
/// and, streamed, through a buffer.
#[inline(always)]
fn map_block<F, T, const K: usize, const M: usize>(
    out: &mut [[T; M]; BLOCK],
    inputs: &[[F; K]; BLOCK],
    kernel: &impl Fn([F; K]) -> [T; M],
    valid: &impl Fn(&[F; K]) -> bool,
    level: Level,
    stream: bool,
) -> bool
where
    F: Copy + Default,
    T: Copy + Default,
{
    let OnLines(results) = &mut OnLines([[T::default(); BLOCK]; M]);
    let ok = map_block_to_columns(results, inputs, kernel, valid, level);
    if !permute_columns_to_rows(results, out, level, stream) {
        if stream {
            let OnLines(rows) = &mut OnLines([[T::default(); M]; BLOCK]);
            interleave(results, rows, level);
            stream_copy(out, rows);
        } else {
            interleave(results, out, level);
        }
    }
    ok
}

/// `columns[m][i] = kernel(rows[i])[m]` for a block of at most [`BLOCK`]
/// rows, at full SIMD width, with the results left in columns (the rest of
/// each column is the kernel of the first row); returns whether `valid`
/// holds for every row. For pipelines that go on from a block's results
/// row by row later (a table read at each), which need no transpose back.
///
/// # Panics
/// If `rows` has more than [`BLOCK`] rows.
#[inline(always)]
pub fn map_to_columns<F, T, const K: usize, const M: usize>(
    columns: &mut [[T; BLOCK]; M],
    rows: &[[F; K]],
    kernel: &impl Fn([F; K]) -> [T; M],
    valid: impl Fn(&[F; K]) -> bool,
) -> bool
where
    F: Copy + Default,
    T: Copy + Default,
{
    assert!(rows.len() <= BLOCK, "a block has at most {BLOCK} rows");
    let level = level();
    if let Ok(block) = <&[[F; K]; BLOCK]>::try_from(rows) {
        return map_block_to_columns(columns, block, kernel, &valid, level);
    }
    match padded_block(rows) {
        Some(padded) => map_block_to_columns(columns, &padded, kernel, &valid, level),
        None => true,
    }
}

/// The rows of a part block (fewer than [`BLOCK`]) padded to a whole one
/// with copies of the first; `None` for no rows.
#[inline(always)]
fn padded_block<F: Copy, const K: usize>(rows: &[[F; K]]) -> Option<[[F; K]; BLOCK]> {
    let &first = rows.first()?;
    Some(std::array::from_fn(|i| {
        rows.get(i).copied().unwrap_or(first)
    }))
}

/// The columns of one block of [`map_rows`] or [`map_to_columns`]: its
/// rows transposed to columns (by permutes on AVX-512 where [`lanes`]
/// handles the shape), then mapped by a loop over columns of constant
/// length that vectorises.
#[inline(always)]
fn map_block_to_columns<F, T, const K: usize, const M: usize>(
    results: &mut [[T; BLOCK]; M],
    inputs: &[[F; K]; BLOCK],
    kernel: &impl Fn([F; K]) -> [T; M],
    valid: &impl Fn(&[F; K]) -> bool,
    level: Level,
) -> bool
where
    F: Copy + Default,
    T: Copy,
{
    let OnLines(columns) = &mut OnLines([[F::default(); BLOCK]; K]);
    if !permute_rows_to_columns(inputs, columns, level)
        && !transpose_rows_to_columns(inputs, columns, level)
    {
        for i in 0..BLOCK {
            for k in 0..K {
                columns[k][i] = inputs[i][k];
            }
        }
    }
    map_columns(results, columns, kernel, valid)
}

/// `results[m][i] = kernel(x)[m]` with `x[k] = columns[k][i]`, for a block
/// of columns, by a loop of constant length that vectorises; returns
/// whether `valid` holds for every `x`.
#[inline(always)]
pub fn map_columns<F, T, const K: usize, const M: usize>(
    results: &mut [[T; BLOCK]; M],
    columns: &[[F; BLOCK]; K],
    kernel: &impl Fn([F; K]) -> [T; M],
    valid: &impl Fn(&[F; K]) -> bool,
) -> bool
where
    F: Copy,
    T: Copy,
{
    let mut ok = true;
    for i in 0..BLOCK {
        let x = std::array::from_fn(|k| columns[k][i]);
        ok &= valid(&x);
        let r = kernel(x);
        for m in 0..M {
            results[m][i] = r[m];
        }
    }
    ok
}

/// Runs the transpose `$call` of [`lanes`] and returns `true` from the
/// enclosing function when `$level` is AVX-512 and `$shape` (which of
/// [`lanes`]' shapes it handles) holds; does nothing otherwise (and on
/// other CPUs).
macro_rules! on_avx512 {
    ($level:expr, $shape:expr, $call:expr) => {
        #[cfg(target_arch = "x86_64")]
        if $level == Level::Avx512 && $shape {
            #[allow(unsafe_code)]
            // SAFETY: `level` reports AVX-512 only when the CPU has AVX-512 F.
            unsafe {
                $call;
            }
            return true;
        }
    };
}

/// [`lanes::rows_to_columns`] where the CPU and the shape allow; returns
/// whether it ran.
#[inline(always)]
fn permute_rows_to_columns<F: Copy, const K: usize>(
    rows: &[[F; K]; BLOCK],
    columns: &mut [[F; BLOCK]; K],
    level: Level,
) -> bool {
    on_avx512!(
        level,
        lanes::handles::<F>(K, BLOCK),
        lanes::rows_to_columns(rows, columns)
    );
    let _ = (rows, columns, level);
    false
}

/// [`lanes::rows_to_columns_transposed`] where the CPU and the shape
/// allow; returns whether it ran.
#[inline(always)]
fn transpose_rows_to_columns<F: Copy, const K: usize>(
    rows: &[[F; K]; BLOCK],
    columns: &mut [[F; BLOCK]; K],
    level: Level,
) -> bool {
    on_avx512!(
        level,
        lanes::transposes_rows::<F>(K, BLOCK),
        lanes::rows_to_columns_transposed(rows, columns)
    );
    let _ = (rows, columns, level);
    false
}

/// [`lanes::columns_to_rows`] where the CPU and the shape allow; returns
/// whether it ran.
#[inline(always)]
fn permute_columns_to_rows<T: Copy, const M: usize>(
    columns: &[[T; BLOCK]; M],
    rows: &mut [[T; M]; BLOCK],
    level: Level,
    stream: bool,
) -> bool {
    on_avx512!(
        level,
        lanes::handles::<T>(M, BLOCK),
        lanes::columns_to_rows(columns, rows, stream)
    );
    let _ = (columns, rows, level, stream);
    false
}

/// [`lanes::columns_to_rows_transposed`] where the CPU and the shape
/// allow; returns whether it ran.
#[inline(always)]
fn transpose_columns_to_rows<T: Copy, const M: usize>(
    columns: &[[T; BLOCK]; M],
    rows: &mut [[T; M]; BLOCK],
    level: Level,
) -> bool {
    on_avx512!(
        level,
        lanes::transposes::<T>(M, BLOCK),
        lanes::columns_to_rows_transposed(columns, rows)
    );
    let _ = (columns, rows, level);
    false
}

/// `columns[k][i]`: component `k` of `pair(items[i])[0]` for `k < 3`, of
/// `pair(items[i])[1]` for `k >= 3` (zeros past the items), for at most `B`
/// items (a multiple of 16), on AVX-512 by transposes in registers
/// ([`lanes::vector_pairs_to_columns`]); returns whether it ran (not at
/// other levels, where the caller's own loop is as good).
#[inline(always)]
pub(crate) fn vector_pairs_to_columns<T, const B: usize>(
    items: &[T],
    pair: impl Fn(&T) -> [glam::Vec3A; 2],
    columns: &mut [[f32; B]; 6],
    level: Level,
) -> bool {
    on_avx512!(
        level,
        lanes::transposes_pairs(B),
        lanes::vector_pairs_to_columns(items, pair, columns)
    );
    let _ = (items, pair, columns, level);
    false
}

/// `rows[i][m] = columns[m][i]`: on AVX-512 by transposes in registers
/// ([`transpose_columns_to_rows`], up to 16 components), else as one flat
/// loop of constant length, which vectorises where a loop over rows does
/// not.
#[inline(always)]
fn interleave<T: Copy, const M: usize>(
    columns: &[[T; BLOCK]; M],
    rows: &mut [[T; M]; BLOCK],
    level: Level,
) {
    if transpose_columns_to_rows(columns, rows, level) {
        return;
    }
    let flat = rows.as_flattened_mut();
    for i in 0..BLOCK {
        for m in 0..M {
            flat[i * M + m] = columns[m][i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `map_rows(kernel)` equals the kernel row by row, streamed or not,
    /// wherever the output starts relative to a cache line and whatever the
    /// length (head, blocks, tail).
    fn check_every_row<F, T, const K: usize, const M: usize>(
        row: impl Fn(usize) -> [F; K],
        kernel: impl Fn([F; K]) -> [T; M],
        blank: T,
    ) where
        F: Copy + Default,
        T: Copy + Default + PartialEq + std::fmt::Debug,
    {
        for len in [0, 1, 63, 64, 65, 200, 1000] {
            let inputs: Vec<[F; K]> = (0..len).map(&row).collect();
            let expected: Vec<[T; M]> = inputs.iter().map(|&x| kernel(x)).collect();
            for offset in 0..17 {
                for stream in [false, true] {
                    let mut backing = vec![[blank; M]; len + offset];
                    let out = &mut backing[offset..];
                    assert!(map_rows(out, &inputs, &kernel, |_| true, stream));
                    assert_eq!(out, &expected[..], "len {len}, offset {offset}, {stream}");
                }
            }
        }
    }

    /// Every shape the transposes have a path of their own for (four-byte
    /// values with two or three components on AVX-512), and others.
    #[test]
    fn map_rows_writes_every_row_at_any_alignment() {
        let f = |i: usize| i as f32;
        check_every_row(
            |i| [f(i), 0.5 * f(i)],
            |x| [x[0] + x[1], 2.0 * x[0], -x[1]],
            f32::NAN,
        );
        check_every_row(|i| [f(i), 0.5 * f(i)], |x| [x[1], x[0] - 1.0], f32::NAN);
        check_every_row(|i| [f(i), -f(i), 3.0], |x| [x[2] * x[0], x[1]], f32::NAN);
        check_every_row(
            |i| [f(i), -f(i), 3.0],
            |x| [x[2], x[0], x[1] + 1.0],
            f32::NAN,
        );
        check_every_row(|i| [f(i)], |x| [x[0] * 0.25], f32::NAN);
        check_every_row(|i| [i as u32, 7], |x| [x[1], x[0], x[0] ^ x[1]], u32::MAX);
        check_every_row(
            |i| [i as f64, 1.5],
            |x| [x[0] * x[1], x[1], -x[0]],
            f64::NAN,
        );
    }

    #[test]
    fn map_rows_reports_an_invalid_row_in_any_part() {
        let inputs: Vec<[f32; 1]> = (0..300).map(|i| [i as f32]).collect();
        for bad in [0, 5, 64, 150, 299] {
            let mut inputs = inputs.clone();
            inputs[bad] = [-1.0];
            let mut out = vec![[0.0f32; 1]; 300];
            assert!(!map_rows(&mut out, &inputs, &|x| x, |x| x[0] >= 0.0, true));
        }
    }
}

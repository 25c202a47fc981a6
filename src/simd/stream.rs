//! Copies by non-temporal stores, for large outputs: such stores skip
//! reading each line before writing it, which cuts the memory traffic of a
//! batch that only writes its output.

use super::{LINE, Level, level};

/// Copies `src` into `dst` (same length) with non-temporal stores of the
/// widest kind the CPU has ([`level`]), when `dst` is whole cache lines (as
/// [`super::map_rows`] arranges, and as the blocks of a page-aligned
/// [`crate::buffer::Buffer`] are); otherwise with plain stores. For copies
/// that are not read again soon: such stores skip reading each line before
/// writing it. Follow the copies by [`store_fence`]. The width is read at
/// run time on purpose: given as the dispatch's constant, LLVM merged the
/// copy into the block's transpose, which cost the AVX2 warps of three
/// components instructions per row.
#[inline(always)]
pub(crate) fn stream_copy<T: Copy>(dst: &mut [T], src: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        let len = size_of_val(dst);
        if len == size_of_val(src)
            && len.is_multiple_of(LINE)
            && dst.as_ptr().align_offset(LINE) == 0
        {
            let (d, s) = (dst.as_mut_ptr().cast::<u8>(), src.as_ptr().cast::<u8>());
            #[allow(unsafe_code)]
            // SAFETY: `d` and `s` point to `len` valid bytes of two distinct
            // slices (one borrowed mutably), `d` aligned to a line and `len`
            // a multiple of it; `T: Copy` has no drop glue, and the bytes
            // copied are those of valid `T` values.
            unsafe {
                stream_lines(d, s, len);
            }
            return;
        }
    }
    dst.copy_from_slice(src);
}

/// Copies `src` into `dst` (same length; else a plain copy) with
/// non-temporal stores, as wide as the CPU has, for the whole cache lines
/// of `dst`, wherever it starts: its bytes before its first line boundary
/// and after its last are copied with plain stores (a line left partly
/// written by non-temporal stores is merged in memory, which costs more
/// than the stores save). For large outputs that are not read again soon:
/// such stores skip reading each line before writing it. Follow the
/// copies by [`store_fence`].
#[inline(always)]
pub fn stream_copy_rows<T: Copy>(dst: &mut [T], src: &[T]) {
    let len = size_of_val(dst);
    if len != size_of_val(src) {
        dst.copy_from_slice(src);
        return;
    }
    let (d, s) = (dst.as_mut_ptr().cast::<u8>(), src.as_ptr().cast::<u8>());
    let head = d.align_offset(LINE).min(len);
    let body = (len - head) / LINE * LINE;
    #[allow(unsafe_code)]
    // SAFETY: `d` and `s` point to `len` valid bytes of two distinct
    // slices (one borrowed mutably); `head + body <= len`; `d + head` is
    // aligned to a line and `body` a multiple of it. `T: Copy` has no drop
    // glue, and every byte of `dst` is overwritten by the matching byte of
    // a valid `T`.
    unsafe {
        std::ptr::copy_nonoverlapping(s, d, head);
        stream_lines(d.add(head), s.add(head), body);
        let done = head + body;
        std::ptr::copy_nonoverlapping(s.add(done), d.add(done), len - done);
    }
}

/// Copies `len` bytes (whole lines) from `s` to the line-aligned `d` by
/// non-temporal stores, the widest the CPU has ([`level`]); plain copies
/// off x86-64.
///
/// # Safety
/// `d` and `s` point to `len` valid bytes that do not overlap, `d` is
/// aligned to [`LINE`], and `len` is a multiple of it.
#[inline(always)]
#[allow(unsafe_code)]
unsafe fn stream_lines(d: *mut u8, s: *const u8, len: usize) {
    // SAFETY: the caller's; `level` reports only instruction sets the CPU
    // has.
    unsafe {
        #[cfg(target_arch = "x86_64")]
        match level() {
            Level::Avx512 => stream_lines_avx512(d, s, len),
            Level::Avx2 => stream_lines_avx(d, s, len),
            Level::Baseline => stream_lines_sse2(d, s, len),
        }
        #[cfg(not(target_arch = "x86_64"))]
        std::ptr::copy_nonoverlapping(s, d, len);
    }
}

/// Defines a function that copies `len` bytes (whole lines) from `s` to the
/// line-aligned `d` with non-temporal stores of one vector type. Marked
/// `#[inline(never)]`: with `#[inline]`, LLVM folded the block's transpose
/// into the copy and assembled each vector from single floats, which ran
/// the streamed warps several times slower.
macro_rules! stream_lines {
    ($name:ident, $feature:literal, $vector:ident, $load:ident, $store:ident) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feature)]
        #[allow(unsafe_code)]
        #[inline(never)]
        unsafe fn $name(d: *mut u8, s: *const u8, len: usize) {
            use std::arch::x86_64::{$load, $store, $vector};
            const STEP: usize = size_of::<$vector>();
            for offset in (0..len).step_by(STEP) {
                // SAFETY: the caller's bounds and alignment: `offset + STEP`
                // is within `len`, and `d + offset` is aligned to `STEP`.
                unsafe {
                    let v = $load(s.add(offset).cast::<$vector>());
                    $store(d.add(offset).cast::<$vector>(), v);
                }
            }
        }
    };
}
stream_lines!(
    stream_lines_avx512,
    "avx512f",
    __m512i,
    _mm512_loadu_si512,
    _mm512_stream_si512
);
stream_lines!(
    stream_lines_avx,
    "avx",
    __m256i,
    _mm256_loadu_si256,
    _mm256_stream_si256
);
stream_lines!(
    stream_lines_sse2,
    "sse2",
    __m128i,
    _mm_loadu_si128,
    _mm_stream_si128
);

/// Orders non-temporal stores (those of [`stream_copy_rows`]) before
/// whatever follows (another thread reading the output after the batch
/// joins).
#[inline(always)]
pub fn store_fence() {
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    // SAFETY: SSE is part of every x86-64 CPU.
    unsafe {
        std::arch::x86_64::_mm_sfence();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `stream_copy_rows` writes exactly `src` into `dst`, wherever `dst`
    /// starts relative to a cache line and whatever its length (no whole
    /// line, one, several; rows of 1, 12 and 16 bytes), and nothing
    /// around it.
    fn copies_exactly<T: Copy + PartialEq + std::fmt::Debug>(row: impl Fn(usize) -> T, blank: T) {
        let line = LINE / size_of::<T>().min(LINE);
        for start in 0..line + 1 {
            for len in [0, 1, 3, line - 1, line, line + 1, 5 * line + 3, 40 * line] {
                let src: Vec<T> = (0..len).map(&row).collect();
                let mut buffer = vec![blank; start + len + 2 * line];
                stream_copy_rows(&mut buffer[start..start + len], &src);
                store_fence();
                assert_eq!(
                    &buffer[start..start + len],
                    &src[..],
                    "start {start}, len {len}"
                );
                assert!(buffer[..start].iter().all(|&b| b == blank));
                assert!(buffer[start + len..].iter().all(|&b| b == blank));
            }
        }
    }

    #[test]
    fn streamed_rows_are_the_rows() {
        copies_exactly(|i| (i % 251) as u8 + 1, 0);
        copies_exactly(|i| [i as i64 + 1, -(i as i64)], [0, 0]);
        copies_exactly(|i| [i as f32, 0.5, -1.0], [0.0; 3]);
    }
}

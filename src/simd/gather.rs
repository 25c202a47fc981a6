//! [`gather_columns`]: the entries of a table of `[f32; C]` at a block of
//! indices, one column per component; [`gather_runs`]: the runs of `C`
//! consecutive `f32`s from a block of offsets, likewise; and [`gather`]:
//! the entries of a table of `f64` or `u32` at a block of 64-bit indices;
//! all read by the CPU's gather instructions where it has them (a loop of
//! indexed reads is not vectorised by the compiler).

use super::{BLOCK, Level, OnLines, detected, level};

/// `columns[c][i] = table[index[i]][c]` for a block of [`BLOCK`] indices,
/// read as [`gather_runs`] reads the runs of the flattened table. An index
/// past the table reads its last entry (callers pass none); an empty table
/// leaves `columns` as they are.
#[inline(always)]
pub fn gather_columns<const C: usize>(
    table: &[[f32; C]],
    index: &[u32; BLOCK],
    columns: &mut [[f32; BLOCK]; C],
) {
    columns_at(level(), table, index, columns);
}

/// [`gather_columns`] with the instruction set `level`, as [`runs_at`].
#[inline(always)]
fn columns_at<const C: usize>(
    level: Level,
    table: &[[f32; C]],
    index: &[u32; BLOCK],
    columns: &mut [[f32; BLOCK]; C],
) {
    let Some(last) = table.len().checked_sub(1) else {
        return;
    };
    if table.as_flattened().len() > u32::MAX as usize {
        // Starts that a `u32` cannot hold: one entry at a time.
        for (i, &k) in index.iter().enumerate() {
            let entry = table[(k as usize).min(last)];
            for (column, value) in columns.iter_mut().zip(entry) {
                column[i] = value;
            }
        }
        return;
    }
    let OnLines(starts) = &mut OnLines([0u32; BLOCK]);
    for (s, &i) in starts.iter_mut().zip(index) {
        // At most `C·last`, below the flattened length (checked above).
        *s = C as u32 * i.min(last as u32);
    }
    runs_at(level, table.as_flattened(), starts, columns);
}

/// `columns[c][i] = flat[starts[i] + c]` for a block of [`BLOCK`] starts:
/// on AVX-512 and AVX2, each pair of components by one 64-bit gather per
/// 8 (or 4) lanes, which loads half the elements two 32-bit gathers would
/// (the pairs then split into their columns), and an odd `C`'s last
/// component by one 32-bit gather per 16 (or 8) lanes; else one read at a
/// time (the same values on every path). A start past `flat.len() − C`
/// reads the last `C` values (callers pass none); a table shorter than
/// `C` leaves `columns` as they are. A table of more than `i32::MAX`
/// values (offsets a gather cannot hold) is read one value at a time.
#[inline(always)]
pub fn gather_runs<const C: usize>(
    flat: &[f32],
    starts: &[u32; BLOCK],
    columns: &mut [[f32; BLOCK]; C],
) {
    runs_at(level(), flat, starts, columns);
}

/// [`gather_runs`] with the instruction set `level` (at most the one the
/// CPU has: a wider one is capped).
#[inline(always)]
fn runs_at<const C: usize>(
    level: Level,
    flat: &[f32],
    starts: &[u32; BLOCK],
    columns: &mut [[f32; BLOCK]; C],
) {
    let Some(last) = flat.len().checked_sub(C) else {
        return;
    };
    let last = last.min(u32::MAX as usize) as u32;
    let level = level.min(detected());
    #[cfg(target_arch = "x86_64")]
    if flat.len() <= i32::MAX as usize && level >= Level::Avx2 {
        let OnLines(offsets) = &mut OnLines([0i32; BLOCK]);
        for (o, &s) in offsets.iter_mut().zip(starts) {
            // At most `flat.len() − C`, below `i32::MAX` (checked above).
            *o = s.min(last) as i32;
        }
        #[allow(unsafe_code)]
        // SAFETY: `level` is at most what the CPU has ([`detected`]); every
        // offset plus a component `c < C` is at most `flat.len() − 1`, so
        // each gathered `f32` lies inside `flat`.
        unsafe {
            if level == Level::Avx512 {
                runs_avx512(flat, offsets, columns);
            } else {
                runs_avx2(flat, offsets, columns);
            }
        }
        return;
    }
    for (i, &s) in starts.iter().enumerate() {
        let s = s.min(last) as usize;
        for (c, column) in columns.iter_mut().enumerate() {
            column[i] = flat[s + c];
        }
    }
}

/// [`gather_runs`] on AVX-512: per 16 lanes, each pair of components by
/// two 64-bit gathers (the lanes' low and high 8) split into two columns
/// by permutes, an odd last component by one 32-bit gather.
///
/// # Safety
/// The CPU has AVX-512 F, and every `offsets[i] + c` (`c < C`) is an index
/// of `flat`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(unsafe_code)]
#[inline]
unsafe fn runs_avx512<const C: usize>(
    flat: &[f32],
    offsets: &[i32; BLOCK],
    columns: &mut [[f32; BLOCK]; C],
) {
    use std::arch::x86_64::{
        __m512i, _mm512_add_epi32, _mm512_castsi512_ps, _mm512_castsi512_si256,
        _mm512_extracti64x4_epi64, _mm512_i32gather_epi64, _mm512_i32gather_ps, _mm512_loadu_si512,
        _mm512_permutex2var_ps, _mm512_set1_epi32, _mm512_setr_epi32, _mm512_storeu_ps,
    };
    const LANES: usize = 16;
    const { assert!(BLOCK.is_multiple_of(LANES)) };
    let base = flat.as_ptr();
    let even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    let odd = _mm512_add_epi32(even, _mm512_set1_epi32(1));
    for g in (0..BLOCK).step_by(LANES) {
        // SAFETY: lanes `g..g + LANES` of the block (BLOCK is a multiple
        // of LANES); `loadu` and `storeu` need no alignment; the gathered
        // indices are the caller's, and a pair's second is `c + 1 < C`.
        unsafe {
            let first = _mm512_loadu_si512(offsets.as_ptr().add(g).cast::<__m512i>());
            let mut c = 0;
            while c + 1 < C {
                let at = _mm512_add_epi32(first, _mm512_set1_epi32(c as i32));
                let pairs = base.cast::<i64>();
                let low = _mm512_i32gather_epi64::<4>(_mm512_castsi512_si256(at), pairs);
                let high = _mm512_i32gather_epi64::<4>(_mm512_extracti64x4_epi64::<1>(at), pairs);
                let (low, high) = (_mm512_castsi512_ps(low), _mm512_castsi512_ps(high));
                let x = _mm512_permutex2var_ps(low, even, high);
                let y = _mm512_permutex2var_ps(low, odd, high);
                _mm512_storeu_ps(columns[c].as_mut_ptr().add(g), x);
                _mm512_storeu_ps(columns[c + 1].as_mut_ptr().add(g), y);
                c += 2;
            }
            if c < C {
                let at = _mm512_add_epi32(first, _mm512_set1_epi32(c as i32));
                _mm512_storeu_ps(
                    columns[c].as_mut_ptr().add(g),
                    _mm512_i32gather_ps::<4>(at, base),
                );
            }
        }
    }
}

/// [`gather_runs`] on AVX2: per 8 lanes, each pair of components by two
/// 64-bit gathers (the lanes' low and high 4) split into two columns by
/// shuffles, an odd last component by one 32-bit gather.
///
/// # Safety
/// The CPU has AVX2, and every `offsets[i] + c` (`c < C`) is an index of
/// `flat`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(unsafe_code)]
#[inline]
unsafe fn runs_avx2<const C: usize>(
    flat: &[f32],
    offsets: &[i32; BLOCK],
    columns: &mut [[f32; BLOCK]; C],
) {
    use std::arch::x86_64::{
        __m256i, _mm256_add_epi32, _mm256_castpd_ps, _mm256_castps_pd, _mm256_castsi256_ps,
        _mm256_castsi256_si128, _mm256_extracti128_si256, _mm256_i32gather_epi64,
        _mm256_i32gather_ps, _mm256_loadu_si256, _mm256_permute4x64_pd, _mm256_set1_epi32,
        _mm256_shuffle_ps, _mm256_storeu_ps,
    };
    const LANES: usize = 8;
    const { assert!(BLOCK.is_multiple_of(LANES)) };
    let base = flat.as_ptr();
    for g in (0..BLOCK).step_by(LANES) {
        // SAFETY: as on AVX-512, 8 lanes at a time.
        unsafe {
            let first = _mm256_loadu_si256(offsets.as_ptr().add(g).cast::<__m256i>());
            let mut c = 0;
            while c + 1 < C {
                let at = _mm256_add_epi32(first, _mm256_set1_epi32(c as i32));
                let pairs = base.cast::<i64>();
                let low = _mm256_i32gather_epi64::<4>(pairs, _mm256_castsi256_si128(at));
                let high = _mm256_i32gather_epi64::<4>(pairs, _mm256_extracti128_si256::<1>(at));
                let (low, high) = (_mm256_castsi256_ps(low), _mm256_castsi256_ps(high));
                // Within each 128-bit half, the firsts (or seconds) of two
                // pairs of each: lanes 0 1 4 5 | 2 3 6 7, then in order.
                let x = _mm256_shuffle_ps::<0b10_00_10_00>(low, high);
                let y = _mm256_shuffle_ps::<0b11_01_11_01>(low, high);
                let x =
                    _mm256_castpd_ps(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_castps_pd(x)));
                let y =
                    _mm256_castpd_ps(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_castps_pd(y)));
                _mm256_storeu_ps(columns[c].as_mut_ptr().add(g), x);
                _mm256_storeu_ps(columns[c + 1].as_mut_ptr().add(g), y);
                c += 2;
            }
            if c < C {
                let at = _mm256_add_epi32(first, _mm256_set1_epi32(c as i32));
                _mm256_storeu_ps(
                    columns[c].as_mut_ptr().add(g),
                    _mm256_i32gather_ps::<4>(base, at),
                );
            }
        }
    }
}

/// `out[i] = table[index[i]]` for a block of [`BLOCK`] indices: on AVX-512
/// one gather instruction per 8 indices, on AVX2 per 4, else one read at a
/// time (the same values on every path). An index past the table reads its
/// last entry; an empty table leaves `out` as it is.
#[inline(always)]
pub fn gather<T: Gathered>(table: &[T], index: &[u64; BLOCK], out: &mut [T; BLOCK]) {
    gather_one_at(level(), table, index, out);
}

/// The types [`gather`] reads: 8-byte floats and 4-byte integers.
pub trait Gathered: Copy + sealed::Sealed {
    /// [`gather`] on AVX-512.
    ///
    /// # Safety
    /// The CPU has AVX-512 F, and every index is below `table.len()`.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    unsafe fn gather_avx512(table: &[Self], index: &[u64; BLOCK], out: &mut [Self; BLOCK]);
    /// [`gather`] on AVX2.
    ///
    /// # Safety
    /// The CPU has AVX2, and every index is below `table.len()`.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    unsafe fn gather_avx2(table: &[Self], index: &[u64; BLOCK], out: &mut [Self; BLOCK]);
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for f64 {}
    impl Sealed for u32 {}
}

/// [`gather`] with the instruction set `level` (at most the one the CPU
/// has: a wider one is capped).
#[inline(always)]
fn gather_one_at<T: Gathered>(
    level: Level,
    table: &[T],
    index: &[u64; BLOCK],
    out: &mut [T; BLOCK],
) {
    let Some(last) = table.len().checked_sub(1) else {
        return;
    };
    let OnLines(at) = &mut OnLines([0u64; BLOCK]);
    for (a, &i) in at.iter_mut().zip(index) {
        *a = i.min(last as u64);
    }
    #[cfg(target_arch = "x86_64")]
    {
        let level = level.min(detected());
        #[allow(unsafe_code)]
        // SAFETY: `level` is at most what the CPU has ([`detected`]); every
        // index was just capped to the table's last.
        unsafe {
            match level {
                Level::Avx512 => return T::gather_avx512(table, at, out),
                Level::Avx2 => return T::gather_avx2(table, at, out),
                Level::Baseline => {}
            }
        }
    }
    let _ = level;
    for (o, &i) in out.iter_mut().zip(at.iter()) {
        *o = table[i as usize];
    }
}

/// Implements [`Gathered`] for `$t` with the gathers of 64-bit indices
/// `$wide` (AVX-512, `[offsets, base]`) and `$narrow` (AVX2, `[base,
/// offsets]`), each vector of lanes stored by `$store_wide` /
/// `$store_narrow` (`$base`: the pointer type the gathers take).
macro_rules! gathered {
    ($t:ty, $base:ty, $wide:ident, $store_wide:ident, $narrow:ident, $store_narrow:ident) => {
        impl Gathered for $t {
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx512f")]
            #[allow(unsafe_code)]
            #[inline]
            unsafe fn gather_avx512(table: &[$t], index: &[u64; BLOCK], out: &mut [$t; BLOCK]) {
                use std::arch::x86_64::{_mm512_loadu_si512, $store_wide, $wide};
                let base = table.as_ptr().cast::<$base>();
                for g in (0..BLOCK).step_by(8) {
                    // SAFETY: lanes `g..g + 8` of the block (a multiple of
                    // 8); `loadu` and `storeu` need no alignment; each
                    // index lies in the table (the caller's).
                    unsafe {
                        let at = _mm512_loadu_si512(index.as_ptr().add(g).cast());
                        let v = $wide::<{ size_of::<$t>() as i32 }>(at, base);
                        $store_wide(out.as_mut_ptr().add(g).cast(), v);
                    }
                }
            }

            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2")]
            #[allow(unsafe_code)]
            #[inline]
            unsafe fn gather_avx2(table: &[$t], index: &[u64; BLOCK], out: &mut [$t; BLOCK]) {
                use std::arch::x86_64::{_mm256_loadu_si256, $narrow, $store_narrow};
                let base = table.as_ptr().cast::<$base>();
                for g in (0..BLOCK).step_by(4) {
                    // SAFETY: as on AVX-512, 4 lanes at a time.
                    unsafe {
                        let at = _mm256_loadu_si256(index.as_ptr().add(g).cast());
                        let v = $narrow::<{ size_of::<$t>() as i32 }>(base, at);
                        $store_narrow(out.as_mut_ptr().add(g).cast(), v);
                    }
                }
            }
        }
    };
}
gathered!(
    f64,
    f64,
    _mm512_i64gather_pd,
    _mm512_storeu_pd,
    _mm256_i64gather_pd,
    _mm256_storeu_pd
);
gathered!(
    u32,
    i32,
    _mm512_i64gather_epi32,
    _mm256_storeu_si256,
    _mm256_i64gather_epi32,
    _mm_storeu_si128
);

#[cfg(test)]
mod tests {
    use super::*;

    /// Every path this CPU has (the wider ones capped to it) against the
    /// entries themselves, for a table of `len` entries of `C` components.
    fn check<const C: usize>(len: usize) {
        let table: Vec<[f32; C]> = (0..len)
            .map(|k| std::array::from_fn(|c| (10 * k + c) as f32))
            .collect();
        // Indices in any order, repeated, first and last, and past the end
        // (read as the last).
        let index: [u32; BLOCK] = std::array::from_fn(|i| match i {
            0 => 0,
            1 => len as u32 - 1,
            2 => len as u32,
            3 => u32::MAX,
            _ => ((i * 7919) % len) as u32,
        });
        for level in [Level::Baseline, Level::Avx2, Level::Avx512] {
            let mut columns = [[-1.0; BLOCK]; C];
            columns_at(level, &table, &index, &mut columns);
            for (i, &k) in index.iter().enumerate() {
                for (c, column) in columns.iter().enumerate() {
                    let expected = table[(k as usize).min(len - 1)][c];
                    assert_eq!(column[i], expected, "{level:?}: index {k}, component {c}");
                }
            }
        }
    }

    /// [`gather`] on every path this CPU has against the entries
    /// themselves, indices past the end reading the last.
    fn check_one<T: Gathered + PartialEq + std::fmt::Debug>(table: &[T]) {
        let len = table.len() as u64;
        let index: [u64; BLOCK] = std::array::from_fn(|i| match i {
            0 => 0,
            1 => len - 1,
            2 => len,
            3 => u64::MAX,
            _ => (i as u64 * 7919) % len,
        });
        for level in [Level::Baseline, Level::Avx2, Level::Avx512] {
            let mut out = [table[0]; BLOCK];
            gather_one_at(level, table, &index, &mut out);
            for (o, &k) in out.iter().zip(&index) {
                assert_eq!(*o, table[k.min(len - 1) as usize], "{level:?}: index {k}");
            }
        }
    }

    #[test]
    fn single_gathers_are_the_entries() {
        let floats: Vec<f64> = (0..1000).map(|k| k as f64 * 0.5 - 7.0).collect();
        let ints: Vec<u32> = (0..1000).map(|k| u32::MAX - 5000 + 3 * k).collect();
        check_one(&floats);
        check_one(&ints);
        check_one(&[2.5f64]);
        let mut out = [-1.0; BLOCK];
        gather::<f64>(&[], &[0; BLOCK], &mut out);
        assert_eq!(out, [-1.0; BLOCK]);
    }

    #[test]
    fn gathers_are_the_entries() {
        check::<4>(1000);
        check::<3>(1000);
        check::<2>(1000);
        check::<1>(1);
        check::<2>(1);
        // An empty table leaves the columns as they were.
        let mut columns = [[-1.0; BLOCK]; 2];
        gather_columns::<2>(&[], &[0; BLOCK], &mut columns);
        assert_eq!(columns, [[-1.0; BLOCK]; 2]);
    }

    /// [`gather_runs`] on every path this CPU has against the values
    /// themselves: runs from odd and even starts, the last run, and starts
    /// past it (read as the last run).
    fn check_runs<const C: usize>(len: usize) {
        let flat: Vec<f32> = (0..len).map(|k| k as f32 * 0.25 - 3.0).collect();
        let last = len - C;
        let starts: [u32; BLOCK] = std::array::from_fn(|i| match i {
            0 => 0,
            1 => last as u32,
            2 => last as u32 + 1,
            3 => u32::MAX,
            _ => ((i * 7919) % (last + 1)) as u32,
        });
        for level in [Level::Baseline, Level::Avx2, Level::Avx512] {
            let mut columns = [[-1.0; BLOCK]; C];
            runs_at(level, &flat, &starts, &mut columns);
            for (i, &s) in starts.iter().enumerate() {
                for (c, column) in columns.iter().enumerate() {
                    let expected = flat[(s as usize).min(last) + c];
                    assert_eq!(column[i], expected, "{level:?}: start {s}, component {c}");
                }
            }
        }
    }

    #[test]
    fn runs_are_the_values_from_each_start() {
        check_runs::<1>(1000);
        check_runs::<2>(1001);
        check_runs::<3>(998);
        check_runs::<4>(1000);
        check_runs::<2>(2);
        check_runs::<5>(5);
        // A table shorter than a run leaves the columns as they were.
        let mut columns = [[-1.0; BLOCK]; 3];
        gather_runs::<3>(&[1.0, 2.0], &[0; BLOCK], &mut columns);
        assert_eq!(columns, [[-1.0; BLOCK]; 3]);
    }
}

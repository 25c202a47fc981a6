//! [`gather_columns`]: the entries of a table of `[f32; C]` at a block of
//! indices, one column per component, read by the CPU's gather
//! instructions where it has them (a loop of indexed reads is not
//! vectorised by the compiler).

use super::{BLOCK, Level, OnLines, detected, level};

/// `columns[c][i] = table[index[i]][c]` for a block of [`BLOCK`] indices:
/// on AVX-512 one gather instruction per component and 16 indices, on
/// AVX2 per 8, else one read at a time (the same values on every path).
/// An index past the table reads its last entry (callers pass none); an
/// empty table leaves `columns` as they are. A table of more than
/// `i32::MAX` values (offsets a gather cannot hold) is read one entry at
/// a time.
#[inline(always)]
pub fn gather_columns<const C: usize>(
    table: &[[f32; C]],
    index: &[u32; BLOCK],
    columns: &mut [[f32; BLOCK]; C],
) {
    gather_at(level(), table, index, columns);
}

/// [`gather_columns`] with the instruction set `level` (at most the one
/// the CPU has: a wider one is capped).
#[inline(always)]
fn gather_at<const C: usize>(
    level: Level,
    table: &[[f32; C]],
    index: &[u32; BLOCK],
    columns: &mut [[f32; BLOCK]; C],
) {
    let Some(last) = table.len().checked_sub(1) else {
        return;
    };
    let level = level.min(detected());
    #[cfg(target_arch = "x86_64")]
    if C * table.len() <= i32::MAX as usize && level >= Level::Avx2 {
        // Each entry's first offset in `f32`s: at most `C·last`, which fits
        // in an `i32` (checked above), as `last` does in a `u32`.
        let OnLines(offsets) = &mut OnLines([0i32; BLOCK]);
        for (o, &i) in offsets.iter_mut().zip(index) {
            *o = (C as u32 * i.min(last as u32)) as i32;
        }
        let flat = table.as_flattened();
        #[allow(unsafe_code)]
        // SAFETY: `level` is at most what the CPU has ([`detected`]); every
        // offset plus a component `c < C` is at most `C·last + C − 1 <
        // flat.len()`, so each gathered `f32` lies inside `flat`.
        unsafe {
            if level == Level::Avx512 {
                gather_avx512(flat, offsets, columns);
            } else {
                gather_avx2(flat, offsets, columns);
            }
        }
        return;
    }
    for (i, &k) in index.iter().enumerate() {
        let entry = table[(k as usize).min(last)];
        for (column, value) in columns.iter_mut().zip(entry) {
            column[i] = value;
        }
    }
}

/// Defines a function that gathers `flat[offsets[i] + c]` into
/// `columns[c][i]` with one vector type's gather, `LANES` offsets at a
/// time (`[base, at]` name the table's pointer and the offsets' vector
/// in the gather's arguments). Safety (the caller's): the CPU has the feature, and every
/// `offsets[i] + c` (`c < C`) is an index of `flat`.
macro_rules! gather_with {
    ($name:ident, $feature:literal, $lanes:literal, [$base:ident, $at:ident], $index:ident, $load:ident,
     $set1:ident, $add:ident, $gather:ident($($arg:ident),+), $store:ident) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feature)]
        #[allow(unsafe_code)]
        #[inline]
        unsafe fn $name<const C: usize>(
            flat: &[f32],
            offsets: &[i32; BLOCK],
            columns: &mut [[f32; BLOCK]; C],
        ) {
            use std::arch::x86_64::{$add, $gather, $index, $load, $set1, $store};
            const LANES: usize = $lanes;
            const { assert!(BLOCK.is_multiple_of(LANES)) };
            let $base = flat.as_ptr();
            for g in (0..BLOCK).step_by(LANES) {
                // SAFETY: lanes `g..g + LANES` of the block (BLOCK is a
                // multiple of LANES); `loadu` and `storeu` need no
                // alignment; the gathered indices are the caller's.
                unsafe {
                    let first = $load(offsets.as_ptr().add(g).cast::<$index>());
                    for (c, column) in columns.iter_mut().enumerate() {
                        let $at = $add(first, $set1(c as i32));
                        $store(column.as_mut_ptr().add(g), $gather::<4>($($arg),+));
                    }
                }
            }
        }
    };
}
gather_with!(
    gather_avx512,
    "avx512f",
    16,
    [base, at],
    __m512i,
    _mm512_loadu_si512,
    _mm512_set1_epi32,
    _mm512_add_epi32,
    _mm512_i32gather_ps(at, base),
    _mm512_storeu_ps
);
gather_with!(
    gather_avx2,
    "avx2",
    8,
    [base, at],
    __m256i,
    _mm256_loadu_si256,
    _mm256_set1_epi32,
    _mm256_add_epi32,
    _mm256_i32gather_ps(base, at),
    _mm256_storeu_ps
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
            gather_at(level, &table, &index, &mut columns);
            for (i, &k) in index.iter().enumerate() {
                for (c, column) in columns.iter().enumerate() {
                    let expected = table[(k as usize).min(len - 1)][c];
                    assert_eq!(column[i], expected, "{level:?}: index {k}, component {c}");
                }
            }
        }
    }

    #[test]
    fn gathers_are_the_entries() {
        check::<4>(1000);
        check::<3>(1000);
        check::<1>(1);
        // An empty table leaves the columns as they were.
        let mut columns = [[-1.0; BLOCK]; 2];
        gather_columns::<2>(&[], &[0; BLOCK], &mut columns);
        assert_eq!(columns, [[-1.0; BLOCK]; 2]);
    }
}

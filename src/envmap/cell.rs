//! A lat-long map's table cells: the cell of a place, its corner texels
//! (wrapped at the seam), and those corners' values for a block of cells
//! read by gathers.

use std::ops::{Add, Sub};

use super::MAX_TEXELS;
use crate::math::Real;
use crate::simd::{self, BLOCK};

/// The cell `[column, row]` of the lat-long place `(x₀, y₀)` on a map
/// `width` texels wide whose table has `rows` rows of cells (one fewer than
/// the map's rows of texels): `⌊x₀⌋` and `⌊y₀⌋`, each clamped to `[0,
/// last]` (NaN to 0; [`Real::floor_u32`]), in `u32` arithmetic that
/// vectorises.
#[inline(always)]
pub(super) fn cell_u32<F: Real>(x0: F, y0: F, width: u32, rows: u32) -> [u32; 2] {
    [x0.floor_u32(width - 1), y0.floor_u32(rows - 1)]
}

/// The texels `[a, b, c, d]` of the lat-long cell whose top-left texel is
/// `k`, of column `col`, on a map `width` texels wide: `k`, the texel right
/// of it ([`right_of`]), and the two below them.
#[inline(always)]
pub(super) fn cell_texels(k: u32, col: u32, width: u32) -> [u32; 4] {
    let right = right_of(k, col, width);
    [k, right, k + width, right + width]
}

/// The `C` values of each corner of a block's cells, from a table of `C`
/// values a texel (`flat`, row-major) and the corners' texels
/// `texels[j][i]` (`[a, b, c, d]` of [`cell_texels`] for each cell `i`):
/// `rows[0]` holds `a`'s values then `b`'s, `rows[1]` `c`'s then `d`'s,
/// one column each. Each row's two corners are one run of `R = 2C` values
/// from its left one ([`simd::gather_runs`]: a 64-bit gather reads two
/// values, half the loads of a gather each), and the cells whose right
/// corners wrap to the row's first column (not right after their left
/// ones) are read again one by one. A texel past the table reads as the
/// last, as [`simd::gather_columns`] reads it (callers pass none).
#[inline(always)]
pub(super) fn gather_corner_rows<const C: usize, const R: usize>(
    flat: &[f32],
    texels: &[[u32; BLOCK]; 4],
) -> simd::OnLines<[[[f32; BLOCK]; R]; 2]> {
    const { assert!(R == 2 * C && 3 * C * MAX_TEXELS <= u32::MAX as usize) };
    let mut rows = simd::OnLines([[[0.0; BLOCK]; R]; 2]);
    let simd::OnLines(starts) = &mut simd::OnLines([0u32; BLOCK]);
    for (row, left) in rows.0.iter_mut().zip([&texels[0], &texels[2]]) {
        for (s, &t) in starts.iter_mut().zip(left) {
            // Within `u32` (asserted above): `C` values a texel of at most
            // `MAX_TEXELS` texels, three times as many padded.
            *s = C as u32 * t;
        }
        simd::gather_runs(flat, starts, row);
    }
    let wraps = |i: usize| texels[1][i] != texels[0][i].wrapping_add(1);
    // A fold without branches, which vectorises; wrapped cells are rare.
    if (0..BLOCK).fold(false, |any, i| any | wraps(i)) {
        let last = (flat.len() / C).saturating_sub(1);
        for i in (0..BLOCK).filter(|&i| wraps(i)) {
            for (j, t) in texels.iter().enumerate() {
                let first = C * (t[i] as usize).min(last);
                for c in 0..C {
                    rows.0[j / 2][C * (j % 2) + c][i] = flat.get(first + c).copied().unwrap_or(0.0);
                }
            }
        }
    }
    rows
}

/// The texel right of texel `k` of column `col` on a lat-long map `width`
/// texels wide, wrapped from the row's last column to its first (in
/// `usize`, or in `u32` where a loop is to vectorise).
#[inline(always)]
pub(super) fn right_of<I>(k: I, col: I, width: I) -> I
where
    I: Copy + PartialEq + Add<Output = I> + Sub<Output = I> + From<u8>,
{
    let one = I::from(1);
    if col + one == width {
        k + one - width
    } else {
        k + one
    }
}

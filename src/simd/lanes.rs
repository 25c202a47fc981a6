//! Transposes of 16 rows of four-byte components (`f32`, `u32`, ...)
//! between rows (`[x, y, z]` interleaved, as the caller's arrays hold them)
//! and one vector per component, in AVX-512 registers: two permutes per
//! vector for three components, one for two. The blocks of
//! [`super::map_rows`] pass through here on AVX-512, where the compiler's
//! own transpose of the same loops moved each value through the stack.
//!
//! Both directions are one operation: vector `v` lane `j` of the result is
//! element `e` of the concatenated sources, with
//! - rows to columns (`m` components): `e = m·j + v`;
//! - columns to rows: `e = 16·c + s`, for output element `16·v + j` =
//!   component `c` of row `s`.

use std::arch::x86_64::{
    __m512i, _mm512_loadu_si512, _mm512_permutex2var_epi32, _mm512_setzero_si512,
    _mm512_storeu_si512, _mm512_stream_si512,
};

/// Lanes of a 512-bit vector of four-byte values.
const LANES: usize = 16;

/// Lane tables for `m` components ([`pick`]'s `first` and `second` per
/// output vector): rows to columns, or with `to_rows` columns to rows.
const fn tables(m: usize, to_rows: bool) -> [[[i32; LANES]; 2]; 3] {
    let mut t = [[[0; LANES]; 2]; 3];
    let mut v = 0;
    while v < m {
        let mut j = 0;
        while j < LANES {
            let e = if to_rows {
                let flat = LANES * v + j;
                LANES * (flat % m) + flat / m
            } else {
                m * j + v
            };
            // First permute: from the first two sources (a placeholder lane
            // for elements of the third); second: keep those lanes, or take
            // the third source's element.
            t[v][0][j] = if e < 2 * LANES { e as i32 } else { 0 };
            t[v][1][j] = if e < 2 * LANES {
                j as i32
            } else {
                (e - LANES) as i32
            };
            j += 1;
        }
        v += 1;
    }
    t
}

const TO_COLUMNS: [[[[i32; LANES]; 2]; 3]; 2] = [tables(2, false), tables(3, false)];
const TO_ROWS: [[[[i32; LANES]; 2]; 3]; 2] = [tables(2, true), tables(3, true)];

/// Vector `v` of the transpose of `sources` (2 or 3 vectors of 16 lanes;
/// `to_rows` or not), as described in the module doc.
#[target_feature(enable = "avx512f")]
#[inline]
fn pick(sources: &[__m512i], v: usize, to_rows: bool) -> __m512i {
    let tables = if to_rows { &TO_ROWS } else { &TO_COLUMNS };
    let [first, second] = tables[sources.len() - 2][v].map(|lanes| {
        // SAFETY: an [i32; 16] and an __m512i are both 64 bytes of plain bits.
        #[allow(unsafe_code)]
        unsafe {
            std::mem::transmute::<[i32; LANES], __m512i>(lanes)
        }
    });
    let two = _mm512_permutex2var_epi32(sources[0], first, sources[1]);
    match sources.get(2) {
        Some(&third) => _mm512_permutex2var_epi32(two, second, third),
        None => two,
    }
}

/// Whether [`rows_to_columns`] and [`columns_to_rows`] handle blocks of `b`
/// rows of `m` components of type `T`.
pub(super) const fn handles<T>(m: usize, b: usize) -> bool {
    size_of::<T>() == 4 && (m == 2 || m == 3) && b.is_multiple_of(LANES)
}

/// `columns[k][i] = rows[i][k]` for a block of `B` rows of `K` four-byte
/// components (see [`handles`]; does nothing for other shapes).
#[target_feature(enable = "avx512f")]
#[inline]
pub(super) fn rows_to_columns<F: Copy, const K: usize, const B: usize>(
    rows: &[[F; K]; B],
    columns: &mut [[F; B]; K],
) {
    if !handles::<F>(K, B) {
        return;
    }
    let src = rows.as_ptr().cast::<__m512i>();
    for g in 0..B / LANES {
        let mut lines = [_mm512_setzero_si512(); K];
        for (v, line) in lines.iter_mut().enumerate() {
            // SAFETY: `rows` holds B·K four-byte values, 64·K bytes per 16
            // rows, so vector K·g + v lies inside it; `loadu` needs no
            // alignment.
            #[allow(unsafe_code)]
            unsafe {
                *line = _mm512_loadu_si512(src.add(K * g + v));
            }
        }
        for (k, column) in columns.iter_mut().enumerate() {
            let vector = pick(&lines, k, false);
            // SAFETY: lanes 16·g to 16·g + 15 of a column of B values (B a
            // multiple of 16); the bits are values of type F, moved whole.
            #[allow(unsafe_code)]
            unsafe {
                _mm512_storeu_si512(column.as_mut_ptr().add(LANES * g).cast(), vector);
            }
        }
    }
}

/// `rows[i][m] = columns[m][i]` for a block of `B` rows of `M` four-byte
/// components (see [`handles`]; does nothing for other shapes). With
/// `stream`, where `rows` starts on a cache line, written with
/// non-temporal stores: each group of 16 rows is `M` whole lines.
#[target_feature(enable = "avx512f")]
#[inline]
pub(super) fn columns_to_rows<T: Copy, const M: usize, const B: usize>(
    columns: &[[T; B]; M],
    rows: &mut [[T; M]; B],
    stream: bool,
) {
    if !handles::<T>(M, B) {
        return;
    }
    let stream = stream && rows.as_ptr().cast::<__m512i>().is_aligned();
    let dst = rows.as_mut_ptr().cast::<__m512i>();
    for g in 0..B / LANES {
        let mut lanes = [_mm512_setzero_si512(); M];
        for (line, column) in lanes.iter_mut().zip(columns) {
            // SAFETY: lanes 16·g to 16·g + 15 of a column of B values.
            #[allow(unsafe_code)]
            unsafe {
                *line = _mm512_loadu_si512(column.as_ptr().add(LANES * g).cast());
            }
        }
        for v in 0..M {
            let vector = pick(&lanes, v, true);
            // SAFETY: `rows` holds B·M four-byte values, so vector M·g + v
            // lies inside it, and is aligned to 64 bytes when `stream` (the
            // start is); the bits are values of type T, moved whole.
            #[allow(unsafe_code)]
            unsafe {
                let at = dst.add(M * g + v);
                if stream {
                    _mm512_stream_si512(at, vector);
                } else {
                    _mm512_storeu_si512(at, vector);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`pick`] on plain arrays: `_mm512_permutex2var_epi32(a, index, b)`
    /// takes lane `index & 15` of `a`, or of `b` when bit 4 is set.
    fn pick_scalar(sources: &[[u32; LANES]], v: usize, to_rows: bool) -> [u32; LANES] {
        let tables = if to_rows { &TO_ROWS } else { &TO_COLUMNS };
        let [first, second] = tables[sources.len() - 2][v];
        let permute = |a: &[u32; LANES], index: &[i32; LANES], b: &[u32; LANES]| {
            index.map(|i| {
                if i & 16 == 0 {
                    a[(i & 15) as usize]
                } else {
                    b[(i & 15) as usize]
                }
            })
        };
        let two = permute(&sources[0], &first, &sources[1]);
        match sources.get(2) {
            Some(third) => permute(&two, &second, third),
            None => two,
        }
    }

    /// The lane tables transpose 16 rows of two or three components both
    /// ways, on any CPU (the AVX-512 code runs only where the CPU has it).
    #[test]
    fn tables_transpose_rows_and_columns() {
        for m in [2, 3] {
            // Row s, component c holds 100·s + c.
            let rows: Vec<[u32; LANES]> = (0..m)
                .map(|v| {
                    std::array::from_fn(|j| {
                        let flat = LANES * v + j;
                        100 * (flat / m) as u32 + (flat % m) as u32
                    })
                })
                .collect();
            let columns: Vec<[u32; LANES]> = (0..m)
                .map(|c| std::array::from_fn(|s| 100 * s as u32 + c as u32))
                .collect();
            for v in 0..m {
                assert_eq!(
                    pick_scalar(&rows, v, false),
                    columns[v],
                    "m {m}, column {v}"
                );
                assert_eq!(pick_scalar(&columns, v, true), rows[v], "m {m}, line {v}");
            }
        }
    }
}

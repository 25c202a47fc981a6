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
//!
//! Rows of other lengths go through a 16 × 16 transpose in registers
//! ([`transpose16`]): rows of up to 16 components written back from
//! their columns ([`columns_to_rows_transposed`]), rows of any length
//! read into columns 16 components at a time
//! ([`rows_to_columns_transposed`]). Left to the compiler, these loops
//! scattered and gathered one element at a time. Pairs of three-vectors
//! (a ray's origin and direction) go to six columns by 4 × 4 transposes
//! within each 128-bit quarter ([`vector_pairs_to_columns`]).

use glam::Vec3A;
use std::arch::x86_64::{
    __m128, __m512, __m512i, _mm512_castpd_ps, _mm512_castps_pd, _mm512_insertf32x4,
    _mm512_loadu_si512, _mm512_mask_storeu_epi32, _mm512_maskz_loadu_epi32,
    _mm512_permutex2var_epi32, _mm512_setzero_ps, _mm512_setzero_si512, _mm512_shuffle_i32x4,
    _mm512_storeu_ps, _mm512_storeu_si512, _mm512_stream_si512, _mm512_unpackhi_epi32,
    _mm512_unpackhi_epi64, _mm512_unpackhi_pd, _mm512_unpackhi_ps, _mm512_unpacklo_epi32,
    _mm512_unpacklo_epi64, _mm512_unpacklo_pd, _mm512_unpacklo_ps,
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

/// Whether [`columns_to_rows_transposed`] handles blocks of `b` rows of
/// `m` components of type `T`.
pub(super) const fn transposes<T>(m: usize, b: usize) -> bool {
    size_of::<T>() == 4 && m >= 2 && m <= LANES && b.is_multiple_of(LANES)
}

/// `rows[i][m] = columns[m][i]` for a block of `B` rows of `M` four-byte
/// components, `M` up to 16 (see [`transposes`]; does nothing for other
/// shapes): each group of 16 rows as a 16 × 16 transpose in registers
/// ([`transpose16`], the columns past `M` zeros), each row then written by
/// one store of its `M` lanes. The compiler's own form of this loop
/// scatters, one element at a time on AMD's cores.
#[target_feature(enable = "avx512f")]
#[inline]
pub(super) fn columns_to_rows_transposed<T: Copy, const M: usize, const B: usize>(
    columns: &[[T; B]; M],
    rows: &mut [[T; M]; B],
) {
    if !transposes::<T>(M, B) {
        return;
    }
    let dst = rows.as_mut_ptr().cast::<i32>();
    let mask = ((1_u32 << M) - 1) as u16;
    for g in 0..B / LANES {
        let mut lines = [_mm512_setzero_si512(); LANES];
        for (line, column) in lines.iter_mut().zip(columns) {
            // SAFETY: lanes 16·g to 16·g + 15 of a column of B values.
            #[allow(unsafe_code)]
            unsafe {
                *line = _mm512_loadu_si512(column.as_ptr().add(LANES * g).cast());
            }
        }
        transpose16(&mut lines);
        for (s, line) in lines.iter().enumerate() {
            // SAFETY: row 16·g + s of B rows of M four-byte values: its M
            // lanes (the mask) lie inside `rows`; the bits are values of
            // type T, moved whole.
            #[allow(unsafe_code)]
            unsafe {
                _mm512_mask_storeu_epi32(dst.add(M * (LANES * g + s)), mask, *line);
            }
        }
    }
}

/// Whether [`rows_to_columns_transposed`] handles blocks of `b` rows of
/// `k` components of type `T`.
pub(super) const fn transposes_rows<T>(k: usize, b: usize) -> bool {
    size_of::<T>() == 4 && k >= 2 && b.is_multiple_of(LANES)
}

/// `columns[k][i] = rows[i][k]` for a block of `B` rows of `K` four-byte
/// components (see [`transposes_rows`]; does nothing for other shapes):
/// each group of 16 rows read 16 components at a time (the row's first `K`
/// by one load when `K < 16`; else components `k0 .. k0 + 16`, the last
/// such window ending at the row's end) and transposed in registers
/// ([`transpose16`]). The compiler's own form of this loop gathers each
/// column.
#[target_feature(enable = "avx512f")]
#[inline]
pub(super) fn rows_to_columns_transposed<F: Copy, const K: usize, const B: usize>(
    rows: &[[F; K]; B],
    columns: &mut [[F; B]; K],
) {
    if !transposes_rows::<F>(K, B) {
        return;
    }
    let src = rows.as_ptr().cast::<i32>();
    let mask = if K < LANES {
        ((1_u32 << K) - 1) as u16
    } else {
        u16::MAX
    };
    for g in 0..B / LANES {
        let mut k0 = 0;
        while k0 < K {
            // The window's first component: k0, or K − 16 for the last
            // window of a row longer than 16.
            let start = if K < LANES { 0 } else { k0.min(K - LANES) };
            let mut lines = [_mm512_setzero_si512(); LANES];
            for (s, line) in lines.iter_mut().enumerate() {
                // SAFETY: components `start ..` of row 16·g + s, of which
                // the mask keeps min(K, 16), all inside the row (`start +
                // 16 <= K` when K >= 16); `loadu` needs no alignment.
                #[allow(unsafe_code)]
                unsafe {
                    *line = _mm512_maskz_loadu_epi32(mask, src.add(K * (LANES * g + s) + start));
                }
            }
            transpose16(&mut lines);
            let end = (start + LANES).min(K);
            for (k, line) in (k0..end).zip(&lines[k0 - start..]) {
                // SAFETY: lanes 16·g to 16·g + 15 of a column of B values;
                // the bits are values of type F, moved whole.
                #[allow(unsafe_code)]
                unsafe {
                    _mm512_storeu_si512(columns[k].as_mut_ptr().add(LANES * g).cast(), *line);
                }
            }
            k0 = end;
        }
    }
}

/// Whether [`vector_pairs_to_columns`] handles blocks of `b` items.
pub(super) const fn transposes_pairs(b: usize) -> bool {
    b.is_multiple_of(LANES)
}

/// `columns[k][i]` = component `k` of `pair(items[i])[0]` for `k < 3`, and
/// component `k − 3` of `pair(items[i])[1]` for `k >= 3`; zeros for `i` at
/// or past `items.len()`. Each group of 16 items as four vectors of four
/// items' three-vectors (item `4q + j` in quarter `q` of vector `j`), then
/// a 4 × 4 transpose within each quarter: 32 inserts (8 of them into
/// zeroed vectors) and 14 shuffles per 16 items. Does nothing unless
/// [`transposes_pairs`] holds for `B`. The compiler's own form of this loop gathers each column (six
/// gathers per 16 items), and copies a block's last items one value at a
/// time.
#[target_feature(enable = "avx512f")]
#[inline]
pub(super) fn vector_pairs_to_columns<T, const B: usize>(
    items: &[T],
    pair: impl Fn(&T) -> [Vec3A; 2],
    columns: &mut [[f32; B]; 6],
) {
    if !transposes_pairs(B) {
        return;
    }
    for g in 0..B / LANES {
        let mut first = [_mm512_setzero_ps(); 4];
        let mut second = [_mm512_setzero_ps(); 4];
        for (j, (a, b)) in first.iter_mut().zip(&mut second).enumerate() {
            for q in 0..4 {
                let Some(item) = items.get(LANES * g + 4 * q + j) else {
                    break;
                };
                let [x, y] = pair(item).map(__m128::from);
                *a = insert_quarter(*a, q, x);
                *b = insert_quarter(*b, q, y);
            }
        }
        for (vectors, at) in [(first, 0), (second, 3)] {
            for (k, column) in transpose_quarters(vectors).iter().enumerate() {
                // SAFETY: lanes 16·g to 16·g + 15 of a column of B values.
                #[allow(unsafe_code)]
                unsafe {
                    _mm512_storeu_ps(columns[at + k].as_mut_ptr().add(LANES * g), *column);
                }
            }
        }
    }
}

/// `v` with its quarter `q` (lanes `4q .. 4q + 4`) set to `x`.
#[target_feature(enable = "avx512f")]
#[inline]
fn insert_quarter(v: __m512, q: usize, x: __m128) -> __m512 {
    match q {
        0 => _mm512_insertf32x4::<0>(v, x),
        1 => _mm512_insertf32x4::<1>(v, x),
        2 => _mm512_insertf32x4::<2>(v, x),
        _ => _mm512_insertf32x4::<3>(v, x),
    }
}

/// The first three rows of the 4 × 4 transposes of `v` within each
/// quarter: lane `4q + j` of row `k` is lane `4q + k` of `v[j]`.
#[target_feature(enable = "avx512f")]
#[inline]
fn transpose_quarters(v: [__m512; 4]) -> [__m512; 3] {
    let lo01 = _mm512_unpacklo_ps(v[0], v[1]);
    let hi01 = _mm512_unpackhi_ps(v[0], v[1]);
    let lo23 = _mm512_unpacklo_ps(v[2], v[3]);
    let hi23 = _mm512_unpackhi_ps(v[2], v[3]);
    let pairs = |a: __m512, b: __m512, high: bool| {
        let (a, b) = (_mm512_castps_pd(a), _mm512_castps_pd(b));
        _mm512_castpd_ps(if high {
            _mm512_unpackhi_pd(a, b)
        } else {
            _mm512_unpacklo_pd(a, b)
        })
    };
    [
        pairs(lo01, lo23, false),
        pairs(lo01, lo23, true),
        pairs(hi01, hi23, false),
    ]
}

/// Transposes 16 vectors of 16 lanes in place (`v[j]` lane `i` becomes
/// `v[i]` lane `j`): pairs of lanes, of pairs, of 128-bit quarters, then of
/// halves are exchanged, 64 shuffles in all.
#[target_feature(enable = "avx512f")]
#[inline]
fn transpose16(v: &mut [__m512i; LANES]) {
    let mut t = [_mm512_setzero_si512(); LANES];
    for i in 0..LANES / 2 {
        t[2 * i] = _mm512_unpacklo_epi32(v[2 * i], v[2 * i + 1]);
        t[2 * i + 1] = _mm512_unpackhi_epi32(v[2 * i], v[2 * i + 1]);
    }
    for q in 0..LANES / 4 {
        let b = 4 * q;
        v[b] = _mm512_unpacklo_epi64(t[b], t[b + 2]);
        v[b + 1] = _mm512_unpackhi_epi64(t[b], t[b + 2]);
        v[b + 2] = _mm512_unpacklo_epi64(t[b + 1], t[b + 3]);
        v[b + 3] = _mm512_unpackhi_epi64(t[b + 1], t[b + 3]);
    }
    for h in 0..2 {
        let b = 8 * h;
        for k in 0..4 {
            t[b + k] = _mm512_shuffle_i32x4::<0x88>(v[b + k], v[b + 4 + k]);
            t[b + 4 + k] = _mm512_shuffle_i32x4::<0xdd>(v[b + k], v[b + 4 + k]);
        }
    }
    for k in 0..8 {
        v[k] = _mm512_shuffle_i32x4::<0x88>(t[k], t[8 + k]);
        v[8 + k] = _mm512_shuffle_i32x4::<0xdd>(t[k], t[8 + k]);
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
    /// Columns of 2 to 16 components become their rows by transposes, in
    /// blocks of one and of four groups of 16 rows (where the CPU has
    /// AVX-512).
    #[test]
    fn transposes_write_every_row_whole() {
        if !std::arch::is_x86_feature_detected!("avx512f") {
            return;
        }
        fn check<const M: usize, const B: usize>() {
            // Column c, row s holds 1000·s + c.
            let columns: [[u32; B]; M] =
                std::array::from_fn(|c| std::array::from_fn(|s| 1000 * s as u32 + c as u32));
            let mut rows = [[u32::MAX; M]; B];
            #[allow(unsafe_code)]
            // SAFETY: the CPU has AVX-512 F (checked above).
            unsafe {
                columns_to_rows_transposed(&columns, &mut rows);
            }
            for (s, row) in rows.iter().enumerate() {
                let want: [u32; M] = std::array::from_fn(|c| 1000 * s as u32 + c as u32);
                assert_eq!(*row, want, "M {M}, B {B}, row {s}");
            }
        }
        check::<2, 16>();
        check::<4, 64>();
        check::<11, 64>();
        check::<11, 16>();
        check::<15, 32>();
        check::<16, 64>();
    }

    /// Rows of 2 to 40 components become their columns by transposes, in
    /// blocks of one and of four groups of 16 rows (where the CPU has
    /// AVX-512).
    #[test]
    fn transposes_read_every_column_whole() {
        if !std::arch::is_x86_feature_detected!("avx512f") {
            return;
        }
        fn check<const K: usize, const B: usize>() {
            // Row s, component c holds 1000·s + c.
            let rows: [[u32; K]; B] =
                std::array::from_fn(|s| std::array::from_fn(|c| 1000 * s as u32 + c as u32));
            let mut columns = [[u32::MAX; B]; K];
            #[allow(unsafe_code)]
            // SAFETY: the CPU has AVX-512 F (checked above).
            unsafe {
                rows_to_columns_transposed(&rows, &mut columns);
            }
            for (c, column) in columns.iter().enumerate() {
                let want: [u32; B] = std::array::from_fn(|s| 1000 * s as u32 + c as u32);
                assert_eq!(*column, want, "K {K}, B {B}, column {c}");
            }
        }
        check::<2, 16>();
        check::<5, 64>();
        check::<15, 16>();
        check::<16, 64>();
        check::<17, 16>();
        check::<18, 64>();
        check::<32, 32>();
        check::<40, 64>();
    }

    /// Every item's two vectors land in their six columns, and the rows
    /// past the items are zeros, for blocks of one and four groups of 16
    /// and every count of items up to the block (where the CPU has
    /// AVX-512).
    #[test]
    fn vector_pairs_fill_every_column() {
        if !std::arch::is_x86_feature_detected!("avx512f") {
            return;
        }
        fn check<const B: usize>() {
            // Item i holds 100·i + 1, 2, 3 and 100·i + 4, 5, 6.
            let items: Vec<[Vec3A; 2]> = (0..B)
                .map(|i| {
                    let v = |c: usize| (100 * i + c) as f32;
                    [Vec3A::new(v(1), v(2), v(3)), Vec3A::new(v(4), v(5), v(6))]
                })
                .collect();
            for n in 0..=B {
                let mut columns = [[f32::NAN; B]; 6];
                #[allow(unsafe_code)]
                // SAFETY: the CPU has AVX-512 F (checked above).
                unsafe {
                    vector_pairs_to_columns(&items[..n], |&p| p, &mut columns);
                }
                for (k, column) in columns.iter().enumerate() {
                    let want: [f32; B] =
                        std::array::from_fn(|i| if i < n { (100 * i + k + 1) as f32 } else { 0.0 });
                    assert_eq!(*column, want, "B {B}, {n} items, column {k}");
                }
            }
        }
        check::<16>();
        check::<64>();
    }
}

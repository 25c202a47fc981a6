//! [`Sobol`]: the Sobol' sequence in base 2, plain (scipy's points), Owen
//! scrambled, or by a random linear matrix scramble and digital shift.

use super::directions::{BITS, MAX_DIMENSIONS, columns};
use super::{Rows, check_dims, check_range, scramble_rng};
use crate::error::Result;
use crate::math::Real;
use crate::rng::Rng;
use crate::{parallel, simd};

/// How [`Sobol`] randomises its points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scramble {
    /// The plain sequence: the points of `scipy.stats.qmc.Sobol(d,
    /// scramble=False)`, bit for bit (its first point is the origin).
    None,
    /// Owen's nested uniform scrambling, each dimension with its own seed,
    /// by a hash (Vegdahl's Laine–Karras hash, pbrt-v4's
    /// `FastOwenScrambler`): every point is uniform on `[0, 1)^d` over
    /// seeds, and every `2^m`-point prefix keeps the sequence's net
    /// structure.
    Owen,
    /// A random lower-triangular (in bit significance) binary matrix with
    /// ones on its diagonal applied to every generator matrix, then a
    /// random digital shift (Matoušek 1998): scipy's `scramble=True`
    /// (with other random bits).
    LinearMatrix,
}

/// The Sobol' sequence in `d` dimensions with Joe and Kuo's direction
/// numbers, in Gray-code order as scipy generates it: point `i` is
///
/// `x_i,j = (⊕_{b : bit b of g(i) set} v_j,b) / 2^32`, `g(i) = i ⊕ ⌊i/2⌋`,
///
/// then scrambled as [`Scramble`] says. Indices run from 0 to `2^32 − 1`.
#[derive(Clone, Debug)]
pub struct Sobol {
    /// Bit-major: `by_bit[b·d + j]` is column `b` of dimension `j`'s
    /// matrix, so that a step of the Gray-code walk is one pass of XORs
    /// over contiguous memory.
    by_bit: Vec<u32>,
    dims: usize,
    scramble: Scramble,
    /// Per dimension: the Owen seed, or the digital shift (0 for plain).
    keys: Vec<u32>,
}

/// Values in the table of [`Sobol::fill`]: at most this many (16 KiB of
/// bits, which stay in the first-level cache while a block's rows are
/// written), or one row when `d` is larger.
const TABLE_VALUES: usize = 4096;

/// Rows in the pattern [`Sobol::fill`] XORs over the table in one pass: 8,
/// so that a pass is a whole number of vectors of up to 8 lanes whatever `d`.
const PATTERN_ROWS: usize = 8;

impl Sobol {
    /// The first `dims` dimensions of the sequence, scrambled by `scramble`
    /// with random bits from `seed`.
    ///
    /// # Errors
    /// [`crate::Error::Integer`] unless `1 ≤ dims ≤` [`MAX_DIMENSIONS`].
    pub fn new(dims: usize, scramble: Scramble, seed: u64) -> Result<Self> {
        check_dims(dims, MAX_DIMENSIONS)?;
        let mut columns = columns(dims);
        let mut rng = scramble_rng(seed);
        let keys = match scramble {
            Scramble::None => vec![0; dims],
            Scramble::Owen => (0..dims).map(|_| rng.next_u32()).collect(),
            Scramble::LinearMatrix => {
                for v in &mut columns {
                    let rows = lower_triangular(&mut rng);
                    *v = v.map(|c| multiply(&rows, c));
                }
                (0..dims).map(|_| rng.next_u32()).collect()
            }
        };
        let by_bit = (0..BITS)
            .flat_map(|b| columns.iter().map(move |v| v[b]))
            .collect();
        Ok(Sobol {
            by_bit,
            dims,
            scramble,
            keys,
        })
    }

    /// Number of dimensions.
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// Column `b` of every dimension's matrix.
    fn column(&self, b: usize) -> &[u32] {
        &self.by_bit[b * self.dims..(b + 1) * self.dims]
    }

    /// Coordinate `dim` of point `index`, before the scramble's last step.
    fn unscrambled(&self, index: u32, dim: usize) -> u32 {
        let gray = index ^ (index >> 1);
        (0..BITS)
            .filter(|&b| gray >> b & 1 == 1)
            .fold(0, |acc, b| acc ^ self.column(b)[dim])
    }

    /// Coordinate `dim` of point `index`, as 32 bits (`x·2^32`).
    pub fn bits(&self, index: u32, dim: usize) -> u32 {
        let x = self.unscrambled(index, dim);
        match self.scramble {
            Scramble::Owen => owen(x, self.keys[dim]),
            Scramble::None | Scramble::LinearMatrix => x ^ self.keys[dim],
        }
    }

    /// Points `first ..` into `out` (row-major, `dims` values a row, as many
    /// rows as fit), on all cores; the same bits at any thread count.
    ///
    /// Blocks of `R` rows (the largest power of two with `R·d ≤ 4096`, or
    /// one row) that start at a multiple of `R` differ only in their high
    /// bits: for `i = B·R + r`,
    /// `g(i) = g(B·R) ⊕ g(r)`, so point `i` is `x_{B·R} ⊕ T[r]` with the table
    /// `T[r] = ⊕_{b : bit b of g(r) set} v_b` (the low `log2 R` columns) the
    /// same for every block. A block is one vectorised pass of XORs with its
    /// first point over the table, then the scramble and the conversion; the
    /// next block's first point is `x_{B·R} ⊕ T[R − 1] ⊕ v_{tz((B+1)·R)}` (the
    /// Gray-code step into it).
    ///
    /// # Errors
    /// [`crate::Error::Integer`] if the points would pass index `2^32 − 1`, or
    /// if `out` does not hold whole rows.
    pub fn fill<F: Real>(&self, first: u64, out: &mut [F]) -> Result<()> {
        let d = self.dims;
        let n = check_range(out.len(), d, first, 1 << BITS)?;
        let rows = prev_power_of_two((TABLE_VALUES / d).max(1));
        let mut table = vec![0u32; rows * d];
        for r in 1..rows {
            let (before, row) = table.split_at_mut(r * d);
            let step = row[..d].iter_mut().zip(&before[(r - 1) * d..]);
            for ((t, &previous), &v) in step.zip(self.column(r.trailing_zeros() as usize)) {
                *t = previous ^ v;
            }
        }
        let keys = repeat_rows(&self.keys, PATTERN_ROWS);
        parallel::for_each_chunk(n, Rows::new(out, d), |range, rows_out| {
            let start = first + range.start as u64;
            let mut block = start / rows as u64;
            let mut r = (start % rows as u64) as usize;
            let mut base: Vec<u32> = (0..d)
                .map(|j| self.unscrambled((block * rows as u64) as u32, j))
                .collect();
            let mut pattern = vec![0u32; PATTERN_ROWS.min(rows) * d];
            let mut values = rows_out.values;
            while !values.is_empty() {
                let take = (rows - r).min(values.len() / d);
                let (now, later) = values.split_at_mut(take * d);
                match self.scramble {
                    Scramble::Owen => {
                        fill_pattern(&mut pattern, &base, |b, _| b);
                        xor_finish(now, &table[r * d..], &pattern, &keys, owen);
                    }
                    Scramble::None | Scramble::LinearMatrix => {
                        fill_pattern(&mut pattern, &base, |b, j| b ^ self.keys[j]);
                        xor_finish(now, &table[r * d..], &pattern, &keys, |x, _| x);
                    }
                }
                values = later;
                if !values.is_empty() {
                    // Into the next block: its first point is one Gray-code
                    // step from this block's last.
                    block += 1;
                    let bit = (block * rows as u64).trailing_zeros() as usize;
                    let last = &table[(rows - 1) * d..];
                    for ((b, &t), &v) in base.iter_mut().zip(last).zip(self.column(bit)) {
                        *b ^= t ^ v;
                    }
                    r = 0;
                }
            }
            true
        })
        .map(|_| ())
    }
}

/// The largest power of two at most `n ≥ 1`.
fn prev_power_of_two(n: usize) -> usize {
    1 << (usize::BITS - 1 - n.leading_zeros())
}

/// `row` repeated `times` times.
fn repeat_rows(row: &[u32], times: usize) -> Vec<u32> {
    row.iter()
        .copied()
        .cycle()
        .take(row.len() * times)
        .collect()
}

/// `pattern`, [`PATTERN_ROWS`] rows of `base.len()` values: `f(base[j], j)`
/// in column `j` of every row.
fn fill_pattern(pattern: &mut [u32], base: &[u32], f: impl Fn(u32, usize) -> u32) {
    for row in pattern.chunks_exact_mut(base.len()) {
        for (j, (p, &b)) in row.iter_mut().zip(base).enumerate() {
            *p = f(b, j);
        }
    }
}

/// `out[k] = step(table[k] ⊕ pattern[k mod P], keys[k mod P])` as a float in `[0, 1)`,
/// `P` the pattern's length (whole rows), in a loop compiled for the widest vector unit.
#[inline(always)]
fn xor_finish<F: Real>(
    out: &mut [F],
    table: &[u32],
    pattern: &[u32],
    keys: &[u32],
    step: impl Fn(u32, u32) -> u32,
) {
    let p = pattern.len();
    simd::dispatch(
        #[inline(always)]
        |_| {
            for (out, table) in out.chunks_mut(p).zip(table.chunks(p)) {
                let lanes = out.iter_mut().zip(table).zip(pattern).zip(keys);
                for (((value, &t), &x), &key) in lanes {
                    *value = F::from_random_bits(step(t ^ x, key));
                }
            }
        },
    );
}

/// Owen's nested uniform scramble of `x` by a hash: reversed, its bits
/// read from the most significant become the least significant, and a
/// Laine–Karras permutation (additions, multiplications by odd numbers and
/// `v ^= v·even`, each changing only bits above those it reads) flips each
/// bit by a function of the bits before it and `seed`; see
/// [`owen_reversed`].
#[inline(always)]
pub fn owen(x: u32, seed: u32) -> u32 {
    owen_reversed(x.reverse_bits(), seed)
}

/// [`owen`] of the value whose bits reversed are `r` (a caller that builds
/// its values from reversed generator matrices saves one reversal).
#[inline(always)]
pub fn owen_reversed(r: u32, seed: u32) -> u32 {
    laine_karras(r, seed).reverse_bits()
}

/// [`owen_reversed`] of two values with their own seeds, bit-reversed
/// together as one 64-bit word (half the reversals of two calls).
#[inline(always)]
pub fn owen_reversed_pair(r: [u32; 2], seed: [u32; 2]) -> [u32; 2] {
    let low = u64::from(laine_karras(r[1], seed[1]));
    let both = (low | u64::from(laine_karras(r[0], seed[0])) << 32).reverse_bits();
    [both as u32, (both >> 32) as u32]
}

/// The Laine–Karras permutation of [`owen`], on reversed bits, with the
/// steps and constants of Vegdahl's 2021 search (used by pbrt-v4's
/// `FastOwenScrambler`), whose flips depend on the higher bits more evenly
/// than those of Burley 2020 (on the demo render with 16 samples a pixel,
/// relMSE 3 % lower).
#[inline(always)]
fn laine_karras(r: u32, seed: u32) -> u32 {
    let mut v = r ^ r.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed).wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^ v.wrapping_mul(0x53a2_2864)
}

/// A random binary matrix, lower triangular when bit 31 is row 0 and
/// unit on the diagonal: row `i` as the mask of the input bits that output
/// bit `31 − i` sums.
fn lower_triangular(rng: &mut Rng) -> [u32; BITS] {
    std::array::from_fn(|i| {
        let diagonal = 1u32 << (BITS - 1 - i);
        // The bits above the diagonal (more significant): i of them.
        let above = !(diagonal | (diagonal - 1));
        diagonal | (rng.next_u32() & above)
    })
}

/// The matrix `rows` times the bit vector `c` over GF(2).
fn multiply(rows: &[u32; BITS], c: u32) -> u32 {
    rows.iter().enumerate().fold(0, |acc, (i, &row)| {
        acc | (((row & c).count_ones() & 1) << (BITS - 1 - i))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

    fn points(s: &Sobol, first: u64, n: usize) -> Vec<f64> {
        let mut out = vec![0.0; n * s.dims()];
        s.fill(first, &mut out).unwrap();
        out
    }

    /// The first points of the plain sequence, by hand: 0, 1/2, then the
    /// Gray-code walk (scipy's order).
    #[test]
    fn plain_points_start_at_the_origin_in_gray_code_order() {
        let s = Sobol::new(2, Scramble::None, 0).unwrap();
        assert_eq!(
            points(&s, 0, 4),
            [0.0, 0.0, 0.5, 0.5, 0.75, 0.25, 0.25, 0.75]
        );
    }

    /// A block started anywhere, and one split across threads, equal the
    /// points computed one at a time.
    #[test]
    fn fill_agrees_with_bits_from_any_start() {
        // 5 dimensions: tables of 512 rows; 600: of 4 rows; 5000: of one.
        for (scramble, d) in [
            (Scramble::None, 5),
            (Scramble::Owen, 5),
            (Scramble::LinearMatrix, 5),
            (Scramble::Owen, 600),
            (Scramble::None, 5000),
        ] {
            let s = Sobol::new(d, scramble, 7).unwrap();
            let first = 123_456;
            let out = points(&s, first, 70_000 * 5 / d);
            for (r, row) in out.chunks(d).enumerate().step_by(97) {
                for (j, &x) in row.iter().enumerate() {
                    let bits = s.bits((first + r as u64) as u32, j);
                    assert_eq!(x, f64::from(bits) / 2f64.powi(32));
                }
            }
        }
    }

    /// Each scramble keeps the (0, m, 2)-net property of dimensions 0 and
    /// 1: every prefix of 2^m points puts one point in each elementary box
    /// of area 2^−m.
    #[test]
    fn scrambles_keep_the_net_of_the_first_two_dimensions() {
        for scramble in [Scramble::None, Scramble::Owen, Scramble::LinearMatrix] {
            let s = Sobol::new(2, scramble, 3).unwrap();
            for m in 0..=10u32 {
                for a in 0..=m {
                    let top = |v: u32, k: u32| if k == 0 { 0 } else { v >> (32 - k) };
                    let mut seen = vec![false; 1 << m];
                    for i in 0..1u32 << m {
                        let cell = (top(s.bits(i, 0), a) << (m - a)) | top(s.bits(i, 1), m - a);
                        let cell = cell as usize;
                        assert!(!seen[cell], "{scramble:?} m {m} a {a} point {i}");
                        seen[cell] = true;
                    }
                }
            }
        }
    }

    /// Past index 2^32 − 1 there are no points.
    #[test]
    fn the_last_index_is_2_to_the_32_minus_1() {
        let s = Sobol::new(1, Scramble::None, 0).unwrap();
        let mut out = [0.0f64; 2];
        assert!(s.fill((1 << 32) - 2, &mut out).is_ok());
        assert!(matches!(
            s.fill((1 << 32) - 1, &mut out),
            Err(Error::Integer { .. })
        ));
        assert!(Sobol::new(0, Scramble::None, 0).is_err());
        assert!(Sobol::new(MAX_DIMENSIONS + 1, Scramble::None, 0).is_err());
    }

    /// Owen's scramble permutes: bijective on the top bits it is fed, and
    /// a bit depends only on the bits above it.
    #[test]
    fn owen_scrambling_is_nested() {
        for seed in [0, 1, 0xdead_beef] {
            for x in (0..1u32 << 12).map(|k| k << 20) {
                let y = owen(x, seed);
                // Flipping bit 19 (below all of x's) changes only bits ≤ 19.
                assert_eq!(owen(x ^ (1 << 19), seed) >> 20, y >> 20);
            }
            let mut top: Vec<u32> = (0..1u32 << 12).map(|k| owen(k << 20, seed) >> 20).collect();
            top.sort_unstable();
            assert!(top.iter().enumerate().all(|(k, &t)| t == k as u32));
        }
    }

    #[test]
    fn a_pair_is_two_scrambles() {
        let mut rng = crate::rng::Rng::new(5, 3);
        for _ in 0..1000 {
            let (r, seed) = (
                [rng.next_u32(), rng.next_u32()],
                [rng.next_u32(), rng.next_u32()],
            );
            let pair = owen_reversed_pair(r, seed);
            assert_eq!(
                pair,
                [owen_reversed(r[0], seed[0]), owen_reversed(r[1], seed[1])]
            );
        }
    }
}

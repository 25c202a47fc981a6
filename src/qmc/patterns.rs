//! Stratified patterns of `n` points drawn whole: [`Pattern::LatinHypercube`],
//! [`Pattern::Stratified`] (Mitsuba's `stratified` sampler) and
//! [`Pattern::MultiJitter`] (Kensler's correlated multi-jittered sampling,
//! Mitsuba's `multijitter`). Each point is computed from its index, the
//! pattern's size and seed alone (Kensler's hashed permutations instead of
//! shuffles), so a pattern fills on all cores with the same bits at any
//! thread count.

use super::{Rows, check_dims, check_range};
use crate::error::Result;
use crate::math::Real;
use crate::{parallel, simd};

/// Dimensions a pattern accepts.
pub const MAX_DIMENSIONS: usize = 1 << 16;

/// Points a pattern may have: `2^30`, so that the strata of
/// [`Pattern::Stratified`]'s square grid are counted in 32 bits.
pub const MAX_POINTS: u64 = 1 << 30;

/// How a pattern of `n` points stratifies `[0, 1)^d`. `π` is a random
/// permutation (Kensler's hash, its own seed per dimension or pair) and
/// `ξ` a uniform jitter; point `s` of `n` gets:
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pattern {
    /// `x_j = (π_j(s) + ξ)/n` in every dimension (McKay et al. 1979): each
    /// dimension has one point per interval of length `1/n`; `centered`
    /// puts `ξ = 1/2` (scipy's `scramble=False`).
    LatinHypercube {
        /// Points at their intervals' centres.
        centered: bool,
    },
    /// Per pair of dimensions, the strata of an `r × r` grid (`r = ⌈√n⌉`)
    /// in a random order, `(x, y) = ((c mod r + ξ)/r, (⌊c/r⌋ + ξ')/r)` with
    /// `c = π(s)`: one point per stratum when `n` is a square (Mitsuba
    /// rounds its sample count up to one); a last odd dimension is
    /// stratified in `n` intervals.
    Stratified,
    /// Per pair of dimensions, Kensler's correlated multi-jitter (2013):
    /// `m = ⌊√n⌋`, `k = ⌈n/m⌉`, `s' = π(s)`, `x = (π_x(s' mod m) +
    /// (π_y(⌊s'/m⌋) + ξ)/k)/m`, `y = (s' + ξ')/n`: stratified in the `m × k`
    /// grid and in `n` intervals along each axis; a last odd dimension is
    /// stratified in `n` intervals.
    MultiJitter,
}

/// A pattern of `n` points in `d` dimensions, seeded.
#[derive(Clone, Copy, Debug)]
pub struct Patterns {
    pattern: Pattern,
    dims: usize,
    seed: u64,
}

impl Patterns {
    /// Patterns of kind `pattern` in `dims` dimensions from `seed`.
    ///
    /// # Errors
    /// [`crate::Error::Integer`] unless `1 ≤ dims ≤` [`MAX_DIMENSIONS`].
    pub fn new(pattern: Pattern, dims: usize, seed: u64) -> Result<Self> {
        check_dims(dims, MAX_DIMENSIONS)?;
        Ok(Patterns {
            pattern,
            dims,
            seed,
        })
    }

    /// Number of dimensions.
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// The pattern numbered `draw` (any number: the engine's count of
    /// points drawn before it), of as many points as `out` holds rows
    /// (row-major, `dims` values a row), on all cores.
    ///
    /// # Errors
    /// [`crate::Error::Integer`] for more than [`MAX_POINTS`] points, or if
    /// `out` does not hold whole rows.
    pub fn fill<F: Real>(&self, draw: u64, out: &mut [F]) -> Result<()> {
        let d = self.dims;
        let n = check_range(out.len(), d, 0, MAX_POINTS)? as u32;
        let layouts = self.layouts(draw, n);
        parallel::for_each_chunk(n as usize, Rows::new(out, d), |range, rows| {
            if let Pattern::LatinHypercube { centered } = self.pattern {
                latin_hypercube(range.start as u32, &layouts, centered, rows.values);
            } else {
                for (s, row) in (range.start as u32..).zip(rows.chunks_mut()) {
                    self.pairs(s, &layouts, row);
                }
            }
            true
        })
        .map(|_| ())
    }

    /// The layouts of pattern `draw` of `n` points: one 32-bit seed per
    /// dimension (LHS) or pair (the others).
    fn layouts(&self, draw: u64, n: u32) -> Vec<Layout> {
        let key = mix64(self.seed ^ mix64(draw));
        (0..self.dims as u64)
            .map(|j| Layout::new(n, (mix64(key ^ j) >> 32) as u32, self.pattern))
            .collect()
    }

    /// Point `s` of a pattern by pairs of dimensions into `row`
    /// (`layouts`: one per pair).
    fn pairs<F: Real>(&self, s: u32, layouts: &[Layout], row: &mut [F]) {
        let unit = |x: f64| F::c(x).min(F::ONE_MINUS_EPSILON);
        let mut pairs = row.chunks_exact_mut(2);
        for (pair, l) in pairs.by_ref().zip(layouts) {
            let (x, y) = l.pair(s, self.pattern);
            pair[0] = unit(x);
            pair[1] = unit(y);
        }
        if let [last] = pairs.into_remainder() {
            *last = unit(layouts[self.dims / 2].single(s, false));
        }
    }
}

/// Rows in a tile of [`latin_hypercube`].
const TILE_ROWS: usize = 256;

/// Points `first ..` of a Latin hypercube into `values` (whole rows, one
/// layout a dimension), [`Layout::single`] of each: a tile of rows one
/// dimension after another, each column computed in one vectorised pass
/// (the permutation's step, the jitter, the division), then the few
/// indices the permutation's cycle walk must step again, then stored.
fn latin_hypercube<F: Real>(first: u32, layouts: &[Layout], centered: bool, values: &mut [F]) {
    let d = layouts.len();
    let mut column = [0.0f64; TILE_ROWS];
    let mut steps = [0u32; TILE_ROWS];
    for (t, tile) in values.chunks_mut(TILE_ROWS * d).enumerate() {
        let first = first + (t * TILE_ROWS) as u32;
        let rows = tile.len() / d;
        for (j, l) in layouts.iter().enumerate() {
            let (n, p) = (l.n, l.p);
            let (column, steps) = (&mut column[..rows], &mut steps[..rows]);
            simd::dispatch(
                #[inline(always)]
                |_| {
                    for (s, step) in (first..).zip(steps.iter_mut()) {
                        *step = kensler_step(s, n, p);
                    }
                },
            );
            for step in steps.iter_mut().filter(|step| **step >= n) {
                *step = walk(*step, n, p);
            }
            let (key, rotation, scale) = (lowbias32(p), l.rotations[0], f64::from(n));
            let value =
                move |k: u32, jitter: f64| (f64::from(rotate(k, n, rotation)) + jitter) / scale;
            simd::dispatch(
                #[inline(always)]
                |_| {
                    let cells = steps.iter().zip(column.iter_mut());
                    if centered {
                        cells.for_each(|(&k, x)| *x = value(k, 0.5));
                    } else {
                        for (s, (&k, x)) in (first..).zip(cells) {
                            *x = value(k, hashed_jitter(s, key));
                        }
                    }
                },
            );
            for (row, &x) in tile.chunks_exact_mut(d).zip(column.iter()) {
                row[j] = F::c(x).min(F::ONE_MINUS_EPSILON);
            }
        }
    }
}

/// The permutations of a pattern of `n` points for one seed `p`, laid out
/// once for all its points: the grids' sides (`r = ⌈√n⌉` of
/// [`Pattern::Stratified`], `m = ⌊√n⌋` and `k = ⌈n/m⌉` of
/// [`Pattern::MultiJitter`]) and the rotation (`seed mod length`) of each
/// of Kensler's permutations its points draw.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Layout {
    n: u32,
    p: u32,
    r: u32,
    m: u32,
    k: u32,
    /// Of the permutations of `0 .. n` by `p`, of the `r²` strata by `p`,
    /// and of [`Layout::multi_jitter`]'s three (of `0 .. n`, `0 .. m` and
    /// `0 .. k`, by `p` times [`MULTI_JITTER`]'s first three constants).
    rotations: [u32; 5],
}

/// The multipliers of the multi-jittered pattern's seed: for the
/// permutations of the points, of the columns and of the rows, then for
/// the two jitters.
const MULTI_JITTER: [u32; 5] = [
    0x5163_3e2d,
    0x68bc_21eb,
    0x02e5_be93,
    0x967a_889b,
    0x368c_c8b7,
];

impl Layout {
    /// The layout of `n` points for seed `p`, for [`Layout::single`] and,
    /// when `pairs` is a stratified pattern, for its points (the rotations
    /// of the other pattern left 0: its points would not be stratified).
    pub(crate) fn new(n: u32, p: u32, pairs: Pattern) -> Self {
        let rotation = |seed: u32, len: u32| seed % len.max(1);
        let mut layout = Layout {
            n,
            p,
            rotations: [rotation(p, n), 0, 0, 0, 0],
            ..Layout::default()
        };
        let c = MULTI_JITTER;
        match pairs {
            Pattern::LatinHypercube { .. } => {}
            Pattern::Stratified => {
                let r = (f64::from(n).sqrt().ceil() as u32).max(1);
                layout.r = r;
                layout.rotations[1] = rotation(p, r * r);
            }
            Pattern::MultiJitter => {
                let m = (f64::from(n).sqrt() as u32).max(1);
                let k = n.div_ceil(m);
                (layout.m, layout.k) = (m, k);
                layout.rotations[2] = rotation(p.wrapping_mul(c[0]), n);
                layout.rotations[3] = rotation(p.wrapping_mul(c[1]), m);
                layout.rotations[4] = rotation(p.wrapping_mul(c[2]), k);
            }
        }
        layout
    }

    /// Point `s` stratified in `n` intervals: `(π(s) + ξ)/n` (`ξ = 1/2`
    /// when `centered`).
    #[inline]
    pub(crate) fn single(&self, s: u32, centered: bool) -> f64 {
        let (n, p) = (self.n, self.p);
        let jitter = if centered { 0.5 } else { jitter(s, p) };
        (f64::from(permute_rotated(s, n, p, self.rotations[0])) + jitter) / f64::from(n)
    }

    /// Point `s` of the 2D pattern `pattern`: [`Layout::stratified`] or,
    /// for any other, [`Layout::multi_jitter`].
    #[inline]
    pub(crate) fn pair(&self, s: u32, pattern: Pattern) -> (f64, f64) {
        if pattern == Pattern::Stratified {
            self.stratified(s)
        } else {
            self.multi_jitter(s)
        }
    }

    /// Point `s` of the shuffled `r × r` grid of strata.
    #[inline]
    pub(crate) fn stratified(&self, s: u32) -> (f64, f64) {
        let (r, p) = (self.r, self.p);
        let cell = permute_rotated(s, r * r, p, self.rotations[1]);
        let r_f = f64::from(r);
        (
            (f64::from(cell % r) + jitter(s, p ^ 0x68bc_21eb)) / r_f,
            (f64::from(cell / r) + jitter(s, p ^ 0x02e5_be93)) / r_f,
        )
    }

    /// Point `s` of Kensler's correlated multi-jittered pattern.
    #[inline]
    pub(crate) fn multi_jitter(&self, s: u32) -> (f64, f64) {
        let (n, m, k) = (self.n, self.m, self.k);
        let [c0, c1, c2, c3, c4] = MULTI_JITTER.map(|c| self.p.wrapping_mul(c));
        let [_, _, r0, r1, r2] = self.rotations;
        let s = permute_rotated(s, n, c0, r0);
        let sx = permute_rotated(s % m, m, c1, r1);
        let sy = permute_rotated(s / m, k, c2, r2);
        let (jx, jy) = (jitter(s, c3), jitter(s, c4));
        let (m, k, n) = (f64::from(m), f64::from(k), f64::from(n));
        (
            (f64::from(sx) + (f64::from(sy) + jx) / k) / m,
            (f64::from(s) + jy) / n,
        )
    }
}

/// Kensler's hashed permutation of `0 .. len` (2013): a bijection on the
/// smallest power-of-two range holding `len` ([`kensler_step`]), applied
/// again while the result is `≥ len` (cycle walking), then rotated by
/// `seed` (`rotation = seed mod len`, which a caller that permutes many
/// indices by one seed computes once). `i < len`.
#[inline]
pub(crate) fn permute_rotated(i: u32, len: u32, seed: u32, rotation: u32) -> u32 {
    rotate(walk(kensler_step(i, len, seed), len, seed), len, rotation)
}

/// The cycle walk of [`permute_rotated`]: [`kensler_step`] again while `i ≥ len`
/// (never when `len` is a power of two above 1).
#[inline(always)]
pub(crate) fn walk(mut i: u32, len: u32, seed: u32) -> u32 {
    while i >= len {
        i = kensler_step(i, len, seed);
    }
    i
}

/// `(i + rotation) mod len` for `i` and `rotation` below `len`.
#[inline(always)]
pub(crate) fn rotate(i: u32, len: u32, rotation: u32) -> u32 {
    let sum = u64::from(i) + u64::from(rotation);
    let len = u64::from(len);
    (if sum >= len { sum - len } else { sum }) as u32
}

/// One step of Kensler's permutation: a bijection of the bits of `i`
/// below the smallest power of two holding `len`, built of steps each
/// invertible on those bits (xor, multiplication by odd constants,
/// xor-shifts). Branch-free, so that loops over it vectorise.
#[inline(always)]
pub(crate) fn kensler_step(mut i: u32, len: u32, seed: u32) -> u32 {
    let w = u32::MAX >> (len.max(2) - 1).leading_zeros();
    i ^= seed;
    i = i.wrapping_mul(0xe170_893d);
    i ^= seed >> 16;
    i ^= (i & w) >> 4;
    i ^= seed >> 8;
    i = i.wrapping_mul(0x0929_eb3f);
    i ^= seed >> 23;
    i ^= (i & w) >> 1;
    i = i.wrapping_mul(1 | seed >> 27);
    i = i.wrapping_mul(0x6935_fa69);
    i ^= (i & w) >> 11;
    i = i.wrapping_mul(0x74dc_b303);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0x9e50_1cc3);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0xc860_a3df);
    i &= w;
    i ^ (i >> 5)
}

/// A uniform jitter in `[0, 1)` for index `i` and seed `p`: 32 bits of
/// Wellons' `lowbias32` hash, as a multiple of `2^−32`.
pub(crate) fn jitter(i: u32, p: u32) -> f64 {
    hashed_jitter(i, lowbias32(p))
}

/// [`jitter`] with the seed's hash `key = lowbias32(p)` computed once.
#[inline(always)]
fn hashed_jitter(i: u32, key: u32) -> f64 {
    f64::from(lowbias32(i ^ key)) * (1.0 / 4_294_967_296.0)
}

/// Chris Wellons' `lowbias32` integer hash.
#[inline(always)]
fn lowbias32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// SplitMix64's finaliser: a bijective 64-bit mix.
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permute_is_a_permutation_for_every_length() {
        for len in (1..300).chain([1000, 4096, 4097]) {
            for seed in [0, 1, 0xdead_beef] {
                let mut seen = vec![false; len as usize];
                for i in 0..len {
                    let j = permute_rotated(i, len, seed, seed % len) as usize;
                    assert!(!seen[j], "len {len} seed {seed}");
                    seen[j] = true;
                }
            }
        }
    }

    fn pattern(pattern: Pattern, d: usize, n: usize) -> Vec<f64> {
        let mut out = vec![0.0; n * d];
        Patterns::new(pattern, d, 5)
            .unwrap()
            .fill(3, &mut out)
            .unwrap();
        out
    }

    /// Which of `n` equal intervals each value of column `j` falls in:
    /// each once.
    fn one_per_interval(points: &[f64], d: usize, j: usize, n: usize) -> bool {
        let mut seen = vec![false; n];
        points.chunks(d).all(|row| {
            let k = (row[j] * n as f64) as usize;
            !std::mem::replace(&mut seen[k], true)
        })
    }

    #[test]
    fn latin_hypercube_has_one_point_per_interval_in_every_dimension() {
        for centered in [false, true] {
            let x = pattern(Pattern::LatinHypercube { centered }, 3, 1000);
            assert!((0..3).all(|j| one_per_interval(&x, 3, j, 1000)));
        }
    }

    /// The Latin hypercube's columns, filled on several threads in tiles
    /// (a length whose permutation walks its cycles, and a power of two),
    /// are its points one at a time.
    #[test]
    fn latin_hypercube_fill_agrees_with_single_points() {
        for (centered, n) in [(false, 70_001u32), (true, 70_001), (false, 1 << 16)] {
            let patterns = Patterns::new(Pattern::LatinHypercube { centered }, 3, 5).unwrap();
            let mut out = vec![0.0f64; n as usize * 3];
            patterns.fill(9, &mut out).unwrap();
            let layouts = patterns.layouts(9, n);
            for (s, row) in (0..n).zip(out.chunks(3)) {
                for (&x, l) in row.iter().zip(&layouts) {
                    assert_eq!(x, l.single(s, centered).min(f64::ONE_MINUS_EPSILON));
                }
            }
        }
    }

    #[test]
    fn stratified_fills_every_stratum_of_a_square_count() {
        let x = pattern(Pattern::Stratified, 3, 64);
        let mut cells: Vec<usize> = x
            .chunks(3)
            .map(|r| (r[0] * 8.0) as usize * 8 + (r[1] * 8.0) as usize)
            .collect();
        cells.sort_unstable();
        assert!(cells.iter().enumerate().all(|(k, &c)| c == k));
        assert!(one_per_interval(&x, 3, 2, 64));
    }

    /// Along y in n intervals for any n; along x too when n = m·k.
    #[test]
    fn multi_jitter_is_stratified_along_each_axis() {
        for n in [64, 100, 37] {
            let x = pattern(Pattern::MultiJitter, 3, n);
            assert!(one_per_interval(&x, 3, 1, n));
            assert!(one_per_interval(&x, 3, 2, n));
            assert_eq!(one_per_interval(&x, 3, 0, n), n != 37);
        }
    }
}

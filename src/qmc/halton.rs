//! [`Halton`]: the Halton sequence, plain (scipy's points) or with random
//! digit permutations.

use super::{Rows, below, check_dims, check_range, scramble_rng};
use crate::alloc;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::rng::Rng;
use crate::{parallel, simd};
use std::ops::Range;

/// Dimensions [`Halton`] accepts: the bases are the first primes, and a
/// scramble holds `base` entries per digit and dimension.
pub const MAX_DIMENSIONS: usize = 1 << 16;

/// Entries a scrambled [`Halton`]'s digit tables may hold in all (`2^26`
/// values of 8 bytes, 512 MiB): `d ≤ 1946` dimensions. (Each dimension
/// also keeps a table of at most 1024 sums of its low positions: 16 MiB
/// at most for 1946 dimensions.)
pub const MAX_PERMUTATION_ENTRIES: usize = 1 << 26;

/// Indices [`Halton`] accepts: below `2^53`, where every index is an exact
/// float and scipy's integer arithmetic has not wrapped.
pub const MAX_INDEX: u64 = 1 << 53;

/// The Halton sequence in `d` dimensions: coordinate `j` of point `i` is
/// the radical inverse of `i` in the `j`-th prime `b`,
///
/// `x_i,j = Σ_k π_k(a_k) b^−(k+1)` for `i = Σ_k a_k b^k`,
///
/// with `π_k` the identity (plain: scipy's `Halton(d, scramble=False)`,
/// bit for bit, summed in its order) or, scrambled, a random permutation
/// of the digits per digit position and dimension, as scipy's
/// `scramble=True` (Owen 2017), over every digit position of an index and
/// down to a double's resolution (so that the leading zeros are permuted
/// too).
///
/// A block of points is filled without a division per digit: plain, by
/// sums over digits counted up by one (an odometer), sixteen points at a
/// time; scrambled, by a table of the low positions' sums plus the sum of
/// the higher positions, which changes once every `b^P` points.
#[derive(Clone, Debug)]
pub struct Halton {
    radices: Vec<Radix>,
}

/// One dimension's base and the terms of its sums.
#[derive(Clone, Debug)]
struct Radix {
    base: u32,
    /// `b^−(k+1)` as scipy computes it: `1/b` divided by `b` `k` times.
    scales: Vec<f64>,
    /// Scrambled: `π_k(a)·b^−(k+1)` at `k·b + a`, for the digit positions
    /// a double resolves; empty when plain.
    terms: Vec<f64>,
    /// Scrambled: `tail[m] = Σ_{k ≥ m} π_k(0)·b^−(k+1)`, the positions above
    /// an index's `m` digits; empty when plain.
    tail: Vec<f64>,
    /// Scrambled: the sums of the low [`Radix::low_digits`] positions'
    /// terms, `low[r] = Σ_{k < P} π_k(a_k(r))·b^−(k+1)` for every `r < b^P`
    /// (see [`Radix::scrambled`]); empty when plain.
    low: Vec<f64>,
    /// `P`: the low positions summed in [`Radix::low`] (`b^P ≤`
    /// [`LOW_ENTRIES`]).
    low_digits: usize,
}

/// Entries of a scrambled dimension's table of low sums (at most): 8 KiB,
/// which stays in the first-level cache.
const LOW_ENTRIES: u64 = 1024;

/// Lanes of [`PlainColumn`]: sixteen indices summed at once, in vectors of
/// 4 or 8.
const LANES: usize = 16;

/// Steps of the lanes in a tile of [`Halton::fill_plain`]: the rows it
/// writes of one dimension before the next (`LANES · TILE_STEPS` rows,
/// 32 KiB of output in 8 dimensions).
const TILE_STEPS: usize = 32;

/// Rows in a tile of [`Halton::fill_scrambled`].
const TILE_ROWS: usize = 512;

/// The digits of an index in one base, lowest first, and how many are
/// significant (the highest nonzero's position + 1).
#[derive(Clone, Debug)]
struct Digits {
    digits: Vec<u32>,
    len: usize,
}

impl Digits {
    /// The digits of `index` in `base`.
    fn new(mut index: u64, base: u32) -> Self {
        let base = u64::from(base);
        let mut digits = Vec::with_capacity(64);
        while index > 0 {
            digits.push((index % base) as u32);
            index /= base;
        }
        let len = digits.len();
        Digits { digits, len }
    }

    /// The digits of the next index.
    #[inline(always)]
    fn increment(&mut self, base: u32) {
        for digit in &mut self.digits {
            *digit += 1;
            if *digit < base {
                return;
            }
            *digit = 0;
        }
        self.digits.push(1);
        self.len = self.digits.len();
    }
}

impl Radix {
    /// Base `base`, scrambled by permutations from `rng` or plain.
    fn new(base: u32, rng: Option<&mut Rng>) -> Result<Self> {
        let positions = positions(base);
        let mut scales = alloc::with_capacity(positions, "the Halton scales")?;
        let mut scale = 1.0 / f64::from(base);
        for _ in 0..positions {
            scales.push(scale);
            scale /= f64::from(base);
        }
        let Some(rng) = rng else {
            return Ok(Radix {
                base,
                scales,
                terms: Vec::new(),
                tail: Vec::new(),
                low: Vec::new(),
                low_digits: 0,
            });
        };
        let b = base as usize;
        let mut terms = alloc::with_capacity(positions * b, "the Halton digit permutations")?;
        let mut digits: Vec<u32> = (0..base).collect();
        for &scale in &scales {
            for k in (1..b).rev() {
                digits.swap(k, below(rng, k as u32 + 1) as usize);
            }
            terms.extend(digits.iter().map(|&a| f64::from(a) * scale));
            digits.sort_unstable();
        }
        let mut tail = vec![0.0; positions + 1];
        for k in (0..positions).rev() {
            tail[k] = tail[k + 1] + terms[k * b];
        }
        let mut low_digits = 0;
        while u64::from(base).pow(low_digits as u32 + 1) <= LOW_ENTRIES {
            low_digits += 1;
        }
        let entries = b.pow(low_digits as u32);
        let mut low = alloc::with_capacity(entries, "the Halton digit permutations")?;
        low.extend((0..entries as u64).map(|r| {
            let mut digits = Digits::new(r, base).digits;
            digits.resize(low_digits, 0);
            let positions = digits.iter().enumerate();
            positions.fold(0.0, |sum, (k, &a)| sum + terms[k * b + a as usize])
        }));
        Ok(Radix {
            base,
            scales,
            terms,
            tail,
            low,
            low_digits,
        })
    }

    /// Plain: the coordinate of the index whose digits are `d`, scipy's sum
    /// from the lowest digit.
    fn plain(&self, d: &Digits) -> f64 {
        let mut sum = 0.0;
        for (&a, &scale) in d.digits[..d.len].iter().zip(&self.scales) {
            sum += f64::from(a) * scale;
        }
        sum
    }

    /// Scrambled: the sum over the positions from [`Radix::low_digits`] up
    /// of the index whose digits from that position are `high` (the
    /// digits of `⌊i / b^P⌋`), the permuted zeros above included.
    fn high_sum(&self, high: &Digits) -> f64 {
        let (b, p) = (self.base as usize, self.low_digits);
        let m = (p + high.len).min(self.tail.len() - 1);
        let digits = high.digits[..m - p].iter().enumerate();
        let sum = digits.fold(0.0, |sum, (k, &a)| {
            sum + self.terms[(p + k) * b + a as usize]
        });
        sum + self.tail[m]
    }

    /// Scrambled: `index = q·b^P + r` as `r`, the digits of `q` and their
    /// sum [`Radix::high_sum`].
    fn split(&self, index: u64) -> (usize, Digits, f64) {
        let period = self.low.len() as u64;
        let high = Digits::new(index / period, self.base);
        let sum = self.high_sum(&high);
        ((index % period) as usize, high, sum)
    }

    /// Scrambled: `low[r] + high`, below 1.
    #[inline(always)]
    fn scrambled(&self, r: usize, high: f64) -> f64 {
        (self.low[r] + high).min(f64::ONE_MINUS_EPSILON)
    }
}

impl Halton {
    /// The first `dims` dimensions, scrambled or not, with random
    /// permutations from `seed`.
    ///
    /// # Errors
    /// [`crate::Error::Integer`] unless `1 ≤ dims ≤` [`MAX_DIMENSIONS`],
    /// or, scrambled, if the permutations would pass
    /// [`MAX_PERMUTATION_ENTRIES`]; [`crate::Error::Memory`] if their
    /// tables cannot be had.
    pub fn new(dims: usize, scramble: bool, seed: u64) -> Result<Self> {
        check_dims(dims, MAX_DIMENSIONS)?;
        let bases = primes(dims);
        let entries: usize = bases.iter().map(|&b| positions(b) * b as usize).sum();
        if scramble && entries > MAX_PERMUTATION_ENTRIES {
            return Err(Error::Integer {
                arg: "d",
                value: dims.to_string(),
                requirement: format!(
                    "a scrambled Halton sequence in {dims} dimensions needs {entries} digit \
                     permutation entries, more than the {MAX_PERMUTATION_ENTRIES} allowed \
                     (d <= 1946)"
                ),
            });
        }
        let mut rng = scramble_rng(seed);
        let radices = bases
            .into_iter()
            .map(|b| Radix::new(b, scramble.then_some(&mut rng)))
            .collect::<Result<_>>()?;
        Ok(Halton { radices })
    }

    /// Number of dimensions.
    pub fn dims(&self) -> usize {
        self.radices.len()
    }

    /// The bases, the first `dims` primes.
    pub fn bases(&self) -> impl Iterator<Item = u32> + '_ {
        self.radices.iter().map(|r| r.base)
    }

    /// Coordinate `dim` of point `index` (`< MAX_INDEX`).
    pub fn value(&self, index: u64, dim: usize) -> f64 {
        let radix = &self.radices[dim];
        if self.is_scrambled() {
            let (r, _, high) = radix.split(index);
            radix.scrambled(r, high)
        } else {
            // A sum of many digits may round up to 1.
            radix
                .plain(&Digits::new(index, radix.base))
                .min(f64::ONE_MINUS_EPSILON)
        }
    }

    /// Whether the digits are permuted.
    fn is_scrambled(&self) -> bool {
        !self.radices[0].terms.is_empty()
    }

    /// Points `first ..` into `out` (row-major, `dims` values a row, as many
    /// rows as fit), on all cores.
    ///
    /// # Errors
    /// [`crate::Error::Integer`] if an index would reach [`MAX_INDEX`], or
    /// if `out` does not hold whole rows.
    pub fn fill<F: Real>(&self, first: u64, out: &mut [F]) -> Result<()> {
        let d = self.dims();
        let n = check_range(out.len(), d, first, MAX_INDEX)?;
        parallel::for_each_chunk(n, Rows::new(out, d), |range, rows| {
            let start = first + range.start as u64;
            if self.is_scrambled() {
                self.fill_scrambled(start, rows.values);
            } else {
                self.fill_plain(start, rows.values);
            }
            true
        })
        .map(|_| ())
    }

    /// Plain rows from index `start` into `values` (whole rows): scipy's
    /// sums, each from the lowest digit, [`LANES`] at once (see
    /// [`PlainColumn`]), a tile of rows one dimension after another; the rows
    /// past a dimension's lanes one at a time.
    fn fill_plain<F: Real>(&self, start: u64, values: &mut [F]) {
        let d = self.dims();
        let rows = values.len() / d;
        if rows == 0 {
            return;
        }
        let mut columns: Vec<PlainColumn> = (self.radices.iter())
            .map(|radix| PlainColumn::new(start, rows, radix.base))
            .collect();
        let steps = columns.iter().map(|c| c.run).max().unwrap_or(0);
        for t0 in (0..steps).step_by(TILE_STEPS) {
            for (j, (radix, column)) in self.radices.iter().zip(&mut columns).enumerate() {
                let tile = t0..(t0 + TILE_STEPS).min(column.run);
                simd::dispatch(
                    #[inline(always)]
                    |_| column.write(tile, &radix.scales, values, (d, j)),
                );
            }
        }
        // The rows past the lanes: an odometer per dimension.
        for (j, (radix, column)) in self.radices.iter().zip(&columns).enumerate() {
            let first = LANES * column.run;
            let mut digits = Digits::new(start + first as u64, radix.base);
            for row in values.chunks_exact_mut(d).skip(first) {
                let value = radix.plain(&digits).min(f64::ONE_MINUS_EPSILON);
                row[j] = F::c(value).min(F::ONE_MINUS_EPSILON);
                digits.increment(radix.base);
            }
        }
    }

    /// Scrambled rows from index `start` into `values` (whole rows): for
    /// `i = q·b^P + r`, the value is `low[r] + h(q)` (see [`Radix::low`]),
    /// `h(q)` the sum of the positions from `P` up, which changes once every
    /// `b^P` indices. A tile of rows is written one dimension after another.
    fn fill_scrambled<F: Real>(&self, start: u64, values: &mut [F]) {
        let d = self.dims();
        // Per dimension: r, the digits of q and h(q).
        let mut columns: Vec<(usize, Digits, f64)> = self
            .radices
            .iter()
            .map(|radix| radix.split(start))
            .collect();
        for tile in values.chunks_mut(TILE_ROWS * d) {
            for (j, (radix, (r, high, sum))) in self.radices.iter().zip(&mut columns).enumerate() {
                for row in tile.chunks_exact_mut(d) {
                    row[j] = F::c(radix.scrambled(*r, *sum)).min(F::ONE_MINUS_EPSILON);
                    *r += 1;
                    if *r == radix.low.len() {
                        *r = 0;
                        high.increment(radix.base);
                        *sum = radix.high_sum(high);
                    }
                }
            }
        }
    }
}

/// One plain dimension of a block of rows from index `start`, in
/// [`LANES`] runs of `run` consecutive indices (lane `l` has the rows
/// `l·run ..`), `run` a multiple of the base `b` so that every lane has the
/// same lowest digit `a_0`: a step computes `a_0·b^−1`, then adds each
/// lane's higher digits' terms to it in vectors, and counts `a_0` up; the
/// lanes' higher digits count up together when it wraps.
struct PlainColumn {
    base: u32,
    /// Steps per lane.
    run: usize,
    /// The lanes' lowest digit.
    low: u32,
    /// `digits[k][l]`: digit `k + 1` of lane `l`, as a float, for the
    /// positions of the block's largest index and one more (where a carry
    /// past it lands).
    digits: Vec<[f64; LANES]>,
    /// The positions of the block's largest index, less one: the sums'
    /// length above the lowest digit.
    len: usize,
}

impl PlainColumn {
    /// The lanes of `rows ≥ 1` rows from index `start` in base `base`.
    fn new(start: u64, rows: usize, base: u32) -> Self {
        let b = base as usize;
        let run = rows / LANES / b * b;
        let len = Digits::new(start + rows as u64 - 1, base).len.max(1) - 1;
        let mut digits = vec![[0.0; LANES]; len + 1];
        let lanes =
            (0..LANES).map(|l| Digits::new((start + (l * run) as u64) / u64::from(base), base));
        for (l, high) in lanes.enumerate() {
            for (position, &a) in digits.iter_mut().zip(&high.digits) {
                position[l] = f64::from(a);
            }
        }
        PlainColumn {
            base,
            run,
            low: (start % u64::from(base)) as u32,
            digits,
            len,
        }
    }

    /// Steps `steps` of every lane into column `j` of the rows of `d`
    /// values in `values`: `Σ_k a_k·scales[k]` from the lowest digit (a
    /// product rounded, then the sum: scipy's arithmetic; the zeros above
    /// an index's digits add nothing).
    #[inline(always)]
    fn write<F: Real>(
        &mut self,
        steps: Range<usize>,
        scales: &[f64],
        values: &mut [F],
        (d, j): (usize, usize),
    ) {
        let (run, base) = (self.run, self.base);
        for t in steps {
            let mut sums = [f64::from(self.low) * scales[0]; LANES];
            for (digits, &scale) in self.digits[..self.len].iter().zip(&scales[1..]) {
                for (sum, &a) in sums.iter_mut().zip(digits) {
                    *sum += a * scale;
                }
            }
            for (l, &sum) in sums.iter().enumerate() {
                values[(l * run + t) * d + j] = F::c(sum).min(F::ONE_MINUS_EPSILON);
            }
            self.low += 1;
            if self.low == base {
                self.low = 0;
                self.carry(f64::from(base));
            }
        }
    }

    /// Every lane's higher digits counted up by one.
    #[inline(always)]
    fn carry(&mut self, base: f64) {
        let mut carry = [1.0; LANES];
        for digits in &mut self.digits {
            let mut any = false;
            for (a, c) in digits.iter_mut().zip(&mut carry) {
                let next = *a + *c;
                let wraps = next >= base;
                *a = if wraps { 0.0 } else { next };
                *c = if wraps { 1.0 } else { 0.0 };
                any |= wraps;
            }
            if !any {
                return;
            }
        }
    }
}

/// Digit positions in base `b`: the digits of the largest index
/// (`MAX_INDEX − 1`), so that every index's digits are summed and a
/// scramble permutes down to `b^−positions ≤ 2^−53` (a double's
/// resolution). (scipy's `⌈54 / log2 b⌉ − 1` is a digit short for most
/// bases from 11 on.)
fn positions(base: u32) -> usize {
    Digits::new(MAX_INDEX - 1, base).len
}

/// The first `n` primes, by a sieve of Eratosthenes up to a bound above
/// the `n`-th prime (`n (ln n + ln ln n)` for `n ≥ 6`).
pub(crate) fn primes(n: usize) -> Vec<u32> {
    let x = n.max(6) as f64;
    let limit = (x * (x.ln() + x.ln().ln())).ceil() as usize + 1;
    let mut composite = vec![false; limit + 1];
    let mut out = Vec::with_capacity(n);
    for p in 2..=limit {
        if out.len() == n {
            break;
        }
        if !composite[p] {
            out.push(p as u32);
            for multiple in (p * p..=limit).step_by(p) {
                composite[multiple] = true;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primes_are_the_first_primes() {
        assert_eq!(primes(10), [2, 3, 5, 7, 11, 13, 17, 19, 23, 29]);
        assert_eq!(primes(1), [2]);
        let many = primes(MAX_DIMENSIONS);
        assert_eq!(many.len(), MAX_DIMENSIONS);
        // The 65536th prime.
        assert_eq!(many[MAX_DIMENSIONS - 1], 821_641);
    }

    /// The plain points of base 2 and 3 are the radical inverses.
    #[test]
    fn plain_points_are_radical_inverses() {
        let h = Halton::new(2, false, 0).unwrap();
        let mut out = vec![0.0f64; 10];
        h.fill(0, &mut out).unwrap();
        assert_eq!(
            out,
            [
                0.0,
                0.0,
                0.5,
                1.0 / 3.0,
                0.25,
                2.0 / 3.0,
                0.75,
                1.0 / 9.0,
                0.125,
                4.0 / 9.0
            ]
        );
    }

    /// A block filled from any start (near the last index too, where the
    /// digits' count changes within a block), split across threads, equals
    /// its points computed one at a time, plain and scrambled.
    #[test]
    fn fill_agrees_with_values_from_any_start() {
        for scramble in [false, true] {
            let h = Halton::new(10, scramble, 5).unwrap();
            assert!(h.fill::<f64>(0, &mut []).is_ok());
            for first in [0, 1_234_567, MAX_INDEX - 70_001] {
                let mut out = vec![0.0f64; 70_000 * 10];
                h.fill(first, &mut out).unwrap();
                for (r, row) in out.chunks(10).enumerate() {
                    for (j, &x) in row.iter().enumerate() {
                        assert_eq!(
                            x,
                            h.value(first + r as u64, j),
                            "{scramble} {first} {r} {j}"
                        );
                    }
                }
            }
        }
    }

    /// Scrambled, the first b^k points of base b still put one point in
    /// each interval of length b^−k (permuting digits keeps the strata).
    #[test]
    fn scrambled_points_keep_their_strata() {
        let h = Halton::new(3, true, 11).unwrap();
        for (dim, b) in h.bases().enumerate() {
            let n = b.pow(4 - dim as u32) as u64;
            let mut seen = vec![false; n as usize];
            for i in 0..n {
                let cell = (h.value(i, dim) * n as f64) as usize;
                assert!(!seen[cell]);
                seen[cell] = true;
            }
        }
        assert!(Halton::new(0, true, 0).is_err());
    }

    /// A scramble permutes every digit an index can have: in base 11,
    /// indices 11^15 apart (both below 2^53) differ in their 16th digit,
    /// which scipy's `⌈54 / log2 b⌉ − 1 = 15` positions would drop.
    #[test]
    fn scrambles_see_every_digit() {
        let h = Halton::new(5, true, 3).unwrap();
        let far = 11u64.pow(15);
        assert!(far + 7 < MAX_INDEX);
        assert_ne!(h.value(7, 4), h.value(7 + far, 4));
        assert_eq!(positions(11), 16);
        assert_eq!(positions(2), 53);
    }
}

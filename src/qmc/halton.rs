//! [`Halton`]: the Halton sequence, plain (scipy's points) or with random
//! digit permutations.

use super::{Rows, below, check_dims, check_range, scramble_rng};
use crate::alloc;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::parallel;
use crate::rng::Rng;

/// Dimensions [`Halton`] accepts: the bases are the first primes, and a
/// scramble holds `base` entries per digit and dimension.
pub const MAX_DIMENSIONS: usize = 1 << 16;

/// Entries a scrambled [`Halton`]'s digit tables may hold in all (`2^26`
/// values of 8 bytes, 512 MiB): `d ≤ 1946` dimensions.
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
/// Consecutive points update their digits by adding one (an odometer), so
/// a value costs a sum over its digits and no division.
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
}

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
        Ok(Radix {
            base,
            scales,
            terms,
            tail,
        })
    }

    /// The coordinate of the index whose digits are `d`: plain, scipy's
    /// sum from the lowest digit; scrambled, the permuted digits' terms up
    /// to the positions a double resolves, then the permuted zeros above.
    #[inline(always)]
    fn value(&self, d: &Digits) -> f64 {
        let sum = if self.terms.is_empty() {
            let mut sum = 0.0;
            for (&a, &scale) in d.digits[..d.len].iter().zip(&self.scales) {
                sum += f64::from(a) * scale;
            }
            sum
        } else {
            let b = self.base as usize;
            let m = d.len.min(self.tail.len() - 1);
            let mut sum = 0.0;
            for (k, &a) in d.digits[..m].iter().enumerate() {
                sum += self.terms[k * b + a as usize];
            }
            sum + self.tail[m]
        };
        // A scrambled sum may round up to 1.
        sum.min(f64::ONE_MINUS_EPSILON)
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
        radix.value(&Digits::new(index, radix.base))
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
            let mut digits: Vec<Digits> = self.bases().map(|b| Digits::new(start, b)).collect();
            for row in rows.chunks_mut() {
                for ((value, radix), digits) in row.iter_mut().zip(&self.radices).zip(&mut digits) {
                    *value = F::c(radix.value(digits)).min(F::ONE_MINUS_EPSILON);
                    digits.increment(radix.base);
                }
            }
            true
        })
        .map(|_| ())
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

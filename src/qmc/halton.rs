//! [`Halton`]: the Halton sequence, plain (scipy's points) or with random
//! digit permutations.

use super::{Rows, below, check_dims, check_range, scramble_rng};
use crate::error::{Error, Result};
use crate::math::Real;
use crate::parallel;
use crate::rng::Rng;

/// Dimensions [`Halton`] accepts: the bases are the first primes, and a
/// scramble holds `base` entries per digit and dimension.
pub const MAX_DIMENSIONS: usize = 1 << 16;

/// Entries a scrambled [`Halton`]'s permutation tables may hold in all
/// (`2^26`, 256 MiB): `d ≤ 2191` dimensions (scipy builds the same
/// tables, in 64-bit integers).
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
/// `scramble=True` (Owen 2017), over all the positions a double resolves
/// (so that the leading zeros are permuted too).
#[derive(Clone, Debug)]
pub struct Halton {
    bases: Vec<u32>,
    /// Per dimension, the permutations of each digit position, one after
    /// the other (`base` entries each); empty when plain.
    permutations: Vec<Vec<u32>>,
}

impl Halton {
    /// The first `dims` dimensions, scrambled or not, with random
    /// permutations from `seed`.
    ///
    /// # Errors
    /// [`crate::Error::Integer`] unless `1 ≤ dims ≤` [`MAX_DIMENSIONS`],
    /// or, scrambled, if the permutations would pass
    /// [`MAX_PERMUTATION_ENTRIES`].
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
                     (d <= 2191)"
                ),
            });
        }
        let mut rng = scramble_rng(seed);
        let permutations = if scramble {
            bases.iter().map(|&b| permutations(b, &mut rng)).collect()
        } else {
            Vec::new()
        };
        Ok(Halton {
            bases,
            permutations,
        })
    }

    /// Number of dimensions.
    pub fn dims(&self) -> usize {
        self.bases.len()
    }

    /// The bases, the first `dims` primes.
    pub fn bases(&self) -> &[u32] {
        &self.bases
    }

    /// Coordinate `dim` of point `index`.
    pub fn value(&self, index: u64, dim: usize) -> f64 {
        let base = u64::from(self.bases[dim]);
        let step = 1.0 / base as f64;
        let (mut sum, mut scale, mut q) = (0.0, step, index);
        match self.permutations.get(dim) {
            None => {
                while q > 0 {
                    sum += (q % base) as f64 * scale;
                    scale /= base as f64;
                    q /= base;
                }
            }
            Some(table) => {
                for digits in table.chunks_exact(base as usize) {
                    sum += f64::from(digits[(q % base) as usize]) * scale;
                    scale /= base as f64;
                    q /= base;
                }
            }
        }
        // A scrambled sum may round up to 1.
        sum.min(f64::ONE_MINUS_EPSILON)
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
            for (i, row) in (first + range.start as u64..).zip(rows.chunks_mut()) {
                for (j, value) in row.iter_mut().enumerate() {
                    *value = F::c(self.value(i, j)).min(F::ONE_MINUS_EPSILON);
                }
            }
            true
        })
        .map(|_| ())
    }
}

/// Digit positions a scramble permutes in base `b`: `⌈54 / log2 b⌉ − 1`
/// (as scipy), enough for a double.
fn positions(base: u32) -> usize {
    (54.0 / f64::from(base).log2()).ceil() as usize - 1
}

/// The digit permutations of one base, one per position, each a uniform
/// random permutation of `0 .. b` (Fisher–Yates).
fn permutations(base: u32, rng: &mut Rng) -> Vec<u32> {
    let positions = positions(base);
    let mut table = Vec::with_capacity(positions * base as usize);
    for _ in 0..positions {
        let start = table.len();
        table.extend(0..base);
        let digits = &mut table[start..];
        for k in (1..digits.len()).rev() {
            digits.swap(k, below(rng, k as u32 + 1) as usize);
        }
    }
    table
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
        for (dim, &b) in h.bases().iter().enumerate() {
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
}

//! Tabulated distributions: discrete tables in one and two dimensions, and
//! piecewise-constant densities built on them.
//!
//! | table | sample cost | inverse | 2D | built on |
//! |---|---|---|---|---|
//! | [`Discrete1D`] | O(1) expected (guide table + binary search on the CDF) | via [`Discrete1D::sample_reuse`] | no | — |
//! | [`AliasTable`] | O(1) (one table lookup) | no | no | — |
//! | [`Discrete2D`] | two [`Discrete1D`] searches | via `sample_reuse` | yes | [`Discrete1D`] |
//! | [`PiecewiseConstant1D`] | one [`Discrete1D`] search | [`PiecewiseConstant1D::invert`] | no | [`Discrete1D`] |
//! | [`PiecewiseConstant2D`] | two [`Discrete1D`] searches | [`PiecewiseConstant2D::invert`] | yes | [`Discrete2D`] |
//!
//! Constructors validate their weights (finite, `>= 0`, not all zero) and
//! return [`crate::Error`]; sampling is infallible and never returns an
//! entry of weight 0. Sums are accumulated in `f64`.

mod alias;
mod discrete;
mod discrete2d;
mod piecewise;
mod search;
mod weights;

pub use alias::AliasTable;
pub use discrete::Discrete1D;
pub use discrete2d::Discrete2D;
pub use piecewise::{PiecewiseConstant1D, PiecewiseConstant2D};
pub use weights::Weights;

use crate::error::{Error, Result};
use crate::parallel;
use rayon::prelude::*;

/// Draws per group of the batch samplers (`sample_into`): each step of a
/// group's draws runs over the whole group (the alias table's reads
/// prefetched first, the searches of the CDF tables side by side), so that
/// the cache misses of a group overlap.
pub(crate) const GROUP: usize = 64;

/// The largest number of entries a table may have (indices are `u32`).
pub const MAX_ENTRIES: usize = u32::MAX as usize;

/// Whether `w` may be a weight: finite and `>= 0` (NaN and ±∞ fail both
/// comparisons). Branch-free.
#[inline(always)]
fn is_weight(w: f64) -> bool {
    (0.0..=f64::MAX).contains(&w)
}

/// Whether every entry of `weights` is a weight (see [`is_weight`]), in one
/// branch-free pass.
fn all_weights(weights: &[f64]) -> bool {
    weights.iter().fold(true, |all, &w| all & is_weight(w))
}

/// Checks that a table of `len` entries has at most [`MAX_ENTRIES`].
fn check_len(arg: &'static str, len: usize) -> Result<()> {
    crate::error::check_at_most(arg, len, MAX_ENTRIES)
}

/// The error for the first entry of `weights` that is not a weight (see
/// [`is_weight`]; `index` formats its position), or `Ok` if there is none.
/// For builders that check their weights in their first pass and look for
/// the culprit only on failure.
fn find_invalid(arg: &'static str, weights: &[f64], index: impl Fn(usize) -> String) -> Result<()> {
    match weights.iter().position(|&w| !is_weight(w)) {
        Some(i) => Err(Error::InvalidWeight {
            arg,
            index: index(i),
            value: weights[i],
        }),
        None => Ok(()),
    }
}

/// Checks that every weight is finite and `>= 0` and that there are at most
/// [`MAX_ENTRIES`]; `index` formats the position of an offending entry.
fn check_weights(
    arg: &'static str,
    weights: &[f64],
    index: impl Fn(usize) -> String,
) -> Result<()> {
    check_len(arg, weights.len())?;
    // One branch-free pass for the common case, in parallel; find the index
    // only on failure.
    let all_ok = parallel::install(|| weights.par_chunks(1 << 16).all(all_weights))?;
    if all_ok {
        return Ok(());
    }
    find_invalid(arg, weights, index)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The size limit, checked without allocating a table of 2³² entries.
    #[test]
    fn tables_may_have_at_most_max_entries() {
        assert!(check_len("weights", MAX_ENTRIES).is_ok());
        let e = check_len("weights", MAX_ENTRIES + 1).unwrap_err();
        assert!(matches!(e, Error::TooLarge { len, .. } if len == MAX_ENTRIES + 1));
        assert!(check_len("weights", 0).is_ok());
    }

    /// The one-pass check agrees with the search for the culprit: it fails
    /// exactly when some entry is negative, NaN or infinite.
    #[test]
    fn the_fast_weight_check_finds_every_bad_weight() {
        assert!(all_weights(&[0.0, 1.0, f64::MAX]));
        for bad in [-1.0, f64::NAN, f64::INFINITY, -0.5e-300] {
            let w = [1.0, 2.0, bad, 3.0];
            assert!(!all_weights(&w), "{bad}");
            assert!(check_weights("w", &w, |i| format!("[{i}]")).is_err());
        }
        assert!(check_weights("w", &[1.0, 0.0], |i| format!("[{i}]")).is_ok());
    }
}

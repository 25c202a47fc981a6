//! Quasi-Monte Carlo point sets: the sequences [`Sobol`] (plain,
//! Owen-scrambled, or by a linear matrix scramble) and [`Halton`] (plain or
//! digit-permuted), and the stratified [`Patterns`] drawn `n` points at a
//! time (Latin hypercube, stratified, multi-jittered). Each fills rows of
//! `d` coordinates in `[0, 1)` on all cores, with the same bits at any
//! thread count; a point is computed from its index alone, so skipping
//! ahead costs nothing.

pub(crate) mod directions;
mod halton;
pub(crate) mod patterns;
pub(crate) mod sobol;

pub use directions::MAX_DIMENSIONS as SOBOL_MAX_DIMENSIONS;
pub use halton::{
    Halton, MAX_DIMENSIONS as HALTON_MAX_DIMENSIONS, MAX_INDEX as HALTON_MAX_INDEX,
    MAX_PERMUTATION_ENTRIES as HALTON_MAX_PERMUTATION_ENTRIES,
};
pub use patterns::{
    MAX_DIMENSIONS as PATTERN_MAX_DIMENSIONS, MAX_POINTS as PATTERN_MAX_POINTS, Pattern, Patterns,
};
pub use sobol::{Scramble, Sobol, owen, owen_reversed, owen_reversed_pair};

use crate::error::{Error, Result};
use crate::parallel::Outputs;
use crate::rng::Rng;

/// The random bits of a scramble: PCG32 with the engine's seed on a stream
/// of its own, so that they are not the first numbers of
/// `uniform(seed = s)`.
fn scramble_rng(seed: u64) -> Rng {
    const SCRAMBLE_STREAM: u64 = 0x7163_6d63; // "qmc"
    Rng::new(seed, SCRAMBLE_STREAM)
}

/// A uniform integer below `n ≥ 1` (Lemire's multiply-shift with
/// rejection: no bias toward small values).
fn below(rng: &mut Rng, n: u32) -> u32 {
    let threshold = n.wrapping_neg() % n;
    loop {
        let m = u64::from(rng.next_u32()) * u64::from(n);
        if (m as u32) >= threshold {
            return (m >> 32) as u32;
        }
    }
}

/// A row-major block of rows of `width` values, split between threads at
/// row boundaries.
struct Rows<'a, T> {
    /// The rows' values, row after row.
    values: &'a mut [T],
    width: usize,
}

impl<'a, T> Rows<'a, T> {
    fn new(values: &'a mut [T], width: usize) -> Self {
        Rows { values, width }
    }

    fn chunks_mut(self) -> std::slice::ChunksExactMut<'a, T> {
        self.values.chunks_exact_mut(self.width)
    }
}

impl<T: Send> Outputs for Rows<'_, T> {
    fn split_at_item(self, mid: usize) -> (Self, Self) {
        let (a, b) = self.values.split_at_mut(mid * self.width);
        (Rows::new(a, self.width), Rows::new(b, self.width))
    }
}

/// Checks a dimension count: `1 ≤ dims ≤ max`.
fn check_dims(dims: usize, max: usize) -> Result<()> {
    if (1..=max).contains(&dims) {
        Ok(())
    } else {
        Err(Error::Integer {
            arg: "d",
            value: dims.to_string(),
            requirement: format!("must be in [1, {max}]"),
        })
    }
}

/// The number of rows of `width` values in `len` values, checked to be
/// whole and to keep every index from `first` below `end`.
fn check_range(len: usize, width: usize, first: u64, end: u64) -> Result<usize> {
    if !len.is_multiple_of(width) {
        return Err(Error::Integer {
            arg: "out",
            value: len.to_string(),
            requirement: format!("must hold whole rows of {width} values"),
        });
    }
    let n = len / width;
    match first.checked_add(n as u64) {
        Some(last) if last <= end => Ok(n),
        _ => Err(Error::Integer {
            arg: "n",
            value: n.to_string(),
            requirement: format!(
                "points {first} .. {first} + n must stay below index {end} (the sequence's end)"
            ),
        }),
    }
}

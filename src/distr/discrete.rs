//! [`Discrete1D`]: a discrete distribution sampled by inverting its CDF.

use super::search::{Lanes, Search, close_guide, guide_len, positive_range, search_group};
use super::{GROUP, Weights, check_len, find_invalid};
use crate::buffer::Buffer;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::parallel;
use crate::simd;
use rayon::prelude::*;
use sums::{SUM_BLOCK, SUM_GROUP, block_totals, sum_blocks_and_fill_guide};

mod sums;

/// A discrete distribution over the indices `0..n`, with probabilities
/// proportional to non-negative weights `w`.
///
/// # Probability
/// `P(i) = w_i / Σ w`. The running sums `C_i = w_0 + … + w_i` are
/// accumulated in `f64` (by blocks of `SUM_BLOCK` entries).
///
/// # Sampling
/// `sample(u)` returns the index `i` with `C_{i−1} < u·Σw ≤ C_i` (as
/// Mitsuba 3's `DiscreteDistribution`), restricted to the range from the
/// first to the last entry of positive weight, so an entry of weight 0 is
/// never returned (`u = 0` and `u = 1` included). A guide table (the
/// cutpoint method of Chen and Asau) narrows the binary search to an
/// expected O(1) entries.
///
/// # References
/// H.-C. Chen, Y. Asau, "On generating random variates from an empirical
/// distribution", AIIE Transactions 6(2), 1974.
#[derive(Clone, Debug)]
pub struct Discrete1D {
    /// The weights as given and their sum (`len`, `sum`, `pmf`, ... by
    /// dereference).
    weights: Weights,
    cdf: Buffer<f64>,
    first: usize,
    last: usize,
    /// `guide[k]`: the first index whose running sum reaches `k/G · Σw`,
    /// clamped to `[first, last]`, for `k = 0..=G` (empty for short tables).
    guide: Buffer<u32>,
}

impl Discrete1D {
    /// A distribution proportional to `weights`.
    ///
    /// # Errors
    /// [`Error::InvalidWeight`] for a NaN, infinite or negative weight,
    /// [`Error::AllZero`] if the table is empty or sums to 0,
    /// [`Error::TooLarge`] above [`super::MAX_ENTRIES`] entries.
    pub fn new(weights: &[f64]) -> Result<Self> {
        check_len("weights", weights.len())?;
        let (table, valid) = parallel::install(|| Self::build(weights))??;
        if !valid {
            find_invalid("weights", weights, |i| format!("[{i}]"))?;
        }
        table.ok_or(Error::AllZero { arg: "weights" })
    }

    /// A distribution from weights already checked to be finite and
    /// `>= 0`; `None` when they are empty or sum to 0.
    ///
    /// # Errors
    /// [`Error::Memory`] when the table's memory cannot be had.
    pub(crate) fn from_checked(weights: &[f64]) -> Result<Option<Self>> {
        // On mcsample's pool: rayon's global pool would ignore the thread
        // count, and its threads do not exist in a forked child.
        Ok(parallel::install(|| Self::build(weights))??.0)
    }

    /// The distribution of `weights` (`None` when they are empty or do not
    /// sum to a positive finite number), and whether every weight is finite
    /// and `>= 0` (checked on the way; a table from invalid weights is
    /// meaningless). Tables longer than [`SUM_GROUP`] are summed in
    /// parallel (on the current rayon pool).
    fn build(weights: &[f64]) -> Result<(Option<Self>, bool)> {
        // Each block's total (in parallel, a group of blocks per task); the
        // offsets of the blocks; then, in one pass, the copy of the weights,
        // the running sums and the guide.
        let (totals, valid): (Vec<_>, Vec<bool>) =
            weights.par_chunks(SUM_GROUP).map(block_totals).unzip();
        let valid = valid.into_iter().all(|v| v);
        let blocks = weights.len().div_ceil(SUM_BLOCK);
        let mut offsets = Vec::with_capacity(blocks);
        let mut acc = 0.0;
        for total in totals.iter().flatten().take(blocks) {
            offsets.push(acc);
            acc += total;
        }
        let Some((first, last)) = positive_range(weights) else {
            return Ok((None, valid));
        };
        if !(valid && acc > 0.0 && acc.is_finite()) {
            return Ok((None, valid));
        }
        let mut copy = Buffer::for_overwrite(weights.len(), "the table's weights")?;
        let mut cdf = Buffer::for_overwrite(weights.len(), "the table's running sums")?;
        let mut guide = Buffer::for_overwrite(guide_len(weights.len()), "the table's guide")?;
        sum_blocks_and_fill_guide(weights, (&mut copy, &mut cdf), &offsets, acc, &mut guide);
        close_guide(&mut guide, (first, last));
        let table = Discrete1D {
            weights: Weights::new(copy, acc),
            cdf,
            first,
            last,
            guide,
        };
        Ok((Some(table), valid))
    }

    /// Running sum of the weights before entry `i`: `C_{i−1}` (0 for i = 0).
    pub fn sum_before(&self, i: usize) -> f64 {
        self.search().sum_before(i)
    }

    /// Cumulative probability `P(index ≤ i) = C_i / Σw` (1 past the end).
    pub fn cdf(&self, i: usize) -> f64 {
        self.cdf.get(i).map_or(1.0, |&c| c / self.sum())
    }

    /// The index `i` with `C_{i−1} < u·Σw ≤ C_i`, among entries of positive
    /// weight. `u` in `[0, 1]`.
    #[inline]
    pub fn sample<F: Real>(&self, u: F) -> usize {
        let search = self.search();
        search.index(u.f64(), search.guide_cell(u.f64()))
    }

    /// `out[i] = sample(us[i])` for a batch, in groups whose searches run
    /// side by side (guide-table windows read by gathers at SIMD width),
    /// compiled for the widest vector unit.
    pub fn sample_into<F: Real, I: From<u32>>(&self, us: &[F], out: &mut [I]) {
        simd::dispatch(
            #[inline(always)]
            |_| {
                self.searched_in_groups(
                    us,
                    out,
                    false,
                    #[inline(always)]
                    |_, index, out| {
                        for (o, &i) in out.iter_mut().zip(index) {
                            *o = I::from(i as u32);
                        }
                    },
                )
            },
        )
    }

    /// The groups of [`Discrete1D::sample_into`], each group's indices
    /// handed to `finish(lanes, index, out)` to write its outputs (with
    /// `rescale`, `lanes` ready for [`Lanes::rescale`]).
    #[inline(always)]
    fn searched_in_groups<F: Real, O>(
        &self,
        us: &[F],
        out: &mut [O],
        rescale: bool,
        finish: impl Fn(&Lanes, &[u64; GROUP], &mut [O]),
    ) {
        let search = self.search();
        let mut lanes = Lanes::new();
        let mut index = [0; GROUP];
        for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
            let draw = {
                #[inline(always)]
                |k: usize| Some((search, us[k].f64()))
            };
            search_group(us.len(), &search, draw, (&mut lanes, rescale), &mut index);
            finish(&lanes, &index, out);
        }
    }

    /// The index as [`Discrete1D::sample`], and `u` rescaled within that
    /// entry's share to `[0, 1)`: `(u·Σw − C_{i−1}) / (C_i − C_{i−1})` (the
    /// step of the running sums: `w_i` up to their round-off), a fresh uniform
    /// number for a second decision.
    #[inline]
    pub fn sample_reuse<F: Real>(&self, u: F) -> (usize, F) {
        self.search().sample_reuse(u)
    }

    /// `out[i] = sample_reuse(us[i])` for a batch, in the groups of
    /// [`Discrete1D::sample_into`], each group's rescaled numbers side by
    /// side, compiled for the widest vector unit.
    pub fn sample_reuse_into<F: Real>(&self, us: &[F], out: &mut [(usize, F)]) {
        simd::dispatch(
            #[inline(always)]
            |_| self.sample_reuse_groups(us, out),
        )
    }

    /// [`Discrete1D::sample_reuse_into`] without the dispatch, for the batch
    /// loops of samplers built on this table (which dispatch themselves).
    #[inline(always)]
    pub(crate) fn sample_reuse_groups<F: Real>(&self, us: &[F], out: &mut [(usize, F)]) {
        self.searched_in_groups(
            us,
            out,
            true,
            #[inline(always)]
            |lanes, index, out| {
                let mut rescaled = [F::zero(); GROUP];
                lanes.rescale(&mut rescaled);
                for (o, (&i, &r)) in out.iter_mut().zip(index.iter().zip(&rescaled)) {
                    *o = (i as usize, r);
                }
            },
        );
    }

    /// The tables as slices, for the steps of a draw.
    #[inline(always)]
    pub(crate) fn search(&self) -> Search<'_> {
        Search::new(
            (self.weights.weights(), &self.cdf, &self.guide),
            (self.sum(), self.first, self.last),
        )
    }
}

impl std::ops::Deref for Discrete1D {
    type Target = Weights;

    fn deref(&self) -> &Weights {
        &self.weights
    }
}

#[cfg(test)]
mod tests;

//! [`Discrete1D`]: a discrete distribution sampled by inverting its CDF.

use super::search::{
    CHAINS, GuideCell, Lanes, Search, close_guide, guide_len, positive_range, scatter_guide,
    search_group, sum_blocks_into,
};
use super::{GROUP, Weights, check_len, find_invalid};
use crate::buffer::Buffer;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::parallel;
use crate::simd;
use rayon::prelude::*;

/// Entries per block of the running sums of a long table: each block is
/// summed from 0 and then offset by the blocks before it, in parallel. Fixed,
/// so that the sums do not depend on the thread count (a table of at most
/// one block is summed strictly in order, as Mitsuba does). Not a power of
/// two: the blocks of a group are read and written side by side, and
/// streams a power of two apart fall into the same cache sets.
const SUM_BLOCK: usize = 8000;

/// Entries per task of the running sums: [`CHAINS`] blocks, summed side by
/// side ([`sum_blocks_into`]).
const SUM_GROUP: usize = CHAINS * SUM_BLOCK;

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

/// Adds to each block of the running sums `cdf` its entry of `offsets`
/// (the total of the blocks before it), and fills the guide of the sums
/// (total `sum`) but for [`close_guide`]: each entry's index written into
/// its cell ([`scatter_guide`]), the cells no entry hits `u32::MAX`. In
/// parallel by groups of blocks: the sums never decrease, so the entries
/// of a group hit the cells after its offset's (the group before's last
/// sum) up to its own last sum's, which no other group writes.
fn offset_blocks_and_fill_guide(cdf: &mut [f64], offsets: &[f64], sum: f64, guide: &mut [u32]) {
    let cell = GuideCell::new(guide.len(), sum);
    let (mut rest, mut start) = (guide, 0);
    let mut groups = Vec::with_capacity(offsets.len().div_ceil(CHAINS));
    for (g, group) in offsets.chunks(CHAINS).enumerate() {
        let end = offsets.get((g + 1) * CHAINS).copied().unwrap_or(sum);
        let next = cell.map_or(0, |cell| cell.of(end) as usize + 1);
        let (own, later) = std::mem::take(&mut rest).split_at_mut(next - start);
        groups.push((group, start, own));
        (rest, start) = (later, next);
    }
    rest.fill(u32::MAX);
    (cdf.par_chunks_mut(SUM_GROUP), groups)
        .into_par_iter()
        .enumerate()
        .for_each(|(g, (cdf, (offsets, start, own)))| {
            own.fill(u32::MAX);
            // The blocks last first, as the guide is filled.
            let blocks = (cdf.chunks_mut(SUM_BLOCK).zip(offsets).enumerate()).rev();
            simd::dispatch(
                #[inline(always)]
                |_| {
                    for (b, (cdf, &offset)) in blocks {
                        cdf.iter_mut().for_each(|c| *c += offset);
                        if let Some(cell) = cell {
                            let first = g * SUM_GROUP + b * SUM_BLOCK;
                            scatter_guide(cdf, first, cell, own, start);
                        }
                    }
                },
            )
        });
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
        // The copy of the weights and each block's running sums from 0, in
        // parallel (a group of blocks per task); then to each block the sum
        // of the blocks before it, with the guide.
        let mut copy = Buffer::for_overwrite(weights.len(), "the table's weights")?;
        let mut cdf = Buffer::for_overwrite(weights.len(), "the table's running sums")?;
        let (totals, valid): (Vec<_>, Vec<bool>) = (
            cdf.par_chunks_mut(SUM_GROUP),
            copy.par_chunks_mut(SUM_GROUP),
            weights.par_chunks(SUM_GROUP),
        )
            .into_par_iter()
            .map(|(cdf, copy, weights)| sum_blocks_into(weights, cdf, copy, SUM_BLOCK))
            .unzip();
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
        let mut guide = Buffer::for_overwrite(guide_len(weights.len()), "the table's guide")?;
        offset_blocks_and_fill_guide(&mut cdf, &offsets, acc, &mut guide);
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
                    #[inline(always)]
                    |_, _, index, out| {
                        for (o, &i) in out.iter_mut().zip(index) {
                            *o = I::from(i as u32);
                        }
                    },
                )
            },
        )
    }

    /// The groups of [`Discrete1D::sample_into`], each group's indices
    /// handed to `finish(table, lanes, index, out)` to write its outputs.
    #[inline(always)]
    fn searched_in_groups<F: Real, O>(
        &self,
        us: &[F],
        out: &mut [O],
        finish: impl Fn(&Search<'_>, &Lanes, &[u64; GROUP], &mut [O]),
    ) {
        let search = self.search();
        let mut lanes = Lanes::new();
        let mut index = [0; GROUP];
        for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
            let draw = {
                #[inline(always)]
                |k: usize| Some((search, us[k].f64()))
            };
            search_group(us.len(), &search, draw, &mut lanes, &mut index);
            finish(&search, &lanes, &index, out);
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
            #[inline(always)]
            |search, lanes, index, out| {
                let mut rescaled = [F::zero(); GROUP];
                lanes.rescale(search, index, &mut rescaled);
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

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
mod tests {
    use super::*;
    use crate::distr::search::{GuideCell, Lanes, fill_guide};
    use proptest::prelude::*;

    /// The reference: a linear scan for `C_{i−1} < u·Σw ≤ C_i` over the
    /// entries of positive weight.
    fn linear(table: &Discrete1D, u: f64) -> usize {
        let value = u * table.sum();
        (table.first..=table.last)
            .find(|&i| table.cdf[i] >= value)
            .unwrap_or(table.last)
    }

    #[test]
    fn known_values_as_mitsuba() {
        // Mitsuba 3: DiscreteDistribution([0, 1, 0, 2, 3, 0]).sample(u)
        let d = Discrete1D::new(&[0.0, 1.0, 0.0, 2.0, 3.0, 0.0]).unwrap();
        assert_eq!(d.sample(0.0), 1);
        assert_eq!(d.sample(1.0 / 6.0), 1);
        assert_eq!(d.sample(0.5), 3);
        assert_eq!(d.sample(1.0), 4);
        let (i, r) = d.sample_reuse(0.25f64);
        assert_eq!(i, 3);
        assert!((r - 0.25).abs() < 1e-12, "{r}");
        assert_eq!(d.sum(), 6.0);
        assert_eq!(d.pmf(3), 1.0 / 3.0);
        assert_eq!(d.cdf(5), 1.0);
    }

    #[test]
    fn errors() {
        assert!(matches!(
            Discrete1D::new(&[1.0, -0.5]),
            Err(Error::InvalidWeight { .. })
        ));
        assert!(matches!(
            Discrete1D::new(&[1.0, f64::NAN]),
            Err(Error::InvalidWeight { .. })
        ));
        assert!(matches!(
            Discrete1D::new(&[0.0, 0.0]),
            Err(Error::AllZero { .. })
        ));
        assert!(matches!(Discrete1D::new(&[]), Err(Error::AllZero { .. })));
        // A sum that overflows is no distribution either.
        assert!(Discrete1D::new(&[f64::MAX, f64::MAX]).is_err());
    }

    #[test]
    fn guide_table_agrees_with_a_linear_scan() {
        let n = 5000;
        let weights: Vec<f64> = (0..n)
            .map(|i| {
                if i % 7 == 3 {
                    0.0
                } else {
                    ((i * 37) % 11) as f64
                }
            })
            .collect();
        let d = Discrete1D::new(&weights).unwrap();
        assert!(!d.guide.is_empty());
        for k in 0..=20_000 {
            let u = k as f64 / 20_000.0;
            assert_eq!(d.sample(u), linear(&d, u), "u = {u}");
        }
        // Exactly on every running sum.
        for i in 0..n {
            let u = d.cdf[i] / d.sum();
            assert_eq!(d.sample(u), linear(&d, u), "u = C_{i}");
        }
    }

    #[test]
    fn batch_sampling_agrees_with_single_draws() {
        // A guided table and a short one, batches not a multiple of GROUP.
        for n in [5000, 10] {
            let weights: Vec<f64> = (0..n).map(|i| ((i * 31) % 9) as f64).collect();
            let d = Discrete1D::new(&weights).unwrap();
            let us: Vec<f64> = (0..=1000).map(|k| k as f64 / 1000.0).collect();
            let mut out = vec![0u64; us.len()];
            d.sample_into(&us, &mut out);
            let mut reused = vec![(0, 0.0); us.len()];
            d.sample_reuse_into(&us, &mut reused);
            for ((&u, &i), &r) in us.iter().zip(&out).zip(&reused) {
                assert_eq!(i as usize, d.sample(u), "n = {n}, u = {u}");
                assert_eq!(r, d.sample_reuse(u), "n = {n}, u = {u}");
            }
        }
    }

    /// Tables whose guide-cell windows fail: a cluster of tiny weights in
    /// one cell (answers past the window), lengths just over the guide's
    /// minimum (windows past the table's end, read as its last sum), zeros
    /// first and last (one table's first entry a window from its end).
    fn window_tables() -> Vec<Vec<f64>> {
        let mut cluster: Vec<f64> = (0..400).map(|i| 1.0 + (i % 5) as f64).collect();
        cluster[150..250].fill(1e-9);
        let mut short = vec![vec![1.0; 64], vec![2.0; 71]];
        short[1][..3].fill(0.0);
        short[1][68..].fill(0.0);
        let ramp = (0..1000)
            .map(|i| ((i * i) % 97) as f64 * (i % 13) as f64)
            .collect();
        let late = [vec![0.0; 60], vec![1.0; 4]].concat();
        [vec![cluster, ramp, late], short].concat()
    }

    /// `u` on a grid, on every running sum and its neighbours, and
    /// negative (drawn as 0, by the single search).
    fn window_us(d: &Discrete1D) -> Vec<f64> {
        let mut us: Vec<f64> = (0..=3000).map(|k| k as f64 / 3000.0).collect();
        us.extend([-0.5, -0.0, -1e-300]);
        for &c in d.cdf.iter() {
            let u = c / d.sum();
            us.extend([u, u.next_down().max(0.0), u.next_up().min(1.0)]);
        }
        us
    }

    #[test]
    fn side_by_side_searches_agree_where_windows_fail() {
        for weights in window_tables() {
            let d = Discrete1D::new(&weights).unwrap();
            let us = window_us(&d);
            let mut out = vec![0u64; us.len()];
            d.sample_into(&us, &mut out);
            let mut reused = vec![(0, 0.0); us.len()];
            d.sample_reuse_into(&us, &mut reused);
            let n = weights.len();
            for ((&u, &i), &r) in us.iter().zip(&out).zip(&reused) {
                assert_eq!(i as usize, d.sample(u), "n = {n}, u = {u}");
                assert_eq!(r, d.sample_reuse(u), "n = {n}, u = {u}");
                assert_eq!(i as usize, linear(&d, u), "n = {n}, u = {u}");
            }
        }
    }

    /// Draws of `search` (over `d`'s weights) side by side: those the
    /// windows settle have the answer of a linear scan; returns how many
    /// were left to the single search.
    fn lanes_redone(d: &Discrete1D, search: &Search<'_>) -> usize {
        let mut lanes = Lanes::new();
        let mut redone = 0;
        for us in window_us(d).chunks(GROUP) {
            for (k, &u) in us.iter().enumerate() {
                lanes.set(k, search, u);
            }
            let mut index = [0; GROUP];
            let redo = lanes.search(search, &mut index);
            for (k, &u) in us.iter().enumerate() {
                if redo & (1 << k) == 0 {
                    assert_eq!(index[k] as usize, linear(d, u), "u = {u}");
                } else {
                    redone += 1;
                }
            }
        }
        redone
    }

    #[test]
    fn lanes_leave_to_the_single_search_the_draws_their_window_misses() {
        let mut redone = 0;
        for weights in window_tables() {
            let d = Discrete1D::new(&weights).unwrap();
            redone += lanes_redone(&d, &d.search());
            // Every guide cell one entry late, as round-off could make
            // one (see the test below): the sum before it gives it away.
            let late: Vec<u32> = (d.guide.iter())
                .map(|&g| (g + 1).min(d.last as u32))
                .collect();
            let search = Search::new((d.weights(), &d.cdf, &late), (d.sum(), d.first, d.last));
            redone += lanes_redone(&d, &search);
        }
        // The cluster's draws and the late cells'.
        assert!(redone > 1000, "{redone}");
    }

    /// Weights of long tables (one part group; groups of blocks whole or
    /// with a part group of several blocks or of one short block): a
    /// pattern, zeros across block and group boundaries (cells shared by
    /// two blocks), a weight that spans many cells, leading and trailing
    /// zeros.
    fn long_tables() -> Vec<Vec<f64>> {
        let zeros = [
            SUM_BLOCK - 50..SUM_BLOCK + 50,
            SUM_GROUP - 9..2 * SUM_GROUP + 9,
        ];
        let sizes = [
            5000,
            2 * SUM_GROUP,
            SUM_GROUP + 3 * SUM_BLOCK + 5,
            3 * SUM_GROUP + 7,
        ];
        let mut tables = Vec::new();
        for n in sizes {
            let cases: [Box<dyn Fn(usize) -> f64>; 4] = [
                Box::new(|i| ((i * 7919) % 13) as f64),
                Box::new(|i| f64::from(!zeros.iter().any(|z| z.contains(&i)) || i == n / 2)),
                Box::new(|i| if i == n / 3 { 1e6 } else { 1.0 }),
                Box::new(|i| f64::from(i > 100 && i + 200 < n && i % 3 == 0)),
            ];
            tables.extend(cases.iter().map(|w| (0..n).map(w).collect()));
        }
        tables
    }

    #[test]
    fn long_tables_are_summed_by_blocks() {
        for weights in long_tables() {
            let d = Discrete1D::new(&weights).unwrap();
            // Each block's sums in order from 0, offset by the sum in order
            // of the totals of the blocks before it: the same bits.
            let mut offset = 0.0;
            for (b, block) in weights.chunks(SUM_BLOCK).enumerate() {
                let mut acc = 0.0;
                for (i, &w) in block.iter().enumerate() {
                    acc += w;
                    assert_eq!(d.cdf[b * SUM_BLOCK + i], acc + offset);
                }
                offset += acc;
            }
            assert_eq!(d.sum(), offset);
            let exact: f64 = weights.iter().sum();
            assert!((d.sum() - exact).abs() <= 1e-12 * exact);
            for k in 0..=100 {
                let u = k as f64 / 100.0;
                let i = d.sample(u);
                assert_eq!(i, linear(&d, u), "u = {u}");
                assert!(weights[i] > 0.0);
            }
        }
    }

    #[test]
    fn guide_cells_are_the_floors_of_the_scaled_sums() {
        let cases = [
            (65, 1.0),
            (250_001, 3.7e5),
            (1 << 20, 7.0),
            (4097, 1e-300),
            (65, 1e-310),
        ];
        for (len, sum) in cases {
            let cell = GuideCell::new(len, sum).unwrap();
            let cells = len - 1;
            // (Kept finite for a subnormal sum.)
            let scale = (cells as f64 / sum).min(f64::MAX);
            // Whole, half and nearly whole cells (ties and round-ups), and
            // sums past the total.
            let xs = (0..=4 * cells)
                .map(|k| k as f64 / 4.0)
                .chain([1e9, f64::MAX]);
            for x in xs.flat_map(|x| [x, x.next_down().max(0.0), x.next_up()]) {
                let c = x / scale;
                let floor = ((c * scale) as usize).min(cells);
                assert_eq!(cell.of(c) as usize, floor, "len {len}, x {x}");
            }
        }
    }

    #[test]
    fn long_tables_get_the_guide_of_their_sums() {
        for (case, weights) in long_tables().iter().enumerate() {
            let d = Discrete1D::new(weights).unwrap();
            // Cell k holds the first entry whose sum's cell is k or more,
            // kept within the entries of positive weight; cells past the
            // last sum's, the last entry.
            let cell = GuideCell::new(d.guide.len(), d.sum()).unwrap();
            let mut expected = vec![d.last; d.guide.len()];
            let mut k = 0;
            for (i, &c) in d.cdf.iter().enumerate() {
                while k <= cell.of(c) as usize {
                    expected[k] = i.clamp(d.first, d.last);
                    k += 1;
                }
            }
            let guide: Vec<usize> = d.guide.iter().map(|&g| g as usize).collect();
            assert_eq!(guide, expected, "case {case}");
            // Filled in one pass over the table, the same guide.
            let mut one_pass = vec![0; d.guide.len()];
            fill_guide(&d.cdf, d.sum(), (d.first, d.last), &mut one_pass);
            assert_eq!(&one_pass[..], &d.guide[..], "case {case}");
        }
    }

    #[test]
    fn negative_zero_draws_as_zero() {
        // u = -0.0 passes the [0, 1] check; the search compares the bits of
        // u·Σw, so -0.0 must count as +0.0 (also past leading zeros).
        let weights: Vec<f64> = (0..300).map(|i| if i < 5 { 0.0 } else { 1.0 }).collect();
        let d = Discrete1D::new(&weights).unwrap();
        assert_eq!(d.sample(-0.0f64), 5);
        assert_eq!(d.sample(-0.0f32), d.sample(0.0f32));
        assert_eq!(d.sample_reuse(-0.0f64), d.sample_reuse(0.0f64));
    }

    #[test]
    fn weights_too_small_to_move_the_sums_leave_rescaled_numbers_in_the_unit_interval() {
        // The rescaled u divides by the step of the running sums, which is 0
        // at an entry too light to move them: the search must never return
        // one. Short (unguided) and long (guided) tables, single draws and
        // batches, u on a grid and at every running sum's own u.
        for n in [5, 300] {
            let weights: Vec<f64> = (0..n)
                .map(|i| if i % 2 == 1 { 1e-30 } else { 1.0 + i as f64 })
                .collect();
            let d = Discrete1D::new(&weights).unwrap();
            let mut us: Vec<f64> = (0..=4000).map(|k| k as f64 / 4000.0).collect();
            us.extend((0..n).map(|i| d.cdf(i)));
            let mut batch = vec![(0, 0.0); us.len()];
            d.sample_reuse_into(&us, &mut batch);
            for (&u, &got) in us.iter().zip(&batch) {
                let (i, r) = d.sample_reuse(u);
                assert_eq!((i, r), got, "n = {n}, u = {u}");
                assert!(weights[i] >= 1.0, "n = {n}, u = {u}: entry {i}");
                assert!((0.0..1.0).contains(&r), "n = {n}, u = {u}: {r}");
                let r32 = d.sample_reuse(u as f32).1;
                assert!((0.0..1.0).contains(&r32), "n = {n}, u = {u}: {r32}");
            }
        }
    }

    #[test]
    fn a_guide_cell_that_starts_too_late_is_caught() {
        // Round-off between u·G and the guide's thresholds could start a
        // cell one entry late (rare); shift every cell's start by one to
        // check that the search notices and still answers right.
        let n = 200;
        let weights: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64).collect();
        let d = Discrete1D::new(&weights).unwrap();
        let late: Vec<u32> = d
            .guide
            .iter()
            .map(|&g| (g + 1).min(d.last as u32))
            .collect();
        let search = Search::new((d.weights(), &d.cdf, &late), (d.sum(), d.first, d.last));
        for k in 0..=4000 {
            let u = k as f64 / 4000.0;
            assert_eq!(
                search.index(u, search.guide_cell(u)),
                linear(&d, u),
                "u = {u}"
            );
        }
    }

    proptest! {
        #[test]
        fn never_returns_a_zero_weight(
            weights in prop::collection::vec(prop_oneof![Just(0.0), 0.0..10.0f64], 1..3000),
            us in prop::collection::vec(0.0..=1.0f64, 50),
        ) {
            if let Ok(d) = Discrete1D::new(&weights) {
                for u in us.into_iter().chain([0.0, 1.0, f64::ONE_MINUS_EPSILON]) {
                    let (i, r) = d.sample_reuse(u);
                    prop_assert!(weights[i] > 0.0, "u = {} gave zero-weight index {}", u, i);
                    prop_assert_eq!(i, linear(&d, u));
                    prop_assert!((0.0..1.0).contains(&r));
                }
                // The CDF is monotone and ends at 1.
                prop_assert!((0..d.len()).all(|i| i == 0 || d.cdf(i) >= d.cdf(i - 1)));
                prop_assert_eq!(d.cdf(d.len() - 1), 1.0);
            }
        }

        #[test]
        fn constructor_never_panics(weights in prop::collection::vec(
            prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(-0.0), Just(f64::MAX), any::<f64>()],
            0..20,
        )) {
            let _ = Discrete1D::new(&weights);
        }
    }
}

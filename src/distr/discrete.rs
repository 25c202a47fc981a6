//! [`Discrete1D`]: a discrete distribution sampled by inverting its CDF.

use super::{GROUP, check_len, find_invalid, is_weight};
use crate::buffer::Buffer;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::{parallel, simd};
use rayon::prelude::*;

/// Tables shorter than this are searched without a guide table: a binary
/// search over a cache line or two is as fast. (Above it, even a table of a
/// few hundred entries, such as an environment map's marginal, gains: its
/// binary search is a chain of dependent loads.)
const GUIDE_MIN_LEN: usize = 64;

/// Entries per block of the running sums of a long table: each block is
/// summed from 0 and then offset by the blocks before it, in parallel. Fixed,
/// so that the sums do not depend on the thread count (a table of at most
/// one block is summed strictly in order, as Mitsuba does).
const SUM_BLOCK: usize = 1 << 16;

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
    weights: Buffer<f64>,
    cdf: Buffer<f64>,
    sum: f64,
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
        let (table, valid) = parallel::install(|| Self::build(weights))?;
        if !valid {
            find_invalid("weights", weights, |i| format!("[{i}]"))?;
        }
        table.ok_or(Error::AllZero { arg: "weights" })
    }

    /// A distribution from weights already checked to be finite and
    /// `>= 0`; `None` when they are empty or sum to 0.
    pub(crate) fn from_checked(weights: &[f64]) -> Option<Self> {
        Self::build(weights).0
    }

    /// The distribution of `weights` (`None` when they are empty or do not
    /// sum to a positive finite number), and whether every weight is finite
    /// and `>= 0` (checked on the way; a table from invalid weights is
    /// meaningless). Tables longer than [`SUM_BLOCK`] are summed in
    /// parallel (on the current rayon pool).
    fn build(weights: &[f64]) -> (Option<Self>, bool) {
        // The copy of the weights and each block's running sums from 0, in
        // parallel; then to each block the sum of the blocks before it.
        let mut copy = Buffer::for_overwrite(weights.len());
        let mut cdf = Buffer::for_overwrite(weights.len());
        let (totals, valid): (Vec<f64>, Vec<bool>) = (
            cdf.par_chunks_mut(SUM_BLOCK),
            copy.par_chunks_mut(SUM_BLOCK),
            weights.par_chunks(SUM_BLOCK),
        )
            .into_par_iter()
            .map(|(cdf, copy, weights)| sum_into(weights, cdf, copy))
            .unzip();
        let valid = valid.into_iter().all(|v| v);
        let mut offsets = Vec::with_capacity(totals.len());
        let mut acc = 0.0;
        for total in &totals {
            offsets.push(acc);
            acc += total;
        }
        let Some((first, last)) = positive_range(weights) else {
            return (None, valid);
        };
        if !(valid && acc > 0.0 && acc.is_finite()) {
            return (None, valid);
        }
        cdf.par_chunks_mut(SUM_BLOCK)
            .zip(offsets)
            .skip(1)
            .for_each(|(cdf, offset)| cdf.iter_mut().for_each(|c| *c += offset));
        let mut guide = Buffer::for_overwrite(guide_len(weights.len()));
        fill_guide(&cdf, acc, (first, last), &mut guide);
        let table = Discrete1D {
            weights: copy,
            cdf,
            sum: acc,
            first,
            last,
            guide,
        };
        (Some(table), valid)
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Whether the table has no entries (never true for a built table).
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// The sum of the weights (the normalisation constant).
    pub fn sum(&self) -> f64 {
        self.sum
    }

    /// The weight of entry `i` as given (0 outside the table).
    pub fn weight(&self, i: usize) -> f64 {
        self.weights.get(i).copied().unwrap_or(0.0)
    }

    /// The weights as given.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Probability of index `i`: `w_i / Σw` (0 outside the table).
    pub fn pmf(&self, i: usize) -> f64 {
        self.weight(i) / self.sum
    }

    /// Running sum of the weights before entry `i`: `C_{i−1}` (0 for i = 0).
    pub fn sum_before(&self, i: usize) -> f64 {
        self.search().sum_before(i)
    }

    /// Cumulative probability `P(index ≤ i) = C_i / Σw` (1 past the end).
    pub fn cdf(&self, i: usize) -> f64 {
        self.cdf.get(i).map_or(1.0, |&c| c / self.sum)
    }

    /// The index `i` with `C_{i−1} < u·Σw ≤ C_i`, among entries of positive
    /// weight. `u` in `[0, 1]`.
    #[inline]
    pub fn sample<F: Real>(&self, u: F) -> usize {
        let search = self.search();
        search.index(u.f64(), search.guide_cell(u.f64()))
    }

    /// `out[i] = sample(us[i])` for a batch. Groups of draws go in three
    /// sweeps: locate their guide cells (prefetched), prefetch the running
    /// sums each search reads, then search; so the cache misses of a group
    /// overlap rather than queue.
    pub fn sample_into<F: Real, I: From<u32>>(&self, us: &[F], out: &mut [I]) {
        let search = self.search();
        for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
            let mut cells = [0; GROUP];
            for (k, &u) in cells.iter_mut().zip(us) {
                *k = search.locate(u.f64());
            }
            for &k in &cells[..us.len()] {
                search.prefetch_window(k);
            }
            for ((o, &u), &k) in out.iter_mut().zip(us).zip(&cells) {
                *o = I::from(search.index(u.f64(), k) as u32);
            }
        }
    }

    /// The index as [`Discrete1D::sample`], and `u` rescaled within that
    /// entry's share to `[0, 1)`: `(u·Σw − C_{i−1}) / w_i`, a fresh uniform
    /// number for a second decision.
    #[inline]
    pub fn sample_reuse<F: Real>(&self, u: F) -> (usize, F) {
        self.search().sample_reuse(u)
    }

    /// The tables as slices, for the steps of a draw.
    #[inline(always)]
    pub(crate) fn search(&self) -> Search<'_> {
        Search::new(
            (&self.weights, &self.cdf, &self.guide),
            (self.sum, self.first, self.last),
        )
    }
}

/// The running sums of `weights` from 0 into `cdf`, in order, and the
/// weights into `copy` (all three of one length): their total, and whether
/// every weight is finite and `>= 0`.
fn sum_into(weights: &[f64], cdf: &mut [f64], copy: &mut [f64]) -> (f64, bool) {
    let (mut acc, mut valid) = (0.0, true);
    for ((c, w_copy), &w) in cdf.iter_mut().zip(copy.iter_mut()).zip(weights) {
        acc += w;
        *c = acc;
        *w_copy = w;
        valid &= is_weight(w);
    }
    (acc, valid)
}

/// The first and last entries of positive weight (`None` if there is none).
fn positive_range(weights: &[f64]) -> Option<(usize, usize)> {
    let positive = |w: &f64| *w > 0.0;
    Some((
        weights.iter().position(positive)?,
        weights.iter().rposition(positive)?,
    ))
}

/// The length of the guide table of a table of `n` entries: one cell per 4
/// entries (a short search, a small table), plus the end; 0 (no guide) for
/// tables shorter than [`GUIDE_MIN_LEN`].
pub(crate) fn guide_len(n: usize) -> usize {
    if n < GUIDE_MIN_LEN { 0 } else { n / 4 + 1 }
}

/// Fills the guide table of the running sums `cdf` (total `sum`, entries of
/// positive weight from `first` to `last`): `guide[k]` is the first `i`
/// with `C_i ≥ k·Σw/G`, for `G + 1 = guide.len()` cells.
///
/// Branch-free: entry `i` writes its index into cell `⌊C_i·G/Σw⌋`, last
/// entries first, so each hit cell keeps its smallest index; a cell no
/// entry hits takes the answer of the next cell up (a suffix minimum).
/// Round-off here only costs a fallback search (see [`Search::bracket`]).
fn fill_guide(cdf: &[f64], sum: f64, (first, last): (usize, usize), guide: &mut [u32]) {
    let Some(cells) = guide.len().checked_sub(1) else {
        return;
    };
    let scale = cells as f64 / sum;
    guide.fill(u32::MAX);
    for (i, &c) in cdf.iter().enumerate().rev() {
        guide[((c * scale) as usize).min(cells)] = i as u32;
    }
    let (first, mut next) = (first as u32, last as u32);
    for g in guide.iter_mut().rev() {
        next = next.min(*g);
        *g = next.max(first);
    }
}

/// The tables of one distribution written into slices of a larger store
/// (the rows of a [`super::Discrete2D`]): `weights` (checked: finite and
/// `>= 0`) copied into `copy`, their running sums into `cdf` (summed in
/// order) and the guide table into `guide` ([`guide_len`] entries). Returns
/// the sum and the first and last entries of positive weight, as
/// [`Search::new`] takes them, or `None` for a table that sums to 0.
pub(crate) fn fill_table(
    weights: &[f64],
    (copy, cdf, guide): (&mut [f64], &mut [f64], &mut [u32]),
) -> Option<(f64, usize, usize)> {
    let (sum, _) = sum_into(weights, cdf, copy);
    let range = positive_range(weights)?;
    if !(sum > 0.0 && sum.is_finite()) {
        return None;
    }
    fill_guide(cdf, sum, range, guide);
    Some((sum, range.0, range.1))
}

/// The running sums from a guide cell's first entry that [`Search::index`]
/// compares with the value all at once (one vector compare, no branch),
/// instead of a binary search whose branches the CPU cannot predict.
const SCAN: usize = 8;

/// The number of entries of `window` below `value`, for running sums and a
/// value that are finite and `>= 0` (`-0.0` counts as `+0.0`). Such floats
/// order as their bits do, so `c < value` is the sign of the difference of
/// the bits: integer lanes that add up in a few vector instructions (where
/// a sum of compare results compiles to one extraction per lane on
/// AVX-512).
#[inline(always)]
fn count_below(window: &[f64; SCAN], value: f64) -> usize {
    let value = value.abs().to_bits();
    window
        .iter()
        .map(|&c| c.to_bits().wrapping_sub(value) >> 63)
        .sum::<u64>() as usize
}

/// A table's weights, running sums and guide cells, as plain slices of a
/// store that may hold several tables (the rows of a
/// [`super::Discrete2D`], row after row), and a draw in steps that a batch
/// can interleave: [`Search::locate`] the guide cell (prefetched),
/// [`Search::prefetch_window`], then [`Search::index`] or
/// [`Search::index_reuse`]. Indices are the table's own (from 0); the
/// table starts at `start` in `weights` and `cdf`, and its guide at
/// `guide_start` in `guide`, so that cutting one table out of the store
/// is arithmetic on its place (no sub-slices to cut and check per draw).
#[derive(Clone, Copy)]
pub(crate) struct Search<'a> {
    weights: &'a [f64],
    cdf: &'a [f64],
    guide: &'a [u32],
    start: usize,
    guide_start: usize,
    len: usize,
    guide_len: usize,
    sum: f64,
    first: usize,
    last: usize,
}

/// Where a table lies in a store of tables (see [`Search::within`]): its
/// first entry in the weights and running sums, its first guide cell, and
/// its number of entries.
#[derive(Clone, Copy)]
pub(crate) struct Place {
    pub(crate) start: usize,
    pub(crate) guide_start: usize,
    pub(crate) len: usize,
}

impl<'a> Search<'a> {
    /// The search of tables written by [`fill_table`] (`weights`, `cdf` and
    /// `guide` as it wrote them; `(sum, first, last)` as it returned them).
    #[inline(always)]
    pub(crate) fn new(
        (weights, cdf, guide): (&'a [f64], &'a [f64], &'a [u32]),
        span: (f64, usize, usize),
    ) -> Self {
        let place = Place {
            start: 0,
            guide_start: 0,
            len: weights.len(),
        };
        Self::within((weights, cdf, guide), place, span)
    }

    /// The search of the table at `place` in a store of tables that
    /// [`fill_table`] wrote one after another (each guide [`guide_len`]
    /// cells long).
    #[inline(always)]
    pub(crate) fn within(
        (weights, cdf, guide): (&'a [f64], &'a [f64], &'a [u32]),
        place: Place,
        (sum, first, last): (f64, usize, usize),
    ) -> Self {
        Search {
            weights,
            cdf,
            guide,
            start: place.start,
            guide_start: place.guide_start,
            len: place.len,
            guide_len: guide_len(place.len),
            sum,
            first,
            last,
        }
    }

    /// The sum of the weights.
    #[inline(always)]
    pub(crate) fn sum(&self) -> f64 {
        self.sum
    }

    /// The weight of entry `i` (0 outside the table).
    #[inline(always)]
    pub(crate) fn weight(&self, i: usize) -> f64 {
        if i < self.len {
            self.weights[self.start + i]
        } else {
            0.0
        }
    }

    /// The running sum `C_i` of entry `i` of the table (`i < len`).
    #[inline(always)]
    fn running(&self, i: usize) -> f64 {
        self.cdf[self.start + i]
    }

    /// The first entry of guide cell `k` (`None` past the guide, or without
    /// one).
    #[inline(always)]
    fn guide_entry(&self, k: usize) -> Option<usize> {
        (k < self.guide_len).then(|| self.guide[self.guide_start + k] as usize)
    }

    /// The guide cell `⌊u·G⌋` of `u` (clamped to the last cell; 0 without a
    /// guide table).
    #[inline(always)]
    fn guide_cell(&self, u: f64) -> usize {
        let cells = self.guide_len.saturating_sub(1);
        (u * cells as f64).floor_index(cells.saturating_sub(1))
    }

    /// The index and the rescaled `u` in one go (see
    /// [`Discrete1D::sample_reuse`]).
    #[inline(always)]
    pub(crate) fn sample_reuse<F: Real>(&self, u: F) -> (usize, F) {
        self.index_reuse(u, self.guide_cell(u.f64()))
    }

    /// Step 1: the guide cell of `u`, prefetched.
    #[inline(always)]
    pub(crate) fn locate(&self, u: f64) -> usize {
        let k = self.guide_cell(u);
        simd::prefetch(self.guide, self.guide_start + k);
        k
    }

    /// Step 2: prefetches what [`Search::index`] reads for guide cell `k`:
    /// the running sum before its first entry `lo`, the window of [`SCAN`]
    /// sums from `lo` (at most two cache lines with it), and the weight at
    /// `lo`.
    #[inline(always)]
    pub(crate) fn prefetch_window(&self, k: usize) {
        if let Some(lo) = self.guide_entry(k) {
            let lo = self.start + lo;
            simd::prefetch(self.cdf, lo.saturating_sub(1));
            simd::prefetch(self.cdf, lo + SCAN - 1);
            simd::prefetch(self.weights, lo);
        }
    }

    /// Step 3: the index for `u`, starting from the first entry `lo` of
    /// guide cell `k`. Where the sum before `lo` is below `u·Σw` (or `lo`
    /// is the first entry of positive weight), the answer is the first of
    /// the [`SCAN`] sums from `lo` that reaches `u·Σw`, found by counting
    /// those below it in one vector compare; they are sorted, and past the
    /// last entry of positive weight every sum is `Σw`. Otherwise (the
    /// guide cell missed by round-off, or an answer further on) a binary
    /// search of the cell's bracket (see [`Search::bracket`]).
    #[inline(always)]
    pub(crate) fn index(&self, u: f64, k: usize) -> usize {
        let value = u * self.sum;
        if let Some(lo) = self.guide_entry(k) {
            let lo_ok = lo == self.first || self.running(lo - 1) < value;
            if lo + SCAN <= self.len {
                let at = self.start + lo;
                if let Some(window) = self.cdf[at..].first_chunk() {
                    let below = count_below(window, value);
                    if lo_ok && below < SCAN {
                        return lo + below;
                    }
                }
            }
        }
        let (lo, hi) = self.bracket(k, value);
        lo + self.cdf[self.start + lo..self.start + hi].partition_point(|&c| c < value)
    }

    /// Step 3 of [`Discrete1D::sample_reuse`]: the index and the rescaled
    /// `u`.
    #[inline(always)]
    pub(crate) fn index_reuse<F: Real>(&self, u: F, k: usize) -> (usize, F) {
        let i = self.index(u.f64(), k);
        (i, self.rescale(u, i))
    }

    /// Prefetches the weight of index `i`, which [`Search::rescale`] reads
    /// (the running sum before it is among those just searched).
    #[inline(always)]
    pub(crate) fn prefetch_weight(&self, i: usize) {
        simd::prefetch(self.weights, self.start + i);
    }

    /// The leftover of `u` past the running sum before index `i`, rescaled
    /// to `[0, 1)` by its weight.
    #[inline(always)]
    pub(crate) fn rescale<F: Real>(&self, u: F, i: usize) -> F {
        let rescaled = (u.f64() * self.sum - self.sum_before(i)) / self.weights[self.start + i];
        F::c(rescaled.clamp(0.0, f64::ONE_MINUS_EPSILON))
    }

    /// `C_{i−1}` (0 for i = 0, Σw past the end).
    #[inline(always)]
    pub(crate) fn sum_before(&self, i: usize) -> f64 {
        match i {
            0 => 0.0,
            _ if i <= self.len => self.running(i - 1),
            _ => self.sum,
        }
    }

    /// The range `[lo, hi]` (inclusive) that holds the answer for `value`:
    /// from guide cell `k` when it provably brackets `value`, else the
    /// whole range of positive weights.
    #[inline(always)]
    fn bracket(&self, k: usize, value: f64) -> (usize, usize) {
        let full = (self.first, self.last);
        let (Some(lo), Some(hi)) = (self.guide_entry(k), self.guide_entry(k + 1)) else {
            return full;
        };
        // Round-off in u·G against the guide's thresholds can miss by one
        // cell: check the bracket and fall back to the full range.
        let lo_ok = lo == self.first || self.running(lo - 1) < value;
        let hi_ok = hi == self.last || self.running(hi) >= value;
        if lo_ok && hi_ok { (lo, hi) } else { full }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The reference: a linear scan for `C_{i−1} < u·Σw ≤ C_i` over the
    /// entries of positive weight.
    fn linear(table: &Discrete1D, u: f64) -> usize {
        let value = u * table.sum;
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
            let u = d.cdf[i] / d.sum;
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
            for (&u, &i) in us.iter().zip(&out) {
                assert_eq!(i as usize, d.sample(u), "n = {n}, u = {u}");
            }
        }
    }

    #[test]
    fn long_tables_are_summed_by_blocks_consistently() {
        let n = 3 * SUM_BLOCK + 7;
        let weights: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64).collect();
        let d = Discrete1D::new(&weights).unwrap();
        let exact: f64 = weights.iter().sum();
        assert!((d.sum() - exact).abs() <= 1e-12 * exact);
        assert!(d.cdf.windows(2).all(|c| c[0] <= c[1]));
        assert_eq!(d.cdf[n - 1], d.sum());
        for k in 0..=500 {
            let u = k as f64 / 500.0;
            let i = d.sample(u);
            assert_eq!(i, linear(&d, u), "u = {u}");
            assert!(weights[i] > 0.0);
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
        let search = Search::new((&d.weights, &d.cdf, &late), (d.sum, d.first, d.last));
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

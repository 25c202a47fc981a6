//! The search behind the CDF-inversion tables ([`super::Discrete1D`] and
//! the rows of [`super::Discrete2D`]): running sums, a guide table (the
//! cutpoint method of Chen and Asau) that narrows the search to an expected
//! O(1) entries, and the search itself.

use super::{GROUP, is_weight};
use crate::math::Real;
use crate::simd;

/// Tables shorter than this are searched without a guide table: a binary
/// search over a cache line or two is as fast. (Above it, even a table of a
/// few hundred entries, such as an environment map's marginal, gains: its
/// binary search is a chain of dependent loads.)
const GUIDE_MIN_LEN: usize = 64;

/// The running sums of `weights` from 0 into `cdf`, in order, and the
/// weights into `copy` (all three of one length): their total, and whether
/// every weight is finite and `>= 0`.
pub(crate) fn sum_into(weights: &[f64], cdf: &mut [f64], copy: &mut [f64]) -> (f64, bool) {
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
pub(crate) fn positive_range(weights: &[f64]) -> Option<(usize, usize)> {
    let positive = |w: &f64| *w > 0.0;
    Some((
        weights.iter().position(positive)?,
        weights.iter().rposition(positive)?,
    ))
}

/// The length of the guide table of a table of `n` entries: one cell per 2
/// entries up to [`DENSE_GUIDE_MAX`] entries, one per 4 above, plus the
/// end; 0 (no guide) for tables shorter than [`GUIDE_MIN_LEN`]. With a
/// cell per 2 entries, [`Lanes::search`]'s window settles all but a few
/// in a hundred draws even of an environment map's peaked rows, for a
/// `u32` per two `f64` sums; a long table's guide is kept half as large,
/// as its reads miss the caches.
pub(crate) fn guide_len(n: usize) -> usize {
    match n {
        _ if n < GUIDE_MIN_LEN => 0,
        _ if n <= DENSE_GUIDE_MAX => n / 2 + 1,
        _ => n / 4 + 1,
    }
}

/// The longest table with a guide cell per 2 entries (see [`guide_len`]):
/// 64K running sums, half a MiB. (At 10^6 entries, one cell per 2 made
/// `Discrete1D.sample` 13 % slower than one per 4.)
const DENSE_GUIDE_MAX: usize = 1 << 16;

/// Fills the guide table of the running sums `cdf` (total `sum`, entries of
/// positive weight from `first` to `last`): `guide[k]` is the first `i`
/// with `C_i ≥ k·Σw/G`, for `G + 1 = guide.len()` cells.
///
/// Branch-free: entry `i` writes its index into cell `⌊C_i·G/Σw⌋`, last
/// entries first, so each hit cell keeps its smallest index
/// ([`scatter_guide`]); a cell no entry hits takes the answer of the next
/// cell up ([`close_guide`]). Round-off here only costs a fallback search
/// (see [`Search::bracket`]).
pub(crate) fn fill_guide(cdf: &[f64], sum: f64, range: (usize, usize), guide: &mut [u32]) {
    let Some(cell) = GuideCell::new(guide.len(), sum) else {
        return;
    };
    guide.fill(u32::MAX);
    scatter_guide(cdf, 0, cell, guide, 0);
    close_guide(guide, range);
}

/// The guide cell `⌊C·G/Σw⌋` (at most `G`) of a running sum `C`, for a
/// guide of `G + 1` cells.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GuideCell {
    scale: f64,
    /// `G` (below 2³¹: a table has fewer than 2³² entries, and half as
    /// many cells).
    cells: f64,
}

impl GuideCell {
    /// The cells of a guide of `len` entries over a total `sum` (`None`
    /// for a table without a guide).
    pub(crate) fn new(len: usize, sum: f64) -> Option<Self> {
        let cells = len.checked_sub(1)? as f64;
        // Finite even for a subnormal sum, so that `c·scale` is never NaN.
        Some(GuideCell {
            scale: (cells / sum).min(f64::MAX),
            cells,
        })
    }

    /// The cell of running sum `c` (finite, `>= 0`; never decreasing as
    /// `c` grows): `⌊x⌋` of `x = min(c·s, G)`, `s = G/Σw` (at most the
    /// largest float), from the bits of `x + 2⁵²`, whose mantissa's low
    /// bits hold `x` rounded to the nearest whole number, less 1 where that
    /// rounded up. A float-to-integer cast, which saturates, compiles to
    /// scalar code; this vectorises.
    #[inline(always)]
    pub(crate) fn of(self, c: f64) -> u32 {
        const TWO_52: f64 = (1u64 << 52) as f64;
        let x = (c * self.scale).min(self.cells);
        let r = x + TWO_52;
        (r.to_bits() as u32) - u32::from(r - TWO_52 > x)
    }
}

/// Writes into `guide` (the cells from `start` on) the index of each of the
/// running sums `cdf` (those of entries `first..`) into its cell, the last
/// entries first, so that each cell keeps the smallest index that hits it;
/// the cells are found [`SCATTER`] entries at a time, at SIMD width, and
/// written by [`store_guide`]. Entries whose cell lies before `start` write
/// nothing. As the sums never decrease, the guide can be filled block by
/// block, the blocks taken last first: a block of entries whose first
/// entry's cell is past the block before's last keeps to its own cells.
#[inline(always)]
pub(crate) fn scatter_guide(
    cdf: &[f64],
    first: usize,
    cell: GuideCell,
    guide: &mut [u32],
    start: usize,
) {
    // On a line boundary: a 64-byte store of the cells split across two
    // lines stalled the build of 10^6 weights (1.3× its time) in a build
    // whose stack happened to fall so.
    let simd::OnLines(cells) = &mut simd::OnLines([0; SCATTER]);
    for (k, chunk) in cdf.chunks(SCATTER).enumerate().rev() {
        for (to, &c) in cells.iter_mut().zip(chunk) {
            *to = cell.of(c);
        }
        store_guide(&cells[..chunk.len()], first + k * SCATTER, guide, start);
    }
}

/// `guide[cells[i] − start] = first + i` for each `i`, the last first
/// (cells outside the guide skipped). Never inlined, so that it is compiled
/// outside the vector dispatch, one store per entry: inlined at AVX-512,
/// LLVM made the loop a scatter instruction, 15 % of a `Discrete1D` build
/// of 10^6 weights on a Zen 4, where scatters are slow.
#[inline(never)]
fn store_guide(cells: &[u32], first: usize, guide: &mut [u32], start: usize) {
    for (i, &to) in cells.iter().enumerate().rev() {
        if let Some(g) = guide.get_mut((to as usize).wrapping_sub(start)) {
            *g = (first + i) as u32;
        }
    }
}

/// Entries whose guide cells [`scatter_guide`] finds together.
pub(crate) const SCATTER: usize = 64;

/// The guide after [`scatter_guide`]: each cell that no entry hit takes
/// the answer of the next cell up (the last cells `last`), and every answer
/// is kept within `first..=last`.
pub(crate) fn close_guide(guide: &mut [u32], (first, last): (usize, usize)) {
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
    window.iter().map(|&c| below(c, value)).sum::<u64>() as usize
}

/// A table's weights, running sums and guide cells, as plain slices of a
/// store that may hold several tables (the rows of a
/// [`super::Discrete2D`], row after row), and one draw's search: its
/// [`Search::guide_cell`], then [`Search::index`] and
/// [`Search::rescale`] (a batch runs these steps side by side in
/// [`Lanes`]). Indices are the table's own (from 0); the
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

    /// Whether the table has a guide table (see [`guide_len`]).
    #[inline(always)]
    pub(crate) fn guided(&self) -> bool {
        self.guide_len > 0
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
    pub(crate) fn running(&self, i: usize) -> f64 {
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
    pub(crate) fn guide_cell(&self, u: f64) -> usize {
        let cells = self.guide_len.saturating_sub(1);
        (u * cells as f64).floor_index(cells.saturating_sub(1))
    }

    /// The index and the rescaled `u` in one go (see
    /// [`Discrete1D::sample_reuse`]).
    #[inline(always)]
    pub(crate) fn sample_reuse<F: Real>(&self, u: F) -> (usize, F) {
        let i = self.index(u.f64(), self.guide_cell(u.f64()));
        (i, self.rescale(u, i))
    }

    /// The index for `u`, starting from the first entry `lo` of guide cell
    /// `k` ([`Search::guide_cell`]). Where the sum before `lo` is below
    /// `u·Σw` (or `lo` is the first entry of positive weight), the answer
    /// is the first of the [`SCAN`] sums from `lo` that reaches `u·Σw`,
    /// found by counting those below it in one vector compare; they are
    /// sorted, and past the last entry of positive weight every sum is
    /// `Σw`. Otherwise (the guide cell missed by round-off, or an answer
    /// further on) a binary search of the cell's bracket (see
    /// [`Search::bracket`]).
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

    /// The leftover of `u` past the running sum before index `i`, rescaled
    /// to `[0, 1)` by the step of the running sums there:
    /// `(u·Σw − C_{i−1}) / (C_i − C_{i−1})`. The step is `w_i` up to the
    /// sums' round-off, and read from the running sums the search has just
    /// read, not from the table of weights (one table fewer in the caches
    /// of a batch); it is positive for every index the search returns (a
    /// weight too small to move the sum is never returned: the entry
    /// before it reaches `u·Σw` first), and a leftover within the step
    /// stays below 1.
    #[inline(always)]
    pub(crate) fn rescale<F: Real>(&self, u: F, i: usize) -> F {
        let before = self.sum_before(i);
        let rescaled = (u.f64() * self.sum - before) / (self.running(i) - before);
        // Clamped in `F`: `1 − 2⁻⁵³` would round to `1.0` in `f32`.
        F::c(rescaled.max(0.0)).min(F::ONE_MINUS_EPSILON)
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

/// A group of draws searched side by side, each in a table of its own
/// (with a guide) in one store of tables: one column per quantity, so that
/// each step of [`Search::index`] runs over the group at SIMD width, its
/// table reads by gathers ([`simd::gather`]). Positions are the store's.
pub(crate) struct Lanes {
    /// `u·Σw` of each draw's table.
    value: [f64; GROUP],
    /// The guide cell of `u`.
    cell: [u64; GROUP],
    /// The table's first entry.
    start: [u64; GROUP],
    /// Its first entry of positive weight.
    first: [u64; GROUP],
    /// One past its last entry.
    end: [u64; GROUP],
    /// After a search: the running sum before each draw's index `i`,
    /// `C_{i−1}` (0 for `i = 0`), and the one at it, `C_i`, for
    /// [`Lanes::rescale`].
    before: [f64; GROUP],
    at: [f64; GROUP],
}

const _: () = assert!(GROUP == simd::BLOCK);

/// Whether running sum `c` lies below `value` (1 or 0), by their bits: for
/// `c` finite and `>= 0` as `c < value` for `value >= 0` (`-0.0` as
/// `+0.0`), 1 for a NaN `value` (the callers redo those draws, and those
/// of negative values, by [`Search::index`]).
#[inline(always)]
fn below(c: f64, value: f64) -> u64 {
    c.to_bits().wrapping_sub(value.abs().to_bits()) >> 63
}

impl Lanes {
    /// A group whose draws are all [`Lanes::empty`] ones.
    pub(crate) fn new() -> Self {
        Lanes {
            value: [0.0; GROUP],
            cell: [0; GROUP],
            start: [0; GROUP],
            first: [0; GROUP],
            end: [0; GROUP],
            before: [0.0; GROUP],
            at: [0.0; GROUP],
        }
    }

    /// Draw `k` is `u` in `table` (which has a guide).
    #[inline(always)]
    pub(crate) fn set(&mut self, k: usize, table: &Search<'_>, u: f64) {
        self.value[k] = u * table.sum;
        self.cell[k] = (table.guide_start + table.guide_cell(u)) as u64;
        self.start[k] = table.start as u64;
        self.first[k] = (table.start + table.first) as u64;
        self.end[k] = (table.start + table.len) as u64;
    }

    /// Draw `k` has no table: [`Lanes::search`] leaves it to its caller.
    #[inline(always)]
    pub(crate) fn empty(&mut self, k: usize) {
        (self.value[k], self.cell[k], self.start[k]) = (0.0, 0, 0);
        (self.first[k], self.end[k]) = (0, 0);
    }

    /// The index each draw's [`Search::index`] finds by its guide cell's
    /// window, into `index` (the table's own, from 0), and the running sums
    /// [`Lanes::rescale`] takes: the cell's first entry `lo` (a gather),
    /// then a branch-free binary search of [`STEPS`] steps, a gather each,
    /// of the window `w_j = C_{lo−1+j}`, `j < 2^STEPS − 1`, for the count
    /// `c` of its sums below `u·Σw`. `w_0` checks the guide cell (round-off
    /// can start it one entry late); at the table's first entry of
    /// positive weight it counts as below and reads 0, the sum before that
    /// entry. For `1 ≤ c ≤ 2^STEPS − 2` the answer is `lo − 1 + c`, and the
    /// search has read both sums around it: the last sum it found below
    /// is `w_{c−1}`, the last not below `w_c`. The window is sorted; its
    /// reads past the table's end read its last sum, `Σw`, as the sums past
    /// its last entry of positive weight are. Returns the draws (bit `k`
    /// for draw `k`) for which the window does not settle the answer (the
    /// cell missed by round-off, the answer past the window, no table, a
    /// negative or NaN `u·Σw`): for those, `index` and the sums hold no
    /// answer, and [`search_group`] finds them by [`Search::index`].
    /// `store` is any table of the store (its slices are the store's).
    #[inline(always)]
    pub(crate) fn search(
        &mut self,
        store: &Search<'_>,
        rescale: bool,
        index: &mut [u64; GROUP],
    ) -> u64 {
        let simd::OnLines(lo) = &mut simd::OnLines([0u32; GROUP]);
        simd::gather(store.guide, &self.cell, lo);
        let simd::OnLines(at) = &mut simd::OnLines([0u64; GROUP]);
        for k in 0..GROUP {
            at[k] = self.start[k] + u64::from(lo[k]);
        }
        let simd::OnLines(read) = &mut simd::OnLines([0u64; GROUP]);
        let simd::OnLines(got) = &mut simd::OnLines([0.0; GROUP]);
        // The sums as bits, so that each step's choice is a mask.
        let simd::OnLines(before) = &mut simd::OnLines([0u64; GROUP]);
        let simd::OnLines(after) = &mut simd::OnLines([0u64; GROUP]);
        index.fill(0);
        for step in (0..STEPS).rev() {
            let half = 1 << step;
            // Window entry `j = c + half − 1` is running sum `at + j − 1`.
            for (k, &c) in index.iter().enumerate() {
                let last = self.end[k].saturating_sub(1);
                read[k] = (at[k] + c + half - 1).saturating_sub(1).min(last);
            }
            simd::gather(store.cdf, read, got);
            for (k, c) in index.iter_mut().enumerate() {
                // Only the last step can read `w_0`.
                let forced = u64::from(step == 0 && *c == 0 && at[k] == self.first[k]);
                let sum = got[k].to_bits() & forced.wrapping_sub(1);
                let is_below = forced | below(f64::from_bits(sum), self.value[k]);
                let mask = is_below.wrapping_neg();
                *c += half & mask;
                if rescale {
                    before[k] = (sum & mask) | (before[k] & !mask);
                    after[k] = (sum & !mask) | (after[k] & mask);
                }
            }
        }
        if rescale {
            for k in 0..GROUP {
                self.before[k] = f64::from_bits(before[k]);
                self.at[k] = f64::from_bits(after[k]);
            }
        }
        let mut redo = 0;
        for (k, i) in index.iter_mut().enumerate() {
            let settled = (1..(1 << STEPS) - 1).contains(i);
            let ok = settled && at[k] < self.end[k] && !self.value[k].is_sign_negative();
            redo |= u64::from(!ok) << k;
            *i = (*i + u64::from(lo[k])).saturating_sub(1);
        }
        redo
    }

    /// `rescaled[k] = table.rescale(u_k, i_k)` for each draw (as
    /// [`Lanes::set`] gave it, `i_k` its answer) from the running sums its
    /// search read, the divisions at SIMD width; draws without a table
    /// ([`Lanes::empty`]) keep their `rescaled[k]`.
    #[inline(always)]
    pub(crate) fn rescale<F: Real>(&self, rescaled: &mut [F; GROUP]) {
        for (k, rescaled) in rescaled.iter_mut().enumerate() {
            let before = self.before[k];
            let r = F::c(((self.value[k] - before) / (self.at[k] - before)).max(0.0));
            if self.end[k] > 0 {
                *rescaled = r.min(F::ONE_MINUS_EPSILON);
            }
        }
    }
}

/// The binary search steps of [`Lanes::search`]: its window holds
/// `2^STEPS − 1` running sums, and settles answers up to `2^STEPS − 3`
/// entries past the guide cell's first.
const STEPS: u32 = 3;

/// For each of the first `n` draws of a group, `index[k]` = the index
/// [`Search::index`] finds for `u` in `table` where `draw(k)` is `Some((table,
/// u))`, else 0: side by side ([`Lanes::search`]) if the tables have
/// guides (all the store's tables have the same length as `store`, in
/// whose store they lie), the draws it leaves one at a time. `lanes`
/// keeps the draws' columns, for [`Lanes::rescale`].
#[inline(always)]
pub(crate) fn search_group<'a>(
    n: usize,
    store: &Search<'a>,
    draw: impl Fn(usize) -> Option<(Search<'a>, f64)>,
    (lanes, rescale): (&mut Lanes, bool),
    index: &mut [u64; GROUP],
) {
    for k in 0..n {
        match draw(k) {
            Some((table, u)) => lanes.set(k, &table, u),
            None => lanes.empty(k),
        }
    }
    let all = if store.guided() {
        lanes.search(store, rescale, index)
    } else {
        u64::MAX
    };
    let mut redo = all & (u64::MAX >> (GROUP - n.max(1)));
    while redo != 0 {
        let k = redo.trailing_zeros() as usize;
        redo &= redo - 1;
        index[k] = match draw(k) {
            Some((table, u)) => {
                let i = table.index(u, table.guide_cell(u));
                if rescale {
                    (lanes.before[k], lanes.at[k]) = (table.sum_before(i), table.running(i));
                }
                i as u64
            }
            None => 0,
        };
    }
}

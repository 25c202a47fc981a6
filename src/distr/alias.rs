//! [`AliasTable`]: O(1) sampling of a discrete distribution (Walker's alias
//! method, built block by block in parallel).

use super::{GROUP, Weights, all_weights, check_len, find_invalid};
use crate::buffer::Buffer;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::{alloc, parallel, simd};
use rayon::prelude::*;
use std::hint::select_unpredictable;

/// Entries per block of the build: a block's sweep runs in the core's own
/// cache. Fixed, so that the table does not depend on the number of threads.
const BLOCK: usize = 1 << 13;

/// Pieces of a merge, run interleaved (see [`Orders::run`]).
const LANES: usize = 4;

/// `2^32`: thresholds are 32-bit fixed-point fractions of a cell.
const ONE: f64 = 4_294_967_296.0;

/// A discrete distribution over `0..n` with probabilities proportional to
/// non-negative weights, sampled in O(1) with one uniform number.
///
/// # Probability
/// `P(i) = w_i / Σw`, the same as [`super::Discrete1D`] (a different map
/// from `u` to indices). Each cell's threshold is rounded to 32 bits, so the
/// probability a draw realises is within `2^-32/n` per cell of it.
///
/// # Sampling
/// With `t = u·n`, cell `c = ⌊t⌋` keeps its own index when the fraction
/// `t − c` is below the cell's threshold, and otherwise returns the cell's
/// alias. Every cell holds mass `1/n`: its own share `s_c = w_c·n/Σw`,
/// topped up from one donor. An entry of weight 0 has threshold 0 and is
/// never returned. The fraction has `52 − log₂n` bits for `f64` input and
/// only `23 − log₂n` for `f32` input, which coarsens the thresholds: use
/// `f64` numbers for large tables.
///
/// # Construction
/// Entries with `s < 1` are light, the others heavy, each kept in order.
/// The sweep of Hübschle-Schneider and Sanders lets the current heavy entry
/// top up light cells in order while its residual exceeds 1, and then
/// closes it as a cell of its own, topped up by the next heavy entry. With
/// the deficits `σ_L(k) = Σ_{k'<k} (1 − s_{L_k'})` of the first `k` light
/// entries and the surpluses `σ_H(j) = Σ_{j'<j} (s_{H_j'} − 1)` of the first
/// `j` heavy ones, that sweep is a merge (see `Orders`):
/// - light `k` takes as alias the heavy `j` with `σ_H(j) ≤ σ_L(k) < σ_H(j+1)`;
/// - heavy `j` closes after the `i` light entries with `σ_L(k) < σ_H(j+1)`,
///   keeping `1 − (σ_L(i) − σ_H(j+1))` of its cell, and takes heavy `j+1` as
///   alias.
///
/// The build sweeps each block of `BLOCK` entries on its own, in parallel
/// and in cache, and leaves over what the block cannot settle: when its
/// heavies' surplus `S` exceeds its lights' deficit `D`, the heavies from
/// the first with `σ_H(j+1) > D` on (the first with its residual surplus
/// `σ_H(j+1) − D`); otherwise its last heavy, whose cell keeps
/// `1 − (σ_L(i) − S)` (`i` the first light with `σ_L(i) ≥ S`), and the
/// lights from `i` on. One last sweep of the leftovers of all blocks, in
/// block order, settles them; its last heavy keeps its whole cell. Random
/// weights leave a few percent of the entries over; weights sorted by size
/// leave most of them, and the last sweep, on one thread and on freshly
/// allocated arrays, then dominates (an order of magnitude slower; see
/// benches/README.md).
/// Thresholds come from prefix sums over one block (or over the
/// leftovers), never from a residual carried along the sweep, and the
/// table is the same whatever the number of threads.
///
/// # References
/// M. D. Vose, "A linear algorithm for generating random numbers with a
/// given distribution", IEEE Transactions on Software Engineering 17(9),
/// 1991. L. Hübschle-Schneider, P. Sanders, "Parallel Weighted Random
/// Sampling", ACM Transactions on Mathematical Software 48(3), 2022.
#[derive(Clone, Debug)]
pub struct AliasTable {
    /// `[threshold, alias]` of each cell: cell `c` keeps `c` when the
    /// fraction of `u·n` past `c`, in 32-bit fixed point, is below the
    /// threshold, else returns the alias. A full cell is its own alias.
    cells: Buffer<[u32; 2]>,
    /// The weights as given and their sum: `pmf(i) = w_i / Σw`, computed
    /// when asked (`len`, `sum`, `pmf`, ... by dereference).
    weights: Weights,
}

/// The cell of entry `index` that keeps it with probability `keep` and
/// otherwise returns `alias`: a full cell (`keep ≥ 1`) is its own alias, and
/// an entry of positive share keeps at least the smallest threshold, so
/// that round-off cannot make it unreachable. Branch-free.
#[inline(always)]
fn cell(index: u32, keep: f64, alias: u32, positive: bool) -> [u32; 2] {
    // `keep·2^32` rounded to the nearest integer by adding 2^52, where the
    // spacing of doubles is 1: no conversion, whose range checks branch.
    const SHIFT: f64 = 4_503_599_627_370_496.0;
    let scaled = keep.clamp(0.0, 1.0) * ONE + SHIFT;
    let bits = (scaled.to_bits() - SHIFT.to_bits()).max(u64::from(positive));
    let full = bits > u64::from(u32::MAX);
    [
        select_unpredictable(full, u32::MAX, bits as u32),
        select_unpredictable(full, index, alias),
    ]
}

/// The light and heavy orders of a sweep: `σ_L(k)` for `k = 0..=n_light`,
/// `σ_H(j+1)` for each heavy `j` (+∞ for the last heavy, which never
/// closes), and which items the heavies are (see [`Sweep`]).
///
/// The sweep is their merge: light `k` is swept before heavy `j` closes iff
/// `σ_L(k) < σ_H(j+1)`. A light step gives light `k` heavy `j` as its
/// alias; a closing step leaves heavy `j` the share `1 − (σ_L(k) −
/// σ_H(j+1))` of its own cell.
struct Orders<'a> {
    deficit_before: &'a [f64],
    surplus_through: &'a [f64],
    heavy_item: &'a [u32],
}

impl Orders<'_> {
    /// The point `(k, j)` of the merge path after `d` steps: the largest
    /// `k` such that light `k − 1` precedes close `d − k` (binary search).
    fn corner(&self, d: usize) -> (usize, usize) {
        let n_light = self.deficit_before.len() - 1;
        let closes = self.surplus_through.len() - 1;
        let (mut lo, mut hi) = (d.saturating_sub(closes), d.min(n_light));
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if self.deficit_before[mid - 1] < self.surplus_through[d - mid] {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        (lo, d - lo)
    }

    /// The step from `(k, j)`: whether light `k` goes before heavy `j`
    /// closes, and the two outputs it would write (light `k`'s alias, the
    /// item of heavy `j`; heavy `j`'s share of its cell).
    #[inline(always)]
    fn step(&self, k: usize, j: usize) -> (bool, u32, f64) {
        let (deficit, surplus) = (self.deficit_before[k], self.surplus_through[j]);
        let light = (k + 1 < self.deficit_before.len()) & (deficit < surplus);
        (light, self.heavy_item[j], 1.0 - (deficit - surplus))
    }

    /// Runs the merge: `alias[k]` for each light `k` (`alias` has a spare
    /// slot past the last) and `keep[j]` for each heavy `j` but the last.
    /// The steps form a chain of dependent loads,
    /// so the merge runs as [`LANES`] pieces, interleaved one step of each
    /// in turn, each started where the merge path crosses its first step's
    /// diagonal, so that the pieces' loads overlap. Both
    /// outputs of a step are written (no unpredictable branch), so a slot
    /// may be written early and is written again by its own step; but the
    /// last steps of a piece also write the first slots of the next one,
    /// which are therefore written again at the end.
    fn run(&self, alias: &mut [u32], keep: &mut [f64]) {
        let steps = self.deficit_before.len() + self.surplus_through.len() - 2;
        let piece = steps.div_ceil(LANES);
        let corners: [(usize, usize); LANES + 1] =
            std::array::from_fn(|p| self.corner((p * piece).min(steps)));
        let steps = |p: usize| {
            let [(k0, j0), (k1, j1)] = [corners[p], corners[p + 1]];
            k1 - k0 + j1 - j0
        };
        let mut step = |(k, j): &mut (usize, usize)| {
            let (light, a, x) = self.step(*k, *j);
            alias[*k] = a;
            keep[*j] = x;
            *k += light as usize;
            *j += !light as usize;
        };
        let mut at: [(usize, usize); LANES] = std::array::from_fn(|p| corners[p]);
        let common = (0..LANES).map(steps).min().unwrap_or(0);
        for _ in 0..common {
            for lane in &mut at {
                step(lane);
            }
        }
        for (p, lane) in at.iter_mut().enumerate() {
            for _ in common..steps(p) {
                step(lane);
            }
        }
        // The first light and first heavy of each piece after the first:
        // step by step, each slot written by its own step only.
        for (p, &(mut k, mut j)) in corners.iter().enumerate().take(LANES).skip(1) {
            let (mut lights, mut heavies) = (0, 0);
            for _ in 0..steps(p) {
                if lights > 0 && heavies > 0 {
                    break;
                }
                let (light, a, x) = self.step(k, j);
                if light {
                    alias[k] = a;
                    (k, lights) = (k + 1, lights + 1);
                } else {
                    keep[j] = x;
                    (j, heavies) = (j + 1, heavies + 1);
                }
            }
        }
    }
}

/// The arrays of one sweep over a sequence of items `0..count` (entries
/// and their shares), kept from block to block: the orders (see
/// [`Orders`]), which items the lights are, and the merge's outputs. Each
/// array is longer than the sweep needs: only the prefixes of length
/// `n_light` (`+ 1` for the deficits) and `n_heavy` hold its values.
#[derive(Default)]
struct Sweep {
    deficit_before: Vec<f64>,
    light_item: Vec<u32>,
    surplus_through: Vec<f64>,
    heavy_item: Vec<u32>,
    light_alias: Vec<u32>,
    heavy_keep: Vec<f64>,
    n_light: usize,
    n_heavy: usize,
}

impl Sweep {
    /// Sorts the items `0..count`, of shares `share(t)`, into lights and
    /// heavies, in order, with their running deficits and surpluses.
    /// Branch-free: every item is written to both orders at their current
    /// ends; the slot not taken is overwritten by the next item of that
    /// kind, or lies past its order.
    fn classify(&mut self, count: usize, share: impl Fn(usize) -> f64) {
        let len = count + 1;
        for v in [
            &mut self.deficit_before,
            &mut self.surplus_through,
            &mut self.heavy_keep,
        ] {
            v.resize(len.max(v.len()), 0.0);
        }
        for v in [
            &mut self.light_item,
            &mut self.heavy_item,
            &mut self.light_alias,
        ] {
            v.resize(len.max(v.len()), 0);
        }
        // Slices held in locals, so that the stores cannot be taken to
        // alias the vectors' own fields.
        let (deficit_before, light_item) =
            (&mut self.deficit_before[..len], &mut self.light_item[..len]);
        let (surplus_through, heavy_item) = (
            &mut self.surplus_through[..len],
            &mut self.heavy_item[..len],
        );
        let (mut lights, mut heavies) = (0, 0);
        let (mut deficit, mut surplus) = (0.0, 0.0);
        for t in 0..count {
            let s = share(t);
            let light = s < 1.0;
            deficit_before[lights] = deficit;
            light_item[lights] = t as u32;
            surplus += (s - 1.0).max(0.0);
            surplus_through[heavies] = surplus;
            heavy_item[heavies] = t as u32;
            deficit += (1.0 - s).max(0.0);
            lights += light as usize;
            heavies += !light as usize;
        }
        deficit_before[lights] = deficit;
        (self.n_light, self.n_heavy) = (lights, heavies);
    }

    /// The lights' total deficit `σ_L(n_light)`.
    fn deficit(&self) -> f64 {
        self.deficit_before[self.n_light]
    }

    /// The heavies' total surplus `σ_H(n_heavy)`.
    fn surplus(&self) -> f64 {
        self.surplus_through[self.n_heavy - 1]
    }

    /// Merges the orders (at least one heavy), the last heavy never
    /// closing: the aliases of all lights and the shares of all heavies
    /// (the last keeps its whole cell).
    fn merge(&mut self) {
        let (n_light, n_heavy) = (self.n_light, self.n_heavy);
        let total_surplus = self.surplus();
        self.surplus_through[n_heavy - 1] = f64::INFINITY;
        let orders = Orders {
            deficit_before: &self.deficit_before[..=n_light],
            surplus_through: &self.surplus_through[..n_heavy],
            heavy_item: &self.heavy_item[..n_heavy],
        };
        orders.run(
            &mut self.light_alias[..=n_light],
            &mut self.heavy_keep[..n_heavy],
        );
        self.heavy_keep[n_heavy - 1] = 1.0;
        self.surplus_through[n_heavy - 1] = total_surplus;
    }

    /// Writes the cells of the first `lights` lights and `heavies` heavies
    /// after [`Sweep::merge`]: item `t` is entry `entry(t)` of share
    /// `share(t)`, at `cells[entry(t) - base]`; heavy `j`'s alias is heavy
    /// `j + 1`.
    fn write_cells(
        &self,
        (lights, heavies): (usize, usize),
        (entry, share): (impl Fn(u32) -> u32, impl Fn(u32) -> f64),
        cells: &mut [[u32; 2]],
        base: usize,
    ) {
        for (&t, &alias) in self.light_item[..lights].iter().zip(&self.light_alias) {
            let (e, s) = (entry(t), share(t));
            cells[e as usize - base] = cell(e, s, entry(alias), s > 0.0);
        }
        let next = self.heavy_item[1..self.n_heavy]
            .iter()
            .chain(&self.heavy_item[self.n_heavy - 1..]);
        for ((&t, &keep), &next) in self.heavy_item[..heavies]
            .iter()
            .zip(&self.heavy_keep)
            .zip(next)
        {
            let e = entry(t);
            cells[e as usize - base] = cell(e, keep, entry(next), true);
        }
    }

    /// Sweeps the block of `weights` that starts at entry `base` into its
    /// cells, and appends what it leaves over to `leftovers` as `(entry,
    /// share)` (see [`AliasTable`]'s construction).
    fn block(
        &mut self,
        weights: &[f64],
        base: usize,
        to_share: f64,
        cells: &mut [[u32; 2]],
        leftovers: &mut Vec<(u32, f64)>,
    ) {
        let entry = |t: u32| (base + t as usize) as u32;
        let share = |t: u32| weights[t as usize] * to_share;
        self.classify(weights.len(), |t| share(t as u32));
        let item = |t: &u32| (entry(*t), share(*t));
        if self.n_heavy == 0 {
            leftovers.extend(self.light_item[..self.n_light].iter().map(item));
            return;
        }
        let (deficit, surplus) = (self.deficit(), self.surplus());
        self.merge();
        let heavies = &self.surplus_through[..self.n_heavy];
        let settled = if surplus > deficit {
            let first = heavies.partition_point(|&s| s <= deficit);
            let rest = &self.heavy_item[first..self.n_heavy];
            leftovers.push((entry(rest[0]), 1.0 + (heavies[first] - deficit)));
            leftovers.extend(rest[1..].iter().map(item));
            (self.n_light, first)
        } else {
            let first = self.deficit_before[..self.n_light].partition_point(|&d| d < surplus);
            let last = self.n_heavy - 1;
            let keep = 1.0 - (self.deficit_before[first] - surplus);
            leftovers.push((entry(self.heavy_item[last]), keep));
            leftovers.extend(self.light_item[first..self.n_light].iter().map(item));
            (first, last)
        };
        self.write_cells(settled, (entry, share), cells, base);
    }
}

/// `Σ values` in eight interleaved partial sums, so that the additions
/// pipeline; the same bits on every run.
fn lane_sum(values: &[f64]) -> f64 {
    let (lanes, rest) = values.as_chunks::<8>();
    let mut acc = [0.0; 8];
    for lane in lanes {
        for (a, &v) in acc.iter_mut().zip(lane) {
            *a += v;
        }
    }
    acc.iter().sum::<f64>() + rest.iter().sum::<f64>()
}

impl AliasTable {
    /// An alias table proportional to `weights`, built on mcsample's thread
    /// pool.
    ///
    /// # Errors
    /// As [`super::Discrete1D::new`].
    pub fn new(weights: &[f64]) -> Result<Self> {
        check_len("weights", weights.len())?;
        parallel::install(|| Self::build(weights))?
    }

    fn build(weights: &[f64]) -> Result<Self> {
        // The sum, by blocks, and the copy of the weights that `pmf` reads
        // (dividing by the sum only when asked keeps divisions out of the
        // build); the weights are checked on the way. The copy is streamed
        // past the caches, so that it leaves them to the sweeps.
        let mut copy = Buffer::<f64>::for_overwrite(weights.len(), "the table's weights")?;
        let (block_totals, valid): (Vec<f64>, Vec<bool>) = copy
            .par_chunks_mut(BLOCK)
            .zip(weights.par_chunks(BLOCK))
            .map(|(copy, w)| {
                simd::stream_copy(copy, w);
                simd::store_fence();
                (lane_sum(w), all_weights(w))
            })
            .unzip();
        if !valid.into_iter().all(|v| v) {
            find_invalid("weights", weights, |i| format!("[{i}]"))?;
        }
        let sum: f64 = block_totals.iter().sum();
        if !(sum > 0.0 && sum.is_finite()) {
            return Err(Error::AllZero { arg: "weights" });
        }
        let to_share = weights.len() as f64 / sum;

        // Each block swept on its own, then the leftovers of all blocks.
        let mut cells = Buffer::<[u32; 2]>::for_overwrite(weights.len(), "the alias cells")?;
        let leftovers: Vec<Vec<(u32, f64)>> = cells
            .par_chunks_mut(BLOCK)
            .zip(weights.par_chunks(BLOCK))
            .enumerate()
            .map_init(Sweep::default, |sweep, (b, (cells, w))| {
                let mut leftovers = Vec::new();
                sweep.block(w, b * BLOCK, to_share, cells, &mut leftovers);
                leftovers
            })
            .collect();
        let mut flat =
            alloc::with_capacity(leftovers.iter().map(Vec::len).sum(), "the alias leftovers")?;
        leftovers.into_iter().for_each(|block| flat.extend(block));
        let leftovers: Vec<(u32, f64)> = flat;
        let mut sweep = Sweep::default();
        sweep.classify(leftovers.len(), |t| leftovers[t].1);
        if sweep.n_heavy == 0 {
            // Only round-off leaves no heavy entry over (the lights left
            // over then lack almost nothing): every cell left is full.
            for &(e, s) in &leftovers {
                cells[e as usize] = cell(e, 1.0, e, s > 0.0);
            }
        } else {
            sweep.merge();
            let item = (
                |t: u32| leftovers[t as usize].0,
                |t: u32| leftovers[t as usize].1,
            );
            sweep.write_cells((sweep.n_light, sweep.n_heavy), item, &mut cells, 0);
        }
        Ok(AliasTable {
            cells,
            weights: Weights::new(copy, sum),
        })
    }

    /// The cell of `u` and the fraction of `u·n` past it, in 32-bit fixed
    /// point (saturating at `u = 1`, where the cell's alias answers).
    #[inline(always)]
    fn locate<F: Real>(&self, u: F) -> (usize, u32) {
        let n = self.cells.len();
        let t = u.f64() * n as f64;
        let c = t.floor_index(n - 1);
        (c, ((t - c as f64) * ONE) as u32)
    }

    /// Cell `c`'s answer for the fraction `fraction`. A select, not a
    /// branch: the outcome is random, and a mispredicted branch would stall
    /// the other draws' memory loads.
    #[inline(always)]
    fn answer(&self, c: usize, fraction: u32) -> u32 {
        let [threshold, alias] = self.cells[c];
        select_unpredictable(fraction < threshold, c as u32, alias)
    }

    /// An index drawn with probability `pmf(i)`; `u` in `[0, 1]`.
    #[inline]
    pub fn sample<F: Real>(&self, u: F) -> usize {
        let (c, fraction) = self.locate(u);
        self.answer(c, fraction) as usize
    }

    /// An index drawn with probability `pmf(i)` from 64 uniform random
    /// bits `b`, read as the fixed-point number `t = b·n/2⁶⁴`: the cell is
    /// its integer part and the 32 bits after the point its fraction. Every
    /// cell gets the full 32-bit resolution of its threshold, whatever `n`
    /// (a float `u` leaves `52 − log₂n` bits).
    #[inline]
    pub fn sample_bits(&self, bits: u64) -> usize {
        let t = u128::from(bits) * self.cells.len() as u128;
        self.answer((t >> 64) as usize, (t >> 32) as u32) as usize
    }

    /// `out[i] = sample(us[i])` for a batch. Groups of draws first locate
    /// their cells and prefetch them, then read them, so that the cache
    /// misses of a group overlap (on tables larger than the cache, several
    /// times the speed of one draw after another).
    pub fn sample_into<F: Real, I: From<u32>>(&self, us: &[F], out: &mut [I]) {
        for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
            let mut located = [(0, 0); GROUP];
            for (l, &u) in located.iter_mut().zip(us) {
                *l = self.locate(u);
                simd::prefetch(&self.cells, l.0);
            }
            for (o, &(c, fraction)) in out.iter_mut().zip(&located) {
                *o = I::from(self.answer(c, fraction));
            }
        }
    }
}

impl std::ops::Deref for AliasTable {
    type Target = Weights;

    fn deref(&self) -> &Weights {
        &self.weights
    }
}

#[cfg(test)]
mod tests;

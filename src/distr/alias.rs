//! [`AliasTable`]: O(1) sampling of a discrete distribution (Walker's alias
//! method, built by a sweep that runs in parallel).

use super::{GROUP, all_weights, check_len, find_invalid};
use crate::buffer::Buffer;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::{parallel, simd};
use rayon::prelude::*;
use std::hint::select_unpredictable;

/// Entries per block of the parallel build. Fixed, so that the table does
/// not depend on the number of threads.
const BLOCK: usize = 1 << 16;

/// Steps per piece of the build's merge.
const PIECE: usize = 1 << 14;

/// Pieces of the merge that one task runs interleaved (see [`Orders::run`]).
const LANES: usize = 8;

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
/// Entries with `s < 1` are light, the others heavy, each kept in index
/// order. The sweep of Hübschle-Schneider and Sanders lets the current heavy
/// entry top up light cells in order while its residual exceeds 1, and then
/// closes it as a cell of its own, topped up by the next heavy entry. With
/// the deficits `σ_L(k) = Σ_{k'<k} (1 − s_{L_k'})` of the first `k` light
/// entries and the surpluses `σ_H(j) = Σ_{j'<j} (s_{H_j'} − 1)` of the first
/// `j` heavy ones, that sweep is a merge:
/// - light `k` takes as alias the heavy `j` with `σ_H(j) ≤ σ_L(k) < σ_H(j+1)`
///   (the last heavy when there is none);
/// - heavy `j` closes after the `i` light entries with `σ_L(k) < σ_H(j+1)`,
///   keeping `1 − (σ_L(i) − σ_H(j+1))` of its cell, and takes heavy `j+1` as
///   alias (the last heavy keeps its whole cell).
///
/// The build runs in parallel: the classification and prefix sums by
/// blocks of entries, the merge by pieces of its path (each started by a
/// binary search on its diagonal, as in a parallel merge sort), the cells
/// again by blocks. Thresholds come from the prefix sums directly, so they
/// carry no round-off accumulated along the sweep, and the table is the
/// same whatever the number of threads.
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
    /// The weights as given: `pmf(i) = w_i / Σw`, computed when asked.
    weights: Buffer<f64>,
    sum: f64,
}

/// What the first pass learns of a block of entries: the number of light
/// entries, the sum of their deficits `1 − s` and that of the heavy
/// entries' surpluses `s − 1`.
#[derive(Clone, Copy, Default)]
struct BlockSums {
    lights: usize,
    deficit: f64,
    surplus: f64,
}

/// The cell of entry `index` that keeps it with probability `keep` and
/// otherwise returns `alias`: a full cell (`keep ≥ 1`) is its own alias, and
/// an entry of positive weight keeps at least the smallest threshold, so
/// that round-off cannot make it unreachable. Branch-free.
#[inline(always)]
fn cell(index: usize, keep: f64, alias: u32, positive: bool) -> [u32; 2] {
    // `keep·2^32` rounded to the nearest integer by adding 2^52, where the
    // spacing of doubles is 1: no conversion, whose range checks branch.
    const SHIFT: f64 = 4_503_599_627_370_496.0;
    let scaled = keep.clamp(0.0, 1.0) * ONE + SHIFT;
    let bits = (scaled.to_bits() - SHIFT.to_bits()).max(u64::from(positive));
    let full = bits > u64::from(u32::MAX);
    [
        select_unpredictable(full, u32::MAX, bits as u32),
        select_unpredictable(full, index as u32, alias),
    ]
}

/// The light and heavy orders of pass 2 of [`AliasTable::new`]'s build:
/// `σ_L(k)` for `k = 0..=n_light`, `σ_H(j+1)` for each heavy `j` (+∞ for the
/// last heavy, which never closes), and the heavy entries' indices.
///
/// The sweep is their merge: light `k` is swept before heavy `j` closes iff
/// `σ_L(k) < σ_H(j+1)`. A light step gives light `k` heavy `j` as its
/// alias; a closing step leaves heavy `j` the share `1 − (σ_L(k) −
/// σ_H(j+1))` of its own cell.
struct Orders<'a> {
    deficit_before: &'a [f64],
    surplus_through: &'a [f64],
    heavy_index: &'a [u32],
}

/// A task of the merge: up to [`LANES`] consecutive pieces, which start at
/// `corners[..LANES]` and end at the next corner, and the outputs of their
/// lights (from the first corner's `k`) and heavies (from its `j`).
struct Task<'a> {
    corners: &'a [(usize, usize)],
    alias: &'a mut [u32],
    keep: &'a mut [f64],
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
    /// closes, and the two outputs it would write (light `k`'s alias, heavy
    /// `j`'s share of its cell).
    #[inline(always)]
    fn step(&self, k: usize, j: usize) -> (bool, u32, f64) {
        let (deficit, surplus) = (self.deficit_before[k], self.surplus_through[j]);
        let light = (k + 1 < self.deficit_before.len()) & (deficit < surplus);
        (light, self.heavy_index[j], 1.0 - (deficit - surplus))
    }

    /// Runs `task`. A piece's steps form a chain of dependent loads, so its
    /// pieces run interleaved, one step of each in turn (measured: the merge
    /// in 1.9–2.1 ms rather than 2.7–3.0 for 10^6 entries; twice the speed
    /// on data already in cache). Both outputs of a step are written (no
    /// unpredictable branch), so a slot may be written early and is written
    /// again by its own step; but the last steps of a piece also write the
    /// first slots of the next one, which are therefore written again after
    /// the interleaved run.
    fn run(&self, task: &mut Task) {
        let (k_base, j_base) = task.corners[0];
        let pieces = task.corners.len() - 1;
        let steps = |p: usize| {
            let [(k0, j0), (k1, j1)] = [task.corners[p], task.corners[p + 1]];
            k1 - k0 + j1 - j0
        };
        let interleaved = pieces == LANES && (0..LANES).all(|p| steps(p) == PIECE);
        if interleaved {
            let mut at: [(usize, usize); LANES] = std::array::from_fn(|p| task.corners[p]);
            for _ in 0..PIECE {
                for (k, j) in &mut at {
                    let (light, alias, keep) = self.step(*k, *j);
                    if let Some(a) = task.alias.get_mut(*k - k_base) {
                        *a = alias;
                    }
                    if let Some(x) = task.keep.get_mut(*j - j_base) {
                        *x = keep;
                    }
                    *k += light as usize;
                    *j += !light as usize;
                }
            }
        }
        // The pieces not run interleaved, and the first light and first
        // heavy of each interleaved piece after the first: step by step,
        // each slot written by its own step only.
        for p in usize::from(interleaved)..pieces {
            let (mut k, mut j) = task.corners[p];
            let (mut lights, mut heavies) = (0, 0);
            for _ in 0..steps(p) {
                if interleaved && lights > 0 && heavies > 0 {
                    break;
                }
                let (light, alias, keep) = self.step(k, j);
                if light {
                    task.alias[k - k_base] = alias;
                    (k, lights) = (k + 1, lights + 1);
                } else {
                    task.keep[j - j_base] = keep;
                    (j, heavies) = (j + 1, heavies + 1);
                }
            }
        }
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
        // build); the weights are checked on the way.
        let mut copy = Buffer::<f64>::for_overwrite(weights.len());
        let (block_totals, valid): (Vec<f64>, Vec<bool>) = copy
            .par_chunks_mut(BLOCK)
            .zip(weights.par_chunks(BLOCK))
            .map(|(copy, w)| {
                copy.copy_from_slice(w);
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
        let n = weights.len();
        let to_share = n as f64 / sum;

        // Pass 1: in each block of `key` and `pos` its light entries in
        // order from the front (with the deficit of the block's lights
        // before each) and its heavy entries from the back (with the surplus
        // of the block's heavies through each).
        // Branch-free: every entry is written to both ends with the same
        // value; the slot not taken is overwritten by a later entry of that
        // kind, or is the other kind's last slot, written last.
        let mut key = Buffer::<f64>::for_overwrite(n);
        let mut pos = Buffer::<u32>::for_overwrite(n);
        let blocks: Vec<BlockSums> = (
            key.par_chunks_mut(BLOCK),
            pos.par_chunks_mut(BLOCK),
            weights.par_chunks(BLOCK),
        )
            .into_par_iter()
            .enumerate()
            .map(|(b, (key, pos, w))| {
                let (last, to_share) = (w.len() - 1, to_share);
                let mut sums = BlockSums::default();
                for (i, &w) in w.iter().enumerate() {
                    let s = w * to_share;
                    let light = s < 1.0;
                    // Selections by arithmetic (exact for 0/1 factors), which
                    // compilers do not turn into branches.
                    let is_light = f64::from(u8::from(light));
                    sums.surplus += (s - 1.0).max(0.0);
                    let value = is_light * sums.deficit + (1.0 - is_light) * sums.surplus;
                    let heavies = i - sums.lights;
                    let index = (b * BLOCK + i) as u32;
                    (key[sums.lights], key[last - heavies]) = (value, value);
                    (pos[sums.lights], pos[last - heavies]) = (index, index);
                    sums.deficit += (1.0 - s).max(0.0);
                    sums.lights += light as usize;
                }
                sums
            })
            .collect();
        let n_light: usize = blocks.iter().map(|b| b.lights).sum();
        let n_heavy = n - n_light;
        let mut cells = Buffer::<[u32; 2]>::for_overwrite(n);
        if n_heavy == 0 {
            // Only round-off leaves no entry at or above its share (all
            // weights then nearly equal and positive): every cell is full.
            cells
                .par_iter_mut()
                .enumerate()
                .for_each(|(i, c)| *c = [u32::MAX, i as u32]);
            return Ok(AliasTable {
                cells,
                weights: copy,
                sum,
            });
        }

        // Pass 2: the two orders over all blocks: σ_L(k) for k = 0..=n_light
        // (σ_L(n_light) the total deficit) and σ_H(j+1) for each heavy j
        // (+∞ for the last, which never closes), with the heavies' indices.
        let mut deficit_before = Buffer::<f64>::for_overwrite(n_light + 1);
        let mut surplus_through = Buffer::<f64>::for_overwrite(n_heavy);
        let mut heavy_index = Buffer::<u32>::for_overwrite(n_heavy);
        let total_deficit = {
            let mut parts = Vec::with_capacity(blocks.len());
            let (mut lights, mut heavies, mut indices) = (
                &mut deficit_before[..n_light],
                &mut surplus_through[..],
                &mut heavy_index[..],
            );
            let (mut deficit, mut surplus) = (0.0, 0.0);
            for (b, sums) in blocks.iter().enumerate() {
                let n_h = (n - b * BLOCK).min(BLOCK) - sums.lights;
                let (l, rest_l) = lights.split_at_mut(sums.lights);
                let (h, rest_h) = heavies.split_at_mut(n_h);
                let (x, rest_x) = indices.split_at_mut(n_h);
                parts.push((l, h, x, deficit, surplus));
                (lights, heavies, indices) = (rest_l, rest_h, rest_x);
                deficit += sums.deficit;
                surplus += sums.surplus;
            }
            parts
                .into_par_iter()
                .zip(key.par_chunks(BLOCK).zip(pos.par_chunks(BLOCK)))
                .for_each(|((l, h, x, deficit, surplus), (key, pos))| {
                    for (d, &k) in l.iter_mut().zip(key) {
                        *d = deficit + k;
                    }
                    let back = key.iter().zip(pos).rev();
                    for ((s, i), (&k, &p)) in h.iter_mut().zip(x.iter_mut()).zip(back) {
                        (*s, *i) = (surplus + k, p);
                    }
                });
            deficit
        };
        deficit_before[n_light] = total_deficit;
        surplus_through[n_heavy - 1] = f64::INFINITY;

        // Pass 3: the sweep as a merge (see [`Orders`]), cut into pieces of
        // [`PIECE`] steps (fixed, so that the table does not depend on the
        // thread count), each starting where the merge path crosses its
        // first step's diagonal; the pieces run in parallel. `light_alias`
        // has one spare slot: pass 4 reads a light's alias for every entry.
        let mut light_alias = Buffer::<u32>::for_overwrite(n_light + 1);
        let mut heavy_keep = Buffer::<f64>::for_overwrite(n_heavy);
        let orders = Orders {
            deficit_before: &deficit_before,
            surplus_through: &surplus_through,
            heavy_index: &heavy_index,
        };
        let steps = n_light + n_heavy - 1;
        let corners: Vec<(usize, usize)> = (0..=steps.div_ceil(PIECE))
            .map(|p| orders.corner((p * PIECE).min(steps)))
            .collect();
        let mut tasks = Vec::with_capacity(corners.len() / LANES + 1);
        let (mut aliases, mut keeps) = (&mut light_alias[..], &mut heavy_keep[..]);
        for start in (0..corners.len() - 1).step_by(LANES) {
            let corners = &corners[start..=(start + LANES).min(corners.len() - 1)];
            let [(k0, j0), (k1, j1)] = [corners[0], corners[corners.len() - 1]];
            let (alias, rest_a) = aliases.split_at_mut(k1 - k0);
            let (keep, rest_k) = keeps.split_at_mut(j1 - j0);
            (aliases, keeps) = (rest_a, rest_k);
            tasks.push(Task {
                corners,
                alias,
                keep,
            });
        }
        tasks.par_iter_mut().for_each(|task| orders.run(task));
        heavy_keep[n_heavy - 1] = 1.0;

        // Pass 4: each block's cells from the two orders; heavy j's alias is
        // heavy j+1.
        let (light_alias, heavy_keep) = (&light_alias[..], &heavy_keep[..]);
        let heavy_index = &heavy_index[..];
        let mut starts = Vec::with_capacity(blocks.len());
        let mut light_start = 0;
        for (b, sums) in blocks.iter().enumerate() {
            starts.push((light_start, b * BLOCK - light_start));
            light_start += sums.lights;
        }
        cells
            .par_chunks_mut(BLOCK)
            .zip(weights.par_chunks(BLOCK))
            .zip(starts)
            .enumerate()
            .for_each(|(b, ((cells, w), (mut k, mut j)))| {
                for (i, (c, &w)) in cells.iter_mut().zip(w).enumerate() {
                    let s = w * to_share;
                    let light = s < 1.0;
                    let heavy = j.min(n_heavy - 1);
                    let keep = select_unpredictable(light, s, heavy_keep[heavy]);
                    let next = heavy_index[(heavy + 1).min(n_heavy - 1)];
                    let alias = select_unpredictable(light, light_alias[k], next);
                    *c = cell(b * BLOCK + i, keep, alias, w > 0.0);
                    k += light as usize;
                    j += !light as usize;
                }
            });
        Ok(AliasTable {
            cells,
            weights: copy,
            sum,
        })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Whether the table has no entries (never true for a built table).
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// The sum of the weights.
    pub fn sum(&self) -> f64 {
        self.sum
    }

    /// Probability of index `i`: `w_i / Σw` (0 outside the table).
    pub fn pmf(&self, i: usize) -> f64 {
        self.weights.get(i).map_or(0.0, |&w| w / self.sum)
    }

    /// The cell of `u` and the fraction of `u·n` past it, in 32-bit fixed
    /// point (saturating at `u = 1`, where the cell's alias answers).
    #[inline(always)]
    fn locate<F: Real>(&self, u: F) -> (usize, u32) {
        let n = self.cells.len();
        let t = u.f64() * n as f64;
        let c = (t as usize).min(n - 1);
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

    /// `out[i] = sample(us[i])` for a batch. Groups of draws first locate
    /// their cells and prefetch them, then read them, so that the cache
    /// misses of a group overlap (on tables larger than the cache, 3–4×
    /// the speed of one draw after another).
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The probability of each index, read off the table: each cell gives
    /// `threshold/n` to itself and the rest to its alias.
    fn table_pmf(t: &AliasTable) -> Vec<f64> {
        let n = t.len();
        let mut p = vec![0.0; n];
        for i in 0..n {
            let [threshold, alias] = t.cells[i];
            let keep = f64::from(threshold) / ONE;
            p[i] += keep / n as f64;
            p[alias as usize] += (1.0 - keep) / n as f64;
        }
        p
    }

    #[test]
    fn table_realises_the_pmf() {
        let w = [0.0, 1.0, 0.0, 2.0, 3.0, 0.0, 10.0];
        let t = AliasTable::new(&w).unwrap();
        for (i, p) in table_pmf(&t).into_iter().enumerate() {
            assert!((p - w[i] / 16.0).abs() < 1e-12, "index {i}: {p}");
        }
        assert_eq!(t.sample(1.0), t.sample(f64::ONE_MINUS_EPSILON));
    }

    #[test]
    fn blocks_built_apart_make_one_table() {
        // Several build blocks, runs of zeros and spikes, so that light and
        // heavy entries pair up across block boundaries; the merge has one
        // task of interleaved pieces and one of fewer pieces, run in turn.
        let n = 3 * BLOCK + 1234;
        assert!(n > (LANES + 1) * PIECE && n < 2 * LANES * PIECE);
        let w: Vec<f64> = (0..n)
            .map(|i| match i % 97 {
                0 => 500.0,
                1..=40 => 0.0,
                k => (k % 13) as f64 * 0.1,
            })
            .collect();
        let t = AliasTable::new(&w).unwrap();
        for (i, p) in table_pmf(&t).into_iter().enumerate() {
            let want = t.pmf(i);
            assert!(
                (p - want).abs() <= 1e-9 * want + 1e-15,
                "index {i}: {p} vs {want}"
            );
        }
        let us: Vec<f64> = (0..=100_000).map(|k| k as f64 / 100_000.0).collect();
        let mut batch = vec![0u64; us.len()];
        t.sample_into(&us, &mut batch);
        for (&u, &i) in us.iter().zip(&batch) {
            assert_eq!(i as usize, t.sample(u));
            assert!(w[i as usize] > 0.0, "u = {u} gave zero-weight index {i}");
        }
    }

    #[test]
    fn errors() {
        assert!(AliasTable::new(&[]).is_err());
        assert!(AliasTable::new(&[0.0]).is_err());
        assert!(AliasTable::new(&[1.0, f64::INFINITY]).is_err());
    }

    proptest! {
        #[test]
        fn never_returns_a_zero_weight_and_keeps_the_pmf(
            weights in prop::collection::vec(prop_oneof![Just(0.0), 0.0..10.0f64, 1e-300..1e-290f64], 1..500),
            us in prop::collection::vec(0.0..=1.0f64, 50),
        ) {
            if let Ok(t) = AliasTable::new(&weights) {
                for u in us.into_iter().chain([0.0, 1.0]) {
                    let i = t.sample(u);
                    prop_assert!(weights[i] > 0.0, "u = {} gave zero-weight index {}", u, i);
                }
                for (i, p) in table_pmf(&t).into_iter().enumerate() {
                    prop_assert!((p - t.pmf(i)).abs() < 1e-9, "index {}: {} vs {}", i, p, t.pmf(i));
                }
            }
        }
    }
}

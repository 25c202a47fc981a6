//! The running sums and the guide of a long [`super::Discrete1D`], in two
//! passes over the weights, in parallel by groups of blocks: each block's
//! total ([`block_totals`]), then the copy of the weights, the running sums
//! and the guide at once ([`sum_blocks_and_fill_guide`]). The sums do not
//! depend on the thread count.

use crate::distr::is_weight;
use crate::distr::search::{GuideCell, SCATTER, scatter_guide};
use crate::simd;
use rayon::prelude::*;

/// Entries per block of the running sums of a long table: each block is
/// summed from 0 and then offset by the blocks before it. Fixed, so that
/// the sums do not depend on the thread count (a table of at most one block
/// is summed strictly in order, as Mitsuba does). Not a power of two: the
/// blocks of a group are read and written side by side, and streams a
/// power of two apart fall into the same cache sets.
pub(super) const SUM_BLOCK: usize = 8000;
const _: () = assert!(SUM_BLOCK.is_multiple_of(SCATTER));

/// Blocks summed side by side: one block's sums are a chain of additions,
/// each waiting on the one before, and the chains of several overlap.
const CHAINS: usize = 8;

/// Entries per task: [`CHAINS`] blocks.
pub(super) const SUM_GROUP: usize = CHAINS * SUM_BLOCK;

/// The total of each block of [`SUM_BLOCK`] entries of `weights` (a group:
/// at most [`CHAINS`] blocks), and whether every weight is finite and
/// `>= 0`. Each block is summed in order, so that its total has the bits of
/// its last running sum in [`sum_blocks_and_fill_guide`]; a whole group's
/// blocks side by side.
pub(super) fn block_totals(weights: &[f64]) -> ([f64; CHAINS], bool) {
    let (mut totals, mut valid) = ([0.0; CHAINS], [true; CHAINS]);
    if let Some(w) = whole_blocks(weights) {
        #[expect(clippy::needless_range_loop, reason = "`i` indexes each block")]
        for i in 0..SUM_BLOCK {
            for j in 0..CHAINS {
                totals[j] += w[j][i];
                valid[j] &= is_weight(w[j][i]);
            }
        }
    } else {
        for ((t, v), w) in totals
            .iter_mut()
            .zip(&mut valid)
            .zip(weights.chunks(SUM_BLOCK))
        {
            for &x in w {
                *t += x;
                *v &= is_weight(x);
            }
        }
    }
    (totals, valid.iter().all(|&v| v))
}

/// The blocks of a whole group, `None` for a shorter one.
fn whole_blocks(weights: &[f64]) -> Option<[&[f64]; CHAINS]> {
    (weights.len() == SUM_GROUP)
        .then(|| std::array::from_fn(|j| &weights[j * SUM_BLOCK..][..SUM_BLOCK]))
}

/// Copies `weights` into `copy` and writes their running sums into `cdf`:
/// each block of [`SUM_BLOCK`] entries summed from 0 in order (as
/// [`block_totals`] summed it), plus its entry of `offsets` (the total of
/// the blocks before it). Fills the guide of the sums (total `sum`) but for
/// its closing: each entry's index written into its cell
/// ([`scatter_guide`]), the cells no entry hits `u32::MAX`.
///
/// One pass, in parallel by groups of [`CHAINS`] blocks. The sums never
/// decrease, so a block's entries hit the cells after its offset's cell
/// (the offset has the bits of the last sum of the block before), which no
/// other block writes. Each block's sums are scattered piece by piece,
/// while the piece is in the cache; a piece writes only the cells after
/// the last one of the piece before it, so that each cell keeps the
/// smallest index that hits it.
pub(super) fn sum_blocks_and_fill_guide(
    weights: &[f64],
    (copy, cdf): (&mut [f64], &mut [f64]),
    offsets: &[f64],
    sum: f64,
    guide: &mut [u32],
) {
    let cell = GuideCell::new(guide.len(), sum);
    // The first cell that entries whose running sums pass `c` may write.
    let after = |c: f64| cell.map_or(0, |cell| cell.of(c) as usize + 1);
    let (mut rest, mut start) = (guide, 0);
    let mut groups = Vec::with_capacity(offsets.len().div_ceil(CHAINS));
    for g in 0..offsets.len().div_ceil(CHAINS) {
        let next = offsets
            .get((g + 1) * CHAINS)
            .map_or(after(sum), |&c| after(c));
        let (own, later) = std::mem::take(&mut rest).split_at_mut(next - start);
        groups.push((start, own));
        (rest, start) = (later, next);
    }
    rest.fill(u32::MAX);
    let parts = (
        weights.par_chunks(SUM_GROUP),
        copy.par_chunks_mut(SUM_GROUP),
    );
    (parts, cdf.par_chunks_mut(SUM_GROUP), groups)
        .into_par_iter()
        .enumerate()
        .for_each(|(g, ((weights, copy), cdf, (start, own)))| {
            own.fill(u32::MAX);
            simd::stream_copy(copy, weights);
            simd::store_fence();
            let b0 = g * CHAINS;
            let offsets = &offsets[b0..(b0 + CHAINS).min(offsets.len())];
            // The first cell each block may write (the table's first
            // block: all).
            let mut from: [usize; CHAINS] = std::array::from_fn(|j| match offsets.get(j) {
                Some(&offset) if b0 + j > 0 => after(offset),
                _ => 0,
            });
            let scatter = |sums: &[f64], j: usize, i: usize| {
                let (Some(cell), Some(&last)) = (cell, sums.last()) else {
                    return;
                };
                let cells = own.get_mut(from[j] - start..).unwrap_or_default();
                scatter_guide(sums, (b0 + j) * SUM_BLOCK + i, cell, cells, from[j]);
                from[j] = cell.of(last) as usize + 1;
            };
            simd::dispatch(
                #[inline(always)]
                |_| match whole_blocks(weights) {
                    Some(w) => sum_whole_group(w, cdf, offsets, scatter),
                    None => sum_blocks_in_turn(weights, cdf, offsets, scatter),
                },
            )
        });
}

/// The running sums of a whole group's blocks `w` into `cdf`, plus their
/// `offsets`, side by side by pieces of [`SCATTER`] entries: each piece is
/// summed into a buffer in the cache, offset, streamed to `cdf`
/// (non-temporal stores: not read again soon) and handed to
/// `scatter(sums, block, first entry)`.
#[inline(always)]
fn sum_whole_group(
    w: [&[f64]; CHAINS],
    cdf: &mut [f64],
    offsets: &[f64],
    mut scatter: impl FnMut(&[f64], usize, usize),
) {
    let w: [&[[f64; SCATTER]]; CHAINS] = w.map(|w| w.as_chunks().0);
    let mut blocks = cdf.chunks_exact_mut(SUM_BLOCK);
    let mut c: [&mut [[f64; SCATTER]]; CHAINS] =
        std::array::from_fn(|_| blocks.next().unwrap_or_default().as_chunks_mut().0);
    let (mut acc, mut sums) = ([0.0; CHAINS], [[0.0; SCATTER]; CHAINS]);
    for p in 0..SUM_BLOCK / SCATTER {
        let w: [&[f64; SCATTER]; CHAINS] = std::array::from_fn(|j| &w[j][p]);
        for k in 0..SCATTER {
            for j in 0..CHAINS {
                acc[j] += w[j][k];
                sums[j][k] = acc[j];
            }
        }
        for (j, ((sums, c), offset)) in sums.iter_mut().zip(&mut c).zip(offsets).enumerate() {
            sums.iter_mut().for_each(|s| *s += offset);
            simd::stream_copy(&mut c[p], sums);
            scatter(sums, j, p * SCATTER);
        }
    }
    simd::store_fence();
}

/// The running sums of a group shorter than whole (the table's last) into
/// `cdf`, block after block, plus their `offsets`, each block handed whole
/// to `scatter(sums, block, 0)`.
#[inline(always)]
fn sum_blocks_in_turn(
    weights: &[f64],
    cdf: &mut [f64],
    offsets: &[f64],
    mut scatter: impl FnMut(&[f64], usize, usize),
) {
    let blocks = weights.chunks(SUM_BLOCK).zip(cdf.chunks_mut(SUM_BLOCK));
    for (j, ((weights, cdf), &offset)) in blocks.zip(offsets).enumerate() {
        let mut acc = 0.0;
        for (c, &w) in cdf.iter_mut().zip(weights) {
            acc += w;
            *c = acc + offset;
        }
        scatter(cdf, j, 0);
    }
}

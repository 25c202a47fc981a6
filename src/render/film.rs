//! A pixel's estimate from sums that merge exactly, so that a render made
//! in chunks of samples has the bits of one render.
//!
//! A pixel keeps, per sample `l` (linear RGB) with Rec. 709 luminance `y`,
//! the sums [`Sums`] of `l_k`, `l_k²` and `y`, `y²` in `f64`. Floating-point
//! addition is not associative, so the sums are taken in one fixed order
//! whatever the chunks: a binary tree over the sample index, whose nodes
//! are the dyadic [`Block`]s `[j·2^m, (j+1)·2^m)` and whose node sums are
//! `sum(left half) + sum(right half)`. A chunk of samples `a .. b` keeps
//! the sums of the largest blocks inside it (at most `2·log2(b − a)`;
//! one for a chunk of `2^m` samples starting at a multiple of `2^m`);
//! adjacent chunks are merged by adding sibling blocks ([`Tree::push`]).
//! The estimate of samples `0 .. n` adds the blocks of `n`'s binary digits
//! from the largest down ([`finish_pixel`]), and turns the sums into the
//! mean, `Σl/n`, and the variance of the mean, `(Σl² − (Σl)²/n)/(n−1)/n`
//! ([`moments`]).

use rayon::prelude::*;

use crate::alloc;
use crate::error::{Error, Result};
use crate::math::luminance;
use crate::parallel;

/// Sums over a pixel's samples: `Σr, Σg, Σb, Σr², Σg², Σb², Σy, Σy²`.
pub type Sums = [f64; 8];

/// The [`Sums`] of one sample of radiance `l`.
#[inline]
pub fn sums_of(l: [f32; 3]) -> Sums {
    let l = l.map(f64::from);
    let y = luminance(l);
    [
        l[0],
        l[1],
        l[2],
        l[0] * l[0],
        l[1] * l[1],
        l[2] * l[2],
        y,
        y * y,
    ]
}

/// `a + b`, entry by entry.
#[inline]
pub fn add(a: &Sums, b: &Sums) -> Sums {
    std::array::from_fn(|k| a[k] + b[k])
}

/// The sample indices `start .. start + len`: `len` a power of two and
/// `start` a multiple of it (a node of the tree over the sample index).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    /// First sample index.
    pub start: u64,
    /// Number of samples.
    pub len: u64,
}

impl Block {
    /// The block of the single sample `index`.
    pub fn sample(index: u64) -> Self {
        Block {
            start: index,
            len: 1,
        }
    }

    /// Whether `self` is the left child and `right` its sibling.
    fn is_left_sibling_of(&self, right: &Block) -> bool {
        self.len == right.len
            && self.start + self.len == right.start
            && self.start.is_multiple_of(2 * self.len)
    }

    /// A block, checked: `len` a power of two, `start` a multiple of it.
    ///
    /// # Errors
    /// [`Error::Argument`] otherwise.
    pub fn checked(start: u64, len: u64) -> Result<Self> {
        if len.is_power_of_two() && start.is_multiple_of(len) && start.checked_add(len).is_some() {
            Ok(Block { start, len })
        } else {
            Err(Error::Argument {
                arg: "blocks",
                message: format!(
                    "blocks: ({start}, {len}) is not a block of samples (a power-of-two \
                     length starting at a multiple of it)"
                ),
            })
        }
    }
}

/// The largest blocks inside the samples `first .. first + count`, in
/// order: the blocks a [`Tree`] holds after those samples are pushed.
pub fn blocks(first: u64, count: u64) -> Vec<Block> {
    let end = first.saturating_add(count);
    let mut out = Vec::new();
    let mut start = first;
    while start < end {
        // The largest power of two dividing `start` (any, for 0) that fits.
        let aligned = if start == 0 {
            63
        } else {
            start.trailing_zeros()
        };
        let fits = 63 - (end - start).leading_zeros();
        let len = 1u64 << aligned.min(fits);
        out.push(Block { start, len });
        start += len;
    }
    out
}

/// Sums of consecutive blocks, the siblings among them added as soon as
/// both are there: after pushing the samples `a .. b` one by one (or the
/// blocks of chunks that cover `a .. b`, in order), it holds the largest
/// blocks inside `a .. b`, each summed as the tree sums it.
#[derive(Clone, Debug, Default)]
pub struct Tree<T> {
    nodes: Vec<(Block, T)>,
}

impl<T> Tree<T> {
    /// An empty tree.
    pub fn new() -> Self {
        Tree { nodes: Vec::new() }
    }

    /// Empties the tree, keeping its storage.
    pub fn clear(&mut self) {
        self.nodes.clear();
    }

    /// The blocks and their sums, in sample order.
    pub fn nodes(&self) -> &[(Block, T)] {
        &self.nodes
    }

    /// The samples covered: `(first, count)`.
    pub fn span(&self) -> (u64, u64) {
        match (self.nodes.first(), self.nodes.last()) {
            (Some((a, _)), Some((b, _))) => (a.start, b.start + b.len - a.start),
            _ => (0, 0),
        }
    }

    /// Appends `block` (which must start where the last one ends) with its
    /// sum `value`, then adds each completed pair of siblings with `plus`.
    ///
    /// # Errors
    /// [`Error::Argument`] when `block` does not start where the tree ends.
    pub fn push(&mut self, block: Block, value: T, plus: impl Fn(&T, &T) -> T) -> Result<()> {
        self.push_into(block, value, |left, right| *left = plus(left, &right))
    }

    /// [`Tree::push`] with siblings merged in place: `merge(left, right)`
    /// makes `left` their sum (for large values, such as whole films).
    ///
    /// # Errors
    /// As [`Tree::push`].
    pub fn push_into(&mut self, block: Block, value: T, merge: impl Fn(&mut T, T)) -> Result<()> {
        if let Some((last, _)) = self.nodes.last()
            && last.start + last.len != block.start
        {
            return Err(Error::Argument {
                arg: "results",
                message: format!(
                    "the chunks do not follow one another: samples {} .. {} are followed by \
                     samples from {}",
                    last.start,
                    last.start + last.len,
                    block.start
                ),
            });
        }
        self.nodes.push((block, value));
        while let [.., (left, _), (right, _)] = &self.nodes[..]
            && left.is_left_sibling_of(right)
        {
            let len = 2 * left.len;
            // Both are there (matched above).
            let Some((_, b)) = self.nodes.pop() else {
                break;
            };
            let Some((left, a)) = self.nodes.last_mut() else {
                break;
            };
            left.len = len;
            merge(a, b);
        }
        Ok(())
    }
}

/// A pixel's estimate from the [`Sums`] of its `n` samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moments {
    /// Mean per channel.
    pub mean: [f32; 3],
    /// Variance of the mean per channel, `s²/n` (infinite for fewer than 2
    /// samples).
    pub variance: [f32; 3],
    /// Variance of the mean luminance.
    pub luminance_variance: f32,
}

/// The mean and variances of `n` samples with sums `s`.
pub fn moments(s: &Sums, n: u64) -> Moments {
    let n_f = n as f64;
    let variance_of_mean = |sum: f64, sum_sq: f64| -> f32 {
        if n > 1 {
            (((sum_sq - sum * sum / n_f) / (n_f - 1.0)).max(0.0) / n_f) as f32
        } else {
            f32::INFINITY
        }
    };
    Moments {
        mean: std::array::from_fn(|k| (s[k] / n_f.max(1.0)) as f32),
        variance: std::array::from_fn(|k| variance_of_mean(s[k], s[k + 3])),
        luminance_variance: variance_of_mean(s[6], s[7]),
    }
}

/// The sums of a pixel's samples over each of `blocks` (which `samples`
/// cover in order), appended to `out`: each block summed as the tree sums
/// it (pairwise: left half + right half), the same bits as [`Tree::push`]
/// of the samples one by one.
pub fn block_sums(samples: &[[f32; 3]], blocks: &[Block], out: &mut Vec<Sums>) {
    let mut rest = samples;
    for block in blocks {
        let (inside, after) = rest.split_at(block.len as usize);
        push_pairwise(inside, out);
        rest = after;
    }
}

/// Appends to `out` the tree sum of `samples`, a power-of-two count of
/// them, without recursion: the samples are summed in pairs, and the sums
/// of the left subtrees still waiting for their right siblings wait on
/// `out`, one per level (the pairs counted in binary: the pair whose count
/// ends in `m` zeros closes `m` subtrees). Each node is `left + right`, as
/// [`Tree::push`] adds siblings: the bits of summing each half apart and
/// adding the two.
fn push_pairwise(samples: &[[f32; 3]], out: &mut Vec<Sums>) {
    debug_assert!(
        samples.len().is_power_of_two(),
        "a block of {}",
        samples.len()
    );
    if let [a] = samples {
        out.push(sums_of(*a));
        return;
    }
    let below = out.len();
    for (pairs, pair) in (1usize..).zip(samples.chunks_exact(2)) {
        let mut sum = add(&sums_of(pair[0]), &sums_of(pair[1]));
        for _ in 0..pairs.trailing_zeros() {
            debug_assert!(out.len() > below, "a subtree closed twice");
            if let Some(left) = out.pop() {
                sum = add(&left, &sum);
            }
        }
        out.push(sum);
    }
}

/// Writes a pixel's estimate from the sums of its blocks (`blocks`, in
/// sample order) of `count` samples in all: its mean and variance per
/// channel (3 values each), the variance of its mean luminance, and, when
/// `sums` is not empty, the blocks' sums, 8 per block.
pub fn finish_pixel(
    blocks: &[Sums],
    count: u64,
    (mean, variance): (&mut [f32], &mut [f32]),
    luminance_variance: &mut f32,
    sums: &mut [f64],
) {
    let total = match blocks {
        [first, rest @ ..] => rest.iter().fold(*first, |acc, s| add(&acc, s)),
        [] => Sums::default(),
    };
    let m = moments(&total, count);
    mean.copy_from_slice(&m.mean);
    variance.copy_from_slice(&m.variance);
    *luminance_variance = m.luminance_variance;
    for (out, s) in sums.chunks_exact_mut(8).zip(blocks) {
        out.copy_from_slice(s);
    }
}

/// Chunks of one render merged: the blocks of each chunk (`blocks`, in
/// sample order, following one another) and its sums (`sums`, pixel by
/// pixel, 8 per block) for a film of `pixels` pixels, each sample index
/// holding `per_sample` samples of a pixel's estimate (1, or the film's
/// pixels for light tracing: [`super::splat`]).
///
/// # Errors
/// [`Error::Argument`] when the chunks do not follow one another or a
/// chunk's sums do not match its blocks and `pixels`;
/// [`Error::Memory`] when the result does not fit in memory.
pub fn merge(chunks: &[(Vec<Block>, &[f64])], pixels: usize, per_sample: u64) -> Result<Merged> {
    for (blocks, sums) in chunks {
        let expected = pixels.checked_mul(blocks.len() * 8);
        if expected != Some(sums.len()) {
            return Err(Error::Argument {
                arg: "results",
                message: format!(
                    "a chunk has {} sums for {} blocks of {pixels} pixels: expected {}",
                    sums.len(),
                    blocks.len(),
                    pixels as u128 * blocks.len() as u128 * 8
                ),
            });
        }
    }
    // The blocks of the merge, the same for every pixel.
    let mut layout = Tree::new();
    for block in chunks.iter().flat_map(|(blocks, _)| blocks) {
        layout.push(*block, (), |_, _| ())?;
    }
    let (_, count) = layout.span();
    let Some(estimates) = count.checked_mul(per_sample) else {
        return Err(Error::Argument {
            arg: "results",
            message: format!("{count} samples of {per_sample} paths each are too many"),
        });
    };
    if count == 0 {
        return Err(Error::Argument {
            arg: "results",
            message: "results hold no samples: nothing to merge".into(),
        });
    }
    let per_pixel = layout.nodes().len() * 8;
    const WHAT: &str = "the merged film";
    let mut merged = Merged {
        blocks: layout.nodes().iter().map(|(b, _)| *b).collect(),
        count,
        mean: alloc::filled(pixels * 3, 0.0f32, WHAT)?,
        variance: alloc::filled(pixels * 3, 0.0f32, WHAT)?,
        luminance_variance: alloc::filled(pixels, 0.0f32, WHAT)?,
        sums: alloc::filled(pixels * per_pixel, 0.0f64, WHAT)?,
    };
    parallel::install(|| {
        merged
            .mean
            .par_chunks_mut(3)
            .zip(merged.variance.par_chunks_mut(3))
            .zip(merged.luminance_variance.par_iter_mut())
            .zip(merged.sums.par_chunks_mut(per_pixel.max(1)))
            .enumerate()
            .for_each_init(
                || (Tree::new(), Vec::new()),
                |(tree, block_sums), (p, (((mean, var), lum), sums))| {
                    tree.clear();
                    for (blocks, chunk) in chunks {
                        let of_pixel = &chunk[p * blocks.len() * 8..][..blocks.len() * 8];
                        for (block, s) in blocks.iter().zip(of_pixel.chunks_exact(8)) {
                            let s: Sums = std::array::from_fn(|k| s[k]);
                            // The layout above has checked that they follow.
                            let _ = tree.push(*block, s, add);
                        }
                    }
                    block_sums.clear();
                    block_sums.extend(tree.nodes().iter().map(|(_, s)| *s));
                    finish_pixel(block_sums, estimates, (mean, var), lum, sums);
                },
            );
    })?;
    Ok(merged)
}

/// A merge of chunks ([`merge`]).
#[derive(Clone, Debug)]
pub struct Merged {
    /// Its blocks.
    pub blocks: Vec<Block>,
    /// Samples per pixel.
    pub count: u64,
    /// Mean per pixel and channel.
    pub mean: Vec<f32>,
    /// Variance of each pixel's mean per channel.
    pub variance: Vec<f32>,
    /// Variance of each pixel's mean luminance.
    pub luminance_variance: Vec<f32>,
    /// Sums per pixel and block.
    pub sums: Vec<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocks' sums added in order, as [`finish_pixel`] adds them.
    fn total(tree: &Tree<f64>) -> f64 {
        tree.nodes()
            .iter()
            .map(|(_, v)| *v)
            .reduce(|a, b| a + b)
            .unwrap()
    }

    /// Pushes samples `range` (value = index) and returns the blocks.
    fn blocks_of(range: std::ops::Range<u64>) -> Vec<Block> {
        let mut tree = Tree::new();
        for i in range {
            tree.push(Block::sample(i), i, |a, b| a + b).unwrap();
        }
        tree.nodes().iter().map(|(b, _)| *b).collect()
    }

    #[test]
    fn a_chunk_keeps_the_largest_blocks_inside_it() {
        let b = |start, len| Block { start, len };
        assert_eq!(blocks_of(0..8), [b(0, 8)]);
        assert_eq!(blocks_of(3..8), [b(3, 1), b(4, 4)]);
        assert_eq!(blocks_of(0..13), [b(0, 8), b(8, 4), b(12, 1)]);
        assert_eq!(blocks_of(5..11), [b(5, 1), b(6, 2), b(8, 2), b(10, 1)]);
    }

    #[test]
    fn blocks_are_those_the_tree_keeps() {
        for first in 0..40 {
            for count in 0..40 {
                assert_eq!(blocks(first, count), blocks_of(first..first + count));
            }
        }
    }

    #[test]
    fn block_sums_are_the_trees() {
        let sample = |i: u64| {
            let x = (i as f32 * 0.618_034).fract();
            [x * 1e4, 1.0 + x * 1e-4, (i % 5) as f32 * 3.3e7]
        };
        for first in 0..20 {
            for count in 1..40 {
                let samples: Vec<[f32; 3]> = (first..first + count).map(sample).collect();
                let mut tree = Tree::new();
                for (i, l) in (first..).zip(&samples) {
                    tree.push(Block::sample(i), sums_of(*l), add).unwrap();
                }
                let mut fast = Vec::new();
                block_sums(&samples, &blocks(first, count), &mut fast);
                let slow: Vec<Sums> = tree.nodes().iter().map(|(_, s)| *s).collect();
                assert_eq!(fast, slow, "{first} {count}");
            }
        }
    }

    #[test]
    fn merged_chunks_sum_as_one_run_for_any_split() {
        // Values whose sums round differently in different orders.
        let value = |i: u64| {
            1.0 + (i as f64 * 0.618_033_988_749_895).fract() * 1e-9 + 1e8 * ((i % 3) as f64)
        };
        let one = {
            let mut t = Tree::new();
            for i in 0..37 {
                t.push(Block::sample(i), value(i), |a, b| a + b).unwrap();
            }
            total(&t)
        };
        for cuts in [
            vec![0, 37],
            vec![0, 5, 37],
            vec![0, 1, 2, 20, 36, 37],
            vec![0, 16, 32, 37],
        ] {
            let mut merged = Tree::new();
            for w in cuts.windows(2) {
                let mut chunk = Tree::new();
                for i in w[0]..w[1] {
                    chunk
                        .push(Block::sample(i), value(i), |a, b| a + b)
                        .unwrap();
                }
                for &(block, v) in chunk.nodes() {
                    merged.push(block, v, |a, b| a + b).unwrap();
                }
            }
            assert_eq!(total(&merged).to_bits(), one.to_bits(), "{cuts:?}");
        }
    }

    #[test]
    fn gaps_and_bad_blocks_are_refused() {
        let mut t = Tree::new();
        t.push(Block::sample(0), 0.0, |a, b| a + b).unwrap();
        assert!(t.push(Block::sample(2), 0.0, |a, b| a + b).is_err());
        assert!(Block::checked(4, 4).is_ok());
        assert!(Block::checked(2, 4).is_err());
        assert!(Block::checked(0, 3).is_err());
    }
}

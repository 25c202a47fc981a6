//! Hierarchical sample warping (Clarberg et al. 2005, the scheme of
//! Mitsuba 3's `Hierarchical2D`): a cell of a 2D table of non-negative
//! weights is chosen by descending a MIP pyramid of its sums, one 2×2
//! block per level, the row by `u[1]` and then the column by `u[0]`, each
//! coordinate's interval of `[0, 1]` narrowed to the chosen part after each
//! choice (Mitsuba rescales `u` to `[0, 1]` instead: the same choices).
//!
//! A cell is chosen with probability `w / Σw`, as by a marginal and a
//! conditional table, but the map from `u` to cells is local at every
//! scale (the cells of a block of the pyramid come from one rectangle of
//! the unit square), so points stratified in `[0, 1]²` land stratified
//! among the cells (the reason Mitsuba samples its environment maps this
//! way).

use crate::alloc;
use crate::error::Result;

/// One level of the pyramid: per 2×2 block of cells (row-major,
/// `blocks_per_row` a row), the splits of its sums `v00 v10 / v01 v11`:
/// the first row's share `(v00 + v10) / Σ`, and in each row the first
/// cell's share (`v00 / (v00 + v10)`, `v01 / (v01 + v11)`).
#[derive(Clone, Debug)]
struct Level {
    blocks_per_row: usize,
    splits: Vec<[f64; 3]>,
}

impl Level {
    /// The level of the row-major `w × h` table `sums` (padded with 0 to
    /// even sides), and the sums of its blocks (the table of the level
    /// above).
    fn of(sums: &[f64], w: usize, h: usize) -> Result<(Self, Vec<f64>)> {
        let (bw, bh) = (w.div_ceil(2), h.div_ceil(2));
        let at = |x: usize, y: usize| if x < w && y < h { sums[y * w + x] } else { 0.0 };
        let mut splits = alloc::with_capacity(bw * bh, "the sampling pyramid")?;
        let mut above = alloc::with_capacity(bw * bh, "the sampling pyramid")?;
        for y in (0..bh).map(|y| 2 * y) {
            for x in (0..bw).map(|x| 2 * x) {
                let [v00, v10, v01, v11] = [at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y + 1)];
                splits.push([
                    share(v00 + v10, v01 + v11),
                    share(v00, v10),
                    share(v01, v11),
                ]);
                above.push(v00 + v10 + v01 + v11);
            }
        }
        let level = Level {
            blocks_per_row: bw,
            splits,
        };
        Ok((level, above))
    }
}

/// The pyramid of a table of weights, finest level first, up to the level
/// that is one 2×2 block (tables of odd sides padded with cells of weight
/// 0 at each level, as Mitsuba's).
#[derive(Clone, Debug)]
pub struct Pyramid {
    levels: Vec<Level>,
}

impl Pyramid {
    /// The pyramid of the row-major `weights` (`rows × cols`, non-negative,
    /// not all 0: the caller checks).
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the levels cannot be had.
    pub fn new(weights: &[f64], cols: usize, rows: usize) -> Result<Self> {
        let (mut level, mut sums) = Level::of(weights, cols, rows)?;
        let (mut w, mut h) = (cols.div_ceil(2), rows.div_ceil(2));
        let mut levels = Vec::new();
        loop {
            alloc::reserve(&mut levels, 1, "the sampling pyramid")?;
            levels.push(level);
            if w == 1 && h == 1 {
                return Ok(Pyramid { levels });
            }
            (level, sums) = Level::of(&sums, w, h)?;
            (w, h) = (w.div_ceil(2), h.div_ceil(2));
        }
    }

    /// The cell `(row, col)` that `u ∈ [0, 1]²` chooses, with probability
    /// `w / Σw`, and `u` rescaled to `[0, 1]²` within the choices.
    #[inline]
    pub fn sample_reuse(&self, u: [f64; 2]) -> ((usize, usize), [f64; 2]) {
        let mut at = Descent::new(u);
        for level in self.levels.iter().rev() {
            at.step(level);
        }
        at.finish()
    }

    /// `out[i] = sample_reuse(us[i])`, the batch descending one level at a
    /// time (its lookups at a level are independent of one another).
    /// Inlined into the caller's vector-unit dispatch.
    #[inline(always)]
    pub fn sample_reuse_into(&self, us: &[[f64; 2]], out: &mut [((usize, usize), [f64; 2])]) {
        let mut at = [Descent::new([0.0; 2]); crate::distr::GROUP];
        for (us, out) in us.chunks(at.len()).zip(out.chunks_mut(at.len())) {
            let at = &mut at[..us.len()];
            for (a, &u) in at.iter_mut().zip(us) {
                *a = Descent::new(u);
            }
            for level in self.levels.iter().rev() {
                for a in at.iter_mut() {
                    a.step(level);
                }
            }
            for (o, a) in out.iter_mut().zip(at.iter()) {
                *o = a.finish();
            }
        }
    }
}

/// `a / (a + b)`, or 1/2 for parts of weight 0 (a split no descent uses:
/// it never enters a block or row of weight 0).
fn share(a: f64, b: f64) -> f64 {
    if a + b > 0.0 { a / (a + b) } else { 0.5 }
}

/// Where a descent is: the cell `(x, y)` of the level above, and for each
/// coordinate of `u` the interval `[lo, lo + width)` of the unit square
/// that the choices so far leave (`u` is not rescaled at each step, as in
/// Mitsuba's code, but the interval narrowed: the same choices, without a
/// division per step).
#[derive(Clone, Copy, Debug)]
struct Descent {
    cell: [usize; 2],
    u: [f64; 2],
    lo: [f64; 2],
    width: [f64; 2],
}

impl Descent {
    fn new(u: [f64; 2]) -> Self {
        Descent {
            cell: [0, 0],
            // A NaN to 0 (`clamp` would keep it).
            u: u.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) }),
            lo: [0.0; 2],
            width: [1.0; 2],
        }
    }

    /// One level down, into the block under the current cell: the row by
    /// `u[1]` (the first with probability `(v00 + v10) / Σ`), then the
    /// column of that row by `u[0]`. A row or cell of weight 0 is never
    /// chosen. Branch-free: the choices are as likely as the weights make
    /// them, which a branch predictor cannot guess.
    #[inline(always)]
    fn step(&mut self, level: &Level) {
        let [x, y] = self.cell;
        debug_assert!(x < level.blocks_per_row, "a cell of the padding");
        let block = y * level.blocks_per_row + x;
        let [row, first, second] = level.splits.get(block).copied().unwrap_or([0.5; 3]);
        let lower = self.choose(1, row);
        let right = self.choose(0, [first, second][lower]);
        self.cell = [2 * x + right, 2 * y + lower];
    }

    /// 1 when coordinate `k` picks the second part of its interval, split
    /// at the share `f` of the first: when `u` lies past the split, or the
    /// first part has weight 0, and the second has weight (`f < 1`); else
    /// 0. The interval becomes the chosen part.
    #[inline(always)]
    fn choose(&mut self, k: usize, f: f64) -> usize {
        let first = self.width[k] * f;
        let split = self.lo[k] + first;
        let second = (f < 1.0) & ((self.u[k] > split) | (f == 0.0));
        // Arithmetic on 0 or 1 (exact), where a select compiles to a jump.
        let s = f64::from(u8::from(second));
        self.lo[k] += s * first;
        self.width[k] = s * (self.width[k] - first) + (1.0 - s) * first;
        usize::from(second)
    }

    /// The cell `(row, col)` reached, and `u` rescaled to `[0, 1]²` in it
    /// (the middle where the weights' ratios underflowed its interval).
    fn finish(&self) -> ((usize, usize), [f64; 2]) {
        let r = std::array::from_fn(|k| {
            let w = self.width[k];
            if w > 0.0 {
                ((self.u[k] - self.lo[k]) / w).clamp(0.0, 1.0)
            } else {
                0.5
            }
        });
        ((self.cell[1], self.cell[0]), r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An odd-sized table with zeros: every cell is chosen in proportion to
    /// its weight (a grid of `u` counts exactly), and rescaled `u` stays in
    /// the unit square.
    #[test]
    fn cells_are_chosen_in_proportion_to_their_weights() {
        let (cols, rows) = (5, 3);
        let weights: Vec<f64> = (0..cols * rows).map(|i| (i % 4) as f64).collect();
        let p = Pyramid::new(&weights, cols, rows).unwrap();
        let n = 1200;
        let mut counts = vec![0usize; cols * rows];
        for i in 0..n {
            for j in 0..n {
                let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                let ((row, col), r) = p.sample_reuse(u);
                assert!(row < rows && col < cols, "{u:?} -> {row}, {col}");
                assert!(r.iter().all(|v| (0.0..=1.0).contains(v)));
                counts[row * cols + col] += 1;
            }
        }
        let total: f64 = weights.iter().sum();
        for (c, w) in counts.iter().zip(&weights) {
            if *w == 0.0 {
                assert_eq!(*c, 0);
            }
            let expected = w / total * (n * n) as f64;
            assert!(
                (*c as f64 - expected).abs() <= 2.0 * n as f64 + 4.0,
                "{c} vs {expected}"
            );
        }
    }

    /// A block of the pyramid takes one rectangle of `u`: the four cells of
    /// a 2×2 table of equal weights are the four quadrants.
    #[test]
    fn equal_weights_split_the_square_into_quadrants() {
        let p = Pyramid::new(&[1.0; 4], 2, 2).unwrap();
        assert_eq!(p.sample_reuse([0.2, 0.3]), ((0, 0), [0.4, 0.6]));
        assert_eq!(p.sample_reuse([0.7, 0.3]).0, (0, 1));
        assert_eq!(p.sample_reuse([0.2, 0.8]).0, (1, 0));
    }

    /// The batch draws what one at a time does, on a table of several
    /// levels; the corners of the square and a NaN land on cells of
    /// weight, where the first row or cell has none (Mitsuba would take
    /// the first part at `u = 0` and divide 0 by 0).
    #[test]
    fn batches_and_edges() {
        let (cols, rows) = (5, 3);
        let mut weights: Vec<f64> = (0..cols * rows).map(|i| (i % 4) as f64).collect();
        weights[..cols].fill(0.0);
        let p = Pyramid::new(&weights, cols, rows).unwrap();
        let batch = [
            [0.2, 0.3],
            [0.9, 0.9],
            [0.0, 0.0],
            [1.0, 1.0],
            [f64::NAN, 0.5],
            [0.5, 0.0],
        ];
        let mut out = [((0, 0), [0.0; 2]); 6];
        p.sample_reuse_into(&batch, &mut out);
        for (u, o) in batch.iter().zip(out) {
            assert_eq!(o, p.sample_reuse(*u));
            let ((row, col), r) = o;
            assert!(weights[row * cols + col] > 0.0, "{u:?} -> {row}, {col}");
            assert!(r.iter().all(|v| (0.0..=1.0).contains(v)), "{u:?} -> {r:?}");
        }
    }
}

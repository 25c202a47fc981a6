//! Hierarchical sample warping (Clarberg et al. 2005, the scheme of
//! Mitsuba 3's `Hierarchical2D`): a cell of a 2D table of non-negative
//! weights is chosen by descending a MIP pyramid of its sums, one 2×2
//! block per level, the row by `u[1]` and then the column by `u[0]`, each
//! coordinate rescaled to `[0, 1]` after each choice.
//!
//! A cell is chosen with probability `w / Σw`, as by a marginal and a
//! conditional table, but the map from `u` to cells is local at every
//! scale (the cells of a block of the pyramid come from one rectangle of
//! the unit square), so points stratified in `[0, 1]²` land stratified
//! among the cells (the reason Mitsuba samples its environment maps this
//! way).

use crate::alloc;
use crate::error::Result;

/// One level: `width × height` sums (both even; cells past the table are
/// 0), stored in 2×2 blocks so that the four cells a step reads are
/// adjacent.
#[derive(Clone, Debug)]
struct Level {
    width: usize,
    values: Vec<f64>,
}

impl Level {
    /// Index of the first (top-left) cell of the 2×2 block at even `(x, y)`.
    #[inline(always)]
    fn block(&self, x: usize, y: usize) -> usize {
        (y / 2 * (self.width / 2) + x / 2) * 4
    }

    /// Index of cell `(x, y)`.
    #[inline(always)]
    fn index(&self, x: usize, y: usize) -> usize {
        self.block(x & !1, y & !1) + (y & 1) * 2 + (x & 1)
    }
}

/// The MIP pyramid of a `cols × rows` table of weights, finest level first,
/// up to the level that is one 2×2 block.
#[derive(Clone, Debug)]
pub struct Pyramid {
    levels: Vec<Level>,
}

impl Pyramid {
    /// The pyramid of the row-major `weights` (`rows × cols`, non-negative,
    /// not all 0: the caller checks).
    pub fn new(weights: &[f64], cols: usize, rows: usize) -> Result<Self> {
        let even = |n: usize| n + (n & 1);
        let (mut w, mut h) = (even(cols), even(rows));
        let mut finest = alloc::filled(w * h, 0.0, "the sampling pyramid")?;
        let mut level = Level {
            width: w,
            values: Vec::new(),
        };
        for y in 0..rows {
            for x in 0..cols {
                finest[level.index(x, y)] = weights[y * cols + x];
            }
        }
        level.values = finest;
        let mut levels = vec![level];
        while w > 2 || h > 2 {
            let below = &levels[levels.len() - 1];
            let (cw, ch) = (w / 2, h / 2);
            (w, h) = (even(cw), even(ch));
            let mut values = alloc::filled(w * h, 0.0, "the sampling pyramid")?;
            let up = Level {
                width: w,
                values: Vec::new(),
            };
            for y in 0..ch {
                for x in 0..cw {
                    let b = below.block(2 * x, 2 * y);
                    values[up.index(x, y)] = below.values[b..b + 4].iter().sum();
                }
            }
            levels.push(Level { values, ..up });
        }
        Ok(Pyramid { levels })
    }

    /// The cell `(row, col)` that `u ∈ [0, 1]²` chooses, with probability
    /// `w / Σw`, and `u` rescaled to `[0, 1]²` within the choices.
    #[inline]
    pub fn sample_reuse(&self, mut u: [f64; 2]) -> ((usize, usize), [f64; 2]) {
        let (mut x, mut y) = (0, 0);
        for level in self.levels.iter().rev() {
            (x, y) = step(level, (2 * x, 2 * y), &mut u);
        }
        ((y, x), u)
    }

    /// `out[i] = sample_reuse(us[i])`, the batch descending one level at a
    /// time (its lookups at a level are independent of one another).
    pub fn sample_reuse_into(&self, us: &[[f64; 2]], out: &mut [((usize, usize), [f64; 2])]) {
        for (o, &u) in out.iter_mut().zip(us) {
            *o = ((0, 0), u);
        }
        for level in self.levels.iter().rev() {
            for ((row, col), u) in out.iter_mut() {
                (*col, *row) = step(level, (2 * *col, 2 * *row), u);
            }
        }
    }
}

/// One step down: in the block at even `(x, y)` of `level`, the row by
/// `u[1]` (first row with probability `r0 / (r0 + r1)`, its two sums),
/// then the column of that row by `u[0]`, each coordinate rescaled to
/// `[0, 1]` within its choice. A row or cell of weight 0 is never chosen.
#[inline(always)]
fn step(level: &Level, (x, y): (usize, usize), u: &mut [f64; 2]) -> (usize, usize) {
    let b = level.block(x, y);
    let v = &level.values[b..b + 4];
    let lower = choose(&mut u[1], v[0] + v[1], v[2] + v[3]);
    let row = &v[2 * usize::from(lower)..][..2];
    let right = choose(&mut u[0], row[0], row[1]);
    (x + usize::from(right), y + usize::from(lower))
}

/// Whether `u` picks the second of two weights `a`, `b` (not both 0):
/// when `u (a + b) > a`, or `a = 0`; `u` is rescaled to `[0, 1]` within
/// the chosen one.
#[inline(always)]
fn choose(u: &mut f64, a: f64, b: f64) -> bool {
    let t = *u * (a + b);
    let second = t > a || a == 0.0;
    *u = if second { (t - a) / b } else { t / a }.clamp(0.0, 1.0);
    second
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
        let batch = [[0.2, 0.3], [0.9, 0.9], [0.0, 0.0]];
        let mut out = [((0, 0), [0.0; 2]); 3];
        p.sample_reuse_into(&batch, &mut out);
        for (u, o) in batch.iter().zip(out) {
            assert_eq!(o, p.sample_reuse(*u));
        }
    }
}

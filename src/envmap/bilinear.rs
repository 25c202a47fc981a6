//! A density on the unit square that is the bilinear interpolant of values
//! on a grid of vertices, sampled as Mitsuba 3's `Hierarchical2D` (which
//! its `envmap` emitter samples) warps the square.

use super::pyramid::Pyramid;
use crate::alloc;
use crate::distr::GROUP;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::simd;

/// The bilinear interpolant of `cols × rows` non-negative vertex values,
/// vertex `(x, y)` at `(x/(cols − 1), y/(rows − 1))`, normalised to a
/// density on `[0, 1]²`.
///
/// # Density
/// `p(q) = bilerp(q) / Ī`, with `Ī = Σ_patches (v00 + v10 + v01 + v11)/4 ÷
/// #patches` the mean of the interpolant. Per unit area.
///
/// # Sampling
/// A patch in proportion to its integral by hierarchical sample warping
/// (`envmap::pyramid`: a 2×2 block per level, row by `u[1]`, column by `u[0]`),
/// then a point in it by the bilinear warp with the rescaled `u`: the
/// marginal in y, then the conditional in x, each a linear density
/// inverted in closed form. The same map from `u` to points as Mitsuba's
/// `Hierarchical2D` (up to rounding at the boundaries of its choices).
#[derive(Clone, Debug)]
pub struct BilinearGrid {
    values: Vec<f64>,
    cols: usize,
    rows: usize,
    inv_mean: f64,
    patches: Pyramid,
}

impl BilinearGrid {
    /// The density of the row-major vertex `values` (`rows × cols`, both
    /// at least 2; finite and non-negative: the caller checks).
    ///
    /// # Errors
    /// [`Error::AllZero`] when every patch integral is 0, [`Error::Memory`].
    pub fn new(values: Vec<f64>, cols: usize, rows: usize) -> Result<Self> {
        let (px, py) = (cols - 1, rows - 1);
        let mut patch = alloc::with_capacity(px * py, "the sampling grid's patches")?;
        for y in 0..py {
            for x in 0..px {
                let i = y * cols + x;
                patch.push(
                    0.25 * (values[i] + values[i + 1] + values[i + cols] + values[i + cols + 1]),
                );
            }
        }
        let sum: f64 = patch.iter().sum();
        if sum <= 0.0 {
            return Err(Error::AllZero { arg: "image" });
        }
        let patches = Pyramid::new(&patch, px, py)?;
        let inv_mean = (px * py) as f64 / sum;
        Ok(BilinearGrid {
            values,
            cols,
            rows,
            inv_mean,
            patches,
        })
    }

    /// The corners `[v00, v10, v01, v11]` of patch `(row, col)`.
    #[inline(always)]
    fn corners(&self, row: usize, col: usize) -> [f64; 4] {
        let i = row * self.cols + col;
        let v = &self.values;
        [v[i], v[i + 1], v[i + self.cols], v[i + self.cols + 1]]
    }

    /// The density at `q` (clamped into the square).
    #[inline]
    pub fn pdf(&self, q: [f64; 2]) -> f64 {
        let (px, py) = (self.cols - 1, self.rows - 1);
        let x = q[0].clamp(0.0, 1.0) * px as f64;
        let y = q[1].clamp(0.0, 1.0) * py as f64;
        let (col, row) = (x.floor_index(px - 1), y.floor_index(py - 1));
        bilerp(self.corners(row, col), x - col as f64, y - row as f64) * self.inv_mean
    }

    /// `(q, p(q))` for `u` in `[0, 1]²`.
    #[inline]
    pub fn sample(&self, u: [f64; 2]) -> ([f64; 2], f64) {
        self.place(self.patches.sample_reuse(u))
    }

    /// `out[i] = sample(us[i])` for a batch: the patches by
    /// `Pyramid::sample_reuse_into`, then their corners prefetched
    /// before any is read. Inlined into the caller's vector-unit dispatch.
    #[inline(always)]
    pub fn sample_into(&self, us: &[[f64; 2]], out: &mut [([f64; 2], f64)]) {
        let mut patches = [((0, 0), [0.0; 2]); GROUP];
        for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
            let patches = &mut patches[..us.len()];
            self.patches.sample_reuse_into(us, patches);
            for &((row, col), _) in patches.iter() {
                let i = row * self.cols + col;
                simd::prefetch(&self.values, i);
                simd::prefetch(&self.values, i + self.cols);
            }
            for (o, &patch) in out.iter_mut().zip(patches.iter()) {
                *o = self.place(patch);
            }
        }
    }

    /// The point that the rescaled `r` places in patch `(row, col)` by the
    /// bilinear warp, and the density there.
    #[inline(always)]
    fn place(&self, ((row, col), r): ((usize, usize), [f64; 2])) -> ([f64; 2], f64) {
        let c = self.corners(row, col);
        let [fx, fy] = warp_bilinear(c, r);
        let (px, py) = ((self.cols - 1) as f64, (self.rows - 1) as f64);
        let q = [(col as f64 + fx) / px, (row as f64 + fy) / py];
        (q, bilerp(c, fx, fy) * self.inv_mean)
    }
}

/// The point of the unit square with density `∝ bilerp(c, x, y)` (corners
/// `[v00, v10, v01, v11]`, not all 0) at `r` in `[0, 1]²`: the marginal in
/// y, then the conditional in x, each a linear density inverted in closed
/// form, in `F`.
#[inline(always)]
pub(super) fn warp_bilinear<F: Real>(c: [F; 4], r: [F; 2]) -> [F; 2] {
    let y = sample_linear(r[1], c[0] + c[1], c[2] + c[3]);
    [
        sample_linear(r[0], lerp(y, c[0], c[2]), lerp(y, c[1], c[3])),
        y,
    ]
}

#[inline(always)]
fn lerp<F: Real>(t: F, a: F, b: F) -> F {
    (F::one() - t) * a + t * b
}

/// `v00 (1−x)(1−y) + v10 x (1−y) + v01 (1−x) y + v11 x y`.
#[inline(always)]
pub(super) fn bilerp<F: Real>(c: [F; 4], x: F, y: F) -> F {
    lerp(y, lerp(x, c[0], c[1]), lerp(x, c[2], c[3]))
}

/// Inverse CDF of the density `∝ (1 − x)·a + x·b` on `[0, 1]` (`a, b >= 0`):
/// `x = u(a + b)/(a + √((1 − u)a² + u b²))`, which is exact for `a = b` and
/// stable for `a = 0` (0 at `u = 0`); `u` itself when `a = b = 0`.
#[inline(always)]
fn sample_linear<F: Real>(u: F, a: F, b: F) -> F {
    let zero = F::zero();
    if a + b == zero {
        return u;
    }
    let denominator = a + lerp(u, a * a, b * b).sqrt();
    if denominator > zero {
        (u * (a + b) / denominator).min(F::one())
    } else {
        zero
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_inversion_matches_its_cdf() {
        for (a, b) in [(1.0, 3.0), (0.0, 2.0), (5.0, 0.0), (2.0, 2.0)] {
            for k in 0..=100 {
                let u = k as f64 / 100.0;
                let x = sample_linear(u, a, b);
                let cdf = (a * x + 0.5 * (b - a) * x * x) / (0.5 * (a + b));
                assert!((cdf - u).abs() < 1e-12, "a={a} b={b}: {u} -> {x} -> {cdf}");
            }
        }
    }

    #[test]
    fn density_integrates_to_one_and_matches_samples() {
        let values = vec![0.0, 1.0, 4.0, 2.0, 0.0, 3.0, 1.0, 1.0, 0.0];
        let g = BilinearGrid::new(values, 3, 3).unwrap();
        let n = 400;
        let mut total = 0.0;
        for i in 0..n {
            for j in 0..n {
                total += g.pdf([(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64]);
            }
        }
        assert!((total / (n * n) as f64 - 1.0).abs() < 1e-6);
        for i in 0..=20 {
            for j in 0..=20 {
                let (q, pdf) = g.sample([i as f64 / 20.0, j as f64 / 20.0]);
                assert!((0.0..=1.0).contains(&q[0]) && (0.0..=1.0).contains(&q[1]));
                assert!((pdf - g.pdf(q)).abs() < 1e-9 * pdf.max(1.0), "{q:?}");
            }
        }
    }
}

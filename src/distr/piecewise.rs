//! Piecewise-constant densities on an interval and on a rectangle, sampled
//! by inverting their piecewise-linear CDFs.

use super::search::Search;
use super::{Discrete1D, Discrete2D, GROUP};
use crate::error::{Error, Result};
use crate::math::Real;
use crate::simd;

/// Checks an interval `[a, b]` given as `arg`.
fn check_interval(arg: &'static str, a: f64, b: f64) -> Result<()> {
    if a.is_finite() && b.is_finite() && a < b {
        Ok(())
    } else {
        Err(Error::Parameter {
            arg,
            value: if a.is_finite() { b } else { a },
            requirement: "the interval (a, b) needs finite a < b",
        })
    }
}

/// An interval `[lo, hi]` cut into `n` equal cells of width `h`.
#[derive(Clone, Copy, Debug)]
struct Axis {
    lo: f64,
    hi: f64,
    n: usize,
    /// `n / (hi − lo)`, cells per unit length.
    cells_per_unit: f64,
    /// `(hi − lo) / n`, the cell width `h`.
    width: f64,
}

impl Axis {
    /// `[lo, hi]` in `n` cells.
    fn new(lo: f64, hi: f64, n: usize) -> Self {
        Axis {
            lo,
            hi,
            n,
            cells_per_unit: n as f64 / (hi - lo),
            width: (hi - lo) / n as f64,
        }
    }

    /// The continuous cell coordinate `t = (x − lo)·n/(hi − lo)` and the
    /// cell `⌊t⌋` clamped to `[0, n − 1]`.
    #[inline(always)]
    fn locate(self, x: f64) -> (f64, usize) {
        let t = (x - self.lo) * self.cells_per_unit;
        (t, t.floor_index(self.n - 1))
    }

    /// The cell holding `x`, or `None` outside `[lo, hi]` (or NaN).
    #[inline(always)]
    fn cell_of(self, x: f64) -> Option<usize> {
        (x >= self.lo && x <= self.hi).then(|| self.locate(x).1)
    }

    /// The point at fraction `r` of cell `cell`, rounded to `F`, and moved
    /// inward by a few ulps where rounding put it in a neighbouring cell (or
    /// outside), so that a density lookup of a sample finds its own cell.
    #[inline(always)]
    fn point<F: Real>(self, cell: usize, r: f64) -> F {
        let x = self.lo + (cell as f64 + r) * self.width;
        let p = F::c(x.clamp(self.lo, self.hi));
        if self.cell_of(p.f64()) == Some(cell) {
            p
        } else {
            self.mend(cell, p)
        }
    }

    /// The point `p` that rounding put outside cell `cell`, moved inward by
    /// a few ulps (rare: out of line).
    #[cold]
    #[inline(never)]
    fn mend<F: Real>(self, cell: usize, mut p: F) -> F {
        let mut step = self.lo.abs().max(self.hi.abs()) * F::epsilon().f64();
        for _ in 0..16 {
            let x = p.f64();
            match self.cell_of(x) {
                Some(c) if c == cell => break,
                Some(c) if c < cell => p = F::c(x + step),
                None if x < self.lo => p = F::c(x + step),
                _ => p = F::c(x - step),
            }
            step *= 2.0;
        }
        p
    }
}

/// The running sum of `table` at the continuous position `t` (`t` in
/// `[0, n]`, within cell `cell`): `C_{cell−1} + (t − cell)·w_cell`.
#[inline(always)]
fn running_sum(table: Search<'_>, t: f64, cell: usize) -> f64 {
    table.sum_before(cell) + (t - cell as f64).clamp(0.0, 1.0) * table.weight(cell)
}

/// A density on `[a, b]`, constant on `n` equal cells with values
/// proportional to non-negative `values`.
///
/// # Density
/// `p(x) = v_i / (Σv · h)` on cell `i`, with `h = (b − a)/n`; 0 outside
/// `[a, b]`. Per unit length.
///
/// # Sampling and inverse
/// `sample(u)`: the cell `i` from the [`Discrete1D`] of the values, and the
/// rescaled `u'` within it: `x = a + (i + u')·h`. Its inverse is the CDF,
/// `u = (C_{i−1} + (x − x_i)/h · v_i)/Σv`, exact on cells of positive value.
#[derive(Clone, Debug)]
pub struct PiecewiseConstant1D {
    table: Discrete1D,
    axis: Axis,
}

impl PiecewiseConstant1D {
    /// The density proportional to `values` on `[a, b]`.
    ///
    /// # Errors
    /// As [`Discrete1D::new`] (argument `values`), and [`Error::Parameter`]
    /// unless `a < b` are finite.
    pub fn new(values: &[f64], a: f64, b: f64) -> Result<Self> {
        check_interval("a", a, b)?;
        let table = Discrete1D::new(values).map_err(|e| rename(e, "values"))?;
        let axis = Axis::new(a, b, table.len());
        Ok(PiecewiseConstant1D { table, axis })
    }

    /// The interval `(a, b)`.
    pub fn domain(&self) -> (f64, f64) {
        (self.axis.lo, self.axis.hi)
    }

    /// The cells' discrete distribution.
    pub fn table(&self) -> &Discrete1D {
        &self.table
    }

    /// The integral of the values over `[a, b]`: `Σv · h`.
    pub fn integral(&self) -> f64 {
        self.table.sum() * (self.axis.hi - self.axis.lo) / self.axis.n as f64
    }

    /// `(x, p(x))` for `u` in `[0, 1]`.
    #[inline]
    pub fn sample<F: Real>(&self, u: F) -> (F, F) {
        let (i, r) = self.table.sample_reuse(u);
        self.sample_in_cell(i, r, self.integral())
    }

    /// The point at fraction `r` (in `[0, 1)`) of cell `i`, and the density
    /// there (`integral`: [`PiecewiseConstant1D::integral`]).
    #[inline(always)]
    fn sample_in_cell<F: Real>(&self, i: usize, r: F, integral: f64) -> (F, F) {
        let pdf = self.table.weight(i) / integral;
        (self.axis.point(i, r.f64()), F::c(pdf))
    }

    /// `out[i] = sample(us[i])` for a batch, the cells drawn as
    /// [`Discrete1D::sample_reuse_into`] draws them (cache misses that
    /// overlap), compiled for the widest vector unit.
    pub fn sample_into<F: Real>(&self, us: &[F], out: &mut [(F, F)]) {
        simd::dispatch(
            #[inline(always)]
            |_| {
                let integral = self.integral();
                let mut cells = [(0, F::zero()); GROUP];
                for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
                    let cells = &mut cells[..us.len()];
                    self.table.sample_reuse_groups(us, cells);
                    for (o, &(i, r)) in out.iter_mut().zip(cells.iter()) {
                        *o = self.sample_in_cell(i, r, integral);
                    }
                }
            },
        )
    }

    /// The density at `x` (0 outside `[a, b]`).
    #[inline]
    pub fn pdf<F: Real>(&self, x: F) -> F {
        self.axis.cell_of(x.f64()).map_or(F::zero(), |cell| {
            F::c(self.table.weight(cell) / self.integral())
        })
    }

    /// The cumulative distribution `P(X ≤ x)`: 0 below `a`, 1 above `b`.
    #[inline]
    pub fn cdf<F: Real>(&self, x: F) -> F {
        let x = x.f64();
        if x <= self.axis.lo {
            return F::zero();
        }
        if x >= self.axis.hi {
            return F::one();
        }
        let (t, cell) = self.axis.locate(x);
        F::c((running_sum(self.table.search(), t, cell) / self.table.sum()).min(1.0))
    }

    /// The `u` that [`PiecewiseConstant1D::sample`] maps to `x` (the CDF),
    /// or `None` when `x` lies outside `[a, b]` or is NaN.
    #[inline]
    pub fn invert<F: Real>(&self, x: F) -> Option<F> {
        self.axis.cell_of(x.f64()).map(|_| self.cdf(x))
    }
}

/// Renames the argument of a table error (`weights` → `values`).
fn rename(e: Error, arg: &'static str) -> Error {
    match e {
        Error::InvalidWeight { index, value, .. } => Error::InvalidWeight { arg, index, value },
        Error::AllZero { .. } => Error::AllZero { arg },
        Error::TooLarge { len, max, .. } => Error::TooLarge { arg, len, max },
        other => other,
    }
}

/// A density on the rectangle `[x0, x1] × [y0, y1]`, constant on the cells
/// of a `rows × cols` grid with values proportional to `values[row][col]`
/// (rows along y, columns along x, row 0 at `y0`).
///
/// # Density
/// `p(x, y) = v[row][col] / (Σv · hx · hy)`, with `hx = (x1 − x0)/cols`,
/// `hy = (y1 − y0)/rows`; 0 outside the rectangle. Per unit area.
///
/// # Sampling and inverse
/// The cell from the [`Discrete2D`] of the values (the row by `u[1]` from
/// the marginal, the column by `u[0]` from that row's conditional), then
/// the rescaled `u'` places the point within the cell. The inverse returns
/// `(u0, u1)`: the conditional CDF along x in the point's row and the
/// marginal CDF along y.
#[derive(Clone, Debug)]
pub struct PiecewiseConstant2D {
    table: Discrete2D,
    x: Axis,
    y: Axis,
    /// [`PiecewiseConstant2D::integral`], which every density divides by.
    integral: f64,
}

impl PiecewiseConstant2D {
    /// The density proportional to the row-major `rows × cols` table
    /// `values` on `domain = [[x0, x1], [y0, y1]]`.
    ///
    /// # Errors
    /// As [`Discrete2D::new`] (argument `values`), and [`Error::Parameter`]
    /// for a degenerate or infinite rectangle.
    pub fn new(values: &[f64], rows: usize, cols: usize, domain: [[f64; 2]; 2]) -> Result<Self> {
        check_interval("domain", domain[0][0], domain[0][1])?;
        check_interval("domain", domain[1][0], domain[1][1])?;
        let table = Discrete2D::with_arg("values", values, rows, cols)?;
        let axis = |[lo, hi]: [f64; 2], n| Axis::new(lo, hi, n);
        let (x, y) = (axis(domain[0], cols), axis(domain[1], rows));
        let area = (x.hi - x.lo) * (y.hi - y.lo);
        let integral = table.sum() * area / (cols * rows) as f64;
        Ok(PiecewiseConstant2D {
            table,
            x,
            y,
            integral,
        })
    }

    /// `[[x0, x1], [y0, y1]]`.
    pub fn domain(&self) -> [[f64; 2]; 2] {
        [[self.x.lo, self.x.hi], [self.y.lo, self.y.hi]]
    }

    /// The cells' discrete distribution.
    pub fn table(&self) -> &Discrete2D {
        &self.table
    }

    /// The integral of the values over the rectangle: `Σv · hx · hy`.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// The density of cell `(row, col)` per unit area.
    #[inline]
    pub fn cell_pdf(&self, row: usize, col: usize) -> f64 {
        self.table.weight(row, col) / self.integral()
    }

    /// The cell `(row, col)` that holds `(x, y)`, or `None` outside the
    /// rectangle.
    #[inline]
    pub fn cell_of<F: Real>(&self, p: [F; 2]) -> Option<(usize, usize)> {
        Some((self.y.cell_of(p[1].f64())?, self.x.cell_of(p[0].f64())?))
    }

    /// `((x, y), p(x, y))` for `u` in `[0, 1]²`.
    #[inline]
    pub fn sample<F: Real>(&self, u: [F; 2]) -> ([F; 2], F) {
        let (cell, r) = self.table.sample_reuse(u);
        self.sample_in_cell(cell, r)
    }

    /// `out[i] = sample(us[i])` for a batch, drawing the cells with
    /// [`Discrete2D::sample_reuse_into`] (whose cache misses overlap),
    /// compiled for the widest vector unit.
    pub fn sample_into<F: Real>(&self, us: &[[F; 2]], out: &mut [([F; 2], F)]) {
        simd::dispatch(
            #[inline(always)]
            |_| self.sample_groups(us, out),
        )
    }

    /// The loop of [`PiecewiseConstant2D::sample_into`], within its
    /// dispatch: each group's cells, then their points.
    #[inline(always)]
    fn sample_groups<F: Real>(&self, us: &[[F; 2]], out: &mut [([F; 2], F)]) {
        let mut cells = [((0, 0), [F::zero(); 2]); GROUP];
        for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
            let cells = &mut cells[..us.len()];
            self.table.sample_groups(us, cells);
            for (o, &(cell, r)) in out.iter_mut().zip(cells.iter()) {
                *o = self.sample_in_cell(cell, r);
            }
        }
    }

    /// The point at fractions `r` (in `[0, 1)²`) of cell `(row, col)`
    /// along x and y, and the density there: where [`Self::sample`] puts a
    /// draw of that cell with rescaled numbers `r`. Rounding never moves the
    /// point out of its cell, so that [`Self::pdf`] finds the same density.
    #[inline(always)]
    pub fn sample_in_cell<F: Real>(&self, (row, col): (usize, usize), r: [F; 2]) -> ([F; 2], F) {
        let p = [self.x.point(col, r[0].f64()), self.y.point(row, r[1].f64())];
        (p, F::c(self.cell_pdf(row, col)))
    }

    /// The density at `(x, y)` (0 outside the rectangle).
    #[inline]
    pub fn pdf<F: Real>(&self, p: [F; 2]) -> F {
        self.cell_of(p)
            .map_or(F::zero(), |(row, col)| F::c(self.cell_pdf(row, col)))
    }

    /// The `u` that [`PiecewiseConstant2D::sample`] maps to `(x, y)`, or
    /// `None` outside the rectangle. In a row of weight 0 (never sampled)
    /// `u0` is the position along x.
    #[inline]
    pub fn invert<F: Real>(&self, p: [F; 2]) -> Option<[F; 2]> {
        self.cell_of(p)?;
        let (tx, col) = self.x.locate(p[0].f64());
        let (ty, row) = self.y.locate(p[1].f64());
        let marginal = self.table.marginal().search();
        let u1 = running_sum(marginal, ty, row) / marginal.sum();
        let u0 = match self.table.conditional(row) {
            Some(c) => running_sum(c, tx, col) / c.sum(),
            None => tx / self.x.n as f64,
        };
        Some([F::c(u0.clamp(0.0, 1.0)), F::c(u1.clamp(0.0, 1.0))])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_d_known_values_and_round_trip() {
        let d = PiecewiseConstant1D::new(&[1.0, 0.0, 3.0], -1.0, 2.0).unwrap();
        assert_eq!(d.integral(), 4.0);
        assert_eq!(d.pdf(-0.5), 0.25);
        assert_eq!(d.pdf(0.5), 0.0);
        assert_eq!(d.pdf(1.5), 0.75);
        assert_eq!(d.pdf(2.5), 0.0);
        assert_eq!(d.cdf(0.5), 0.25);
        assert_eq!(d.cdf(1.5), 0.25 + 0.375);
        assert_eq!(d.invert(3.0), None);
        for k in 0..=1000 {
            let u = k as f64 / 1000.0;
            let (x, pdf) = d.sample(u);
            assert!((-1.0..=2.0).contains(&x));
            assert!(pdf > 0.0, "u = {u} -> x = {x} in a zero cell");
            assert_eq!(pdf, d.pdf(x));
            let back = d.invert(x).unwrap();
            assert!((back - u).abs() < 1e-12, "{u} -> {x} -> {back}");
        }
    }

    #[test]
    fn two_d_known_values_and_round_trip() {
        let values = [1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 5.0, 0.0, 8.0];
        let d = PiecewiseConstant2D::new(&values, 3, 3, [[0.0, 3.0], [-1.0, 2.0]]).unwrap();
        assert_eq!(d.integral(), 16.0);
        assert_eq!(d.pdf([2.5, 1.5]), 0.5);
        assert_eq!(d.pdf([0.5, 0.5]), 0.0);
        for i in 0..=40 {
            for j in 0..=40 {
                let u = [i as f64 / 40.0, j as f64 / 40.0];
                let (p, pdf) = d.sample(u);
                assert!(pdf > 0.0);
                assert_eq!(pdf, d.pdf(p));
                let back = d.invert(p).unwrap();
                assert!(
                    (back[0] - u[0]).abs() < 1e-12 && (back[1] - u[1]).abs() < 1e-12,
                    "{u:?} -> {p:?} -> {back:?}"
                );
            }
        }
        assert_eq!(d.invert([3.5, 0.0]), None);
    }

    #[test]
    fn batch_sampling_agrees_with_single_draws() {
        // Cells of weight 0, a guided table, a batch not a multiple of GROUP.
        let values: Vec<f64> = (0..300).map(|i| ((i * 7) % 5) as f64).collect();
        let d = PiecewiseConstant1D::new(&values, -1.0, 2.0).unwrap();
        for us in [
            (0..=1000).map(|k| k as f64 / 1000.0).collect::<Vec<_>>(),
            vec![0.0, 1.0, 0.5],
        ] {
            let mut out = vec![(0.0, 0.0); us.len()];
            d.sample_into(&us, &mut out);
            for (&u, &o) in us.iter().zip(&out) {
                assert_eq!(o, d.sample(u), "u = {u}");
            }
        }
        let us32: Vec<f32> = (0..=200).map(|k| k as f32 / 200.0).collect();
        let mut out32 = vec![(0.0f32, 0.0f32); us32.len()];
        d.sample_into(&us32, &mut out32);
        for (&u, &o) in us32.iter().zip(&out32) {
            assert_eq!(o, d.sample(u), "u = {u}");
        }
    }

    #[test]
    fn errors_name_values_and_domain() {
        let e = PiecewiseConstant1D::new(&[1.0, -2.0], 0.0, 1.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "values[1] = -2: values must be finite and >= 0"
        );
        assert!(PiecewiseConstant1D::new(&[1.0], 1.0, 1.0).is_err());
        assert!(PiecewiseConstant1D::new(&[1.0], 0.0, f64::INFINITY).is_err());
        assert!(PiecewiseConstant2D::new(&[1.0], 1, 1, [[0.0, 1.0], [2.0, 1.0]]).is_err());
    }
}

//! [`Discrete2D`]: a discrete distribution over the cells of a table.

use super::search::{Lanes, Place, Search, fill_table, guide_len, search_group};
use super::{Discrete1D, GROUP, check_weights};
use crate::buffer::Buffer;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::{alloc, parallel, simd};
use rayon::prelude::*;

/// A discrete distribution over the cells `(row, col)` of a `rows × cols`
/// table of non-negative weights, sampled by the two-step method.
///
/// # Probability
/// `P(row, col) = w[row][col] / Σw`.
///
/// # Sampling
/// A row from the marginal distribution (the row sums) by `u[1]`, then a
/// column from that row's conditional distribution by `u[0]`: the same
/// assignment of `u` as Mitsuba 3's `DiscreteDistribution2D` (whose
/// `Point2u` is `(col, row)`). Both steps are [`Discrete1D`] searches, so a
/// cell of weight 0 is never returned.
///
/// # Layout
/// The conditionals' tables (weights, running sums, guide tables) lie
/// row after row in three flat arrays, so that a draw finds a row's tables
/// by arithmetic on its index, with no load of a per-row structure
/// between the marginal's answer and the row's search.
#[derive(Clone, Debug)]
pub struct Discrete2D {
    marginal: Discrete1D,
    cols: usize,
    /// Each row's weights, row after row.
    weights: Buffer<f64>,
    /// Each row's running sums from 0.
    cdf: Buffer<f64>,
    /// Each row's guide table, [`guide_len`]`(cols)` entries per row (left
    /// unwritten for rows of weight 0, which are never searched).
    guide: Buffer<u32>,
    /// Each row's sum and first and last entries of positive weight;
    /// `None` for rows of weight 0 (never drawn).
    rows: Vec<Option<(f64, usize, usize)>>,
}

/// A [`Discrete2D`]'s flat tables as slices, from which a row's
/// [`Search`] is cut.
#[derive(Clone, Copy)]
struct Rows<'a> {
    cols: usize,
    weights: &'a [f64],
    cdf: &'a [f64],
    guide: &'a [u32],
    rows: &'a [Option<(f64, usize, usize)>],
}

impl<'a> Rows<'a> {
    /// A table of the store (the first row's place, of no weight): the
    /// flat tables and a row's length, for [`search_group`].
    #[inline(always)]
    fn store(&self) -> Search<'a> {
        let place = Place {
            start: 0,
            guide_start: 0,
            len: self.cols,
        };
        Search::within((self.weights, self.cdf, self.guide), place, (0.0, 0, 0))
    }

    /// The conditional of `row` (`None` for a row of weight 0): its place
    /// in the flat tables, found by arithmetic.
    #[inline(always)]
    fn search(&self, row: usize) -> Option<Search<'a>> {
        let span = (*self.rows.get(row)?)?;
        let place = Place {
            start: row * self.cols,
            guide_start: row * guide_len(self.cols),
            len: self.cols,
        };
        Some(Search::within(
            (self.weights, self.cdf, self.guide),
            place,
            span,
        ))
    }
}

impl Discrete2D {
    /// A distribution over the cells of the row-major `rows × cols` table
    /// `weights`.
    ///
    /// # Errors
    /// [`Error::Shape`] if `weights.len() != rows·cols`; otherwise as
    /// [`Discrete1D::new`], with the offending entry named `[row, col]`.
    pub fn new(weights: &[f64], rows: usize, cols: usize) -> Result<Self> {
        Self::with_arg("weights", weights, rows, cols)
    }

    /// As [`Discrete2D::new`], naming the argument `arg` in errors.
    pub fn with_arg(arg: &'static str, weights: &[f64], rows: usize, cols: usize) -> Result<Self> {
        if rows.checked_mul(cols) != Some(weights.len()) {
            return Err(Error::Shape {
                arg,
                expected: format!("({rows}, {cols})"),
                got: format!("{} values", weights.len()),
            });
        }
        let cols_nz = cols.max(1);
        check_weights(arg, weights, |i| {
            format!("[{}, {}]", i / cols_nz, i % cols_nz)
        })?;
        crate::error::check_at_most(arg, rows.max(cols), super::MAX_ENTRIES)?;
        let g = guide_len(cols);
        let mut copy = Buffer::<f64>::for_overwrite(weights.len(), "the table's weights")?;
        let mut cdf = Buffer::<f64>::for_overwrite(weights.len(), "the table's running sums")?;
        let n_rows = weights.len() / cols_nz;
        let mut guide = Buffer::<u32>::for_overwrite(n_rows * g, "the table's guides")?;
        let guides: Vec<&mut [u32]> = match g {
            0 => alloc::collect((0..n_rows).map(|_| &mut [][..]), "the table's rows")?,
            _ => alloc::collect(guide.chunks_mut(g), "the table's rows")?,
        };
        let row_tables = weights
            .chunks(cols_nz)
            .zip(copy.chunks_mut(cols_nz))
            .zip(cdf.chunks_mut(cols_nz))
            .zip(guides);
        let fill = |(((w, copy), cdf), guide): (((_, _), _), _)| fill_table(w, (copy, cdf, guide));
        // Rows are independent: build them on all cores (large tables only).
        let spans: Vec<Option<(f64, usize, usize)>> = if weights.len() < 1 << 16 {
            row_tables.map(fill).collect()
        } else {
            let row_tables = alloc::collect(row_tables, "the table's rows")?;
            parallel::install(|| {
                alloc::par_collect(row_tables.into_par_iter().map(fill), "the table's rows")
            })??
        };
        let row_sums =
            alloc::collect(spans.iter().map(|s| s.map_or(0.0, |s| s.0)), "the row sums")?;
        let marginal = Discrete1D::from_checked(&row_sums)?.ok_or(Error::AllZero { arg })?;
        Ok(Discrete2D {
            marginal,
            cols,
            weights: copy,
            cdf,
            guide,
            rows: spans,
        })
    }

    /// The flat tables as slices.
    #[inline(always)]
    fn tables(&self) -> Rows<'_> {
        Rows {
            cols: self.cols,
            weights: &self.weights,
            cdf: &self.cdf,
            guide: &self.guide,
            rows: &self.rows,
        }
    }

    /// `(rows, cols)`.
    pub fn shape(&self) -> (usize, usize) {
        (self.rows.len(), self.cols)
    }

    /// The sum of all weights.
    pub fn sum(&self) -> f64 {
        self.marginal.sum()
    }

    /// The marginal distribution of rows (weights: the row sums).
    pub fn marginal(&self) -> &Discrete1D {
        &self.marginal
    }

    /// The conditional distribution of columns in `row` (`None` for a row
    /// of weight 0).
    pub(crate) fn conditional(&self, row: usize) -> Option<Search<'_>> {
        self.tables().search(row)
    }

    /// The weights as given, row after row.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The weight of cell `(row, col)` as given (0 outside the table).
    pub fn weight(&self, row: usize, col: usize) -> f64 {
        if row < self.rows.len() && col < self.cols {
            self.weights[row * self.cols + col]
        } else {
            0.0
        }
    }

    /// Probability of cell `(row, col)`: `w / Σw` (0 outside the table).
    pub fn pmf(&self, row: usize, col: usize) -> f64 {
        self.weight(row, col) / self.sum()
    }

    /// A cell `(row, col)` drawn with probability `pmf`; `u` in `[0, 1]²`.
    #[inline]
    pub fn sample<F: Real>(&self, u: [F; 2]) -> (usize, usize) {
        self.sample_reuse(u).0
    }

    /// The cell as [`Discrete2D::sample`], and `u` rescaled within the
    /// chosen row and column shares to `[0, 1)²` (see
    /// [`Discrete1D::sample_reuse`]).
    #[inline]
    pub fn sample_reuse<F: Real>(&self, u: [F; 2]) -> ((usize, usize), [F; 2]) {
        let (row, u_row) = self.marginal.sample_reuse(u[1]);
        // The marginal never draws a row of weight 0.
        match self.conditional(row) {
            Some(conditional) => {
                let (col, u_col) = conditional.sample_reuse(u[0]);
                ((row, col), [u_col, u_row])
            }
            None => ((row, 0), [u[0], u_row]),
        }
    }

    /// `out[i] = sample_reuse(us[i])` for a batch, in groups: the rows of a
    /// group searched side by side and their rescaled `u`, then the
    /// columns, each in its row's tables, and theirs. Each step is a loop
    /// over the group at SIMD width, its table reads by gathers, so that
    /// the cache misses of a group overlap.
    pub fn sample_reuse_into<F: Real>(&self, us: &[[F; 2]], out: &mut [((usize, usize), [F; 2])]) {
        simd::dispatch(
            #[inline(always)]
            |_| self.sample_groups(us, out),
        )
    }

    /// `out[i] = sample(us[i])` for a batch: the draws of
    /// [`Discrete2D::sample_reuse_into`] without their rescaled numbers
    /// (two divisions and a load fewer per draw), compiled for the widest
    /// vector unit.
    pub fn sample_into<F: Real>(&self, us: &[[F; 2]], out: &mut [(usize, usize)]) {
        simd::dispatch(
            #[inline(always)]
            |_| {
                let mut drawn = [((0, 0), [F::zero(); 2]); GROUP];
                for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
                    let drawn = &mut drawn[..us.len()];
                    self.groups(us, drawn, false);
                    for (o, d) in out.iter_mut().zip(drawn.iter()) {
                        *o = d.0;
                    }
                }
            },
        )
    }

    /// [`Discrete2D::sample_reuse_into`] without the dispatch, for the batch
    /// loops of samplers built on this table (which dispatch themselves).
    #[inline(always)]
    pub(crate) fn sample_groups<F: Real>(
        &self,
        us: &[[F; 2]],
        out: &mut [((usize, usize), [F; 2])],
    ) {
        self.groups(us, out, true);
    }

    /// The steps of [`Discrete2D::sample_groups`]; without `rescale`, each
    /// draw's numbers are left as given (for [`Discrete2D::sample_into`]).
    #[inline(always)]
    fn groups<F: Real>(&self, us: &[[F; 2]], out: &mut [((usize, usize), [F; 2])], rescale: bool) {
        let marginal = self.marginal.search();
        let tables = self.tables();
        let store = tables.store();
        let mut lanes = Lanes::new();
        let (mut rows, mut cols) = ([0; GROUP], [0; GROUP]);
        let (mut u_row, mut u_col) = ([F::zero(); GROUP], [F::zero(); GROUP]);
        for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
            let n = us.len();
            let row_draw = {
                #[inline(always)]
                |k: usize| Some((marginal, us[k][1].f64()))
            };
            search_group(n, &marginal, row_draw, (&mut lanes, rescale), &mut rows);
            for ((r, c), u) in u_row.iter_mut().zip(u_col.iter_mut()).zip(us) {
                (*c, *r) = (u[0], u[1]);
            }
            if rescale {
                lanes.rescale(&mut u_row);
            }
            // Each row's search is found by arithmetic on its index.
            let col_draw = {
                #[inline(always)]
                |k: usize| Some((tables.search(rows[k] as usize)?, us[k][0].f64()))
            };
            search_group(n, &store, col_draw, (&mut lanes, rescale), &mut cols);
            if rescale {
                lanes.rescale(&mut u_col);
            }
            for (k, o) in out.iter_mut().enumerate() {
                *o = ((rows[k] as usize, cols[k] as usize), [u_col[k], u_row[k]]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values_as_mitsuba() {
        // Mitsuba 3: DiscreteDistribution2D([[1, 2, 3], [4, 5, 6]]).sample(u)
        // gives Point2u (col, row).
        let d = Discrete2D::new(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 2, 3).unwrap();
        assert_eq!(d.sample([0.1, 0.1]), (0, 0));
        assert_eq!(d.sample([0.9, 0.1]), (0, 2));
        assert_eq!(d.sample([0.1, 0.9]), (1, 0));
        assert_eq!(d.sample([0.9, 0.9]), (1, 2));
        assert_eq!(d.sample([0.5, 0.5]), (1, 1));
        assert!((d.pmf(1, 2) - 6.0 / 21.0).abs() < 1e-15);
    }

    #[test]
    fn batch_sampling_agrees_with_single_draws() {
        // Rows of weight 0, long rows (guided) and a batch not a multiple of
        // GROUP.
        let (rows, cols) = (7, 300);
        let w: Vec<f64> = (0..rows * cols)
            .map(|i| {
                if i / cols == 2 {
                    0.0
                } else {
                    ((i * 17) % 5) as f64
                }
            })
            .collect();
        let d = Discrete2D::new(&w, rows, cols).unwrap();
        let us: Vec<[f64; 2]> = (0..=500)
            .map(|k| [(k as f64 * 0.618_033_988_749_895).fract(), k as f64 / 500.0])
            .collect();
        let mut out = vec![((0, 0), [0.0; 2]); us.len()];
        d.sample_reuse_into(&us, &mut out);
        let mut cells = vec![(0, 0); us.len()];
        d.sample_into(&us, &mut cells);
        for ((&u, &o), &c) in us.iter().zip(&out).zip(&cells) {
            assert_eq!(o, d.sample_reuse(u), "u = {u:?}");
            assert_eq!(c, d.sample(u), "u = {u:?}");
        }
    }

    #[test]
    fn a_window_past_its_row_is_not_read_into_the_next() {
        // Row 0's last guide cell starts at its last entry, whose window
        // runs into row 1, whose running sums (1, 2, 102, ...) straddle
        // the value: read as row 0's, they would answer past the row.
        let cols = 64;
        let mut w = vec![1.0; 2 * cols];
        w[cols - 1] = 10.0;
        w[cols + 2] = 100.0;
        let d = Discrete2D::new(&w, 2, cols).unwrap();
        let us: Vec<[f64; 2]> = (0..=2000).map(|k| [k as f64 / 2000.0, 0.1]).collect();
        let mut cells = vec![(0, 0); us.len()];
        d.sample_into(&us, &mut cells);
        for (&u, &c) in us.iter().zip(&cells) {
            assert_eq!(c, (0, linear(&w[..cols], u[0])), "u = {u:?}");
        }
    }

    #[test]
    fn a_rows_first_entry_is_rescaled_from_zero_not_the_row_before() {
        // Each row's first entry holds most of its weight, and each row
        // outweighs the one before: the running sum before a row's first
        // entry is 0, not the last sum of the row before (read past the
        // row's start, it lies below the value and would settle the draw
        // with a wrong rescaled u).
        let cols = 80;
        let w: Vec<f64> = (0..4 * cols)
            .map(|i| match i % cols {
                0 => 50.0 * 10f64.powi((i / cols) as i32),
                _ => 1.0,
            })
            .collect();
        let d = Discrete2D::new(&w, 4, cols).unwrap();
        let us: Vec<[f64; 2]> = (0..=2000)
            .map(|k| {
                [
                    k as f64 / 2000.0,
                    (k as f64 * 0.618_033_988_749_895).fract(),
                ]
            })
            .collect();
        let mut out = vec![((0, 0), [0.0; 2]); us.len()];
        d.sample_reuse_into(&us, &mut out);
        for (&u, &(cell, r)) in us.iter().zip(&out) {
            let (single_cell, single) = d.sample_reuse(u);
            assert_eq!(cell, single_cell, "u = {u:?}");
            assert_eq!(r.map(f64::to_bits), single.map(f64::to_bits), "u = {u:?}");
        }
    }

    /// The reference: `C_{i−1} < u·Σw ≤ C_i` by a linear scan of running
    /// sums taken in order, among the entries of positive weight.
    fn linear(weights: &[f64], u: f64) -> usize {
        let value = u * weights.iter().sum::<f64>();
        let positive: Vec<usize> = (0..weights.len()).filter(|&i| weights[i] > 0.0).collect();
        let below = |&i: &usize| weights[..=i].iter().sum::<f64>() < value;
        positive[positive.partition_point(below).min(positive.len() - 1)]
    }

    proptest::proptest! {
        #[test]
        fn draws_agree_with_a_linear_scan(
            cols in 1..300usize,
            cells in proptest::collection::vec(
                proptest::prop_oneof![proptest::strategy::Just(0.0), 0.0..10.0f64], 1..1500),
            us in proptest::collection::vec([0.0..=1.0f64, 0.0..=1.0f64], 40),
        ) {
            // Long rows (guided, searched in windows near their ends), rows
            // and runs of weight 0.
            let rows = cells.len().div_ceil(cols);
            let mut w = cells.clone();
            w.resize(rows * cols, 0.0);
            let Ok(d) = Discrete2D::new(&w, rows, cols) else { return Ok(()) };
            let sums: Vec<f64> = w.chunks(cols).map(|r| r.iter().sum()).collect();
            let us: Vec<[f64; 2]> = us.into_iter().chain([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]]).collect();
            let mut batch = vec![((0, 0), [0.0; 2]); us.len()];
            d.sample_reuse_into(&us, &mut batch);
            for (&u, &b) in us.iter().zip(&batch) {
                let row = linear(&sums, u[1]);
                let col = linear(&w[row * cols..(row + 1) * cols], u[0]);
                proptest::prop_assert_eq!(d.sample(u), (row, col), "u = {:?}", u);
                proptest::prop_assert_eq!(b, d.sample_reuse(u));
            }
        }
    }

    #[test]
    fn guided_rows_and_marginal_agree_with_a_linear_scan() {
        // Both the marginal and the rows guided (at least 64 entries), with
        // rows of weight 0, runs of zeros and a few heavy cells.
        let (rows, cols) = (90, 130);
        let w: Vec<f64> = (0..rows * cols)
            .map(|i| match (i / cols, (i * 7919) % 23) {
                (r, _) if r % 11 == 4 => 0.0,
                (_, 0) => 500.0,
                (_, k) if k < 9 => 0.0,
                (_, k) => k as f64,
            })
            .collect();
        let d = Discrete2D::new(&w, rows, cols).unwrap();
        let sums: Vec<f64> = w.chunks(cols).map(|r| r.iter().sum()).collect();
        let us: Vec<[f64; 2]> = (0..=4000)
            .map(|k| {
                [
                    (k as f64 * 0.618_033_988_749_895).fract(),
                    k as f64 / 4000.0,
                ]
            })
            .collect();
        let mut batch = vec![((0, 0), [0.0; 2]); us.len()];
        d.sample_reuse_into(&us, &mut batch);
        for (&u, &b) in us.iter().zip(&batch) {
            let row = linear(&sums, u[1]);
            let col = linear(&w[row * cols..(row + 1) * cols], u[0]);
            assert_eq!(b.0, (row, col), "u = {u:?}");
            assert_eq!(b, d.sample_reuse(u));
        }
    }

    #[test]
    fn zero_rows_and_cells_are_never_drawn() {
        let d = Discrete2D::new(&[0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0], 3, 3).unwrap();
        for u in [[0.0, 0.0], [1.0, 1.0], [0.5, 0.0], [0.0, 1.0]] {
            assert_eq!(d.sample(u), (1, 1));
        }
    }

    #[test]
    fn errors_name_row_and_column() {
        let e = Discrete2D::new(&[1.0, 2.0, 3.0, -4.0], 2, 2).unwrap_err();
        assert_eq!(
            e.to_string(),
            "weights[1, 1] = -4: weights must be finite and >= 0"
        );
        assert!(matches!(
            Discrete2D::new(&[0.0; 4], 2, 2),
            Err(Error::AllZero { .. })
        ));
        assert!(matches!(
            Discrete2D::new(&[1.0; 3], 2, 2),
            Err(Error::Shape { .. })
        ));
        assert!(Discrete2D::new(&[], 0, 3).is_err());
    }
}

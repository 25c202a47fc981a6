//! [`Discrete2D`]: a discrete distribution over the cells of a table.

use super::{Discrete1D, GROUP, check_weights};
use crate::error::{Error, Result};
use crate::math::Real;
use crate::parallel;
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
#[derive(Clone, Debug)]
pub struct Discrete2D {
    marginal: Discrete1D,
    /// One conditional per row; `None` for rows of weight 0 (never drawn).
    conditionals: Vec<Option<Discrete1D>>,
    cols: usize,
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
        if rows > super::MAX_ENTRIES || cols > super::MAX_ENTRIES {
            return Err(Error::TooLarge {
                arg,
                len: rows.max(cols),
                max: super::MAX_ENTRIES,
            });
        }
        // Rows are independent: build them on all cores (large tables only).
        let rows_of = || -> Vec<Option<Discrete1D>> {
            if weights.len() < 1 << 16 {
                weights
                    .chunks(cols_nz)
                    .map(Discrete1D::from_checked)
                    .collect()
            } else {
                weights
                    .par_chunks(cols_nz)
                    .map(Discrete1D::from_checked)
                    .collect()
            }
        };
        let conditionals = parallel::install(rows_of)?;
        let row_sums: Vec<f64> = conditionals
            .iter()
            .map(|c| c.as_ref().map_or(0.0, Discrete1D::sum))
            .collect();
        let marginal = Discrete1D::from_checked(&row_sums).ok_or(Error::AllZero { arg })?;
        Ok(Discrete2D {
            marginal,
            conditionals,
            cols,
        })
    }

    /// `(rows, cols)`.
    pub fn shape(&self) -> (usize, usize) {
        (self.conditionals.len(), self.cols)
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
    pub fn conditional(&self, row: usize) -> Option<&Discrete1D> {
        self.conditionals.get(row).and_then(Option::as_ref)
    }

    /// The weight of cell `(row, col)` as given (0 outside the table).
    pub fn weight(&self, row: usize, col: usize) -> f64 {
        self.conditional(row).map_or(0.0, |c| c.weight(col))
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
        match &self.conditionals[row] {
            Some(conditional) => {
                let (col, u_col) = conditional.sample_reuse(u[0]);
                ((row, col), [u_col, u_row])
            }
            None => ((row, 0), [u[0], u_row]),
        }
    }

    /// `out[i] = sample_reuse(us[i])` for a batch, in groups whose steps are
    /// interleaved as [`Discrete1D::sample_into`]'s: the marginal's guide
    /// cells, its brackets, the rows (and the conditionals' guide cells),
    /// their brackets, the columns (prefetching their weights), then the
    /// rescaled `u` of each column; the cache misses of a group overlap.
    pub fn sample_reuse_into<F: Real>(&self, us: &[[F; 2]], out: &mut [((usize, usize), [F; 2])]) {
        let marginal = self.marginal.search();
        for (us, out) in us.chunks(GROUP).zip(out.chunks_mut(GROUP)) {
            let mut cells = [0; GROUP];
            for (k, u) in cells.iter_mut().zip(us) {
                *k = marginal.locate(u[1].f64());
            }
            for &k in &cells[..us.len()] {
                marginal.prefetch_bracket(k);
            }
            for ((o, u), k) in out.iter_mut().zip(us).zip(&mut cells) {
                let (row, u_row) = marginal.index_reuse(u[1], *k);
                *o = ((row, 0), [u[0], u_row]);
                if let Some(c) = &self.conditionals[row] {
                    *k = c.search().locate(u[0].f64());
                }
            }
            for (o, &k) in out.iter().zip(&cells) {
                if let Some(c) = &self.conditionals[o.0.0] {
                    c.search().prefetch_bracket(k);
                }
            }
            for ((o, u), &k) in out.iter_mut().zip(us).zip(&cells) {
                // The marginal never draws a row of weight 0.
                if let Some(c) = &self.conditionals[o.0.0] {
                    let search = c.search();
                    o.0.1 = search.index(u[0].f64(), k);
                    search.prefetch_weight(o.0.1);
                }
            }
            for (o, u) in out.iter_mut().zip(us) {
                if let Some(c) = &self.conditionals[o.0.0] {
                    o.1[0] = c.search().rescale(u[0], o.0.1);
                }
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
        for (&u, &o) in us.iter().zip(&out) {
            assert_eq!(o, d.sample_reuse(u), "u = {u:?}");
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

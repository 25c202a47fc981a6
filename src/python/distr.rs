//! `mcsample.Discrete1D`, `AliasTable` and `Discrete2D`: batched bindings
//! of [`crate::distr`]'s discrete tables (the piecewise densities are in
//! [`super::piecewise`]). Tables are built with the GIL released; every `u`
//! is checked to lie in [0, 1] in the sampling pass.

use super::arrays::{Check, Indices, Points, Table, output, with_precision, writable};
use super::batch::{map_chunks, map_chunks2, map_indices};
use super::parallel::detached;
use super::pickle::reduce;
use super::records::record;
use crate::distr::{self, GROUP};
use crate::python::{Obj, Out};
use crate::simd;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// A `(rows, cols)` array of the row-major `values`.
pub(super) fn table_2d<'py>(
    py: Python<'py>,
    values: &[f64],
    (rows, cols): (usize, usize),
) -> PyResult<Obj<'py>> {
    Ok(PyArray1::from_slice(py, values)
        .reshape([rows, cols])?
        .into_any())
}

/// The array of `f(k)` for each flat (row-major) index `k` of `shape`,
/// written into `out` when it is given.
fn per_index<'py>(
    py: Python<'py>,
    shape: &[usize],
    out: Out<'_, 'py>,
    f: impl Fn(usize) -> f64,
) -> PyResult<Obj<'py>> {
    let array = output::<f64>(py, shape, out, "out")?;
    {
        let mut guard = writable(&array)?;
        for (k, v) in guard.as_slice_mut()?.iter_mut().enumerate() {
            *v = f(k);
        }
    }
    Ok(array.into_array().into_any())
}

/// Draws per call of a table's batch draw in [`in_groups`]: each call
/// dispatches on the vector unit and sets up its groups' scratch columns,
/// which a call of one group of [`GROUP`] paid for every 64 draws.
const DRAWS_PER_CALL: usize = 16 * GROUP;

/// The batch draw `draw` of `inputs` (a table's own results,
/// [`DRAWS_PER_CALL`] at a time in a buffer on the stack), each result `r`
/// of input `k` handed to `write(k, r)`.
pub(super) fn in_groups<U: Copy, R: Copy + Default>(
    inputs: &[U],
    draw: impl Fn(&[U], &mut [R]),
    mut write: impl FnMut(usize, R),
) {
    let mut buffer = [R::default(); DRAWS_PER_CALL];
    for (g, group) in inputs.chunks(DRAWS_PER_CALL).enumerate() {
        let drawn = &mut buffer[..group.len()];
        draw(group, drawn);
        for (k, &r) in drawn.iter().enumerate() {
            write(g * DRAWS_PER_CALL + k, r);
        }
    }
}

/// [`in_groups`] into one array of rows: each call's results made rows by
/// `row` in a buffer on the stack and copied into `out` (as long as
/// `inputs`), with `stream` (for outputs of [`simd::STREAM_MIN_BYTES`] or
/// more) by non-temporal stores ([`simd::stream_copy_rows`]), which skip
/// reading each line of the output before writing it.
pub(super) fn in_groups_into<U: Copy, R: Copy + Default, T: Copy + Default, const M: usize>(
    (inputs, out): (&[U], &mut [[T; M]]),
    draw: impl Fn(&[U], &mut [R]),
    row: impl Fn(R) -> [T; M],
    stream: bool,
) {
    let mut buffer = [R::default(); DRAWS_PER_CALL];
    let simd::OnLines(rows) = &mut simd::OnLines([[T::default(); M]; DRAWS_PER_CALL]);
    for (group, out) in inputs
        .chunks(DRAWS_PER_CALL)
        .zip(out.chunks_mut(DRAWS_PER_CALL))
    {
        let (drawn, rows) = (&mut buffer[..group.len()], &mut rows[..group.len()]);
        draw(group, drawn);
        for (to, &r) in rows.iter_mut().zip(drawn.iter()) {
            *to = row(r);
        }
        if stream {
            simd::stream_copy_rows(out, rows);
        } else {
            out.copy_from_slice(rows);
        }
    }
    if stream {
        simd::store_fence();
    }
}

/// The Python methods of a 1D index table (`Discrete1D`, `AliasTable`):
/// the constructor, ``sample``, ``pmf``, ``sum``, ``len`` and the repr,
/// and the table's own methods given in `{ ... }`.
macro_rules! index_table_methods {
    ($py_type:ident, $table:ty, $name:literal, { $($extra:tt)* }) => {
        #[pymethods]
        impl $py_type {
            #[new]
            fn new(py: Python<'_>, weights: &Obj<'_>) -> PyResult<Self> {
                let w = Table::extract(weights, "weights", 1)?;
                let w = w.values();
                Ok(Self(detached(py, || <$table>::new(w))?))
            }

            /// Indices drawn from the distribution.
            ///
            /// Parameters
            /// ----------
            /// u : float or array_like, shape (N,), values in [0, 1]
            /// out : ndarray, optional, keyword only
            ///     Written with the result and returned (its shape and dtype).
            ///
            /// Returns
            /// -------
            /// ndarray, shape (N,) int64 (a scalar for a scalar u).
            #[pyo3(signature = (u, *, out = None))]
            fn sample<'py>(
                &self,
                py: Python<'py>,
                u: &Obj<'py>,
                out: Out<'_, 'py>,
            ) -> PyResult<Obj<'py>> {
                with_precision!(u, F => {
                    let u = Points::<F, 1>::extract(u, "u")?;
                    map_chunks(py, &u, Check::Unit, out, |u, out: &mut [[i64; 1]]| {
                        self.0.sample_into(u.as_flattened(), out.as_flattened_mut())
                    })
                })
            }

            /// Probabilities w[i] / sum of the indices ``i`` (all n when
            /// omitted).
            ///
            /// Parameters
            /// ----------
            /// i : int or array_like of int, shape (N,), optional
            /// out : ndarray, optional, keyword only
            ///     Written with the result and returned (its shape, float64).
            ///
            /// Returns
            /// -------
            /// ndarray, shape (N,) float64 (a scalar for a scalar i).
            #[pyo3(signature = (i = None, *, out = None))]
            fn pmf<'py>(
                &self,
                py: Python<'py>,
                i: Option<&Obj<'py>>,
                out: Out<'_, 'py>,
            ) -> PyResult<Obj<'py>> {
                let table = &self.0;
                match i {
                    None => per_index(py, &[table.len()], out, |k| table.pmf(k)),
                    Some(i) => {
                        let i = Indices::<1>::extract(i, "i", [table.len()])?;
                        map_indices(py, &i, out, |[k]| table.pmf(k))
                    }
                }
            }

            /// The sum of the weights (the normalisation constant).
            #[getter]
            fn sum(&self) -> f64 {
                self.0.sum()
            }

            fn __len__(&self) -> usize {
                self.0.len()
            }

            fn __repr__(&self) -> String {
                format!(concat!($name, "(n={}, sum={})"), self.0.len(), self.0.sum())
            }

            /// Pickles as the weights it was built from.
            fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
                let w = PyArray1::from_slice(slf.py(), slf.get().0.weights());
                reduce(slf.as_any(), None, PyTuple::new(slf.py(), [w])?, None)
            }

            $($extra)*
        }
    };
}

record! {
    /// Draws of ``Discrete1D.sample_reuse`` / ``Discrete2D.sample_reuse``;
    /// unpacks as ``index, u``.
    PyReusedSample, "ReusedSample", "mcsample._core", {
        /// The indices, (N,) int64, or (N, 2) (row, col).
        index,
        /// u rescaled within the chosen entry's share to [0, 1), a fresh
        /// uniform number: (N,) or (N, 2), in u's precision.
        u,
    }
}

/// A discrete distribution over 0..n-1 proportional to ``weights``,
/// sampled by inverting its CDF (binary search on running sums accumulated
/// in float64, in order within blocks of 8000 entries, narrowed by a guide
/// table).
///
/// ``sample(u)`` returns the index i with C[i-1] < u * sum <= C[i], as
/// Mitsuba 3's ``DiscreteDistribution``; an entry of weight 0 is never
/// returned.
///
/// Parameters
/// ----------
/// weights : array_like, shape (n,)
///     Finite, >= 0, not all zero.
#[pyclass(module = "mcsample._core", name = "Discrete1D", frozen)]
pub struct PyDiscrete1D(distr::Discrete1D);

index_table_methods!(PyDiscrete1D, distr::Discrete1D, "Discrete1D", {
    /// Indices as ``sample``, and u rescaled within the chosen entry's share
    /// to [0, 1): (u * sum - C[i-1]) / (C[i] - C[i-1]) (the step of the
    /// running sums: w[i] up to their round-off), a fresh uniform number.
    ///
    /// Parameters
    /// ----------
    /// u : float or array_like, shape (N,), values in [0, 1]
    /// out : (ndarray, ndarray), optional, keyword only
    ///     Written with ``index`` and ``u`` and returned in the result.
    ///
    /// Returns
    /// -------
    /// ReusedSample: ``.index`` ndarray (N,) int64 and ``.u`` ndarray (N,)
    /// float of u's precision; unpacks as ``index, u``.
    #[pyo3(signature = (u, *, out = None))]
    fn sample_reuse<'py>(
        &self,
        py: Python<'py>,
        u: &Obj<'py>,
        out: Out<'_, 'py>,
    ) -> PyResult<PyReusedSample> {
        with_precision!(u, F => {
            let u = Points::<F, 1>::extract(u, "u")?;
            let kernel = |u: &[[F; 1]], index: &mut [[i64; 1]], rescaled: &mut [[F; 1]]| {
                let draw = |u: &[F], out: &mut [(usize, F)]| self.0.sample_reuse_into(u, out);
                in_groups(u.as_flattened(), draw, |k, (i, r)| {
                    (index[k], rescaled[k]) = ([i as i64], [r]);
                });
            };
            let (index, u) = map_chunks2(py, &u, Check::Unit, (out, "index, u"), kernel)?;
            Ok(PyReusedSample::new(index, u))
        })
    }

    /// The normalised CDF, shape (n,): P(index <= i); the last entry is 1.
    #[getter]
    fn cdf<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        per_index(py, &[self.0.len()], None, |k| self.0.cdf(k))
    }
});

/// An alias table (Walker's method, built by a parallel sweep): O(1)
/// sampling over 0..n-1 proportional to ``weights``, with one uniform number
/// per sample. Same probabilities as ``Discrete1D`` (each cell's threshold
/// is rounded to 32 bits), a different map from u to indices; an entry of
/// weight 0 is never returned. The part of u·n past its cell decides between
/// the cell and its alias: pass float64 u for large tables (float32 leaves
/// it 23 - log2(n) bits).
///
/// Parameters
/// ----------
/// weights : array_like, shape (n,)
///     Finite, >= 0, not all zero.
#[pyclass(module = "mcsample._core", name = "AliasTable", frozen)]
pub struct PyAliasTable(distr::AliasTable);

index_table_methods!(PyAliasTable, distr::AliasTable, "AliasTable", {});

/// A discrete distribution over the cells (row, col) of a table,
/// proportional to ``weights``: a row from the marginal (row sums) by
/// u[:, 1], then a column from that row's conditional by u[:, 0] — the
/// assignment of Mitsuba 3's ``DiscreteDistribution2D`` (whose results are
/// (col, row)).
///
/// Parameters
/// ----------
/// weights : array_like, shape (rows, cols)
///     Finite, >= 0, not all zero.
#[pyclass(module = "mcsample._core", name = "Discrete2D", frozen)]
pub struct PyDiscrete2D {
    table: distr::Discrete2D,
    /// (rows, cols) of the table.
    #[pyo3(get)]
    shape: (usize, usize),
    /// The sum of the weights.
    #[pyo3(get)]
    sum: f64,
}

#[pymethods]
impl PyDiscrete2D {
    #[new]
    fn new(py: Python<'_>, weights: &Obj<'_>) -> PyResult<Self> {
        let t = Table::extract(weights, "weights", 2)?;
        let (w, rows, cols) = (t.values(), t.shape[0], t.shape[1]);
        let table = detached(py, || distr::Discrete2D::new(w, rows, cols))?;
        let sum = table.sum();
        Ok(Self {
            table,
            shape: (rows, cols),
            sum,
        })
    }

    /// Cells drawn from the distribution.
    ///
    /// Parameters
    /// ----------
    /// u : array_like, shape (N, 2) or (2,), values in [0, 1]
    /// out : ndarray, optional, keyword only
    ///     Written with the result and returned (its shape and dtype).
    ///
    /// Returns
    /// -------
    /// ndarray, shape (N, 2) or (2,) int64: (row, col).
    #[pyo3(signature = (u, *, out = None))]
    fn sample<'py>(&self, py: Python<'py>, u: &Obj<'py>, out: Out<'_, 'py>) -> PyResult<Obj<'py>> {
        with_precision!(u, F => {
            let u = Points::<F, 2>::extract(u, "u")?;
            let stream = u.n.saturating_mul(size_of::<[i64; 2]>()) >= simd::STREAM_MIN_BYTES;
            map_chunks(py, &u, Check::Unit, out, |u, cells: &mut [[i64; 2]]| {
                let draw = |u: &[[F; 2]], out: &mut [_]| self.table.sample_into(u, out);
                in_groups_into((u, cells), draw, |(r, c)| [r as i64, c as i64], stream);
            })
        })
    }

    /// Cells as ``sample``, and u rescaled within the chosen row and column
    /// shares to [0, 1)^2.
    ///
    /// Parameters
    /// ----------
    /// u : array_like, shape (N, 2) or (2,), values in [0, 1]
    /// out : (ndarray, ndarray), optional, keyword only
    ///     Written with ``index`` and ``u`` and returned in the result.
    ///
    /// Returns
    /// -------
    /// ReusedSample: ``.index`` ndarray (N, 2) int64 (row, col) and ``.u``
    /// ndarray (N, 2) float of u's precision; unpacks as ``index, u``.
    #[pyo3(signature = (u, *, out = None))]
    fn sample_reuse<'py>(
        &self,
        py: Python<'py>,
        u: &Obj<'py>,
        out: Out<'_, 'py>,
    ) -> PyResult<PyReusedSample> {
        with_precision!(u, F => {
            let u = Points::<F, 2>::extract(u, "u")?;
            let kernel = |u: &[[F; 2]], index: &mut [[i64; 2]], rescaled: &mut [[F; 2]]| {
                let draw = |u: &[[F; 2]], out: &mut [_]| self.table.sample_reuse_into(u, out);
                in_groups(u, draw, |k, ((r, c), v)| {
                    (index[k], rescaled[k]) = ([r as i64, c as i64], v);
                });
            };
            let (index, u) = map_chunks2(py, &u, Check::Unit, (out, "index, u"), kernel)?;
            Ok(PyReusedSample::new(index, u))
        })
    }

    /// Probabilities w[row, col] / sum of the cells ``idx`` (rows of
    /// (row, col)); the whole (rows, cols) table when omitted.
    ///
    /// Parameters
    /// ----------
    /// idx : array_like of int, shape (N, 2) or (2,), optional
    /// out : ndarray, optional, keyword only
    ///     Written with the result and returned (its shape, float64).
    ///
    /// Returns
    /// -------
    /// ndarray, shape (N,) float64 (a scalar for one cell).
    #[pyo3(signature = (idx = None, *, out = None))]
    fn pmf<'py>(
        &self,
        py: Python<'py>,
        idx: Option<&Obj<'py>>,
        out: Out<'_, 'py>,
    ) -> PyResult<Obj<'py>> {
        let (rows, cols) = self.table.shape();
        match idx {
            None => per_index(py, &[rows, cols], out, |k| {
                self.table.pmf(k / cols, k % cols)
            }),
            Some(idx) => {
                let idx = Indices::<2>::extract(idx, "idx", [rows, cols])?;
                map_indices(py, &idx, out, |[r, c]| self.table.pmf(r, c))
            }
        }
    }

    fn __repr__(&self) -> String {
        let (rows, cols) = self.shape;
        format!("Discrete2D(shape=({rows}, {cols}), sum={})", self.sum)
    }

    /// Pickles as the weights it was built from.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let this = slf.get();
        let w = table_2d(slf.py(), this.table.weights(), this.shape)?;
        reduce(slf.as_any(), None, PyTuple::new(slf.py(), [w])?, None)
    }
}

/// Registers the distribution classes in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyDiscrete1D>()?;
    m.add_class::<PyAliasTable>()?;
    m.add_class::<PyDiscrete2D>()?;
    m.add_class::<PyReusedSample>()?;
    Ok(())
}

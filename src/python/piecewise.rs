//! `mcsample.PiecewiseConstant1D` and `PiecewiseConstant2D`: batched
//! bindings of [`crate::distr`]'s piecewise-constant densities, drawn by the
//! core's grouped samplers (see [`super::distr`]).

use super::arrays::{Check, Points, Table, with_precision};
use super::batch::{map_chunks2, map_into};
use super::distr::{in_groups, table_2d};
use super::parallel::detached;
use super::pickle::reduce;
use super::records::record;
use crate::distr;
use crate::python::{Obj, Out};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

record! {
    /// Draws of ``PiecewiseConstant1D.sample`` / ``PiecewiseConstant2D.sample``;
    /// unpacks as ``x, pdf``.
    PyPiecewiseSample, "PiecewiseSample", "mcsample._core", {
        /// The points, (N,) on the interval or (N, 2) in the rectangle.
        x,
        /// Their densities, per unit length or area, (N,).
        pdf,
    }
}

/// A piecewise-constant density on [a, b]: n equal cells with densities
/// proportional to ``values``, sampled by inverting its piecewise-linear
/// CDF. p(x) = values[i] / (sum(values) * h) on cell i, h = (b - a) / n;
/// 0 outside [a, b]. Per unit length.
///
/// Parameters
/// ----------
/// values : array_like, shape (n,)
///     Finite, >= 0, not all zero.
/// a, b : float, keyword only
///     The interval, finite with a < b.
#[pyclass(module = "mcsample._core", name = "PiecewiseConstant1D", frozen)]
pub struct PyPiecewiseConstant1D(distr::PiecewiseConstant1D);

#[pymethods]
impl PyPiecewiseConstant1D {
    #[new]
    #[pyo3(signature = (values, *, a = 0.0, b = 1.0))]
    fn new(py: Python<'_>, values: &Obj<'_>, a: f64, b: f64) -> PyResult<Self> {
        let t = Table::extract(values, "values", 1)?;
        let v = t.values();
        Ok(Self(detached(py, || {
            distr::PiecewiseConstant1D::new(v, a, b)
        })?))
    }

    /// Points drawn from the density, and their densities.
    ///
    /// Parameters
    /// ----------
    /// u : float or array_like, shape (N,), values in [0, 1]
    /// out : (ndarray, ndarray), optional, keyword only
    ///     Written with ``x`` and ``pdf`` and returned in the result.
    ///
    /// Returns
    /// -------
    /// PiecewiseSample: ``.x`` and ``.pdf``, ndarrays of shape (N,) in u's
    /// precision (scalars for a scalar u), pdf per unit length; unpacks as
    /// ``x, pdf``.
    #[pyo3(signature = (u, *, out = None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        u: &Obj<'py>,
        out: Out<'_, 'py>,
    ) -> PyResult<PyPiecewiseSample> {
        with_precision!(u, F => {
            let u = Points::<F, 1>::extract(u, "u")?;
            let kernel = |u: &[[F; 1]], x: &mut [[F; 1]], pdf: &mut [[F; 1]]| {
                let draw = |u: &[F], out: &mut [(F, F)]| self.0.sample_into(u, out);
                in_groups(u.as_flattened(), draw, |k, (p, d)| (x[k], pdf[k]) = ([p], [d]));
            };
            let (x, pdf) = map_chunks2(py, &u, Check::Unit, (out, "x, pdf"), kernel)?;
            Ok(PyPiecewiseSample::new(x, pdf))
        })
    }

    /// The density at ``x`` (0 outside [a, b]), per unit length.
    ///
    /// Parameters
    /// ----------
    /// x : float or array_like, shape (N,)
    /// out : ndarray, optional, keyword only
    ///     Written with the result and returned (its shape and dtype).
    #[pyo3(signature = (x, *, out = None))]
    fn pdf<'py>(&self, py: Python<'py>, x: &Obj<'py>, out: Out<'_, 'py>) -> PyResult<Obj<'py>> {
        with_precision!(x, F => {
            let x = Points::<F, 1>::extract(x, "x")?;
            map_into(py, &x, Check::Finite, out, #[inline(always)] |x| [self.0.pdf(x[0])])
        })
    }

    /// The CDF P(X <= x): 0 below a, 1 above b.
    ///
    /// Parameters
    /// ----------
    /// x : float or array_like, shape (N,)
    /// out : ndarray, optional, keyword only
    ///     Written with the result and returned (its shape and dtype).
    #[pyo3(signature = (x, *, out = None))]
    fn cdf<'py>(&self, py: Python<'py>, x: &Obj<'py>, out: Out<'_, 'py>) -> PyResult<Obj<'py>> {
        with_precision!(x, F => {
            let x = Points::<F, 1>::extract(x, "x")?;
            map_into(py, &x, Check::Finite, out, #[inline(always)] |x| [self.0.cdf(x[0])])
        })
    }

    /// The u that ``sample`` maps to ``x`` (the CDF on [a, b]).
    ///
    /// Parameters
    /// ----------
    /// x : float or array_like, shape (N,), values in [a, b]
    /// out : ndarray, optional, keyword only
    ///     Written with the result and returned (its shape and dtype).
    ///
    /// Raises
    /// ------
    /// ValueError
    ///     For x outside [a, b], naming the first such index.
    #[pyo3(signature = (x, *, out = None))]
    fn invert<'py>(&self, py: Python<'py>, x: &Obj<'py>, out: Out<'_, 'py>) -> PyResult<Obj<'py>> {
        let (a, b) = self.0.domain();
        with_precision!(x, F => {
            let x = Points::<F, 1>::extract(x, "x")?;
            map_into(py, &x, Check::Within([[a, b], [a, b]]), out, #[inline(always)] |x| {
                [self.0.invert(x[0]).unwrap_or(0.0)]
            })
        })
    }

    /// The interval (a, b).
    #[getter]
    fn domain(&self) -> (f64, f64) {
        self.0.domain()
    }

    /// The integral of ``values`` over [a, b] (sum(values) * h).
    #[getter]
    fn integral(&self) -> f64 {
        self.0.integral()
    }

    fn __len__(&self) -> usize {
        self.0.table().len()
    }

    fn __repr__(&self) -> String {
        let (a, b) = self.0.domain();
        format!(
            "PiecewiseConstant1D(n={}, a={a}, b={b})",
            self.0.table().len()
        )
    }

    /// Pickles as the values and interval it was built from.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let py = slf.py();
        let this = &slf.get().0;
        let values = PyArray1::from_slice(py, this.table().weights());
        let (a, b) = this.domain();
        let kwargs = PyDict::new(py);
        kwargs.set_item("a", a)?;
        kwargs.set_item("b", b)?;
        reduce(
            slf.as_any(),
            None,
            PyTuple::new(py, [values])?,
            Some(kwargs),
        )
    }
}

/// A piecewise-constant density on the rectangle
/// ``domain = ((x0, x1), (y0, y1))``, constant on the cells of a
/// (rows, cols) grid with densities proportional to ``values[row, col]``
/// (rows along y, row 0 at y0; columns along x). Sampled by the marginal
/// along y (u[:, 1]) and the conditional along x (u[:, 0]). Per unit area.
///
/// Parameters
/// ----------
/// values : array_like, shape (rows, cols)
///     Finite, >= 0, not all zero.
/// domain : ((x0, x1), (y0, y1)), keyword only
///     Finite, with x0 < x1 and y0 < y1.
#[pyclass(module = "mcsample._core", name = "PiecewiseConstant2D", frozen)]
pub struct PyPiecewiseConstant2D(distr::PiecewiseConstant2D);

#[pymethods]
impl PyPiecewiseConstant2D {
    #[new]
    #[pyo3(signature = (values, *, domain = ((0.0, 1.0), (0.0, 1.0))))]
    fn new(py: Python<'_>, values: &Obj<'_>, domain: ((f64, f64), (f64, f64))) -> PyResult<Self> {
        let t = Table::extract(values, "values", 2)?;
        let (v, rows, cols) = (t.values(), t.shape[0], t.shape[1]);
        let d = [[domain.0.0, domain.0.1], [domain.1.0, domain.1.1]];
        Ok(Self(detached(py, || {
            distr::PiecewiseConstant2D::new(v, rows, cols, d)
        })?))
    }

    /// Points drawn from the density, and their densities.
    ///
    /// Parameters
    /// ----------
    /// u : array_like, shape (N, 2) or (2,), values in [0, 1]
    /// out : (ndarray, ndarray), optional, keyword only
    ///     Written with ``x`` and ``pdf`` and returned in the result.
    ///
    /// Returns
    /// -------
    /// PiecewiseSample: ``.x`` (N, 2) and ``.pdf`` (N,) in u's precision,
    /// pdf per unit area; unpacks as ``x, pdf``.
    #[pyo3(signature = (u, *, out = None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        u: &Obj<'py>,
        out: Out<'_, 'py>,
    ) -> PyResult<PyPiecewiseSample> {
        with_precision!(u, F => {
            let u = Points::<F, 2>::extract(u, "u")?;
            let kernel = |u: &[[F; 2]], x: &mut [[F; 2]], pdf: &mut [[F; 1]]| {
                let draw = |u: &[[F; 2]], out: &mut [([F; 2], F)]| self.0.sample_into(u, out);
                in_groups(u, draw, |k, (p, d)| (x[k], pdf[k]) = (p, [d]));
            };
            let (x, pdf) = map_chunks2(py, &u, Check::Unit, (out, "x, pdf"), kernel)?;
            Ok(PyPiecewiseSample::new(x, pdf))
        })
    }

    /// The density at ``xy`` (0 outside the rectangle), per unit area.
    ///
    /// Parameters
    /// ----------
    /// xy : array_like, shape (N, 2) or (2,)
    /// out : ndarray, optional, keyword only
    ///     Written with the result and returned (its shape and dtype).
    #[pyo3(signature = (xy, *, out = None))]
    fn pdf<'py>(&self, py: Python<'py>, xy: &Obj<'py>, out: Out<'_, 'py>) -> PyResult<Obj<'py>> {
        with_precision!(xy, F => {
            let xy = Points::<F, 2>::extract(xy, "xy")?;
            map_into(py, &xy, Check::Finite, out, #[inline(always)] |p| [self.0.pdf(p)])
        })
    }

    /// The u that ``sample`` maps to ``xy``: (conditional CDF along x in
    /// the point's row, marginal CDF along y).
    ///
    /// Parameters
    /// ----------
    /// xy : array_like, shape (N, 2) or (2,), inside the rectangle
    /// out : ndarray, optional, keyword only
    ///     Written with the result and returned (its shape and dtype).
    ///
    /// Raises
    /// ------
    /// ValueError
    ///     For a point outside the rectangle, naming the first such index.
    #[pyo3(signature = (xy, *, out = None))]
    fn invert<'py>(&self, py: Python<'py>, xy: &Obj<'py>, out: Out<'_, 'py>) -> PyResult<Obj<'py>> {
        let domain = self.0.domain();
        with_precision!(xy, F => {
            let xy = Points::<F, 2>::extract(xy, "xy")?;
            map_into(py, &xy, Check::Within(domain), out, #[inline(always)] |p| {
                self.0.invert(p).unwrap_or([0.0; 2])
            })
        })
    }

    /// ((x0, x1), (y0, y1)).
    #[getter]
    fn domain(&self) -> ((f64, f64), (f64, f64)) {
        let [[x0, x1], [y0, y1]] = self.0.domain();
        ((x0, x1), (y0, y1))
    }

    /// (rows, cols) of the grid.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        self.0.table().shape()
    }

    /// The integral of ``values`` over the rectangle.
    #[getter]
    fn integral(&self) -> f64 {
        self.0.integral()
    }

    fn __repr__(&self) -> String {
        let (rows, cols) = self.0.table().shape();
        format!(
            "PiecewiseConstant2D(shape=({rows}, {cols}), domain={:?})",
            self.0.domain()
        )
    }

    /// Pickles as the values and domain it was built from.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let py = slf.py();
        let this = &slf.get().0;
        let values = table_2d(py, this.table().weights(), this.table().shape())?;
        let [x, y] = this.domain();
        let kwargs = PyDict::new(py);
        kwargs.set_item("domain", ((x[0], x[1]), (y[0], y[1])))?;
        reduce(
            slf.as_any(),
            None,
            PyTuple::new(py, [values])?,
            Some(kwargs),
        )
    }
}

/// Registers the piecewise-constant densities and their sample record in
/// module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyPiecewiseConstant1D>()?;
    m.add_class::<PyPiecewiseConstant2D>()?;
    m.add_class::<PyPiecewiseSample>()?;
    Ok(())
}

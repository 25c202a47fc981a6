//! Array conventions of every binding, written once: conversion, checks and
//! allocation (the loops that fill the arrays are in [`super::batch`]).
//!
//! - any array-like is accepted (lists, ints, float16, non-contiguous views);
//! - float32 input is computed and returned in float32, anything else in
//!   float64 ([`with_precision!`]);
//! - batches are sample-major `(N, K)`; a single `(K,)` point (or a scalar
//!   for `K = 1`) gives an unbatched result, and in a pair of inputs a
//!   single point or a single row serves every row of the other;
//! - shape and value errors name the argument and the first offending index;
//! - outputs are fresh numpy arrays (over recycled memory when large:
//!   [`fresh`]), or the caller's `out` ([`output`]).

use super::args::type_name;
use super::c_order;
use crate::alloc;
use crate::buffer::Buffer;
use crate::error::{Error, shape_str};
use crate::math::Real;
use crate::python::{Obj, Out};
use numpy::{AllowTypeChange, Element, PyArrayDescrMethods, PyArrayDyn, PyArrayLikeDyn};
use numpy::{PyArrayMethods, PyReadwriteArrayDyn, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyMemoryError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// A float type the bindings compute in: `f32` or `f64`, readable from
/// Python and storable in numpy arrays.
pub trait PyFloat: Element + Real + bytemuck::Pod + for<'a, 'py> FromPyObject<'a, 'py> {}
impl PyFloat for f32 {}
impl PyFloat for f64 {}

/// Whether `ob` is a float32 array or numpy float32 scalar.
pub fn is_float32(ob: &Obj<'_>) -> bool {
    ob.getattr(pyo3::intern!(ob.py(), "dtype"))
        .ok()
        .and_then(|d| d.cast_into::<numpy::PyArrayDescr>().ok())
        .is_some_and(|d| d.is_equiv_to(&numpy::dtype::<f32>(ob.py())))
}

/// Evaluates `$body` with the type alias `$F` set to `f32` if `$ob` is
/// float32 data, else to `f64`: one generic kernel, two precisions.
macro_rules! with_precision {
    ($ob:expr, $F:ident => $body:expr) => {
        if $crate::python::arrays::is_float32($ob) {
            type $F = f32;
            $body
        } else {
            type $F = f64;
            $body
        }
    };
}
pub(crate) use with_precision;

/// What every input value must satisfy.
#[derive(Clone, Copy, Debug)]
pub enum Check {
    /// In the closed unit interval (uniform samples `u`).
    Unit,
    /// Finite (points, directions).
    Finite,
    /// Component `k` in the closed interval `bounds[k]` (points of a
    /// rectangle or, for one component, an interval).
    Within([[f64; 2]; 2]),
    /// A density: `>= 0`, possibly infinite (a delta), not NaN.
    Density,
}

impl Check {
    /// Whether component `k` of a point may be `x`.
    #[inline(always)]
    fn holds<F: Real>(self, k: usize, x: F) -> bool {
        match self {
            Check::Unit => x >= F::zero() && x <= F::one(),
            Check::Finite => x.is_finite(),
            Check::Within(bounds) => {
                let [lo, hi] = bounds[k.min(1)];
                x.f64() >= lo && x.f64() <= hi
            }
            Check::Density => x >= F::zero(),
        }
    }

    /// Whether every component of `point` passes.
    #[inline(always)]
    pub fn holds_all<F: Real, const K: usize>(self, point: &[F; K]) -> bool {
        point
            .iter()
            .enumerate()
            .fold(true, |acc, (k, &v)| acc & self.holds(k, v))
    }

    fn requirement(self, k: usize) -> String {
        match self {
            Check::Unit => "must lie in [0, 1]".into(),
            Check::Finite => "must be finite".into(),
            Check::Within(bounds) => {
                let [lo, hi] = bounds[k.min(1)];
                format!("must lie in [{lo}, {hi}]")
            }
            Check::Density => "a density must be >= 0 (inf allowed, NaN not)".into(),
        }
    }
}

/// The batch shape of a batch of `K`-vectors of `shape`: `(N,)` for
/// `(N, K)`, empty for a single `(K,)` point, or for `K = 1`, `(N,)` or
/// `()`; else the error naming `arg`.
fn batch_shape<const K: usize>(arg: &'static str, shape: &[usize]) -> PyResult<Vec<usize>> {
    match (K, shape) {
        (1, [] | [_]) => Ok(shape.to_vec()),
        (_, [k]) if *k == K => Ok(vec![]),
        // Leading axes, as numpy's ufuncs take them: (..., K).
        (_, [batch @ .., k]) if *k == K => Ok(batch.to_vec()),
        _ => {
            let expected = if K == 1 {
                "(N,) or ()".to_string()
            } else {
                format!("(N, {K}), (..., {K}) or ({K},)")
            };
            Err(Error::Shape {
                arg,
                expected,
                got: shape_str(shape),
            }
            .into())
        }
    }
}

/// The shape of a result with `m` values per point of a batch of shape
/// `batch` (`m = 1`: a scalar each).
pub fn result_shape(batch: &[usize], m: usize) -> Vec<usize> {
    let mut shape = batch.to_vec();
    if m != 1 {
        shape.push(m);
    }
    shape
}

/// Where the `i`-th point of a batch of shape `batch` sits, with its
/// component `k` when the points are vectors: `[i0, i1, k]`, `[i]`, or
/// empty for the one value of an unbatched scalar.
pub fn position(batch: &[usize], i: usize, k: Option<usize>) -> String {
    let mut index = vec![0; batch.len()];
    let mut rest = i;
    for (slot, &len) in index.iter_mut().zip(batch).rev() {
        *slot = rest % len.max(1);
        rest /= len.max(1);
    }
    let parts: Vec<String> = index.iter().chain(&k).map(|v| v.to_string()).collect();
    if parts.is_empty() {
        String::new()
    } else {
        format!("[{}]", parts.join(", "))
    }
}

/// The batch shape of the result of a pair of inputs of batch shapes `a`
/// and `b` (argument names `arg_a`, `arg_b`): a single point, or a batch of
/// one point, is used for every point of the other input; otherwise both
/// must have the same batch shape.
pub fn broadcast(
    (arg_a, a): (&'static str, &[usize]),
    (arg_b, b): (&'static str, &[usize]),
) -> PyResult<Vec<usize>> {
    let (n_a, n_b) = (a.iter().product::<usize>(), b.iter().product::<usize>());
    match (n_a == 1, n_b == 1) {
        (false, true) => Ok(a.to_vec()),
        (true, false) => Ok(b.to_vec()),
        (true, true) => Ok((if a.len() >= b.len() { a } else { b }).to_vec()),
        (false, false) if a == b => Ok(a.to_vec()),
        (false, false) if a.len() <= 1 && b.len() <= 1 => Err(Error::Rows {
            arg_a,
            rows_a: n_a,
            arg_b,
            rows_b: n_b,
        }
        .into()),
        (false, false) => Err(Error::Argument {
            arg: arg_b,
            message: format!(
                "{arg_a} has batch shape {} and {arg_b} {}: give both the same batch shape, \
                 or one of them as a single point (used for every point of the other)",
                shape_str(a),
                shape_str(b)
            ),
        }
        .into()),
    }
}

/// A batch of `K`-vectors read from an array-like: `(N, K)`, `(..., K)`
/// (any leading axes, as numpy's ufuncs) or `(K,)`, or for `K = 1`, `(N,)`
/// or a scalar.
pub struct Points<'py, F: Element + bytemuck::Pod, const K: usize> {
    array: PyArrayLikeDyn<'py, F, AllowTypeChange>,
    /// A C-ordered copy when the input is not contiguous.
    owned: Option<Buffer<F>>,
    /// Number of points.
    pub n: usize,
    /// The batch shape: the input's shape without its last axis (`(N,)`
    /// for `(N, K)`); empty for a single point given without a batch axis.
    pub batch: Vec<usize>,
    /// Argument name, for messages.
    pub arg: &'static str,
}

impl<'py, F: PyFloat, const K: usize> Points<'py, F, K> {
    /// Reads `ob` as points of dimension `K`.
    pub fn extract(ob: &Obj<'py>, arg: &'static str) -> PyResult<Self> {
        let array: PyArrayLikeDyn<'py, F, AllowTypeChange> =
            ob.extract().map_err(|e| not_numbers(ob.py(), arg, e))?;
        let batch = batch_shape::<K>(arg, array.shape())?;
        // Only C order can be read in place (a Fortran-ordered array is
        // contiguous too, in the wrong order): copy anything else once.
        let owned = if array.is_c_contiguous() {
            None
        } else {
            Some(c_order::copy_to_buffer(
                array.as_array(),
                "a copy of the points",
            )?)
        };
        Ok(Points {
            array,
            owned,
            n: batch.iter().product(),
            batch,
            arg,
        })
    }

    /// The points, one `[F; K]` each.
    pub fn rows(&self) -> &[[F; K]] {
        let flat = match &self.owned {
            Some(v) => v,
            None => self.array.as_slice().unwrap_or_default(),
        };
        flat.as_chunks::<K>().0
    }

    /// Shape of a result with `m` values per point (`m = 1`: a scalar each).
    pub fn out_shape(&self, m: usize) -> Vec<usize> {
        result_shape(&self.batch, m)
    }

    /// The error for the first value that fails `check`.
    pub fn invalid(&self, check: Check) -> PyErr {
        for (i, row) in self.rows().iter().enumerate() {
            if let Some(j) = (0..K).find(|&k| !check.holds(k, row[k])) {
                return Error::Element {
                    arg: self.arg,
                    index: position(&self.batch, i, (K > 1).then_some(j)),
                    value: row[j].f64(),
                    requirement: check.requirement(j),
                }
                .into();
            }
        }
        Error::Element {
            arg: self.arg,
            index: String::new(),
            value: f64::NAN,
            requirement: check.requirement(0),
        }
        .into()
    }
}

/// The error of an argument `arg` that does not convert to an array of
/// numbers: TypeError, except numpy's MemoryError (a conversion that needs
/// a copy too big for memory), which passes unchanged.
pub fn not_numbers(py: Python<'_>, arg: &str, e: PyErr) -> PyErr {
    if e.is_instance_of::<PyMemoryError>(py) {
        e
    } else {
        PyTypeError::new_err(format!("{arg} must be an array of numbers: {e}"))
    }
}

/// A fresh zeroed numpy array of `shape`, made by `numpy.zeros` (so that a
/// request too big for memory is numpy's MemoryError, or its ValueError
/// for a size beyond the address space, and untouched pages cost nothing).
pub fn zeros<'py, F: Element>(
    py: Python<'py>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<F>>> {
    if shape.len() > 32 {
        // rust-numpy reads at most 32 dimensions (numpy 2 allows 64).
        return Err(Error::Argument {
            arg: "shape",
            message: format!(
                "a result of {} dimensions: at most 32 are supported",
                shape.len()
            ),
        }
        .into());
    }
    let array = py
        .import("numpy")?
        .getattr("zeros")?
        .call1((PyTuple::new(py, shape)?, numpy::dtype::<F>(py)))?;
    Ok(array.cast_into::<PyArrayDyn<F>>()?)
}

/// A fresh numpy array of `shape` for a kernel that writes every element:
/// at least [`super::recycle::MIN_BYTES`], over recycled memory
/// ([`super::recycle`]: an earlier array's values until written), else
/// [`zeros`] (which refuses more than 32 dimensions, as rust-numpy does).
pub fn fresh<'py, F: Element + bytemuck::Pod>(
    py: Python<'py>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<F>>> {
    let bytes = shape
        .iter()
        .product::<usize>()
        .saturating_mul(size_of::<F>());
    if bytes >= super::recycle::MIN_BYTES && shape.len() <= 32 {
        super::recycle::array(py, shape)
    } else {
        zeros(py, shape)
    }
}

/// `array` as returned to Python: a numpy scalar when it is 0-d.
pub fn finish<'py, F: Element>(array: Bound<'py, PyArrayDyn<F>>) -> PyResult<Obj<'py>> {
    if array.ndim() == 0 {
        array.get_item(PyTuple::empty(array.py()))
    } else {
        Ok(array.into_any())
    }
}

/// An array results are written to ([`output`]): the caller's `out`, or
/// a fresh one.
pub struct Output<'py, T> {
    array: Bound<'py, PyArrayDyn<T>>,
    given: bool,
}

impl<'py, T> std::ops::Deref for Output<'py, T> {
    type Target = Bound<'py, PyArrayDyn<T>>;

    fn deref(&self) -> &Self::Target {
        &self.array
    }
}

impl<'py, T: Element> Output<'py, T> {
    /// The result as returned to Python: the caller's `out` itself, 0-d
    /// included (as numpy's ufuncs return theirs), else the fresh array
    /// through [`finish`] (a numpy scalar when 0-d).
    pub fn finish(self) -> PyResult<Obj<'py>> {
        if self.given {
            Ok(self.array.into_any())
        } else {
            finish(self.array)
        }
    }

    /// The array, whichever it is.
    pub fn into_array(self) -> Bound<'py, PyArrayDyn<T>> {
        self.array
    }
}

/// The array results go to: `out` (argument `arg`) when given, checked as
/// numpy's ufuncs check theirs (a numpy array of dtype `T` and of `shape`,
/// C-ordered and writeable; each failure says which), else a fresh one.
pub fn output<'py, T: Element + bytemuck::Pod>(
    py: Python<'py>,
    shape: &[usize],
    out: Out<'_, 'py>,
    arg: &'static str,
) -> PyResult<Output<'py, T>> {
    let Some(out) = out.filter(|o| !o.is_none()) else {
        return Ok(Output {
            array: fresh::<T>(py, shape)?,
            given: false,
        });
    };
    let array = out.cast::<PyUntypedArray>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{arg} must be a numpy array, got {}",
            type_name(out)
        ))
    })?;
    let (want, got) = (numpy::dtype::<T>(py), array.dtype());
    if !got.is_equiv_to(&want) {
        return Err(PyTypeError::new_err(format!(
            "{arg} must have dtype {want}, got {got}"
        )));
    }
    if array.shape() != shape {
        return Err(Error::Shape {
            arg,
            expected: format!("{} (a writeable C-ordered array)", shape_str(shape)),
            got: shape_str(array.shape()),
        }
        .into());
    }
    let problem = if !array.is_c_contiguous() {
        Some(format!(
            "{arg} must be C-ordered (C-contiguous, as np.empty makes it), not a view with other \
             strides"
        ))
    } else if !array
        .getattr(pyo3::intern!(py, "flags"))?
        .getattr(pyo3::intern!(py, "writeable"))?
        .extract::<bool>()?
    {
        Some(format!("{arg} is read-only (its flags.writeable is False)"))
    } else {
        None
    };
    if let Some(message) = problem {
        return Err(Error::Argument { arg, message }.into());
    }
    Ok(Output {
        array: array.cast::<PyArrayDyn<T>>()?.clone(),
        given: true,
    })
}

/// The arrays of an `out` that holds one array per result, as numpy's
/// ufuncs of several results take them: a tuple of `N` (the results named
/// by `names`, for the message), or none when `out` is omitted or None.
pub fn tuple_outputs<'py, const N: usize>(
    out: Out<'_, 'py>,
    names: &str,
) -> PyResult<[Option<Obj<'py>>; N]> {
    let Some(out) = out.filter(|o| !o.is_none()) else {
        return Ok(std::array::from_fn(|_| None));
    };
    let items = out.cast::<PyTuple>().ok().filter(|t| t.len() == N);
    let Some(items) = items else {
        let count = ["no", "one", "two", "three"]
            .get(N)
            .copied()
            .unwrap_or("several");
        return Err(PyTypeError::new_err(format!(
            "out must be a tuple of {count} arrays: ({names})"
        )));
    };
    let mut arrays: [Option<Obj<'py>>; N] = std::array::from_fn(|_| None);
    for (k, slot) in arrays.iter_mut().enumerate() {
        *slot = Some(items.get_item(k)?);
    }
    Ok(arrays)
}

/// Write access to an output array, which fails (rather than panics) when
/// an `out` array shares memory with an input or another output.
pub fn writable<'py, T: Element>(
    out: &Bound<'py, PyArrayDyn<T>>,
) -> PyResult<PyReadwriteArrayDyn<'py, T>> {
    out.try_readwrite().map_err(|_| {
        Error::Argument {
            arg: "out",
            message: "out must not share memory with an input array or another output".into(),
        }
        .into()
    })
}

/// Integer indices read from an array-like: `(N, K)` or `(K,)` (for
/// `K = 1`, `(N,)` or a scalar), each column `k` checked to lie in
/// `[0, bounds[k])`.
pub struct Indices<const K: usize> {
    /// The indices, one `[usize; K]` per point.
    pub rows: Vec<[usize; K]>,
    /// The batch shape; empty for a single point.
    pub batch: Vec<usize>,
}

impl<const K: usize> Indices<K> {
    /// Reads and checks `ob` (argument `arg`); floats raise TypeError, an
    /// index out of range (however large) ValueError naming its position.
    pub fn extract(ob: &Obj<'_>, arg: &'static str, bounds: [usize; K]) -> PyResult<Self> {
        let py = ob.py();
        let array = py
            .import(pyo3::intern!(py, "numpy"))?
            .call_method1(pyo3::intern!(py, "asarray"), (ob,))?;
        let dtype = array.getattr("dtype")?;
        let kind: String = dtype.getattr("kind")?.extract()?;
        let shape: Vec<usize> = array.getattr("shape")?.extract()?;
        let batch = batch_shape::<K>(arg, &shape)?;
        // Read every index exactly, whatever its integer type (an int too
        // large for int64 comes as an object array).
        let flat: Vec<i128> = match kind.as_str() {
            "i" => {
                let a: PyArrayLikeDyn<'_, i64, AllowTypeChange> = array.extract()?;
                alloc::collect(a.as_array().iter().map(|&v| i128::from(v)), "the indices")?
            }
            "u" => {
                let a: PyArrayLikeDyn<'_, u64, AllowTypeChange> = array.extract()?;
                alloc::collect(a.as_array().iter().map(|&v| i128::from(v)), "the indices")?
            }
            "O" => {
                let mut values = Vec::new();
                for v in array.call_method0("ravel")?.try_iter()? {
                    match v?.call_method0("__index__") {
                        // Beyond i128: out of range all the same.
                        Ok(int) => values.push(int.extract::<i128>().unwrap_or(i128::MAX)),
                        Err(_) => return Err(not_integers(arg, &dtype)),
                    }
                }
                values
            }
            _ => return Err(not_integers(arg, &dtype)),
        };
        let mut rows = alloc::with_capacity(flat.len() / K, "the indices")?;
        for (i, chunk) in flat.as_chunks::<K>().0.iter().enumerate() {
            let mut row = [0usize; K];
            for (k, (&v, &bound)) in chunk.iter().zip(&bounds).enumerate() {
                match usize::try_from(v) {
                    Ok(index) if index < bound => row[k] = index,
                    _ => {
                        let index = position(&batch, i, (K > 1).then_some(k));
                        return Err(match i64::try_from(v) {
                            Ok(value) => Error::Index {
                                arg,
                                index,
                                value,
                                len: bound,
                            },
                            Err(_) => Error::Integer {
                                arg,
                                value: array
                                    .call_method0("ravel")?
                                    .get_item(i * K + k)?
                                    .to_string(),
                                requirement: format!("must be an index in [0, {bound})"),
                            },
                        }
                        .into());
                    }
                }
            }
            rows.push(row);
        }
        Ok(Indices { rows, batch })
    }
}

/// The TypeError for indices `arg` given as an array of `dtype`.
fn not_integers(arg: &str, dtype: &Obj<'_>) -> PyErr {
    PyTypeError::new_err(format!(
        "{arg} must be integers, got an array of dtype {dtype}"
    ))
}

/// A table of weights read as float64 (converted only if it is not already
/// a C-ordered float64 array); `ndim` must be 1 or 2 as asked. The values
/// are checked by the core constructors.
pub struct Table<'py> {
    array: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    owned: Option<Buffer<f64>>,
    /// The table's shape.
    pub shape: Vec<usize>,
}

impl<'py> Table<'py> {
    /// Reads `ob` (argument `arg`).
    pub fn extract(ob: &Obj<'py>, arg: &'static str, ndim: usize) -> PyResult<Self> {
        let array: PyArrayLikeDyn<'py, f64, AllowTypeChange> =
            ob.extract().map_err(|e| not_numbers(ob.py(), arg, e))?;
        let shape = array.shape().to_vec();
        if shape.len() != ndim {
            return Err(Error::Shape {
                arg,
                expected: if ndim == 1 {
                    "(N,)".into()
                } else {
                    "(rows, cols)".into()
                },
                got: shape_str(&shape),
            }
            .into());
        }
        let owned = match array.is_c_contiguous() {
            true => None,
            false => Some(c_order::copy_to_buffer(
                array.as_array(),
                "a copy of the table",
            )?),
        };
        Ok(Table {
            array,
            owned,
            shape,
        })
    }

    /// The values in row-major order.
    pub fn values(&self) -> &[f64] {
        match &self.owned {
            Some(v) => v,
            None => self.array.as_slice().unwrap_or_default(),
        }
    }
}

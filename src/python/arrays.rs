//! Array conventions of every binding, written once:
//!
//! - any array-like is accepted (lists, ints, float16, non-contiguous views);
//! - float32 input is computed and returned in float32, anything else in
//!   float64 ([`with_precision!`]);
//! - batches are sample-major `(N, K)`; a single `(K,)` point (or a scalar
//!   for `K = 1`) gives an unbatched result;
//! - shape and value errors name the argument and the first offending index;
//! - outputs are fresh numpy arrays, filled with the GIL released.

use super::parallel::run_batch;
use crate::error::{Error, shape_str};
use crate::math::Real;
use numpy::{AllowTypeChange, Element, PyArray, PyArrayDescrMethods, PyArrayDyn, PyArrayLikeDyn};
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// A float type the bindings compute in: `f32` or `f64`, readable from
/// Python and storable in numpy arrays.
pub trait PyFloat: Element + Real + for<'a, 'py> FromPyObject<'a, 'py> {}
impl PyFloat for f32 {}
impl PyFloat for f64 {}

/// Whether `ob` is a float32 array or numpy float32 scalar.
pub fn is_float32(ob: &Bound<'_, PyAny>) -> bool {
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

/// An integer argument in `[min, max]`; values outside (however large)
/// raise ValueError (never OverflowError), non-integers TypeError.
pub fn index_arg(ob: &Bound<'_, PyAny>, arg: &'static str, min: u64, max: u64) -> PyResult<u64> {
    let py = ob.py();
    let int = py
        .import(pyo3::intern!(py, "operator"))?
        .call_method1(pyo3::intern!(py, "index"), (ob,))
        .map_err(|_| {
            PyTypeError::new_err(format!(
                "{arg} must be an integer, got {}",
                ob.get_type()
                    .name()
                    .map_or_else(|_| "?".into(), |n| n.to_string())
            ))
        })?;
    if int.lt(min)? || int.gt(max)? {
        return Err(Error::Integer {
            arg,
            value: int.to_string(),
            requirement: format!("must be an integer from {min} to {max}"),
        }
        .into());
    }
    int.extract()
}

/// What every input value must satisfy.
#[derive(Clone, Copy, Debug)]
pub enum Check {
    /// In the closed unit interval (uniform samples `u`).
    Unit,
    /// Finite (points, directions).
    Finite,
}

impl Check {
    #[inline(always)]
    fn holds<F: Real>(self, x: F) -> bool {
        match self {
            Check::Unit => x >= F::zero() && x <= F::one(),
            Check::Finite => x.is_finite(),
        }
    }

    fn requirement(self) -> &'static str {
        match self {
            Check::Unit => "must lie in [0, 1]",
            Check::Finite => "must be finite",
        }
    }
}

/// A batch of `K`-vectors read from an array-like: `(N, K)` or `(K,)`, or
/// for `K = 1`, `(N,)` or a scalar.
pub struct Points<'py, F: Element, const K: usize> {
    array: PyArrayLikeDyn<'py, F, AllowTypeChange>,
    /// A C-ordered copy when the input is not contiguous.
    owned: Option<Vec<F>>,
    /// Number of points.
    pub n: usize,
    /// False for a single point given without the batch axis.
    pub batched: bool,
    /// Argument name, for messages.
    pub arg: &'static str,
}

impl<'py, F: PyFloat, const K: usize> Points<'py, F, K> {
    /// Reads `ob` as points of dimension `K`.
    pub fn extract(ob: &Bound<'py, PyAny>, arg: &'static str) -> PyResult<Self> {
        let array: PyArrayLikeDyn<'py, F, AllowTypeChange> = ob
            .extract()
            .map_err(|e| PyTypeError::new_err(format!("{arg} must be an array of numbers: {e}")))?;
        let shape = array.shape().to_vec();
        let (n, batched) = match (K, shape.as_slice()) {
            (1, []) => (1, false),
            (1, [n]) => (*n, true),
            (_, [k]) if *k == K => (1, false),
            (_, [n, k]) if *k == K => (*n, true),
            _ => {
                let expected = if K == 1 {
                    "(N,) or ()".to_string()
                } else {
                    format!("(N, {K}) or ({K},)")
                };
                return Err(Error::Shape {
                    arg,
                    expected,
                    got: shape_str(&shape),
                }
                .into());
            }
        };
        // Only C order can be read in place (a Fortran-ordered array is
        // contiguous too, in the wrong order): copy anything else once.
        let owned = if array.is_c_contiguous() {
            None
        } else {
            Some(array.as_array().iter().copied().collect())
        };
        Ok(Points {
            array,
            owned,
            n,
            batched,
            arg,
        })
    }

    /// The points, one `[F; K]` each.
    pub fn rows(&self) -> &[[F; K]] {
        let flat = match &self.owned {
            Some(v) => v.as_slice(),
            None => self.array.as_slice().unwrap_or_default(),
        };
        flat.as_chunks::<K>().0
    }

    /// Shape of a result with `m` values per point (`m = 1`: a scalar each).
    pub fn out_shape(&self, m: usize) -> Vec<usize> {
        match (self.batched, m) {
            (true, 1) => vec![self.n],
            (true, _) => vec![self.n, m],
            (false, 1) => vec![],
            (false, _) => vec![m],
        }
    }

    /// The error for the first value that fails `check`.
    pub fn invalid(&self, check: Check) -> PyErr {
        for (i, row) in self.rows().iter().enumerate() {
            if let Some(j) = row.iter().position(|&x| !check.holds(x)) {
                let index = match (self.batched, K) {
                    (true, 1) => format!("[{i}]"),
                    (true, _) => format!("[{i}, {j}]"),
                    (false, 1) => String::new(),
                    (false, _) => format!("[{j}]"),
                };
                return Error::Element {
                    arg: self.arg,
                    index,
                    value: row[j].f64(),
                    requirement: check.requirement(),
                }
                .into();
            }
        }
        Error::Element {
            arg: self.arg,
            index: String::new(),
            value: f64::NAN,
            requirement: check.requirement(),
        }
        .into()
    }
}

/// A fresh zeroed numpy array of `shape` (allocated by numpy, so a failed
/// allocation is a `MemoryError`, and untouched pages cost nothing).
pub fn zeros<'py, F: Element>(py: Python<'py>, shape: &[usize]) -> Bound<'py, PyArrayDyn<F>> {
    PyArray::zeros(py, shape, false)
}

/// `array` as returned to Python: a numpy scalar when it is 0-d.
pub fn finish<'py, F: Element>(array: Bound<'py, PyArrayDyn<F>>) -> PyResult<Bound<'py, PyAny>> {
    if array.ndim() == 0 {
        array.get_item(PyTuple::empty(array.py()))
    } else {
        Ok(array.into_any())
    }
}

/// Maps every point through `kernel` (`K` values in, `M` out), checking
/// each input value in the same pass; the GIL is released and the batch
/// runs on all cores.
pub fn map<'py, F, const K: usize, const M: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    kernel: impl Fn([F; K]) -> [F; M] + Sync + Send,
) -> PyResult<Bound<'py, PyAny>>
where
    F: PyFloat,
{
    let out = zeros::<F>(py, &x.out_shape(M));
    {
        let mut guard = out.readwrite();
        let flat = guard.as_slice_mut()?;
        let out_rows = flat.as_chunks_mut::<M>().0;
        let in_rows = x.rows();
        let valid = run_batch(py, x.n, out_rows, |range, chunk: &mut [[F; M]]| {
            let mut ok = true;
            for (o, u) in chunk.iter_mut().zip(&in_rows[range]) {
                ok &= u.iter().fold(true, |acc, &v| acc & check.holds(v));
                *o = kernel(*u);
            }
            ok
        })?;
        if !valid {
            return Err(x.invalid(check));
        }
    }
    finish(out)
}

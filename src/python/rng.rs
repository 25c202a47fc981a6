//! `mcsample.Rng` and `mcsample.uniform`.

use super::args::{index_arg, seed};
use super::arrays::{finish, fresh};
use super::parallel::detached;
use super::pickle::reduce;
use crate::math::Real;
use crate::python::Obj;
use crate::rng::{MAX_STREAM, Rng};
use numpy::{Element, PyArrayDescr, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// Largest number of values one call may ask for.
const MAX_COUNT: u64 = 1 << 40;

/// The shape argument: None (one value), an int, or a sequence of ints.
fn parse_shape(shape: Option<&Obj<'_>>) -> PyResult<Vec<usize>> {
    let Some(shape) = shape.filter(|s| !s.is_none()) else {
        return Ok(vec![]);
    };
    let dims: Vec<usize> = if let Ok(seq) = shape.cast::<PyTuple>() {
        seq.iter()
            .map(|d| index_arg(&d, "shape", 0, MAX_COUNT).map(|v| v as usize))
            .collect::<PyResult<_>>()?
    } else if let Ok(list) = shape.cast::<pyo3::types::PyList>() {
        list.iter()
            .map(|d| index_arg(&d, "shape", 0, MAX_COUNT).map(|v| v as usize))
            .collect::<PyResult<_>>()?
    } else {
        vec![index_arg(shape, "shape", 0, MAX_COUNT)? as usize]
    };
    let total = dims
        .iter()
        .try_fold(1u64, |acc, &d| acc.checked_mul(d as u64));
    match total {
        Some(t) if t <= MAX_COUNT => Ok(dims),
        _ => Err(crate::error::Error::Integer {
            arg: "shape",
            value: crate::error::shape_str(&dims),
            requirement: format!("must hold at most {MAX_COUNT} values"),
        }
        .into()),
    }
}

/// Whether `dtype` (None, "float32", np.float32, ...) asks for float32;
/// only float32 and float64 are offered.
pub(super) fn wants_float32(py: Python<'_>, dtype: Option<&Obj<'_>>) -> PyResult<bool> {
    let Some(dtype) = dtype.filter(|d| !d.is_none()) else {
        return Ok(false);
    };
    let descr = PyArrayDescr::new(py, dtype)?;
    if descr.is_equiv_to(&numpy::dtype::<f32>(py)) {
        Ok(true)
    } else if descr.is_equiv_to(&numpy::dtype::<f64>(py)) {
        Ok(false)
    } else {
        Err(PyTypeError::new_err(format!(
            "dtype must be float32 or float64, got {dtype}"
        )))
    }
}

/// The next `shape` floats of `rng` as a fresh array (a numpy scalar for
/// shape `()`), filled on all cores with the GIL released.
fn random_array<'py, F: Element + Real + bytemuck::Pod>(
    py: Python<'py>,
    rng: &mut Rng,
    shape: &[usize],
) -> PyResult<Obj<'py>> {
    let out: Bound<'py, PyArrayDyn<F>> = fresh(py, shape)?;
    {
        let mut guard = out.readwrite();
        let flat = guard.as_slice_mut()?;
        detached(py, || rng.fill(flat))?;
    }
    finish(out)
}

/// The `stream` argument: 0 to [`MAX_STREAM`], or None for 0.
fn stream_arg(ob: &Obj<'_>) -> PyResult<u64> {
    if ob.is_none() {
        return Ok(0);
    }
    index_arg(ob, "stream", 0, MAX_STREAM)
}

/// PCG32 random number generator (O'Neill's ``pcg32_random_r``, seeded as
/// ``pcg32_srandom_r(seed, stream)``), the generator of Mitsuba 3 / Dr.Jit.
///
/// Parameters
/// ----------
/// seed : int, None or numpy.random.Generator
///     Initial state, 0 to 2**64 - 1 (default 0); None draws a fresh seed
///     from the operating system, a Generator draws one from itself.
/// stream : int
///     Stream id, 0 to 2**63 - 1 (default 0; None is 0 too); different
///     streams are independent sequences.
///
/// Floats are made from one 32-bit output each, exactly as Dr.Jit's
/// ``PCG32.next_float64`` / ``next_float32`` make them, so the same seed and
/// stream give the same numbers as ``drjit.scalar.PCG32(1, seed, stream)``.
#[pyclass(module = "mcsample._core", name = "Rng")]
#[derive(Clone)]
pub struct PyRng {
    rng: Rng,
    seed: u64,
    stream: u64,
    /// Outputs drawn or skipped since seeding, modulo 2^64 (PCG32's
    /// period): with the seed and stream, the whole state.
    drawn: u64,
}

impl PyRng {
    /// The generator of `seed` and `stream` after `drawn` outputs.
    fn at(seed: u64, stream: u64, drawn: u64) -> Self {
        let mut rng = Rng::new(seed, stream);
        rng.advance(drawn);
        PyRng {
            rng,
            seed,
            stream,
            drawn,
        }
    }
}

#[pymethods]
impl PyRng {
    #[new]
    #[pyo3(signature = (seed = 0, stream = 0))]
    fn new(
        #[pyo3(from_py_with = seed)] seed: u64,
        #[pyo3(from_py_with = stream_arg)] stream: u64,
    ) -> PyResult<Self> {
        Ok(Self::at(seed, stream, 0))
    }

    /// The generator of `seed` and `stream` after `drawn` outputs (the
    /// unpickling constructor).
    #[staticmethod]
    fn _from_position(seed: u64, stream: u64, drawn: u64) -> Self {
        Self::at(seed, stream, drawn)
    }

    /// Pickles as its seed, stream and position.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let this = slf.borrow();
        let args = (this.seed, this.stream, this.drawn).into_pyobject(slf.py())?;
        reduce(slf.as_any(), Some("_from_position"), args, None)
    }

    /// Uniform floats in [0, 1).
    ///
    /// Parameters
    /// ----------
    /// shape : None, int or tuple of int
    ///     None gives one value (a numpy scalar); otherwise an array of that
    ///     shape, filled in C order from the stream.
    /// dtype : float64 (default) or float32
    ///
    /// Returns
    /// -------
    /// ndarray of `shape`, float64 multiples of 2**-32 (float32: of 2**-23).
    #[pyo3(signature = (shape = None, dtype = None))]
    fn random<'py>(
        &mut self,
        py: Python<'py>,
        shape: Option<&Obj<'py>>,
        dtype: Option<&Obj<'py>>,
    ) -> PyResult<Obj<'py>> {
        let shape = parse_shape(shape)?;
        let values = if wants_float32(py, dtype)? {
            random_array::<f32>(py, &mut self.rng, &shape)?
        } else {
            random_array::<f64>(py, &mut self.rng, &shape)?
        };
        self.count(&shape);
        Ok(values)
    }

    /// Raw 32-bit outputs.
    ///
    /// Parameters
    /// ----------
    /// shape : None, int or tuple of int
    ///
    /// Returns
    /// -------
    /// ndarray of `shape`, uint32 (a numpy scalar for None).
    #[pyo3(signature = (shape = None))]
    fn next_uint32<'py>(
        &mut self,
        py: Python<'py>,
        shape: Option<&Obj<'py>>,
    ) -> PyResult<Obj<'py>> {
        let shape = parse_shape(shape)?;
        let out: Bound<'py, PyArrayDyn<u32>> = fresh(py, &shape)?;
        {
            let mut guard = out.readwrite();
            let flat = guard.as_slice_mut()?;
            let rng = &mut self.rng;
            detached(py, || rng.fill_u32(flat))?;
        }
        self.count(&shape);
        finish(out)
    }

    /// Skips ``n`` outputs (0 <= n < 2**64) in O(log n) steps.
    fn advance(&mut self, n: &Obj<'_>) -> PyResult<()> {
        let n = index_arg(n, "n", 0, u64::MAX)?;
        self.rng.advance(n);
        self.drawn = self.drawn.wrapping_add(n);
        Ok(())
    }

    /// The seed given to the constructor.
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }

    /// The stream given to the constructor.
    #[getter]
    fn stream(&self) -> u64 {
        self.stream
    }

    /// An independent copy at the same position.
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __copy__(&self) -> Self {
        self.clone()
    }

    fn __deepcopy__(&self, _memo: &Obj<'_>) -> Self {
        self.clone()
    }

    fn __repr__(&self) -> String {
        format!("Rng(seed={}, stream={})", self.seed, self.stream)
    }
}

impl PyRng {
    /// Counts the outputs an array of `shape` draws (one each).
    fn count(&mut self, shape: &[usize]) {
        let n = shape.iter().map(|&d| d as u64).product::<u64>();
        self.drawn = self.drawn.wrapping_add(n);
    }
}

/// The `dim` argument of [`uniform`]: 0 to 2²⁰, or None for 2.
fn dim_arg(ob: &Obj<'_>) -> PyResult<usize> {
    if ob.is_none() {
        return Ok(2);
    }
    Ok(index_arg(ob, "dim", 0, 1 << 20)? as usize)
}

/// ``n × dim`` uniform floats in [0, 1): the first ``n·dim`` numbers of
/// ``Rng(seed)``, computed on all cores (bit-identical for any thread count).
///
/// Parameters
/// ----------
/// n : int
///     Number of samples.
/// dim : int
///     Numbers per sample (default 2).
/// seed : int, None or numpy.random.Generator
///     As for ``Rng`` (default 0).
/// dtype : float64 (default) or float32
///
/// Returns
/// -------
/// ndarray, shape (n, dim)
#[pyfunction]
#[pyo3(signature = (n, dim = 2, seed = 0, dtype = None))]
pub fn uniform<'py>(
    py: Python<'py>,
    n: &Obj<'py>,
    #[pyo3(from_py_with = dim_arg)] dim: usize,
    #[pyo3(from_py_with = seed)] seed: u64,
    dtype: Option<&Obj<'py>>,
) -> PyResult<Obj<'py>> {
    let n = index_arg(n, "n", 0, MAX_COUNT)? as usize;
    let shape = [n, dim];
    parse_shape(Some(&PyTuple::new(py, shape)?.into_any()))?;
    let mut rng = Rng::new(seed, 0);
    if wants_float32(py, dtype)? {
        random_array::<f32>(py, &mut rng, &shape)
    } else {
        random_array::<f64>(py, &mut rng, &shape)
    }
}

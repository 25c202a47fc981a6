//! `mcsample._core.qmc`: the point generators of [`crate::qmc`], filled
//! from any index into fresh arrays with the GIL released. The engines of
//! `mcsample.qmc` (scipy's interface, their position, seeds) wrap them.

use super::args::{choice, index_arg, seed};
use super::arrays::zeros;
use super::parallel::detached;
use super::rng::wants_float32;
use crate::error::Error;
use crate::math::Real;
use crate::python::Obj;
use crate::qmc::{
    HALTON_MAX_INDEX, Halton, PATTERN_MAX_POINTS, Pattern, Patterns, Scramble, Sobol,
};
use numpy::{Element, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;

/// Values one call may ask for (`n·d`), as `mcsample.uniform`.
const MAX_VALUES: u64 = 1 << 40;

/// A core point generator: rows of `dims` values filled from `start` (an
/// index, or a pattern's number).
trait Fill: Sync {
    fn dims(&self) -> usize;
    fn fill<F: Real>(&self, start: u64, out: &mut [F]) -> crate::Result<()>;
}

macro_rules! fill_by_core {
    ($($engine:ty),*) => {$(
        impl Fill for $engine {
            fn dims(&self) -> usize {
                <$engine>::dims(self)
            }
            fn fill<F: Real>(&self, start: u64, out: &mut [F]) -> crate::Result<()> {
                <$engine>::fill(self, start, out)
            }
        }
    )*};
}
fill_by_core!(Sobol, Halton, Patterns);

/// `n` points of `engine` from `start` (argument `n`, an int), as a fresh
/// `(n, d)` array of the float type `dtype` asks for. Checked before
/// anything is allocated: the points' indices `first .. first + n` stay
/// below `end`, and `n·d` ≤ [`MAX_VALUES`].
fn draw<'py>(
    py: Python<'py>,
    engine: &impl Fill,
    start: u64,
    n: &Obj<'py>,
    dtype: Option<&Obj<'py>>,
    (first, end): (u64, u64),
) -> PyResult<Obj<'py>> {
    let n = index_arg(n, "n", 0, u64::MAX)?;
    let d = engine.dims();
    let too_many = |requirement: String| -> PyResult<Obj<'py>> {
        Err(Error::Integer {
            arg: "n",
            value: n.to_string(),
            requirement,
        }
        .into())
    };
    if first.checked_add(n).is_none_or(|last| last > end) {
        return too_many(format!(
            "points {first} .. {first} + n must stay below index {end} (the sequence's end)"
        ));
    }
    if n.saturating_mul(d as u64) > MAX_VALUES {
        return too_many(format!("n·d = n·{d} must be at most {MAX_VALUES} values"));
    }
    if wants_float32(py, dtype)? {
        filled::<f32>(py, engine, start, [n as usize, d])
    } else {
        filled::<f64>(py, engine, start, [n as usize, d])
    }
}

/// A fresh array of `shape` filled by `engine` from `start`, GIL released.
fn filled<'py, F: Element + Real>(
    py: Python<'py>,
    engine: &impl Fill,
    start: u64,
    shape: [usize; 2],
) -> PyResult<Obj<'py>> {
    let out: Bound<'py, PyArrayDyn<F>> = zeros(py, &shape)?;
    {
        let mut guard = out.readwrite();
        let flat = guard.as_slice_mut()?;
        detached(py, || engine.fill(start, flat))?;
    }
    Ok(out.into_any())
}

/// Sobol' points with Joe and Kuo's direction numbers (scipy's), in
/// scipy's Gray-code order: the engine behind ``mcsample.qmc.Sobol``.
///
/// Parameters
/// ----------
/// d : int
///     Dimensions, 1 to 21201.
/// scramble : "none", "owen" or "lms"
///     The plain sequence (scipy's ``scramble=False`` points, bit for bit),
///     Owen's nested uniform scrambling (a hash per dimension), or a random
///     linear matrix scramble with a digital shift (scipy's kind).
/// seed : int, None or numpy.random.Generator
///     The scramble's random bits (default 0).
#[pyclass(module = "mcsample._core.qmc", name = "SobolPoints", frozen)]
pub struct PySobolPoints(Sobol);

#[pymethods]
impl PySobolPoints {
    #[new]
    #[pyo3(signature = (d, scramble = "owen", seed = 0))]
    fn new(d: &Obj<'_>, scramble: &str, #[pyo3(from_py_with = seed)] seed: u64) -> PyResult<Self> {
        let d = index_arg(d, "d", 1, crate::qmc::SOBOL_MAX_DIMENSIONS as u64)? as usize;
        let scramble = choice(
            "scramble",
            scramble,
            &[
                ("none", Scramble::None),
                ("owen", Scramble::Owen),
                ("lms", Scramble::LinearMatrix),
            ],
        )?;
        Ok(Self(Sobol::new(d, scramble, seed)?))
    }

    /// Points ``first .. first + n - 1`` (indices below 2**32).
    ///
    /// Parameters
    /// ----------
    /// first, n : int >= 0
    /// dtype : float64 (default) or float32
    ///
    /// Returns
    /// -------
    /// ndarray, shape (n, d), in [0, 1): float64 multiples of 2**-32
    /// (float32: of 2**-23).
    #[pyo3(signature = (first, n, dtype = None))]
    fn points<'py>(
        &self,
        py: Python<'py>,
        first: &Obj<'py>,
        n: &Obj<'py>,
        dtype: Option<&Obj<'py>>,
    ) -> PyResult<Obj<'py>> {
        let first = index_arg(first, "first", 0, u64::MAX)?;
        draw(py, &self.0, first, n, dtype, (first, 1 << 32))
    }

    /// The number of dimensions.
    #[getter]
    fn d(&self) -> usize {
        self.0.dims()
    }
}

/// Halton points (the first ``d`` primes as bases), plain or with random
/// digit permutations: the engine behind ``mcsample.qmc.Halton``.
///
/// Parameters
/// ----------
/// d : int
///     Dimensions, 1 to 65536 (scrambled: while the digit permutations fit
///     in 2**26 entries: d <= 2191).
/// scramble : bool
///     False: scipy's ``scramble=False`` points, bit for bit; True: a random
///     permutation of the digits per digit position and dimension.
/// seed : int, None or numpy.random.Generator
///     The permutations' random bits (default 0).
#[pyclass(module = "mcsample._core.qmc", name = "HaltonPoints", frozen)]
pub struct PyHaltonPoints(Halton);

#[pymethods]
impl PyHaltonPoints {
    #[new]
    #[pyo3(signature = (d, scramble = true, seed = 0))]
    fn new(d: &Obj<'_>, scramble: bool, #[pyo3(from_py_with = seed)] seed: u64) -> PyResult<Self> {
        let d = index_arg(d, "d", 1, crate::qmc::HALTON_MAX_DIMENSIONS as u64)? as usize;
        Ok(Self(Halton::new(d, scramble, seed)?))
    }

    /// Points ``first .. first + n - 1`` (indices below 2**53).
    ///
    /// Parameters
    /// ----------
    /// first, n : int >= 0
    /// dtype : float64 (default) or float32
    ///
    /// Returns
    /// -------
    /// ndarray, shape (n, d), in [0, 1).
    #[pyo3(signature = (first, n, dtype = None))]
    fn points<'py>(
        &self,
        py: Python<'py>,
        first: &Obj<'py>,
        n: &Obj<'py>,
        dtype: Option<&Obj<'py>>,
    ) -> PyResult<Obj<'py>> {
        let first = index_arg(first, "first", 0, u64::MAX)?;
        draw(py, &self.0, first, n, dtype, (first, HALTON_MAX_INDEX))
    }

    /// The number of dimensions.
    #[getter]
    fn d(&self) -> usize {
        self.0.dims()
    }
}

/// Stratified patterns of ``n`` points drawn whole: the engine behind
/// ``mcsample.qmc.LatinHypercube``, ``Stratified`` and ``MultiJitter``.
///
/// Parameters
/// ----------
/// kind : "lhs", "lhs-centered", "stratified" or "multijitter"
///     A Latin hypercube (jittered in its intervals, or at their centres);
///     shuffled strata of a square grid per pair of dimensions (Mitsuba's
///     ``stratified``); Kensler's correlated multi-jitter per pair
///     (Mitsuba's ``multijitter``).
/// d : int
///     Dimensions, 1 to 65536.
/// seed : int, None or numpy.random.Generator
///     The patterns' random bits (default 0).
#[pyclass(module = "mcsample._core.qmc", name = "PatternPoints", frozen)]
pub struct PyPatternPoints(Patterns);

#[pymethods]
impl PyPatternPoints {
    #[new]
    #[pyo3(signature = (kind, d, seed = 0))]
    fn new(kind: &str, d: &Obj<'_>, #[pyo3(from_py_with = seed)] seed: u64) -> PyResult<Self> {
        let kind = choice(
            "kind",
            kind,
            &[
                ("lhs", Pattern::LatinHypercube { centered: false }),
                ("lhs-centered", Pattern::LatinHypercube { centered: true }),
                ("stratified", Pattern::Stratified),
                ("multijitter", Pattern::MultiJitter),
            ],
        )?;
        let d = index_arg(d, "d", 1, crate::qmc::PATTERN_MAX_DIMENSIONS as u64)? as usize;
        Ok(Self(Patterns::new(kind, d, seed)?))
    }

    /// The pattern numbered ``number`` (the points drawn before it), of ``n``
    /// points (at most 2**30).
    ///
    /// Parameters
    /// ----------
    /// number, n : int >= 0
    /// dtype : float64 (default) or float32
    ///
    /// Returns
    /// -------
    /// ndarray, shape (n, d), in [0, 1).
    #[pyo3(signature = (number, n, dtype = None))]
    fn points<'py>(
        &self,
        py: Python<'py>,
        number: &Obj<'py>,
        n: &Obj<'py>,
        dtype: Option<&Obj<'py>>,
    ) -> PyResult<Obj<'py>> {
        let number = index_arg(number, "number", 0, u64::MAX)?;
        // A pattern's points are numbered from 0.
        draw(py, &self.0, number, n, dtype, (0, PATTERN_MAX_POINTS))
    }

    /// The number of dimensions.
    #[getter]
    fn d(&self) -> usize {
        self.0.dims()
    }
}

/// Registers the point generators in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySobolPoints>()?;
    m.add_class::<PyHaltonPoints>()?;
    m.add_class::<PyPatternPoints>()?;
    Ok(())
}

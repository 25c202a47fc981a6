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

/// Points `first .. first + n` of `fill`'s sequence in `d` dimensions, as a
/// fresh `(n, d)` array of `F`; checked before anything is allocated: the
/// indices stay below `end`, and `n·d` ≤ [`MAX_VALUES`].
fn points<'py, F: Element + Real>(
    py: Python<'py>,
    (first, n, d, end): (u64, u64, usize, u64),
    fill: impl FnOnce(&mut [F]) -> crate::Result<()> + Send,
) -> PyResult<Obj<'py>> {
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
    let out: Bound<'py, PyArrayDyn<F>> = zeros(py, &[n as usize, d])?;
    {
        let mut guard = out.readwrite();
        let flat = guard.as_slice_mut()?;
        detached(py, || fill(flat))?;
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
        let n = index_arg(n, "n", 0, u64::MAX)?;
        let (sobol, request) = (&self.0, (first, n, self.0.dims(), 1 << 32));
        if wants_float32(py, dtype)? {
            points::<f32>(py, request, |out| sobol.fill(first, out))
        } else {
            points::<f64>(py, request, |out| sobol.fill(first, out))
        }
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
        let n = index_arg(n, "n", 0, u64::MAX)?;
        let (halton, request) = (&self.0, (first, n, self.0.dims(), HALTON_MAX_INDEX));
        if wants_float32(py, dtype)? {
            points::<f32>(py, request, |out| halton.fill(first, out))
        } else {
            points::<f64>(py, request, |out| halton.fill(first, out))
        }
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

    /// The pattern numbered ``draw`` (the points drawn before it), of ``n``
    /// points (at most 2**30).
    ///
    /// Parameters
    /// ----------
    /// draw, n : int >= 0
    /// dtype : float64 (default) or float32
    ///
    /// Returns
    /// -------
    /// ndarray, shape (n, d), in [0, 1).
    #[pyo3(signature = (draw, n, dtype = None))]
    fn points<'py>(
        &self,
        py: Python<'py>,
        draw: &Obj<'py>,
        n: &Obj<'py>,
        dtype: Option<&Obj<'py>>,
    ) -> PyResult<Obj<'py>> {
        let draw = index_arg(draw, "draw", 0, u64::MAX)?;
        let n = index_arg(n, "n", 0, PATTERN_MAX_POINTS)?;
        // A pattern's points are numbered from 0.
        let (patterns, request) = (&self.0, (0, n, self.0.dims(), PATTERN_MAX_POINTS));
        if wants_float32(py, dtype)? {
            points::<f32>(py, request, |out| patterns.fill(draw, out))
        } else {
            points::<f64>(py, request, |out| patterns.fill(draw, out))
        }
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

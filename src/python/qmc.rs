//! `mcsample._core.qmc`: the point generators of [`crate::qmc`], filled
//! from any index into fresh arrays with the GIL released. The engines of
//! `mcsample.qmc` (scipy's interface, their position, seeds) wrap them.

use super::args::{choice, index_arg, seed};
use super::arrays::fresh;
use super::parallel::detached;
use super::pickle::reduce;
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

/// A core point generator of any kind.
enum Engine {
    Sobol(Sobol),
    Halton(Halton),
    Patterns(Patterns),
}

impl Engine {
    fn dims(&self) -> usize {
        match self {
            Engine::Sobol(e) => e.dims(),
            Engine::Halton(e) => e.dims(),
            Engine::Patterns(e) => e.dims(),
        }
    }

    /// Rows of `dims` values from `start`: the index of the first point
    /// of a sequence, the number of a pattern.
    fn fill<F: Real>(&self, start: u64, out: &mut [F]) -> crate::Result<()> {
        match self {
            Engine::Sobol(e) => e.fill(start, out),
            Engine::Halton(e) => e.fill(start, out),
            Engine::Patterns(e) => e.fill(start, out),
        }
    }

    /// The indices `n` points from `start` take, `(first, end)`: they must
    /// stay below `end`. A pattern's points are numbered from 0.
    fn span(&self, start: u64) -> (u64, u64) {
        match self {
            Engine::Sobol(_) => (start, 1 << 32),
            Engine::Halton(_) => (start, HALTON_MAX_INDEX),
            Engine::Patterns(_) => (0, PATTERN_MAX_POINTS),
        }
    }
}

/// `n` points of `engine` from `start` (argument `n`, an int), as a fresh
/// `(n, d)` array of the float type `dtype` asks for. Checked before
/// anything is allocated: the points' indices stay in the engine's
/// [`Engine::span`], and `n·d` ≤ [`MAX_VALUES`].
fn draw<'py>(
    py: Python<'py>,
    engine: &Engine,
    start: u64,
    n: &Obj<'py>,
    dtype: Option<&Obj<'py>>,
) -> PyResult<Obj<'py>> {
    let n = index_arg(n, "n", 0, u64::MAX)?;
    let d = engine.dims();
    let (first, end) = engine.span(start);
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
fn filled<'py, F: Element + Real + bytemuck::Pod>(
    py: Python<'py>,
    engine: &Engine,
    start: u64,
    shape: [usize; 2],
) -> PyResult<Obj<'py>> {
    let out: Bound<'py, PyArrayDyn<F>> = fresh(py, &shape)?;
    {
        let mut guard = out.readwrite();
        let flat = guard.as_slice_mut()?;
        detached(py, || engine.fill(start, flat))?;
    }
    Ok(out.into_any())
}

/// Quasi-random points and stratified patterns, filled from any index: the
/// engine behind ``mcsample.qmc``'s ``Sobol``, ``Halton``,
/// ``LatinHypercube``, ``Stratified`` and ``MultiJitter``.
///
/// Parameters
/// ----------
/// kind : str
///     Sequences, drawn from any index: ``"sobol"`` (Joe and Kuo's direction
///     numbers in scipy's Gray-code order, scipy's ``scramble=False``
///     points bit for bit), ``"sobol-owen"`` (Owen's nested uniform
///     scrambling, a hash per dimension), ``"sobol-lms"`` (a random linear
///     matrix scramble with a digital shift, scipy's kind), ``"halton"``
///     (the first ``d`` primes as bases; scipy's ``scramble=False`` points)
///     and ``"halton-permuted"`` (a random permutation of the digits per
///     digit position and dimension). Patterns of ``n`` points drawn whole:
///     ``"lhs"`` / ``"lhs-centered"`` (a Latin hypercube, jittered in its
///     intervals or at their centres), ``"stratified"`` (shuffled strata of a
///     square grid per pair of dimensions, Mitsuba's ``stratified``) and
///     ``"multijitter"`` (Kensler's correlated multi-jitter per pair,
///     Mitsuba's ``multijitter``).
/// d : int
///     Dimensions: 1 to 21201 for Sobol', 1 to 65536 for the rest (permuted
///     Halton: while the digit permutations fit in 2**26 entries, d <= 1946).
/// seed : int, None or numpy.random.Generator
///     The scramble's or pattern's random bits (default 0).
#[pyclass(module = "mcsample._core.qmc", name = "Points", frozen)]
pub struct PyPoints {
    engine: Engine,
    /// The constructor's arguments (for pickling).
    kind: &'static str,
    seed: u64,
}

#[pymethods]
impl PyPoints {
    #[new]
    #[pyo3(signature = (kind, d, seed = 0))]
    fn new(kind: &str, d: &Obj<'_>, #[pyo3(from_py_with = seed)] seed: u64) -> PyResult<Self> {
        #[derive(Clone, Copy, PartialEq)]
        enum Kind {
            Sobol(Scramble),
            Halton(bool),
            Pattern(Pattern),
        }
        let options = [
            ("sobol", Kind::Sobol(Scramble::None)),
            ("sobol-owen", Kind::Sobol(Scramble::Owen)),
            ("sobol-lms", Kind::Sobol(Scramble::LinearMatrix)),
            ("halton", Kind::Halton(false)),
            ("halton-permuted", Kind::Halton(true)),
            (
                "lhs",
                Kind::Pattern(Pattern::LatinHypercube { centered: false }),
            ),
            (
                "lhs-centered",
                Kind::Pattern(Pattern::LatinHypercube { centered: true }),
            ),
            ("stratified", Kind::Pattern(Pattern::Stratified)),
            ("multijitter", Kind::Pattern(Pattern::MultiJitter)),
        ];
        let (kind, name) = choice("kind", kind, &options.map(|(n, k)| (n, (k, n))))?;
        let max_dims = match kind {
            Kind::Sobol(_) => crate::qmc::SOBOL_MAX_DIMENSIONS,
            Kind::Halton(_) => crate::qmc::HALTON_MAX_DIMENSIONS,
            Kind::Pattern(_) => crate::qmc::PATTERN_MAX_DIMENSIONS,
        };
        let d = index_arg(d, "d", 1, max_dims as u64)? as usize;
        let engine = match kind {
            Kind::Sobol(scramble) => Engine::Sobol(Sobol::new(d, scramble, seed)?),
            Kind::Halton(scramble) => Engine::Halton(Halton::new(d, scramble, seed)?),
            Kind::Pattern(pattern) => Engine::Patterns(Patterns::new(pattern, d, seed)?),
        };
        Ok(Self {
            engine,
            kind: name,
            seed,
        })
    }

    /// Pickles as its kind, dimensions and seed.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let this = slf.get();
        let args = (this.kind, this.engine.dims(), this.seed).into_pyobject(slf.py())?;
        reduce(slf.as_any(), None, args, None)
    }

    /// ``n`` points from ``start``: of a sequence, the points
    /// ``start .. start + n - 1`` (indices below 2**32 for Sobol', 2**53 for
    /// Halton); of patterns, the pattern numbered ``start`` (the points
    /// drawn before it), of ``n`` points (at most 2**30).
    ///
    /// Parameters
    /// ----------
    /// start, n : int >= 0
    /// dtype : float64 (default) or float32
    ///
    /// Returns
    /// -------
    /// ndarray, shape (n, d), in [0, 1) (Sobol': float64 multiples of 2**-32,
    /// float32 of 2**-23).
    #[pyo3(signature = (start, n, dtype = None))]
    fn points<'py>(
        &self,
        py: Python<'py>,
        start: &Obj<'py>,
        n: &Obj<'py>,
        dtype: Option<&Obj<'py>>,
    ) -> PyResult<Obj<'py>> {
        let start = index_arg(start, "start", 0, u64::MAX)?;
        draw(py, &self.engine, start, n, dtype)
    }

    /// The number of dimensions.
    #[getter]
    fn d(&self) -> usize {
        self.engine.dims()
    }
}

/// Registers the point generators in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyPoints>()?;
    Ok(())
}

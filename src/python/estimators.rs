//! `mcsample.estimators`: irradiance and reflected radiance under an
//! environment map (see [`crate::estimators`]).

use super::args::{choice, heuristic_arg, index_arg, seed, three_floats};
use super::envmap::PyEnvMap;
use super::parallel::detached;
use super::phong::PyPhong;
use crate::estimators::{self, Estimate, Plan, Strategy};
use crate::python::Obj;
use numpy::PyArray1;
use pyo3::prelude::*;

/// A Monte Carlo estimate of an RGB quantity.
#[pyclass(module = "mcsample._core.estimators", name = "Estimate", frozen)]
pub struct PyEstimate {
    estimate: Estimate,
    strategy: Strategy,
}

#[pymethods]
impl PyEstimate {
    /// The mean of the n evaluations, (3,) RGB.
    #[getter]
    fn value<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.estimate.value)
    }

    /// Its standard error (sample standard deviation / sqrt(n)), (3,).
    #[getter]
    fn stderr<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.estimate.stderr)
    }

    /// The number of evaluations (an MIS evaluation draws one sample of each
    /// strategy).
    #[getter]
    fn n(&self) -> usize {
        self.estimate.n
    }

    /// The strategy that produced it ("envmap" is reported as "emitter").
    #[getter]
    fn strategy(&self) -> &'static str {
        self.strategy.name()
    }

    fn __repr__(&self) -> String {
        let e = &self.estimate;
        format!(
            "Estimate(value={:?}, stderr={:?}, n={}, strategy={:?})",
            e.value,
            e.stderr,
            e.n,
            self.strategy.name()
        )
    }
}

/// The strategies of [`irradiance`] (and their names).
const IRRADIANCE: &[(&str, Strategy)] = &[
    ("uniform", Strategy::Uniform),
    ("cosine", Strategy::Cosine),
    ("emitter", Strategy::Emitter),
    ("envmap", Strategy::Emitter),
    ("mis", Strategy::Mis),
];

/// The strategies of [`reflected_radiance`].
const REFLECTED: &[(&str, Strategy)] = &[
    ("bsdf", Strategy::Bsdf),
    ("emitter", Strategy::Emitter),
    ("envmap", Strategy::Emitter),
    ("mis", Strategy::Mis),
];

/// The irradiance E = integral of L(w) max(0, n.w) dw at a surface of
/// normal ``normal`` under ``env``, by Monte Carlo.
///
/// Parameters
/// ----------
/// env : EnvMap
/// normal : (3,) array_like, world space (normalised here)
/// n : int >= 1
///     Evaluations (an "mis" evaluation uses one cosine and one emitter
///     sample).
/// strategy : "uniform", "cosine", "emitter" or "mis" (default)
///     "emitter" samples the map ("envmap" is the same).
/// seed : int, None or numpy.random.Generator
///     Seed of the PCG32 stream (default 0); the result does not depend on
///     the thread count. None draws a fresh seed from the operating system,
///     a Generator draws one from itself.
/// heuristic : "power" (default) or "balance"
///
/// Everything after ``n`` is keyword-only.
///
/// Returns
/// -------
/// Estimate
///     ``.value`` (3,) RGB, ``.stderr`` (3,), ``.n``, ``.strategy``.
#[pyfunction]
#[pyo3(signature = (env, normal, n, *, strategy = "mis", seed = 0, heuristic = "power"))]
pub fn irradiance(
    py: Python<'_>,
    env: &Bound<'_, PyEnvMap>,
    normal: &Obj<'_>,
    n: &Obj<'_>,
    strategy: &str,
    #[pyo3(from_py_with = seed)] seed: u64,
    heuristic: &str,
) -> PyResult<PyEstimate> {
    let normal = three_floats(normal, "normal", false)?;
    let plan = plan(
        n,
        seed,
        choice("strategy", strategy, IRRADIANCE)?,
        heuristic,
    )?;
    let env = env.get().inner();
    let estimate = detached(py, || estimators::irradiance(env, normal, plan))?;
    Ok(PyEstimate {
        estimate,
        strategy: plan.strategy,
    })
}

/// The radiance L_r(wi) = integral of L(w) f_r(wi, w) max(0, n.w) dw that a
/// Phong surface of normal ``normal`` reflects toward ``wi`` under ``env``.
///
/// Parameters
/// ----------
/// env : EnvMap
/// phong : Phong
/// normal, wi : (3,) array_like, world space (normalised here); wi points
///     toward the viewer
/// n : int >= 1
/// strategy : "bsdf", "emitter" or "mis" (default)
///     "emitter" samples the map ("envmap" is the same).
/// seed : int, None or numpy.random.Generator
///     As for ``irradiance`` (default 0).
/// heuristic : "power" (default) or "balance"
///
/// Everything after ``n`` is keyword-only.
///
/// Returns
/// -------
/// Estimate
#[pyfunction]
#[pyo3(signature = (env, phong, normal, wi, n, *, strategy = "mis", seed = 0, heuristic = "power"))]
#[allow(clippy::too_many_arguments)] // the Python signature
pub fn reflected_radiance(
    py: Python<'_>,
    env: &Bound<'_, PyEnvMap>,
    phong: &Bound<'_, PyPhong>,
    normal: &Obj<'_>,
    wi: &Obj<'_>,
    n: &Obj<'_>,
    strategy: &str,
    #[pyo3(from_py_with = seed)] seed: u64,
    heuristic: &str,
) -> PyResult<PyEstimate> {
    let (normal, wi) = (
        three_floats(normal, "normal", false)?,
        three_floats(wi, "wi", false)?,
    );
    let plan = plan(n, seed, choice("strategy", strategy, REFLECTED)?, heuristic)?;
    let (env, phong) = (env.get().inner(), phong.get().inner());
    let estimate = detached(py, || {
        estimators::reflected_radiance(env, phong, normal, wi, plan)
    })?;
    Ok(PyEstimate {
        estimate,
        strategy: plan.strategy,
    })
}

/// The checked arguments of an estimator.
fn plan(n: &Obj<'_>, seed: u64, strategy: Strategy, heuristic: &str) -> PyResult<Plan> {
    Ok(Plan {
        n: index_arg(n, "n", 1, 1 << 40)? as usize,
        strategy,
        heuristic: heuristic_arg(heuristic)?,
        seed,
    })
}

/// Registers the estimators in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyEstimate>()?;
    m.add_function(wrap_pyfunction!(irradiance, m)?)?;
    m.add_function(wrap_pyfunction!(reflected_radiance, m)?)?;
    Ok(())
}

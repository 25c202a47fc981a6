//! `mcsample.estimators`: irradiance and reflected radiance under an
//! environment map (see [`crate::estimators`]).

use super::args::{choice, heuristic_arg, index_arg, seed, three_floats};
use super::envmap::PyEnvMap;
use super::parallel::detached;
use super::phong::PyPhong;
use super::pickle::reduce;
use crate::estimators::{self, Estimate, Plan, Strategy};
use crate::python::Obj;
use crate::sampler::Sampler;
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

    /// The estimate of these numbers (the unpickling constructor).
    #[staticmethod]
    #[doc(hidden)]
    fn _from_fields(value: [f64; 3], stderr: [f64; 3], n: usize, strategy: &str) -> PyResult<Self> {
        let strategy = choice("strategy", strategy, &[IRRADIANCE, REFLECTED].concat())?;
        Ok(PyEstimate {
            estimate: Estimate { value, stderr, n },
            strategy,
        })
    }

    /// Pickles as its numbers.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let this = slf.get();
        let e = &this.estimate;
        let args = (e.value, e.stderr, e.n, this.strategy.name()).into_pyobject(slf.py())?;
        reduce(slf.as_any(), Some("_from_fields"), args, None)
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

/// The strategies of the irradiance estimator (and their names).
const IRRADIANCE: &[(&str, Strategy)] = &[
    ("uniform", Strategy::Uniform),
    ("cosine", Strategy::Cosine),
    ("emitter", Strategy::Emitter),
    ("envmap", Strategy::Emitter),
    ("mis", Strategy::Mis),
];

/// The strategies of the reflected-radiance estimator.
const REFLECTED: &[(&str, Strategy)] = &[
    ("bsdf", Strategy::Bsdf),
    ("emitter", Strategy::Emitter),
    ("envmap", Strategy::Emitter),
    ("mis", Strategy::Mis),
];

/// One estimate: the irradiance at ``normal`` without ``phong``, the
/// radiance ``phong`` reflects toward ``wi`` with it.
/// ``mcsample.estimators.irradiance`` and ``reflected_radiance`` call it
/// and document the arguments.
#[pyfunction]
#[pyo3(signature = (env, normal, n, *, phong = None, wi = None, strategy, seed, heuristic, sampler))]
#[allow(clippy::too_many_arguments)] // the Python signature
pub fn estimate(
    py: Python<'_>,
    env: &Bound<'_, PyEnvMap>,
    normal: &Obj<'_>,
    n: &Obj<'_>,
    phong: Option<&Bound<'_, PyPhong>>,
    wi: Option<&Obj<'_>>,
    strategy: &str,
    #[pyo3(from_py_with = seed)] seed: u64,
    heuristic: &str,
    sampler: &str,
) -> PyResult<PyEstimate> {
    let normal = three_floats(normal, "normal", false)?;
    let plan = Plan {
        n: index_arg(n, "n", 1, 1 << 40)? as usize,
        strategy: choice(
            "strategy",
            strategy,
            if phong.is_some() {
                REFLECTED
            } else {
                IRRADIANCE
            },
        )?,
        heuristic: heuristic_arg(heuristic)?,
        seed,
        sampler: choice("sampler", sampler, Sampler::NAMES)?,
    };
    let env = env.get().inner();
    let estimate = match phong {
        None => detached(py, || estimators::irradiance(env, normal, plan))?,
        Some(phong) => {
            let wi = match wi {
                Some(wi) => three_floats(wi, "wi", false)?,
                None => {
                    return Err(pyo3::exceptions::PyTypeError::new_err(
                        "wi is required with phong",
                    ));
                }
            };
            let phong = phong.get().inner();
            detached(py, || {
                estimators::reflected_radiance(env, phong, normal, wi, plan)
            })?
        }
    };
    Ok(PyEstimate {
        estimate,
        strategy: plan.strategy,
    })
}

/// Registers the estimators in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyEstimate>()?;
    m.add_function(wrap_pyfunction!(estimate, m)?)?;
    Ok(())
}

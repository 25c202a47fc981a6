//! `mcsample.estimators`: irradiance and reflected radiance under an
//! environment map (see [`crate::estimators`]).

use super::arrays::index_arg;
use super::envmap::PyEnvMap;
use super::parallel::detached;
use super::phong::PyPhong;
use crate::error::Error;
use crate::estimators::{self, Estimate, Heuristic, Plan, Strategy};
use numpy::PyArray1;
use pyo3::prelude::*;

/// A Monte Carlo estimate of an RGB quantity.
#[pyclass(module = "mcsample._core.estimators", name = "Estimate", frozen)]
pub struct PyEstimate {
    estimate: Estimate,
    strategy: String,
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

    /// The strategy that produced it.
    #[getter]
    fn strategy(&self) -> &str {
        &self.strategy
    }

    fn __repr__(&self) -> String {
        let e = &self.estimate;
        format!(
            "Estimate(value={:?}, stderr={:?}, n={}, strategy={:?})",
            e.value, e.stderr, e.n, self.strategy
        )
    }
}

fn choice<T>(
    arg: &'static str,
    name: &str,
    parse: impl Fn(&str) -> Option<T>,
    allowed: &str,
) -> PyResult<T> {
    parse(name).ok_or_else(|| {
        Error::Choice {
            arg,
            value: name.into(),
            requirement: format!("must be one of {allowed}"),
        }
        .into()
    })
}

fn vector(ob: &Bound<'_, PyAny>, arg: &'static str) -> PyResult<[f64; 3]> {
    let v: Vec<f64> = ob.extract().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(format!("{arg} must be three numbers"))
    })?;
    v.try_into().map_err(|v: Vec<f64>| {
        Error::Shape {
            arg,
            expected: "(3,)".into(),
            got: format!("({},)", v.len()),
        }
        .into()
    })
}

/// The irradiance E = integral of L(w) max(0, n.w) dw at a surface of
/// normal ``normal`` under ``env``, by Monte Carlo.
///
/// Parameters
/// ----------
/// env : EnvMap
/// normal : (3,) array_like, world space (normalised here)
/// n : int >= 1
///     Evaluations (an "mis" evaluation uses one cosine and one envmap
///     sample).
/// strategy : "uniform", "cosine", "envmap" or "mis" (default)
/// seed : int
///     Seed of the PCG32 stream; the result does not depend on the thread
///     count.
/// heuristic : "balance" (default) or "power"
///
/// Returns
/// -------
/// Estimate
///     ``.value`` (3,) RGB, ``.stderr`` (3,), ``.n``.
#[pyfunction]
#[pyo3(signature = (env, normal, n, strategy = "mis", seed = None, heuristic = "balance"))]
pub fn irradiance(
    py: Python<'_>,
    env: &Bound<'_, PyEnvMap>,
    normal: &Bound<'_, PyAny>,
    n: &Bound<'_, PyAny>,
    strategy: &str,
    seed: Option<&Bound<'_, PyAny>>,
    heuristic: &str,
) -> PyResult<PyEstimate> {
    let normal = vector(normal, "normal")?;
    let plan = plan(n, seed, strategy, "uniform, cosine, envmap, mis", heuristic)?;
    let env = env.get().inner();
    let estimate = detached(py, || estimators::irradiance(env, normal, plan))?;
    Ok(PyEstimate {
        estimate,
        strategy: strategy.into(),
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
/// strategy : "bsdf", "envmap" or "mis" (default)
/// seed : int
/// heuristic : "balance" (default) or "power"
///
/// Returns
/// -------
/// Estimate
#[pyfunction]
#[pyo3(signature = (env, phong, normal, wi, n, strategy = "mis", seed = None, heuristic = "balance"))]
#[allow(clippy::too_many_arguments)] // the Python signature
pub fn reflected_radiance(
    py: Python<'_>,
    env: &Bound<'_, PyEnvMap>,
    phong: &Bound<'_, PyPhong>,
    normal: &Bound<'_, PyAny>,
    wi: &Bound<'_, PyAny>,
    n: &Bound<'_, PyAny>,
    strategy: &str,
    seed: Option<&Bound<'_, PyAny>>,
    heuristic: &str,
) -> PyResult<PyEstimate> {
    let (normal, wi) = (vector(normal, "normal")?, vector(wi, "wi")?);
    let plan = plan(n, seed, strategy, "bsdf, envmap, mis", heuristic)?;
    let (env, phong) = (env.get().inner(), phong.get().inner());
    let estimate = detached(py, || {
        estimators::reflected_radiance(env, phong, normal, wi, plan)
    })?;
    Ok(PyEstimate {
        estimate,
        strategy: strategy.into(),
    })
}

/// The checked arguments of an estimator; `allowed` lists its strategies.
fn plan(
    n: &Bound<'_, PyAny>,
    seed: Option<&Bound<'_, PyAny>>,
    strategy: &str,
    allowed: &str,
    heuristic: &str,
) -> PyResult<Plan> {
    let offered =
        |name: &str| Strategy::from_name(name).filter(|_| allowed.split(", ").any(|a| a == name));
    Ok(Plan {
        n: index_arg(n, "n", 1, 1 << 40)? as usize,
        strategy: choice("strategy", strategy, offered, allowed)?,
        heuristic: choice(
            "heuristic",
            heuristic,
            Heuristic::from_name,
            "balance, power",
        )?,
        seed: match seed.filter(|s| !s.is_none()) {
            Some(s) => index_arg(s, "seed", 0, u64::MAX)?,
            None => 0,
        },
    })
}

/// Registers the estimators in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyEstimate>()?;
    m.add_function(wrap_pyfunction!(irradiance, m)?)?;
    m.add_function(wrap_pyfunction!(reflected_radiance, m)?)?;
    Ok(())
}

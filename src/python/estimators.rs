//! `mcsample.estimators`: irradiance and reflected radiance under an
//! environment map (see [`crate::estimators`]).

use super::args::{choice, heuristic_arg, index_arg, seed, three_floats};
use super::envmap::PyEnvMap;
use super::parallel::detached;
use super::phong::PyPhong;
use super::pickle::reduce;
use crate::error::Error;
use crate::estimators::{self, Estimate, Part, Plan, Strategy};
use crate::mis::Heuristic;
use crate::python::Obj;
use crate::sampler::Sampler;
use numpy::PyArray1;
use pyo3::prelude::*;

/// A Monte Carlo estimate of an RGB quantity.
#[pyclass(module = "mcsample._core.estimators", name = "Estimate", frozen)]
pub struct PyEstimate {
    estimate: Estimate,
    strategy: Strategy,
    /// What chunks of one run share: seed, sampler, heuristic, and the
    /// sequence's length for the samplers that depend on it (`None` for
    /// estimates made without `first_sample`).
    run: Option<Run>,
}

/// The settings that chunks of one run share.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Run {
    seed: u64,
    sampler: Sampler,
    heuristic: Heuristic,
    total: Option<usize>,
}

/// A run's settings as pickled: seed, sampler and heuristic by name, total.
type RunFields = (u64, String, String, Option<usize>);

impl Run {
    fn fields(&self) -> RunFields {
        let sampler = Sampler::NAMES.iter().find(|(_, s)| *s == self.sampler);
        let heuristic = match self.heuristic {
            Heuristic::Power => "power",
            Heuristic::Balance => "balance",
        };
        let sampler = sampler.map_or("independent", |(name, _)| name);
        (self.seed, sampler.into(), heuristic.into(), self.total)
    }

    fn from_fields((seed, sampler, heuristic, total): RunFields) -> PyResult<Self> {
        Ok(Run {
            seed,
            sampler: choice("sampler", &sampler, Sampler::NAMES)?,
            heuristic: heuristic_arg(&heuristic)?,
            total,
        })
    }
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

    /// The index of its first evaluation in the run's sequence (0 unless
    /// estimated with ``first_sample=``).
    #[getter]
    fn first_sample(&self) -> usize {
        self.estimate.parts.first().map_or(0, |p| p.start)
    }

    /// Whether it keeps the partial sums ``Estimate.merge`` needs (estimates
    /// made with ``first_sample=``, and merges, do).
    #[getter]
    fn mergeable(&self) -> bool {
        !self.estimate.parts.is_empty()
    }

    /// The estimate of chunks of one run (``estimators.*`` with the same
    /// arguments and ``first_sample=``), in any order, covering consecutive
    /// evaluations: the bits of one run of all their evaluations. It can be
    /// merged again with the chunks that follow.
    ///
    /// Raises ValueError for chunks with gaps or overlaps, of different
    /// strategies, or made without ``first_sample``.
    #[staticmethod]
    fn merge(py: Python<'_>, estimates: Vec<Bound<'_, PyEstimate>>) -> PyResult<PyEstimate> {
        let Some(first) = estimates.first() else {
            return Err(Error::Argument {
                arg: "estimates",
                message: "estimates is empty: nothing to merge".into(),
            }
            .into());
        };
        let strategy = first.get().strategy;
        let mut chunks = Vec::with_capacity(estimates.len());
        for e in &estimates {
            let e = e.get();
            if e.estimate.parts.is_empty() || e.strategy != strategy {
                return Err(Error::Argument {
                    arg: "estimates",
                    message: "estimates must be chunks of one run: made with first_sample= \
                              (which keeps the partial sums a merge needs), by one strategy"
                        .into(),
                }
                .into());
            }
            if e.run != first.get().run {
                return Err(Error::Argument {
                    arg: "estimates",
                    message: format!(
                        "estimates are chunks of different runs: seed, sampler, heuristic or \
                         total_n differ ({:?} and {:?})",
                        first.get().run,
                        e.run
                    ),
                }
                .into());
            }
            chunks.push(&e.estimate);
        }
        let estimate = detached(py, || estimators::merge(&chunks))?;
        let run = first.get().run;
        Ok(PyEstimate {
            estimate,
            strategy,
            run,
        })
    }

    /// The estimate of these numbers (the unpickling constructor): parts as
    /// (start, n, mean, m2).
    #[staticmethod]
    #[doc(hidden)]
    fn _from_fields(
        value: [f64; 3],
        stderr: [f64; 3],
        n: usize,
        strategy: &str,
        parts: Vec<(usize, usize, [f64; 3], [f64; 3])>,
        run: Option<RunFields>,
    ) -> PyResult<Self> {
        let run = run.map(Run::from_fields).transpose()?;
        let strategy = choice("strategy", strategy, &[IRRADIANCE, REFLECTED].concat())?;
        let parts = parts
            .into_iter()
            .map(|(start, n, mean, m2)| Part { start, n, mean, m2 })
            .collect();
        Ok(PyEstimate {
            estimate: Estimate {
                value,
                stderr,
                n,
                parts,
            },
            strategy,
            run,
        })
    }

    /// Pickles as its numbers.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let this = slf.get();
        let e = &this.estimate;
        let parts: Vec<_> = e
            .parts
            .iter()
            .map(|p| (p.start, p.n, p.mean, p.m2))
            .collect();
        let run = this.run.map(|r| r.fields());
        let args =
            (e.value, e.stderr, e.n, this.strategy.name(), parts, run).into_pyobject(slf.py())?;
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
#[pyo3(signature = (env, normal, n, *, phong = None, wi = None, strategy, seed, heuristic, sampler, first_sample = None, total_n = None))]
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
    first_sample: Option<Obj<'_>>,
    total_n: Option<Obj<'_>>,
) -> PyResult<PyEstimate> {
    let normal = three_floats(normal, "normal", false)?;
    let n = index_arg(n, "n", 1, 1 << 40)? as usize;
    let first = match &first_sample {
        Some(k) => index_arg(k, "first_sample", 0, 1 << 40)? as usize,
        None => 0,
    };
    let total = match &total_n {
        Some(t) => index_arg(t, "total_n", (first + n) as u64, 1 << 41)? as usize,
        None => first + n,
    };
    let plan = Plan {
        n,
        first,
        total,
        keep_parts: first_sample.is_some(),
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
    // Chunks of one run share these (the sequence's length only matters
    // to the samplers that lay patterns over it).
    let run = first_sample.is_some().then_some(Run {
        seed: plan.seed,
        sampler: plan.sampler,
        heuristic: plan.heuristic,
        total: (plan.sampler != Sampler::Independent).then_some(plan.total),
    });
    Ok(PyEstimate {
        estimate,
        strategy: plan.strategy,
        run,
    })
}

/// Registers the estimators in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyEstimate>()?;
    m.add_function(wrap_pyfunction!(estimate, m)?)?;
    Ok(())
}

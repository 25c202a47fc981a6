//! `mcsample.mis`: the multiple importance sampling heuristics of
//! [`crate::mis`], batched.

use super::arrays::{Check, Points, with_precision};
use super::batch::map_pair;
use crate::error::Error;
use crate::math::Real;
use crate::mis;
use crate::python::Obj;
use pyo3::prelude::*;

/// Balance heuristic p_a / (p_a + p_b): the MIS weight of a sample drawn by
/// strategy a. 0 where p_a = 0 (also 0/0); 1 where p_a is infinite and
/// p_b finite; 0.5 where both are infinite. Never NaN.
///
/// Parameters
/// ----------
/// pdf_a, pdf_b : float or array_like, shape (N,)
///     Densities (>= 0, NaN refused) of the sample under the two
///     strategies; a scalar broadcasts.
///
/// Returns
/// -------
/// ndarray, shape (N,) (a scalar for two scalars).
#[pyfunction]
pub fn balance_heuristic<'py>(
    py: Python<'py>,
    pdf_a: &Obj<'py>,
    pdf_b: &Obj<'py>,
) -> PyResult<Obj<'py>> {
    heuristic(py, pdf_a, pdf_b, 1.0)
}

/// Power heuristic p_a^beta / (p_a^beta + p_b^beta) (beta = 2 by
/// convention), with the degenerate cases of ``balance_heuristic``.
///
/// Parameters
/// ----------
/// pdf_a, pdf_b : float or array_like, shape (N,)
/// beta : float > 0
///
/// Returns
/// -------
/// ndarray, shape (N,) (a scalar for two scalars).
#[pyfunction]
#[pyo3(signature = (pdf_a, pdf_b, beta = 2.0))]
pub fn power_heuristic<'py>(
    py: Python<'py>,
    pdf_a: &Obj<'py>,
    pdf_b: &Obj<'py>,
    beta: f64,
) -> PyResult<Obj<'py>> {
    if !(beta > 0.0 && beta.is_finite()) {
        return Err(Error::Parameter {
            arg: "beta",
            value: beta,
            requirement: "must be finite and > 0",
        }
        .into());
    }
    heuristic(py, pdf_a, pdf_b, beta)
}

fn heuristic<'py>(
    py: Python<'py>,
    pdf_a: &Obj<'py>,
    pdf_b: &Obj<'py>,
    beta: f64,
) -> PyResult<Obj<'py>> {
    with_precision!(pdf_a, F => {
        let a = Points::<F, 1>::extract(pdf_a, "pdf_a")?;
        let b = Points::<F, 1>::extract(pdf_b, "pdf_b")?;
        let beta = F::c(beta);
        map_pair(py, (&a, Check::Density), (&b, Check::Density), #[inline(always)] move |a, b| {
            [mis::power_heuristic(a[0], b[0], beta)]
        })
    })
}

/// Registers the heuristics in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(balance_heuristic, m)?)?;
    m.add_function(wrap_pyfunction!(power_heuristic, m)?)?;
    Ok(())
}

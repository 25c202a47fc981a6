//! Multiple importance sampling: weights for combining two sampling
//! strategies (Veach and Guibas 1995).
//!
//! For a sample drawn by strategy `a` with density `p_a` (and `p_b` the
//! other strategy's density at the same point), the weight is
//! `w_a = p_a^β / (p_a^β + p_b^β)`: β = 1 is the balance heuristic, β = 2
//! the power heuristic. Degenerate cases are defined, never NaN:
//! `p_a = p_b = 0` gives 0 (the sample has no density under either), and
//! an infinite `p_a` gives 1 (½ if `p_b` is infinite too), see
//! [`power_heuristic`].
//!
//! # References
//! E. Veach, L. Guibas, "Optimally Combining Sampling Techniques for Monte
//! Carlo Rendering", SIGGRAPH 1995.

use crate::math::Real;

/// How MIS weights a sample of one strategy against the other: the one
/// choice of heuristic shared by the renderer and the estimators.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Heuristic {
    /// `p_a / (p_a + p_b)` ([`balance_heuristic`]).
    Balance,
    /// `p_a² / (p_a² + p_b²)` ([`power_heuristic`] with β = 2), the default
    /// (as Mitsuba's and pbrt's path tracers).
    #[default]
    Power,
}

impl Heuristic {
    /// The weight `w_a` of a sample drawn by strategy `a` (density `pdf_a`)
    /// against strategy `b` (density `pdf_b` at the same point), with the
    /// degenerate cases of [`power_heuristic`].
    #[inline(always)]
    pub fn weight<F: Real>(self, pdf_a: F, pdf_b: F) -> F {
        match self {
            Heuristic::Balance => balance_heuristic(pdf_a, pdf_b),
            Heuristic::Power => power_heuristic(pdf_a, pdf_b, F::c(2.0)),
        }
    }
}

/// Balance heuristic `p_a / (p_a + p_b)`; see [`power_heuristic`] for the
/// degenerate cases.
#[inline(always)]
pub fn balance_heuristic<F: Real>(pdf_a: F, pdf_b: F) -> F {
    weight(pdf_a, pdf_b, F::one())
}

/// Power heuristic with exponent `beta` (2 by convention):
/// `p_a^β / (p_a^β + p_b^β)`. 0 when `p_a = 0` (also when `p_b = 0`);
/// when `p_a` is infinite, 1 if `p_b` is finite and ½ if `p_b` is infinite
/// too (two delta strategies share the sample).
#[inline(always)]
pub fn power_heuristic<F: Real>(pdf_a: F, pdf_b: F, beta: F) -> F {
    weight(pdf_a, pdf_b, beta)
}

#[inline(always)]
fn weight<F: Real>(pdf_a: F, pdf_b: F, beta: F) -> F {
    if pdf_a.is_nan() || pdf_a <= F::zero() {
        return F::zero();
    }
    match (pdf_a.is_infinite(), pdf_b.is_infinite()) {
        (true, true) => F::c(0.5),
        (true, false) => F::one(),
        (false, true) => F::zero(),
        (false, false) => {
            // Scale by the larger density so that the powers neither
            // overflow nor underflow.
            let m = pdf_a.max(pdf_b);
            let (a, b) = (
                (pdf_a / m).powf(beta),
                (pdf_b.max(F::zero()) / m).powf(beta),
            );
            a / (a + b)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values_and_degenerate_cases() {
        assert_eq!(balance_heuristic(1.0, 3.0), 0.25);
        assert!((power_heuristic(1.0, 3.0, 2.0) - 0.1f64).abs() < 1e-16);
        assert_eq!(balance_heuristic(0.0, 0.0), 0.0);
        assert_eq!(balance_heuristic(0.0, 2.0), 0.0);
        assert_eq!(balance_heuristic(2.0, 0.0), 1.0);
        assert_eq!(balance_heuristic(f64::INFINITY, 2.0), 1.0);
        assert_eq!(balance_heuristic(2.0, f64::INFINITY), 0.0);
        assert_eq!(balance_heuristic(f64::INFINITY, f64::INFINITY), 0.5);
        assert_eq!(power_heuristic(1e200, 1e200, 2.0), 0.5);
        assert_eq!(power_heuristic(1e-200, 1e-200, 2.0), 0.5);
        // The two weights of a pair sum to 1.
        let (a, b) = (0.37f64, 1.9f64);
        assert!((power_heuristic(a, b, 2.0) + power_heuristic(b, a, 2.0) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn heuristic_weights_are_the_functions() {
        let (a, b) = (0.37f32, 1.9f32);
        assert_eq!(Heuristic::Balance.weight(a, b), balance_heuristic(a, b));
        assert_eq!(Heuristic::Power.weight(a, b), power_heuristic(a, b, 2.0));
        assert_eq!(Heuristic::default(), Heuristic::Power);
    }
}

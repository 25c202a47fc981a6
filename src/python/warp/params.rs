//! Checks of the warps' parameters: each returns the value in the kernel's
//! precision, or an error naming the argument.

use crate::error::{Error, Result, check_parameter};
use crate::math::{self, Real, V3};
use crate::python::args::choice;
use crate::warp;
use pyo3::prelude::*;

/// `exponent`, checked: finite and >= 0.
pub fn exponent_arg<F: Real>(exponent: f64) -> Result<F> {
    let ok = exponent.is_finite() && exponent >= 0.0;
    check_parameter("exponent", exponent, ok, "must be finite and >= 0")?;
    Ok(F::c(exponent))
}

/// `cos_cutoff`, checked: in [-1, 1).
pub fn cos_cutoff_arg<F: Real>(cos_cutoff: f64) -> Result<F> {
    let ok = (-1.0..1.0).contains(&cos_cutoff);
    check_parameter("cos_cutoff", cos_cutoff, ok, "must lie in [-1, 1)")?;
    Ok(F::c(cos_cutoff))
}

/// `(a, b, c)` of the nonuniform tent, checked: finite, `a ≤ b ≤ c`, `a < c`,
/// and `c − a` finite in the kernel's precision.
pub fn tent_args<F: Real>(a: f64, b: f64, c: f64) -> Result<(F, F, F)> {
    for (arg, value) in [("a", a), ("b", b), ("c", c)] {
        check_parameter(arg, value, value.is_finite(), "must be finite")?;
    }
    check_parameter("c", c, c > a, "must be greater than a")?;
    check_parameter("b", b, (a..=c).contains(&b), "must lie in [a, c]")?;
    let (a, b, c) = (F::c(a), F::c(b), F::c(c));
    let width = c - a;
    let requirement = "c - a must be a finite number in the input's precision";
    check_parameter("c", c.f64(), width.is_finite(), requirement)?;
    Ok((a, b, c))
}

/// `(v0, v1)` of the linear warps, checked (finite, `>= 0`, not both 0)
/// and divided by the larger (the density depends only on their ratio, and
/// their squares then cannot overflow).
pub fn linear_args<F: Real>(v0: f64, v1: f64) -> Result<(F, F)> {
    for (arg, value) in [("v0", v0), ("v1", v1)] {
        let ok = value.is_finite() && value >= 0.0;
        check_parameter(arg, value, ok, "must be finite and >= 0")?;
    }
    let larger = v0.max(v1);
    check_parameter("v1", v1, larger > 0.0, "v0 and v1 must not both be 0")?;
    Ok((F::c(v0 / larger), F::c(v1 / larger)))
}

/// `alpha` of the Beckmann warps, checked: finite and > 0, with `alpha²`
/// a positive finite number in the kernel's precision.
pub fn alpha_arg<F: Real>(alpha: f64) -> Result<F> {
    let a = F::c(alpha);
    let ok = alpha.is_finite() && alpha > 0.0;
    check_parameter("alpha", alpha, ok, "must be finite and > 0")?;
    let fits = (a * a).is_finite() && a * a > F::zero();
    let requirement = "alpha^2 must be a positive finite number in the input's precision";
    check_parameter("alpha", alpha, fits, requirement)?;
    Ok(a)
}

/// The von Mises–Fisher lobe of `kappa` (of the vMF and rough-fibre
/// warps), checked: finite and >= 0.
pub fn lobe_arg<F: Real>(kappa: f64) -> Result<warp::VonMisesFisher<F>> {
    let ok = kappa.is_finite() && kappa >= 0.0;
    check_parameter("kappa", kappa, ok, "must be finite and >= 0")?;
    let requirement = "must be finite in the input's precision";
    check_parameter("kappa", kappa, F::c(kappa).is_finite(), requirement)?;
    Ok(warp::VonMisesFisher::new(F::c(kappa)))
}

/// A direction argument, checked (finite, not zero) and normalised in f64.
pub fn unit_arg<F: Real>(arg: &'static str, v: [f64; 3]) -> Result<V3<F>> {
    let length = math::dot(v, v).sqrt();
    if !(length > 0.0 && length.is_finite()) {
        return Err(Error::Argument {
            arg,
            message: format!("{arg} = {v:?}: must be a finite, non-zero vector"),
        });
    }
    Ok(v.map(|c| F::c(c / length)))
}

/// The lunes of the normals `n1` and `n2`, checked: finite, non-zero,
/// neither parallel nor opposite.
pub fn lunes_arg<F: Real>(n1: [f64; 3], n2: [f64; 3]) -> Result<warp::Lunes<F>> {
    unit_arg::<f64>("n1", n1)?;
    unit_arg::<f64>("n2", n2)?;
    warp::Lunes::new(n1, n2).ok_or_else(|| Error::Argument {
        arg: "n2",
        message: format!(
            "n1 = {n1:?}, n2 = {n2:?}: the normals must be neither parallel nor opposite"
        ),
    })
}

/// The corners `(v00, v10, v01, v11)` of a bilinear density, checked
/// (finite, >= 0, not all 0) and divided by their mean (the density is the
/// interpolant of corners with mean 1).
pub fn corners_arg<F: Real>(v00: f64, v10: f64, v01: f64, v11: f64) -> Result<warp::Corners<F>> {
    let v = [("v00", v00), ("v10", v10), ("v01", v01), ("v11", v11)];
    for (arg, value) in v {
        let ok = value.is_finite() && value >= 0.0;
        check_parameter(arg, value, ok, "must be finite and >= 0")?;
    }
    let largest = v.iter().fold(0.0f64, |m, &(_, value)| m.max(value));
    check_parameter("v11", v11, largest > 0.0, "the corners must not all be 0")?;
    // Scaled by the largest first, so that the sum cannot overflow.
    let scaled = v.map(|(_, value)| value / largest);
    let mean = scaled.iter().sum::<f64>() / 4.0;
    Ok(scaled.map(|value| F::c(value / mean)))
}

/// `method` of the cosine-hemisphere warps: true for "polar", false for
/// "concentric".
pub fn polar_arg(method: &str) -> PyResult<bool> {
    choice("method", method, &[("concentric", false), ("polar", true)])
}

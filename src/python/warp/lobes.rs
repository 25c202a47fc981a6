//! Lobes with a spread parameter (the standard normal, Beckmann, von
//! Mises–Fisher, rough fibre), the spherical lunes, tangent directions and
//! the bilinear density.

use super::params::{alpha_arg, corners_arg, lobe_arg, lunes_arg, unit_arg};
use super::shaped;
use crate::python::arrays::{Check, Points, PyFloat, with_precision};
use crate::python::batch::{map_into, map2};
use crate::python::{Obj, Out};
use crate::warp;
use pyo3::prelude::*;

warps! {
    /// The standard normal on the plane by the Box-Muller map:
    /// r = sqrt(-2 ln(1 - v[..., 0])), phi = 2 pi v[..., 1].
    fn square_to_std_normal(v: [2; Unit] "values in [0, 1]")
        -> [2] "points of the plane; density exp(-|x|^2 / 2) / (2 pi) per unit area"
        = |F| warp::square_to_std_normal::<F>;

    /// Density of ``square_to_std_normal``: exp(-|x|^2 / 2) / (2 pi).
    fn square_to_std_normal_pdf(v: [2; Finite] "points of the plane")
        -> [1] "per unit area"
        = |F| #[inline(always)] |p| [warp::square_to_std_normal_pdf::<F>(p)];

    /// Beckmann-distributed microfacet normals (Mitsuba's low-distortion
    /// map): tan^2 theta = -alpha^2 ln(1 - r^2) of the concentric disk
    /// point.
    fn square_to_beckmann(
        sample: [2; Unit] "values in [0, 1]",
        alpha: f64 = "float > 0, the roughness"
    ) -> [3] "unit vectors with z >= 0; density exp(-tan^2 theta / alpha^2) / (pi alpha^2 cos^3 theta) per sr"
        = |F| let alpha = alpha_arg(alpha)?; #[inline(always)] move |u| warp::square_to_beckmann(u, alpha);

    /// Density of ``square_to_beckmann``: exp(-tan^2 theta / alpha^2) /
    /// (pi alpha^2 cos^3 theta) per steradian for z > 0, else 0.
    fn square_to_beckmann_pdf(
        v: [3; Finite] "unit vectors",
        alpha: f64 = "float > 0, the roughness"
    ) -> [1] "per steradian"
        = |F| let alpha = alpha_arg(alpha)?; #[inline(always)] move |m| [warp::square_to_beckmann_pdf(m, alpha)];

    /// Inverse of ``square_to_beckmann``.
    fn beckmann_to_square(
        v: [3; Finite] "unit vectors with z >= 0",
        alpha: f64 = "float > 0, the roughness"
    ) -> [2] "in [0, 1]^2"
        = |F| let alpha = alpha_arg(alpha)?; #[inline(always)] move |m| warp::beckmann_to_square(m, alpha);

    /// Directions of the von Mises-Fisher lobe around +z: phi = 2 pi
    /// sample[..., 0], 1 - cos theta = -ln(1 - sample[..., 1] (1 -
    /// exp(-2 kappa))) / kappa (the uniform sphere for kappa = 0).
    fn square_to_von_mises_fisher(
        sample: [2; Unit] "values in [0, 1]",
        kappa: f64 = "float >= 0, the concentration"
    ) -> [3] "unit vectors; density kappa exp(kappa (cos theta - 1)) / (2 pi (1 - exp(-2 kappa))) per sr"
        = |F| let lobe = lobe_arg(kappa)?; #[inline(always)] move |u| warp::square_to_von_mises_fisher(u, &lobe);

    /// Density of ``square_to_von_mises_fisher``: kappa exp(kappa (cos
    /// theta - 1)) / (2 pi (1 - exp(-2 kappa))) per steradian (1 / (4 pi)
    /// for kappa = 0).
    fn square_to_von_mises_fisher_pdf(
        v: [3; Finite] "unit vectors",
        kappa: f64 = "float >= 0, the concentration"
    ) -> [1] "per steradian"
        = |F| let lobe = lobe_arg(kappa)?;
            #[inline(always)] move |d| [warp::square_to_von_mises_fisher_pdf(d, &lobe)];

    /// Inverse of ``square_to_von_mises_fisher``: (phi / 2 pi, (1 -
    /// exp(kappa (cos theta - 1))) / (1 - exp(-2 kappa))).
    fn von_mises_fisher_to_square(
        v: [3; Finite] "unit vectors",
        kappa: f64 = "float >= 0, the concentration"
    ) -> [2] "in [0, 1]^2"
        = |F| let lobe = lobe_arg(kappa)?; #[inline(always)] move |d| warp::von_mises_fisher_to_square(d, &lobe);

    /// Directions of the rough-fibre lobe: sample[..., 0] picks a direction
    /// on the fibre's specular cone of wi, sample[..., 1:] perturbs it by the
    /// von Mises-Fisher lobe of concentration kappa.
    fn square_to_rough_fiber(
        sample: [3; Unit] "values in [0, 1]",
        wi: [f64; 3] = "3 floats, the incident direction (normalised)",
        tangent: [f64; 3] = "3 floats, the fibre's tangent (normalised)",
        kappa: f64 = "float >= 0, the concentration"
    ) -> [3] "unit vectors"
        = |F| let (wi, t) = (unit_arg("wi", wi)?, unit_arg("tangent", tangent)?);
            let lobe = lobe_arg(kappa)?;
            #[inline(always)] move |u| warp::square_to_rough_fiber(u, wi, t, &lobe);

    /// Density of ``square_to_rough_fiber`` per steradian: exp(-s) I0(c)
    /// kappa exp(-kappa) / (2 pi (1 - exp(-2 kappa))) with s = kappa (wi.t)
    /// (v.t), c = kappa cos_i cos_o (d'Eon et al. 2011; I0 exact, where
    /// Mitsuba's truncated series is 0.6 % low at c = 12).
    fn square_to_rough_fiber_pdf(
        v: [3; Finite] "unit vectors",
        wi: [f64; 3] = "3 floats, the incident direction (normalised)",
        tangent: [f64; 3] = "3 floats, the fibre's tangent (normalised)",
        kappa: f64 = "float >= 0, the concentration"
    ) -> [1] "per steradian"
        = |F| let (wi, t) = (unit_arg("wi", wi)?, unit_arg("tangent", tangent)?);
            let lobe = lobe_arg(kappa)?;
            #[inline(always)] move |d| [warp::square_to_rough_fiber_pdf(d, wi, t, &lobe)];

    /// Uniform directions in the two spherical lunes between the faces of
    /// normals n1 and n2: azimuth within theta = acos(n1.n2) / 2 of either
    /// end of the axis orthogonal to n1 + n2 and n1 x n2.
    fn square_to_uniform_spherical_lune(
        sample: [2; Unit] "values in [0, 1]",
        n1: [f64; 3] = "3 floats, the first normal (normalised)",
        n2: [f64; 3] = "3 floats, the second normal, not parallel to n1"
    ) -> [3] "unit vectors; density 1 / (8 theta) per sr"
        = |F| let lunes = lunes_arg(n1, n2)?;
            #[inline(always)] move |u| warp::square_to_uniform_spherical_lune(u, &lunes);

    /// Density of ``square_to_uniform_spherical_lune``: 1 / (8 theta) per
    /// steradian in the lunes, else 0 (Mitsuba: 1 / (8 theta) everywhere).
    fn square_to_uniform_spherical_lune_pdf(
        d: [3; Finite] "unit vectors",
        n1: [f64; 3] = "3 floats, the first normal (normalised)",
        n2: [f64; 3] = "3 floats, the second normal, not parallel to n1"
    ) -> [1] "per steradian"
        = |F| let lunes = lunes_arg(n1, n2)?;
            #[inline(always)] move |d| [warp::square_to_uniform_spherical_lune_pdf(d, &lunes)];

    /// Inverse of ``square_to_uniform_spherical_lune``.
    fn uniform_spherical_lune_to_square(
        d: [3; Finite] "unit vectors in the lunes",
        n1: [f64; 3] = "3 floats, the first normal (normalised)",
        n2: [f64; 3] = "3 floats, the second normal, not parallel to n1"
    ) -> [2] "in [0, 1]^2"
        = |F| let lunes = lunes_arg(n1, n2)?;
            #[inline(always)] move |d| warp::uniform_spherical_lune_to_square(d, &lunes);

    /// Directions in the plane orthogonal to n: cos(2 pi u) s + sin(2 pi
    /// u) t, with (s, t, n) Mitsuba's frame of n.
    fn interval_to_tangent_direction(
        { n: [f64; 3] = "3 floats, the normal (normalised)" }
        sample: [1; Unit] "values in [0, 1]"
    ) -> [3] "unit vectors orthogonal to n; uniform in angle"
        = |F| let n = unit_arg("n", n)?;
            #[inline(always)] move |u: [F; 1]| warp::interval_to_tangent_direction(n, u[0]);

    /// Inverse of ``interval_to_tangent_direction``: the angle of the
    /// direction in n's frame as a fraction of a turn.
    fn tangent_direction_to_interval(
        { n: [f64; 3] = "3 floats, the normal (normalised)" }
        dir: [3; Finite] "directions orthogonal to n"
    ) -> [1] "in [0, 1)"
        = |F| let n = unit_arg("n", n)?; #[inline(always)] move |d| [warp::tangent_direction_to_interval(n, d)];

    /// Density of ``square_to_bilinear``: the bilinear interpolant of the
    /// corners divided by their mean, on [0, 1]^2, else 0 (Mitsuba returns
    /// the interpolant itself: the same for corners of mean 1).
    fn square_to_bilinear_pdf(
        { v00: f64 = "float >= 0, the value at (0, 0)",
          v10: f64 = "float >= 0, at (1, 0)", v01: f64 = "float >= 0, at (0, 1)",
          v11: f64 = "float >= 0, at (1, 1) (not all 0)" }
        sample: [2; Finite] "points of the plane"
    ) -> [1] "per unit area"
        = |F| let v = corners_arg(v00, v10, v01, v11)?;
            #[inline(always)] move |p| [warp::square_to_bilinear_pdf(v, p)];
}

/// Points of the bilinear density with corner values v00 at (0, 0), v10 at
/// (1, 0), v01 at (0, 1) and v11 at (1, 1), by inversion: y from the
/// marginal density, then x from the conditional (Mitsuba's order).
///
/// Parameters
/// ----------
/// v00, v10, v01, v11 : float >= 0, not all 0
///     The corner values, at any scale: the density is their interpolant
///     divided by their mean.
/// sample : array_like, shape (..., 2), values in [0, 1]
/// out : (ndarray, ndarray), optional, keyword only
///     Written with the points and densities and returned.
///
/// Returns
/// -------
/// (ndarray, ndarray)
///     The points, shape (..., 2), in [0, 1]^2, and their densities per
///     unit area, the batch's shape (Mitsuba returns the interpolant
///     itself: the same for corners of mean 1).
#[pyfunction]
#[pyo3(signature = (v00, v10, v01, v11, sample, *, out = None))]
pub fn square_to_bilinear<'py>(
    py: Python<'py>,
    v00: f64,
    v10: f64,
    v01: f64,
    v11: f64,
    sample: &Obj<'py>,
    out: Out<'_, 'py>,
) -> PyResult<(Obj<'py>, Obj<'py>)> {
    let corners = [v00, v10, v01, v11];
    with_precision!(sample, F => with_density(
        py, corners, sample, (Check::Unit, (out, "points, pdf")), warp::square_to_bilinear::<F>,
    ))
}

/// Inverse of ``square_to_bilinear``.
///
/// Parameters
/// ----------
/// v00, v10, v01, v11 : float >= 0, not all 0
///     The corner values, as given to ``square_to_bilinear``.
/// sample : array_like, shape (..., 2), points of [0, 1]^2
/// out : (ndarray, ndarray), optional, keyword only
///     Written with the numbers and densities and returned.
///
/// Returns
/// -------
/// (ndarray, ndarray)
///     The numbers in [0, 1]^2 that map to the points, shape (..., 2), and
///     the points' densities per unit area, the batch's shape.
#[pyfunction]
#[pyo3(signature = (v00, v10, v01, v11, sample, *, out = None))]
pub fn bilinear_to_square<'py>(
    py: Python<'py>,
    v00: f64,
    v10: f64,
    v01: f64,
    v11: f64,
    sample: &Obj<'py>,
    out: Out<'_, 'py>,
) -> PyResult<(Obj<'py>, Obj<'py>)> {
    let corners = [v00, v10, v01, v11];
    with_precision!(sample, F => with_density(
        py, corners, sample, (Check::Finite, (out, "u, pdf")), warp::bilinear_to_square::<F>,
    ))
}

/// Maps the points `sample` (checked by `check`) through a bilinear
/// `kernel` of the checked `corners`, returning its points and densities as
/// two arrays (into those of `out` when given; see [`map2`]).
fn with_density<'py, F: PyFloat, K>(
    py: Python<'py>,
    [v00, v10, v01, v11]: [f64; 4],
    sample: &Obj<'py>,
    (check, out): (Check, (Out<'_, 'py>, &str)),
    kernel: K,
) -> PyResult<(Obj<'py>, Obj<'py>)>
where
    K: Fn(warp::Corners<F>, [F; 2]) -> ([F; 2], F) + Sync + Send,
{
    let corners = corners_arg(v00, v10, v01, v11)?;
    let points = Points::<F, 2>::extract(sample, "sample")?;
    map2(
        py,
        &points,
        check,
        out,
        #[inline(always)]
        |p| {
            let (q, pdf) = kernel(corners, p);
            (q, [pdf])
        },
    )
}

/// Registers the lobes, lunes, tangent and bilinear warps in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    add_functions!(
        m,
        square_to_std_normal,
        square_to_std_normal_pdf,
        square_to_beckmann,
        square_to_beckmann_pdf,
        beckmann_to_square,
        square_to_von_mises_fisher,
        square_to_von_mises_fisher_pdf,
        von_mises_fisher_to_square,
        square_to_rough_fiber,
        square_to_rough_fiber_pdf,
        square_to_uniform_spherical_lune,
        square_to_uniform_spherical_lune_pdf,
        uniform_spherical_lune_to_square,
        interval_to_tangent_direction,
        tangent_direction_to_interval,
        square_to_bilinear,
        square_to_bilinear_pdf,
        bilinear_to_square
    );
    Ok(())
}

//! Warps onto disks, spheres, hemispheres, cones, triangles and intervals
//! (power, tent and linear densities).

use super::params::{cos_cutoff_arg, exponent_arg, linear_args, polar_arg, tent_args};
use super::shaped;
use crate::python::arrays::{Check, Points, PyFloat, with_precision};
use crate::python::batch::map_into;
use crate::python::{Obj, Out};
use crate::warp;
use pyo3::prelude::*;

warps! {
    /// Uniform points on the unit disk by the polar map r = sqrt(u[..., 1]),
    /// phi = 2 pi u[..., 0] (Mitsuba's order).
    fn square_to_uniform_disk(u: [2; Unit] "values in [0, 1]")
        -> [2] "points of the unit disk; density 1/pi per unit area"
        = |F| warp::square_to_uniform_disk::<F>;

    /// Density of ``square_to_uniform_disk``: 1/pi on the unit disk, else 0.
    fn square_to_uniform_disk_pdf(x: [2; Finite] "points of the plane")
        -> [1] "per unit area"
        = |F| #[inline(always)] |p| [warp::square_to_uniform_disk_pdf::<F>(p)];

    /// Inverse of ``square_to_uniform_disk``: (phi / 2 pi, r^2).
    fn uniform_disk_to_square(x: [2; Finite] "points of the unit disk")
        -> [2] "in [0, 1]^2"
        = |F| warp::uniform_disk_to_square::<F>;

    /// Uniform points on the unit disk by Shirley and Chiu's concentric map.
    fn square_to_uniform_disk_concentric(u: [2; Unit] "values in [0, 1]")
        -> [2] "points of the unit disk; density 1/pi per unit area"
        = |F| warp::square_to_uniform_disk_concentric::<F>;

    /// Density of ``square_to_uniform_disk_concentric``: 1/pi on the unit
    /// disk, else 0.
    fn square_to_uniform_disk_concentric_pdf(x: [2; Finite] "points of the plane")
        -> [1] "per unit area"
        = |F| #[inline(always)] |p| [warp::square_to_uniform_disk_concentric_pdf::<F>(p)];

    /// Inverse of ``square_to_uniform_disk_concentric``.
    fn uniform_disk_to_square_concentric(x: [2; Finite] "points of the unit disk")
        -> [2] "in [0, 1]^2; the origin gives (0.5, 0.5)"
        = |F| warp::uniform_disk_to_square_concentric::<F>;

    /// Uniform directions on the unit sphere: z = 1 - 2 u[..., 1],
    /// phi = 2 pi u[..., 0].
    fn square_to_uniform_sphere(u: [2; Unit] "values in [0, 1]")
        -> [3] "unit vectors; density 1/(4 pi) per sr"
        = |F| warp::square_to_uniform_sphere::<F>;

    /// Density of ``square_to_uniform_sphere``: 1/(4 pi) per steradian.
    fn square_to_uniform_sphere_pdf(x: [3; Finite] "unit vectors")
        -> [1] "per steradian"
        = |F| #[inline(always)] |d| [warp::square_to_uniform_sphere_pdf::<F>(d)];

    /// Inverse of ``square_to_uniform_sphere``: (phi / 2 pi, (1 - z) / 2).
    fn uniform_sphere_to_square(x: [3; Finite] "unit vectors")
        -> [2] "in [0, 1]^2"
        = |F| warp::uniform_sphere_to_square::<F>;

    /// Uniform directions on the +z hemisphere (a concentric disk point
    /// lifted by an area-preserving map).
    fn square_to_uniform_hemisphere(u: [2; Unit] "values in [0, 1]")
        -> [3] "unit vectors with z >= 0; density 1/(2 pi) per sr"
        = |F| warp::square_to_uniform_hemisphere::<F>;

    /// Density of ``square_to_uniform_hemisphere``: 1/(2 pi) per steradian
    /// for z >= 0, else 0.
    fn square_to_uniform_hemisphere_pdf(x: [3; Finite] "unit vectors")
        -> [1] "per steradian"
        = |F| #[inline(always)] |d| [warp::square_to_uniform_hemisphere_pdf::<F>(d)];

    /// Inverse of ``square_to_uniform_hemisphere``.
    fn uniform_hemisphere_to_square(x: [3; Finite] "unit vectors with z >= 0")
        -> [2] "in [0, 1]^2"
        = |F| warp::uniform_hemisphere_to_square::<F>;

    /// Density of ``square_to_cosine_hemisphere`` (either method):
    /// max(cos theta, 0) / pi per steradian.
    fn square_to_cosine_hemisphere_pdf(x: [3; Finite] "unit vectors")
        -> [1] "per steradian"
        = |F| #[inline(always)] |d| [warp::square_to_cosine_hemisphere_pdf::<F>(d)];

    /// Directions of the cos^n lobe around +z (the Phong lobe):
    /// cos theta = u1^(1/(n+1)), phi = 2 pi u0.
    fn square_to_cosine_power_hemisphere(
        u: [2; Unit] "values in [0, 1]",
        exponent: f64 = "float >= 0, the lobe's n"
    ) -> [3] "unit vectors; density (n + 1)/(2 pi) cos^n theta per sr"
        = |F| let n = exponent_arg(exponent)?;
            #[inline(always)] move |u| warp::square_to_cosine_power_hemisphere(u, n);

    /// Density of ``square_to_cosine_power_hemisphere``:
    /// (n + 1)/(2 pi) cos^n theta per steradian for cos theta > 0, else 0.
    fn square_to_cosine_power_hemisphere_pdf(
        x: [3; Finite] "unit vectors",
        exponent: f64 = "float >= 0, the lobe's n"
    ) -> [1] "per steradian"
        = |F| let n = exponent_arg(exponent)?;
            #[inline(always)] move |d| [warp::square_to_cosine_power_hemisphere_pdf(d, n)];

    /// Inverse of ``square_to_cosine_power_hemisphere``:
    /// (phi / 2 pi, cos^(n+1) theta).
    fn cosine_power_hemisphere_to_square(
        x: [3; Finite] "unit vectors with z >= 0",
        exponent: f64 = "float >= 0, the lobe's n"
    ) -> [2] "in [0, 1]^2"
        = |F| let n = exponent_arg(exponent)?;
            #[inline(always)] move |d| warp::cosine_power_hemisphere_to_square(d, n);

    /// Uniform directions in the cone cos theta >= cos_cutoff around +z.
    fn square_to_uniform_cone(
        u: [2; Unit] "values in [0, 1]",
        cos_cutoff: f64 = "float in [-1, 1)"
    ) -> [3] "unit vectors; density 1 / (2 pi (1 - cos_cutoff)) per sr"
        = |F| let c = cos_cutoff_arg(cos_cutoff)?; #[inline(always)] move |u| warp::square_to_uniform_cone(u, c);

    /// Density of ``square_to_uniform_cone``: 1 / (2 pi (1 - cos_cutoff))
    /// per steradian inside the cone, else 0.
    fn square_to_uniform_cone_pdf(
        x: [3; Finite] "unit vectors",
        cos_cutoff: f64 = "float in [-1, 1)"
    ) -> [1] "per steradian"
        = |F| let c = cos_cutoff_arg(cos_cutoff)?;
            #[inline(always)] move |d| [warp::square_to_uniform_cone_pdf(d, c)];

    /// Inverse of ``square_to_uniform_cone``.
    fn uniform_cone_to_square(
        x: [3; Finite] "unit vectors inside the cone",
        cos_cutoff: f64 = "float in [-1, 1)"
    ) -> [2] "in [0, 1]^2"
        = |F| let c = cos_cutoff_arg(cos_cutoff)?; #[inline(always)] move |d| warp::uniform_cone_to_square(d, c);

    /// Uniform points on the triangle (0, 0), (1, 0), (0, 1):
    /// t = sqrt(1 - u0), point (1 - t, t u1).
    fn square_to_uniform_triangle(u: [2; Unit] "values in [0, 1]")
        -> [2] "barycentric coordinates; density 2 per unit area"
        = |F| warp::square_to_uniform_triangle::<F>;

    /// Density of ``square_to_uniform_triangle``: 2 inside the triangle,
    /// else 0.
    fn square_to_uniform_triangle_pdf(x: [2; Finite] "points of the plane")
        -> [1] "per unit area"
        = |F| #[inline(always)] |p| [warp::square_to_uniform_triangle_pdf::<F>(p)];

    /// Inverse of ``square_to_uniform_triangle``.
    fn uniform_triangle_to_square(x: [2; Finite] "points of the triangle")
        -> [2] "in [0, 1]^2"
        = |F| warp::uniform_triangle_to_square::<F>;

    /// The power density (n + 1) x^n on [0, 1] by inversion:
    /// x = u^(1/(n+1)).
    fn interval_to_power(u: [1; Unit] "values in [0, 1]", exponent: f64 = "float >= 0")
        -> [1] "in [0, 1]"
        = |F| let n = exponent_arg(exponent)?; #[inline(always)] move |u: [F; 1]| [warp::interval_to_power(u[0], n)];

    /// Density of ``interval_to_power``: (n + 1) x^n on [0, 1], else 0.
    fn interval_to_power_pdf(x: [1; Finite] "finite", exponent: f64 = "float >= 0")
        -> [1] "per unit length"
        = |F| let n = exponent_arg(exponent)?;
            #[inline(always)] move |x: [F; 1]| [warp::interval_to_power_pdf(x[0], n)];

    /// Inverse of ``interval_to_power``: u = x^(n+1).
    fn power_to_interval(x: [1; Finite] "values in [0, 1]", exponent: f64 = "float >= 0")
        -> [1] "in [0, 1]"
        = |F| let n = exponent_arg(exponent)?; #[inline(always)] move |x: [F; 1]| [warp::power_to_interval(x[0], n)];

    /// The tent 1 - |x| on [-1, 1] by inversion (Mitsuba's
    /// ``interval_to_tent``): s = u - 1/2, x = sign(s) (1 - sqrt(1 - 2|s|)).
    fn interval_to_tent(sample: [1; Unit] "values in [0, 1]")
        -> [1] "in [-1, 1]; density 1 - |x| per unit length"
        = |F| #[inline(always)] |u: [F; 1]| [warp::interval_to_tent(u[0])];

    /// Inverse of ``interval_to_tent``: u = (x (2 - |x|) + 1) / 2.
    fn tent_to_interval(value: [1; Finite] "values in [-1, 1]")
        -> [1] "in [0, 1]"
        = |F| #[inline(always)] |x: [F; 1]| [warp::tent_to_interval(x[0])];

    /// ``interval_to_tent`` in each coordinate: the tent
    /// (1 - |x|)(1 - |y|) on [-1, 1]^2.
    fn square_to_tent(sample: [2; Unit] "values in [0, 1]")
        -> [2] "in [-1, 1]^2; density (1 - |x|)(1 - |y|) per unit area"
        = |F| warp::square_to_tent::<F>;

    /// Inverse of ``square_to_tent``.
    fn tent_to_square(value: [2; Finite] "points of [-1, 1]^2")
        -> [2] "in [0, 1]^2"
        = |F| warp::tent_to_square::<F>;

    /// Density of ``square_to_tent``: (1 - |x|)(1 - |y|) on [-1, 1]^2,
    /// else 0.
    fn square_to_tent_pdf(v: [2; Finite] "points of the plane")
        -> [1] "per unit area"
        = |F| #[inline(always)] |p| [warp::square_to_tent_pdf::<F>(p)];

    /// The tent on [a, c] with its peak at b (Mitsuba's
    /// ``interval_to_nonuniform_tent``; the falling side runs from c down
    /// to b as u grows): density 2(x - a)/((c - a)(b - a)) below b and
    /// 2(c - x)/((c - a)(c - b)) above.
    fn interval_to_nonuniform_tent(
        { a: f64 = "float, the left end", b: f64 = "float in [a, c], the peak",
          c: f64 = "float > a, the right end" }
        d: [1; Unit] "values in [0, 1] (the sample)"
    ) -> [1] "in [a, c]"
        = |F| let (a, b, c) = tent_args(a, b, c)?;
            #[inline(always)] move |u: [F; 1]| [warp::interval_to_nonuniform_tent(a, b, c, u[0])];

    /// The linear density on [0, 1] from v0 at 0 to v1 at 1 by inversion:
    /// x = (v0 - sqrt((1 - u) v0^2 + u v1^2)) / (v0 - v1) (x = u when the
    /// ends agree to 1e-4, as Mitsuba).
    fn interval_to_linear(
        { v0: f64 = "float >= 0, the density's value at 0",
          v1: f64 = "float >= 0, its value at 1 (not both 0)" }
        sample: [1; Unit] "values in [0, 1]"
    ) -> [1] "in [0, 1]; density 2((1 - x) v0 + x v1)/(v0 + v1) per unit length"
        = |F| let (v0, v1) = linear_args(v0, v1)?;
            #[inline(always)] move |u: [F; 1]| [warp::interval_to_linear(v0, v1, u[0])];

    /// Inverse of ``interval_to_linear``: u = x (x v1 + (2 - x) v0)/(v0 + v1).
    fn linear_to_interval(
        { v0: f64 = "float >= 0", v1: f64 = "float >= 0 (not both 0)" }
        sample: [1; Finite] "values in [0, 1]"
    ) -> [1] "in [0, 1]"
        = |F| let (v0, v1) = linear_args(v0, v1)?;
            #[inline(always)] move |x: [F; 1]| [warp::linear_to_interval(v0, v1, x[0])];

    /// The concentric map's polar coordinates as a point of the square
    /// (Mitsuba's ``square_to_uniform_square_concentric``): (phi / 2 pi,
    /// r^2) of ``square_to_uniform_disk_concentric(sample)``, a
    /// measure-preserving map of the square onto itself.
    fn square_to_uniform_square_concentric(sample: [2; Unit] "values in [0, 1]")
        -> [2] "in [0, 1]^2; density 1; the centre gives (0, 0)"
        = |F| warp::square_to_uniform_square_concentric::<F>;

}

/// Cosine-weighted directions on the +z hemisphere (Malley's method).
///
/// Parameters
/// ----------
/// u : array_like, shape (..., 2), values in [0, 1]
/// method : "concentric" (default; lifts a concentric disk point, as
///     ``mi.warp`` does) or "polar" (x = cos(2 pi u0) sqrt(1 - u1),
///     y = sin(2 pi u0) sqrt(1 - u1), z = sqrt(u1))
/// out : ndarray, optional, keyword only
///     Written with the result and returned (its shape and dtype).
///
/// Returns
/// -------
/// ndarray, shape (..., 3), unit vectors; density cos(theta)/pi per sr.
#[pyfunction]
#[pyo3(signature = (u, method = "concentric", *, out = None))]
pub fn square_to_cosine_hemisphere<'py>(
    py: Python<'py>,
    u: &Obj<'py>,
    method: &str,
    out: Out<'_, 'py>,
) -> PyResult<Obj<'py>> {
    with_precision!(u, F => by_method(
        py, u, "u", Check::Unit, method, out,
        warp::square_to_cosine_hemisphere_polar::<F>,
        warp::square_to_cosine_hemisphere::<F>,
    ))
}

/// Maps `x` (argument `arg`) through `polar` or `concentric` as `method`
/// asks: the choice is made outside the batch loop, which must stay
/// branch-free to vectorise.
#[allow(clippy::too_many_arguments)]
fn by_method<'py, F: PyFloat, const K: usize, const M: usize, P, C>(
    py: Python<'py>,
    x: &Obj<'py>,
    arg: &'static str,
    check: Check,
    method: &str,
    out: Out<'_, 'py>,
    polar: P,
    concentric: C,
) -> PyResult<Obj<'py>>
where
    // Generic (not fn pointers), so that the kernels stay inlined into the
    // vectorised loop.
    P: Fn([F; K]) -> [F; M] + Sync + Send,
    C: Fn([F; K]) -> [F; M] + Sync + Send,
{
    let use_polar = polar_arg(method)?;
    let points = Points::<F, K>::extract(x, arg)?;
    if use_polar {
        map_into(py, &points, check, out, polar)
    } else {
        map_into(py, &points, check, out, concentric)
    }
}

/// Inverse of ``square_to_cosine_hemisphere`` for the same ``method``.
///
/// Parameters
/// ----------
/// x : array_like, shape (..., 3), unit vectors with z >= 0
/// method : "concentric" (default) or "polar"
/// out : ndarray, optional, keyword only
///     Written with the result and returned (its shape and dtype).
///
/// Returns
/// -------
/// ndarray, shape (..., 2), in [0, 1]^2.
#[pyfunction]
#[pyo3(signature = (x, method = "concentric", *, out = None))]
pub fn cosine_hemisphere_to_square<'py>(
    py: Python<'py>,
    x: &Obj<'py>,
    method: &str,
    out: Out<'_, 'py>,
) -> PyResult<Obj<'py>> {
    with_precision!(x, F => by_method(
        py, x, "x", Check::Finite, method, out,
        warp::cosine_hemisphere_to_square_polar::<F>,
        warp::cosine_hemisphere_to_square::<F>,
    ))
}

/// Registers the warps onto shapes and intervals in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    add_functions!(
        m,
        square_to_uniform_disk,
        square_to_uniform_disk_pdf,
        uniform_disk_to_square,
        square_to_uniform_disk_concentric,
        square_to_uniform_disk_concentric_pdf,
        uniform_disk_to_square_concentric,
        square_to_uniform_sphere,
        square_to_uniform_sphere_pdf,
        uniform_sphere_to_square,
        square_to_uniform_hemisphere,
        square_to_uniform_hemisphere_pdf,
        uniform_hemisphere_to_square,
        square_to_cosine_hemisphere,
        square_to_cosine_hemisphere_pdf,
        cosine_hemisphere_to_square,
        square_to_cosine_power_hemisphere,
        square_to_cosine_power_hemisphere_pdf,
        cosine_power_hemisphere_to_square,
        square_to_uniform_cone,
        square_to_uniform_cone_pdf,
        uniform_cone_to_square,
        square_to_uniform_triangle,
        square_to_uniform_triangle_pdf,
        uniform_triangle_to_square,
        interval_to_power,
        interval_to_power_pdf,
        power_to_interval,
        interval_to_tent,
        tent_to_interval,
        square_to_tent,
        tent_to_square,
        square_to_tent_pdf,
        interval_to_nonuniform_tent,
        interval_to_linear,
        linear_to_interval,
        square_to_uniform_square_concentric
    );
    Ok(())
}

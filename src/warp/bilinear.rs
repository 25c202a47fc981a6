//! The bilinear density on the unit square, as Mitsuba 3's `mi.warp`.

use super::P2;
use super::ramps::{interval_to_linear, linear_to_interval};
use crate::math::{Real, in_unit_interval};

/// `a + t (b − a)`.
#[inline(always)]
fn lerp<F: Real>(a: F, b: F, t: F) -> F {
    a + t * (b - a)
}

/// The corner values `[v00, v10, v01, v11]` at `(0, 0)`, `(1, 0)`, `(0, 1)`
/// and `(1, 1)` of a bilinear density on the unit square: non-negative,
/// with mean 1, so that the interpolant is the density.
pub type Corners<F> = [F; 4];

/// The conditional's end values `(c0, c1)` at `x = 0` and `x = 1` on the
/// row `y`.
#[inline(always)]
fn row<F: Real>(v: Corners<F>, y: F) -> (F, F) {
    (lerp(v[0], v[2], y), lerp(v[1], v[3], y))
}

/// Points of the bilinear density with corners `v` by inversion, `y`
/// first (Mitsuba's order): `y` = [`interval_to_linear`]`(v00 + v10,
/// v01 + v11, u_y)`, then `x = interval_to_linear(c0, c1, u_x)` with
/// `c0 = v00 + y (v01 − v00)`, `c1 = v10 + y (v11 − v10)`. Returns the
/// point and its density. Density per unit area.
///
/// # Density
/// [`square_to_bilinear_pdf`]: `c0 + x (c1 − c0)`, the interpolant.
///
/// # Inverse
/// [`bilinear_to_square`].
#[inline(always)]
pub fn square_to_bilinear<F: Real>(v: Corners<F>, u: P2<F>) -> (P2<F>, F) {
    let y = interval_to_linear(v[0] + v[1], v[2] + v[3], u[1]);
    let (c0, c1) = row(v, y);
    let x = interval_to_linear(c0, c1, u[0]);
    ([x, y], lerp(c0, c1, x))
}

/// Density of [`square_to_bilinear`] per unit area: the interpolant on the
/// unit square, else 0.
#[inline(always)]
pub fn square_to_bilinear_pdf<F: Real>(v: Corners<F>, p: P2<F>) -> F {
    if in_unit_interval(p[0]) && in_unit_interval(p[1]) {
        let (c0, c1) = row(v, p[1]);
        lerp(c0, c1, p[0])
    } else {
        F::zero()
    }
}

/// Inverse of [`square_to_bilinear`], with the point's density (as
/// Mitsuba returns it).
#[inline(always)]
pub fn bilinear_to_square<F: Real>(v: Corners<F>, p: P2<F>) -> (P2<F>, F) {
    let (c0, c1) = row(v, p[1]);
    let u = [
        linear_to_interval(c0, c1, p[0]),
        linear_to_interval(v[0] + v[1], v[2] + v[3], p[1]),
    ];
    (u, lerp(c0, c1, p[0]))
}

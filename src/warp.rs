//! Warps from the unit square (or interval) to disks, spheres, hemispheres,
//! lobes, triangles, tents, linear and bilinear ramps, the standard normal,
//! lunes and tangent directions: `square_to_X(u, ..)`, its density
//! `square_to_X_pdf(x, ..)`
//! and its inverse `X_to_square(x, ..)`, with the names and point
//! conventions of Mitsuba 3's `mi.warp` (same `u` → same point).
//!
//! Densities: per unit area on planar domains, per steradian on directions,
//! per unit length on intervals; 0 off the support. Kernels are total:
//! `u = 1` maps inside the domain, and inverses of degenerate points (the
//! origin, a pole) return a valid point of the square.

pub use crate::math::{P2, V3};
use crate::math::{Real, atan2, safe_sqrt, sin_cos_turn};

#[inline(always)]
fn two_pi<F: Real>() -> F {
    F::c(std::f64::consts::TAU)
}

/// Azimuth of `(x, y)` as a fraction of a turn, in `[0, 1)`.
#[inline(always)]
fn turn_fraction<F: Real>(x: F, y: F) -> F {
    let phi = atan2(y, x) / two_pi::<F>();
    let phi = if phi < F::zero() { phi + F::one() } else { phi };
    // -0.0 and phi + 1 rounding up to 1 both map to the start of the turn.
    if phi >= F::one() {
        F::zero()
    } else {
        phi.abs()
    }
}

/// Tolerance of support tests (the boundary of a disk or hemisphere), in
/// units of the type's epsilon, so that `u = 1` and round-off stay inside.
#[inline(always)]
fn slack<F: Real>() -> F {
    F::epsilon() * F::c(8.0)
}

/// Uniform point on the unit disk by the polar map `r = √u_y`,
/// `φ = 2π u_x` (Mitsuba's order). Density per unit area.
///
/// # Density
/// `p(x) = 1/π` for `|x| ≤ 1`, else 0.
///
/// # Inverse
/// [`uniform_disk_to_square`]: `(φ/2π, r²)`; the origin maps to `(0, 0)`.
#[inline(always)]
pub fn square_to_uniform_disk<F: Real>(u: P2<F>) -> P2<F> {
    let r = u[1].sqrt();
    let (s, c) = sin_cos_turn(u[0]);
    [c * r, s * r]
}

/// Density of [`square_to_uniform_disk`] and
/// [`square_to_uniform_disk_concentric`]: `1/π` on the unit disk, else 0.
#[inline(always)]
pub fn square_to_uniform_disk_pdf<F: Real>(p: P2<F>) -> F {
    if p[0] * p[0] + p[1] * p[1] <= F::one() + slack::<F>() {
        F::FRAC_1_PI()
    } else {
        F::zero()
    }
}

/// Inverse of [`square_to_uniform_disk`].
#[inline(always)]
pub fn uniform_disk_to_square<F: Real>(p: P2<F>) -> P2<F> {
    [
        turn_fraction(p[0], p[1]),
        (p[0] * p[0] + p[1] * p[1]).min(F::one()),
    ]
}

/// Uniform point on the unit disk by Shirley and Chiu's concentric map,
/// which keeps strata compact. Density per unit area.
///
/// With `a = 2u_x − 1`, `b = 2u_y − 1`: if `|a| ≥ |b|`, `r = a`,
/// `φ = (π/4)·b/a`; else `r = b`, `φ = π/2 − (π/4)·a/b`; the point is
/// `(r cos φ, r sin φ)`.
///
/// # Density
/// `p(x) = 1/π` for `|x| ≤ 1`, else 0 ([`square_to_uniform_disk_pdf`]).
///
/// # Inverse
/// [`uniform_disk_to_square_concentric`]; the origin maps to `(½, ½)`.
///
/// # References
/// P. Shirley, K. Chiu, "A Low Distortion Map Between Disk and Square",
/// Journal of Graphics Tools 2(3), 1997.
#[inline(always)]
pub fn square_to_uniform_disk_concentric<F: Real>(u: P2<F>) -> P2<F> {
    let two = F::c(2.0);
    let (a, b) = (two * u[0] - F::one(), two * u[1] - F::one());
    // Branch-free: the dominant coordinate is the radius, the ratio of the
    // other to it the angle within the octant (φ measured from the nearer
    // axis, so the vertical case swaps sine and cosine).
    let horizontal = a.abs() >= b.abs();
    let (r, other) = if horizontal { (a, b) } else { (b, a) };
    let ratio = if r == F::zero() { F::zero() } else { other / r };
    let (s, c) = F::sin_cos_octant(F::FRAC_PI_4() * ratio);
    if horizontal {
        [r * c, r * s]
    } else {
        [r * s, r * c]
    }
}

/// Density of [`square_to_uniform_disk_concentric`]: `1/π` on the unit disk.
#[inline(always)]
pub fn square_to_uniform_disk_concentric_pdf<F: Real>(p: P2<F>) -> F {
    square_to_uniform_disk_pdf(p)
}

/// Inverse of [`square_to_uniform_disk_concentric`].
#[inline(always)]
pub fn uniform_disk_to_square_concentric<F: Real>(p: P2<F>) -> P2<F> {
    let (x, y) = (p[0], p[1]);
    let horizontal = x.abs() > y.abs();
    // Signed radius: the sign of the dominant coordinate.
    let dominant = if horizontal { x } else { y };
    let r = (x * x + y * y).sqrt().copysign(dominant);
    // Angle of the point mirrored into the half plane of the dominant axis.
    let phi = atan2(y * dominant.signum(), x * dominant.signum());
    let t = if horizontal {
        phi / F::FRAC_PI_4()
    } else {
        F::c(2.0) - phi / F::FRAC_PI_4()
    } * r;
    let (a, b) = if r == F::zero() {
        (F::zero(), F::zero())
    } else if horizontal {
        (r, t)
    } else {
        (t, r)
    };
    let half = F::c(0.5);
    [
        clamp01((a + F::one()) * half),
        clamp01((b + F::one()) * half),
    ]
}

/// The concentric map's polar coordinates as a point of the square, as
/// Mitsuba's `square_to_uniform_square_concentric`: with `(r, φ)` the
/// radius and the angle (a fraction of a turn) of
/// [`square_to_uniform_disk_concentric`]`(u)`, the point `(φ, r²)`: a
/// measure-preserving map of the square onto itself that keeps
/// neighbourhoods together within each octant. Density per unit area.
///
/// # Density
/// `p = 1` on `[0, 1]²`. The centre (`r = 0`, where Mitsuba's angle is
/// 0/0) gives `(0, 0)`.
#[inline(always)]
pub fn square_to_uniform_square_concentric<F: Real>(u: P2<F>) -> P2<F> {
    let two = F::c(2.0);
    let (x, y) = (two * u[0] - F::one(), two * u[1] - F::one());
    let vertical = x.abs() < y.abs();
    let (r, other) = if vertical { (y, x) } else { (x, y) };
    let eighth = if r == F::zero() {
        F::zero()
    } else {
        other / r * F::c(0.125)
    };
    let phi = if vertical {
        F::c(0.25) - eighth
    } else {
        eighth
    };
    let phi = if r < F::zero() { phi + F::c(0.5) } else { phi };
    let phi = if phi < F::zero() { phi + F::one() } else { phi };
    [phi, r * r]
}

#[inline(always)]
fn clamp01<F: Real>(x: F) -> F {
    x.max(F::zero()).min(F::one())
}

/// Uniform direction on the unit sphere: `z = 1 − 2u_y`, `φ = 2π u_x`.
/// Density per steradian.
///
/// # Density
/// `p(ω) = 1/(4π)`.
///
/// # Inverse
/// [`uniform_sphere_to_square`]: `(φ/2π, (1 − z)/2)`; at the poles φ = 0.
#[inline(always)]
pub fn square_to_uniform_sphere<F: Real>(u: P2<F>) -> V3<F> {
    let z = F::one() - F::c(2.0) * u[1];
    let r = safe_sqrt(F::one() - z * z);
    let (s, c) = sin_cos_turn(u[0]);
    [r * c, r * s, z]
}

/// Density of [`square_to_uniform_sphere`]: `1/(4π)` per steradian.
#[inline(always)]
pub fn square_to_uniform_sphere_pdf<F: Real>(_d: V3<F>) -> F {
    F::c(0.25 * std::f64::consts::FRAC_1_PI)
}

/// Inverse of [`square_to_uniform_sphere`].
#[inline(always)]
pub fn uniform_sphere_to_square<F: Real>(d: V3<F>) -> P2<F> {
    [
        turn_fraction(d[0], d[1]),
        clamp01((F::one() - d[2]) * F::c(0.5)),
    ]
}

/// Uniform direction on the +z hemisphere, by lifting a concentric disk
/// point `p` to `(p·√(2 − |p|²), 1 − |p|²)` (an area-preserving map).
/// Density per steradian.
///
/// # Density
/// `p(ω) = 1/(2π)` for `z ≥ 0`, else 0.
///
/// # Inverse
/// [`uniform_hemisphere_to_square`]: the disk point `(x, y)/√(1 + z)`, then
/// the concentric inverse.
#[inline(always)]
pub fn square_to_uniform_hemisphere<F: Real>(u: P2<F>) -> V3<F> {
    let p = square_to_uniform_disk_concentric(u);
    let r2 = p[0] * p[0] + p[1] * p[1];
    let z = F::one() - r2;
    let scale = safe_sqrt(F::one() + z);
    [p[0] * scale, p[1] * scale, z]
}

/// Density of [`square_to_uniform_hemisphere`]: `1/(2π)` for `z ≥ 0`.
#[inline(always)]
pub fn square_to_uniform_hemisphere_pdf<F: Real>(d: V3<F>) -> F {
    if d[2] >= F::zero() {
        F::c(0.5 * std::f64::consts::FRAC_1_PI)
    } else {
        F::zero()
    }
}

/// Inverse of [`square_to_uniform_hemisphere`].
#[inline(always)]
pub fn uniform_hemisphere_to_square<F: Real>(d: V3<F>) -> P2<F> {
    let inv = F::one() / safe_sqrt(F::one() + d[2]).max(F::min_positive_value());
    uniform_disk_to_square_concentric([d[0] * inv, d[1] * inv])
}

/// Cosine-weighted direction on the +z hemisphere (Malley's method): a
/// concentric disk point `p` lifted to `(p, √(1 − |p|²))`. Density per
/// steradian.
///
/// # Density
/// `p(ω) = cos θ / π` for `cos θ > 0`, else 0.
///
/// # Inverse
/// [`cosine_hemisphere_to_square`]: the concentric inverse of `(x, y)`.
#[inline(always)]
pub fn square_to_cosine_hemisphere<F: Real>(u: P2<F>) -> V3<F> {
    let p = square_to_uniform_disk_concentric(u);
    let r2 = p[0] * p[0] + p[1] * p[1];
    [p[0], p[1], safe_sqrt(F::one() - r2)]
}

/// Density of the cosine-weighted hemisphere warps: `max(cos θ, 0)/π`.
#[inline(always)]
pub fn square_to_cosine_hemisphere_pdf<F: Real>(d: V3<F>) -> F {
    d[2].max(F::zero()) * F::FRAC_1_PI()
}

/// Inverse of [`square_to_cosine_hemisphere`].
#[inline(always)]
pub fn cosine_hemisphere_to_square<F: Real>(d: V3<F>) -> P2<F> {
    uniform_disk_to_square_concentric([d[0], d[1]])
}

/// Cosine-weighted direction by the polar form:
/// `(cos 2πu_x · √(1 − u_y), sin 2πu_x · √(1 − u_y), √u_y)`.
/// Density `cos θ / π` per steradian, as [`square_to_cosine_hemisphere`].
///
/// # Inverse
/// [`cosine_hemisphere_to_square_polar`]: `(φ/2π, z²)`.
#[inline(always)]
pub fn square_to_cosine_hemisphere_polar<F: Real>(u: P2<F>) -> V3<F> {
    let r = safe_sqrt(F::one() - u[1]);
    let (s, c) = sin_cos_turn(u[0]);
    [c * r, s * r, u[1].sqrt()]
}

/// Inverse of [`square_to_cosine_hemisphere_polar`].
#[inline(always)]
pub fn cosine_hemisphere_to_square_polar<F: Real>(d: V3<F>) -> P2<F> {
    let z = d[2].max(F::zero());
    [turn_fraction(d[0], d[1]), (z * z).min(F::one())]
}

/// Direction of the cosⁿ lobe around +z (the Phong lobe):
/// `cos θ = u_y^{1/(n+1)}`, `φ = 2π u_x`. Density per steradian.
///
/// # Density
/// `p(ω) = (n + 1)/(2π) · cosⁿθ` for `cos θ > 0`, else 0 (also for n = 0).
///
/// # Inverse
/// [`cosine_power_hemisphere_to_square`]: `(φ/2π, cos^{n+1} θ)`.
#[inline(always)]
pub fn square_to_cosine_power_hemisphere<F: Real>(u: P2<F>, exponent: F) -> V3<F> {
    let cos_theta = F::pow_positive(u[1], F::one() / (exponent + F::one()));
    let sin_theta = safe_sqrt(F::one() - cos_theta * cos_theta);
    let (s, c) = sin_cos_turn(u[0]);
    [c * sin_theta, s * sin_theta, cos_theta]
}

/// Density of [`square_to_cosine_power_hemisphere`].
#[inline(always)]
pub fn square_to_cosine_power_hemisphere_pdf<F: Real>(d: V3<F>, exponent: F) -> F {
    if d[2] > F::zero() {
        (exponent + F::one()) / two_pi::<F>() * F::pow_positive(d[2], exponent)
    } else {
        F::zero()
    }
}

/// Inverse of [`square_to_cosine_power_hemisphere`].
#[inline(always)]
pub fn cosine_power_hemisphere_to_square<F: Real>(d: V3<F>, exponent: F) -> P2<F> {
    let z = d[2].max(F::zero()).min(F::one());
    [
        turn_fraction(d[0], d[1]),
        F::pow_positive(z, exponent + F::one()),
    ]
}

/// Uniform direction in the cone `cos θ ≥ cos_cutoff` around +z, from a
/// concentric disk point `p`: `cos θ = 1 − (1 − c)|p|²`, and `(x, y)` is `p`
/// scaled to `sin θ`. Density per steradian; `c = cos_cutoff ∈ [−1, 1)`.
///
/// # Density
/// `p(ω) = 1 / (2π (1 − c))` for `cos θ ≥ c`, else 0.
///
/// # Inverse
/// [`uniform_cone_to_square`]: the disk point `(x, y)/√((1 − c)(1 + z))`, then
/// the concentric inverse.
#[inline(always)]
pub fn square_to_uniform_cone<F: Real>(u: P2<F>, cos_cutoff: F) -> V3<F> {
    let one_minus_c = F::one() - cos_cutoff;
    let p = square_to_uniform_disk_concentric(u);
    let r2 = p[0] * p[0] + p[1] * p[1];
    let z = F::one() - one_minus_c * r2;
    let scale = safe_sqrt(one_minus_c * (F::c(2.0) - one_minus_c * r2));
    [p[0] * scale, p[1] * scale, z]
}

/// Density of [`square_to_uniform_cone`].
#[inline(always)]
pub fn square_to_uniform_cone_pdf<F: Real>(d: V3<F>, cos_cutoff: F) -> F {
    if d[2] >= cos_cutoff - slack::<F>() {
        F::one() / (two_pi::<F>() * (F::one() - cos_cutoff))
    } else {
        F::zero()
    }
}

/// Inverse of [`square_to_uniform_cone`].
#[inline(always)]
pub fn uniform_cone_to_square<F: Real>(d: V3<F>, cos_cutoff: F) -> P2<F> {
    let denom = safe_sqrt((F::one() - cos_cutoff) * (F::one() + d[2]));
    let inv = F::one() / denom.max(F::min_positive_value());
    uniform_disk_to_square_concentric([d[0] * inv, d[1] * inv])
}

/// Uniform point on the triangle `(0, 0), (1, 0), (0, 1)`:
/// `t = √(1 − u_x)`, point `(1 − t, t·u_y)`. Density per unit area.
///
/// # Density
/// `p(x) = 2` inside the triangle, else 0.
///
/// # Inverse
/// [`uniform_triangle_to_square`]: `(1 − t², y/t)` with `t = 1 − x`; the
/// vertex `(1, 0)` maps to `(1, 0)`.
#[inline(always)]
pub fn square_to_uniform_triangle<F: Real>(u: P2<F>) -> P2<F> {
    let t = safe_sqrt(F::one() - u[0]);
    [F::one() - t, t * u[1]]
}

/// Density of [`square_to_uniform_triangle`].
#[inline(always)]
pub fn square_to_uniform_triangle_pdf<F: Real>(p: P2<F>) -> F {
    let tol = slack::<F>();
    if p[0] >= -tol && p[1] >= -tol && p[0] + p[1] <= F::one() + tol {
        F::c(2.0)
    } else {
        F::zero()
    }
}

/// Inverse of [`square_to_uniform_triangle`].
#[inline(always)]
pub fn uniform_triangle_to_square<F: Real>(p: P2<F>) -> P2<F> {
    let t = F::one() - p[0];
    let v = if t > F::zero() { p[1] / t } else { F::zero() };
    [clamp01(F::one() - t * t), clamp01(v)]
}

/// The power density on `[0, 1]` by inversion: `x = u^{1/(n+1)}`.
/// Density per unit length.
///
/// # Density
/// `p(x) = (n + 1) xⁿ` on `[0, 1]`, else 0.
///
/// # Inverse
/// [`power_to_interval`]: `u = x^{n+1}`.
#[inline(always)]
pub fn interval_to_power<F: Real>(u: F, exponent: F) -> F {
    F::pow_positive(u, F::one() / (exponent + F::one()))
}

/// Density of [`interval_to_power`].
#[inline(always)]
pub fn interval_to_power_pdf<F: Real>(x: F, exponent: F) -> F {
    if x >= F::zero() && x <= F::one() {
        (exponent + F::one()) * F::pow_positive(x, exponent)
    } else {
        F::zero()
    }
}

/// Inverse of [`interval_to_power`].
#[inline(always)]
pub fn power_to_interval<F: Real>(x: F, exponent: F) -> F {
    F::pow_positive(clamp01(x), exponent + F::one())
}

mod ramps;

pub use ramps::{
    interval_to_linear, interval_to_nonuniform_tent, interval_to_tent, linear_to_interval,
    square_to_tent, square_to_tent_pdf, tent_to_interval, tent_to_square,
};

mod lobes;

pub use lobes::{
    VonMisesFisher, beckmann_to_square, square_to_beckmann, square_to_beckmann_pdf,
    square_to_rough_fiber, square_to_rough_fiber_pdf, square_to_std_normal,
    square_to_std_normal_pdf, square_to_von_mises_fisher, square_to_von_mises_fisher_pdf,
    von_mises_fisher_to_square,
};

mod bilinear;

pub use bilinear::{Corners, bilinear_to_square, square_to_bilinear, square_to_bilinear_pdf};

mod frames;

pub use frames::{
    Lunes, interval_to_tangent_direction, square_to_uniform_spherical_lune,
    square_to_uniform_spherical_lune_pdf, tangent_direction_to_interval,
    uniform_spherical_lune_to_square,
};

#[cfg(test)]
mod tests;

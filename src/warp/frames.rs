//! Warps in frames built from given normals, as Mitsuba 3's `mi.warp`:
//! directions in the plane orthogonal to a normal, and the two spherical
//! lunes between the faces of two normals.

use super::{P2, V3, slack, turn_fraction};
use crate::frame::Frame;
use crate::math::{Real, cross, dot, safe_sqrt, sin_cos_turn};

/// A direction in the plane orthogonal to the unit normal `n`:
/// `cos(2πu) s + sin(2πu) t`, with `(s, t, n)` the [`Frame`] of `n` (the
/// same frame as Mitsuba's). Uniform in angle: density `1/(2π)` per radian.
///
/// # Inverse
/// [`tangent_direction_to_interval`]: the angle of `(d·s, d·t)` as a
/// fraction of a turn.
#[inline(always)]
pub fn interval_to_tangent_direction<F: Real>(n: V3<F>, u: F) -> V3<F> {
    let frame = Frame::from_normal(n);
    let (s, c) = sin_cos_turn(u);
    std::array::from_fn(|k| c * frame.s[k] + s * frame.t[k])
}

/// Inverse of [`interval_to_tangent_direction`].
#[inline(always)]
pub fn tangent_direction_to_interval<F: Real>(n: V3<F>, d: V3<F>) -> F {
    let frame = Frame::from_normal(n);
    turn_fraction(dot(d, frame.s), dot(d, frame.t))
}

/// The two spherical lunes between the faces of unit normals `n1` and `n2`
/// (not parallel): in the frame `ẑ = n1 × n2 / |n1 × n2|`,
/// `ŷ = (n1 + n2)/|n1 + n2|`, `x̂ = ẑ × ŷ`, the directions whose azimuth lies
/// within `θ = ½ atan2(|n1 × n2|, n1·n2)` (half the normals' angle) of `+x̂`
/// or of `−x̂`. Their solid angle is `8θ`.
#[derive(Clone, Copy, Debug)]
pub struct Lunes<F> {
    x: V3<F>,
    y: V3<F>,
    z: V3<F>,
    /// The half angle `θ` of each lune, and its sine and cosine.
    theta: F,
    sin_theta: F,
    cos_theta: F,
}

/// `v / |v|`, or `None` for a zero or non-finite `v`.
fn normalized(v: [f64; 3]) -> Option<[f64; 3]> {
    let length = dot(v, v).sqrt();
    (length > 0.0 && length.is_finite()).then(|| v.map(|c| c / length))
}

impl<F: Real> Lunes<F> {
    /// The lunes of the normals `n1` and `n2` (normalised here, in f64), or
    /// `None` when either is zero or not finite, or when they are parallel
    /// or opposite (the lunes are then empty or their frame undefined).
    pub fn new(n1: [f64; 3], n2: [f64; 3]) -> Option<Self> {
        let (n1, n2) = (normalized(n1)?, normalized(n2)?);
        let normal = cross(n1, n2);
        let z = normalized(normal)?;
        let y = normalized(std::array::from_fn(|k| n1[k] + n2[k]))?;
        // atan2 keeps the angle of nearly parallel normals, where acos of
        // their dot product rounds to 0.
        let theta = 0.5 * dot(normal, normal).sqrt().atan2(dot(n1, n2));
        // Positive (finite normals of a nonzero cross product).
        if theta <= 0.0 {
            return None;
        }
        Some(Lunes {
            x: cross(z, y).map(F::c),
            y: y.map(F::c),
            z: z.map(F::c),
            theta: F::c(theta),
            sin_theta: F::c(theta.sin()),
            cos_theta: F::c(theta.cos()),
        })
    }
}

/// Uniform directions in the two lunes (Mitsuba's
/// `square_to_uniform_spherical_lune`): `z = 1 − 2u_y` along `ẑ`, and the
/// azimuth from `x̂` is `(4u_x − 1) θ` for `u_x < ½` and `π + (4u_x − 3) θ`
/// otherwise. Density per steradian.
///
/// # Density
/// [`square_to_uniform_spherical_lune_pdf`]: `1/(8θ)` in the lunes.
///
/// # Inverse
/// [`uniform_spherical_lune_to_square`].
#[inline(always)]
pub fn square_to_uniform_spherical_lune<F: Real>(u: P2<F>, lunes: &Lunes<F>) -> V3<F> {
    let z = F::one() - F::c(2.0) * u[1];
    let r = safe_sqrt(F::one() - z * z);
    let angle = if u[0] < F::c(0.5) {
        (F::c(4.0) * u[0] - F::one()) * lunes.theta
    } else {
        (F::c(4.0) * u[0] - F::c(3.0)) * lunes.theta + F::PI()
    };
    let (s, c) = angle.sin_cos();
    std::array::from_fn(|k| r * c * lunes.x[k] + r * s * lunes.y[k] + z * lunes.z[k])
}

/// Density of [`square_to_uniform_spherical_lune`]: `1/(8θ)` per steradian
/// where the azimuth lies within `θ` of `±x̂` (`|d·ŷ| cos θ ≤ |d·x̂| sin θ`),
/// else 0 (Mitsuba returns `1/(8θ)` everywhere).
#[inline(always)]
pub fn square_to_uniform_spherical_lune_pdf<F: Real>(d: V3<F>, lunes: &Lunes<F>) -> F {
    let (x, y) = (dot(d, lunes.x), dot(d, lunes.y));
    if y.abs() * lunes.cos_theta <= x.abs() * lunes.sin_theta + slack::<F>() {
        F::one() / (F::c(8.0) * lunes.theta)
    } else {
        F::zero()
    }
}

/// Inverse of [`square_to_uniform_spherical_lune`]; a direction outside the
/// lunes maps to the nearest edge's azimuth.
#[inline(always)]
pub fn uniform_spherical_lune_to_square<F: Real>(d: V3<F>, lunes: &Lunes<F>) -> P2<F> {
    let (x, y, z) = (dot(d, lunes.x), dot(d, lunes.y), dot(d, lunes.z));
    let theta = lunes.theta;
    let quarter = F::c(0.25) / theta;
    // The azimuth from +x̂ in (−π/2, 3π/2], clamped into the lune it is nearer.
    let angle = y.atan2(x);
    let angle = if angle < -F::FRAC_PI_2() {
        angle + F::c(std::f64::consts::TAU)
    } else {
        angle
    };
    let u0 = if x >= F::zero() {
        (angle.max(-theta).min(theta) + theta) * quarter
    } else {
        let (lo, hi) = (F::PI() - theta, F::PI() + theta);
        (angle.max(lo).min(hi) + F::c(3.0) * theta - F::PI()) * quarter
    };
    [
        u0.max(F::zero()).min(F::one()),
        (F::c(0.5) * (F::one() - z)).max(F::zero()).min(F::one()),
    ]
}

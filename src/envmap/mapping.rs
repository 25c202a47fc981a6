//! The three parameterisations of the sphere of directions an environment
//! map can use, each between a direction (local frame of the map) and a
//! point `p = (s, t)` of its parameter domain.
//!
//! | mapping | domain of `(s, t)` | `s` | `t` |
//! |---|---|---|---|
//! | [`Mapping::LatLong`] | `[0, 1] × [0, 1]` | Mitsuba's `u` (azimuth, periodic) | Mitsuba's `v` (θ/π, 0 at +Y) |
//! | [`Mapping::Angular`] | `[0, 1] × [0, 1]` | column fraction (left → right) | row fraction (top → bottom) |
//! | [`Mapping::Cube`] | `[0, 1] × [0, 6]` | column fraction of the face | `face + row fraction` |
//!
//! `jacobian(p)` is `dω/dp`, the solid angle per unit area of the domain, so
//! that a density `p_p` on the domain is `p_p / jacobian` per steradian.

use crate::math::{Real, atan2, sin_cos_turn};
use crate::warp::V3;
use std::f64::consts::{FRAC_1_PI, PI};

/// How an image covers the sphere of directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mapping {
    /// Latitude-longitude, exactly as Mitsuba 3's `envmap` emitter: Y up,
    /// `s = atan2(d.x, −d.z)/(2π)` wrapped into `[0, 1)` (so `s = 0` is −Z
    /// and `s = ¼` is +X), `t = acos(d.y)/π`.
    ///
    /// `d = (sin 2πs · sin πt, cos πt, −cos 2πs · sin πt)`;
    /// `dω/dp = 2π² sin θ`.
    LatLong,
    /// Debevec's angular light probe: `(a, b) = (d.x, d.y)·r/√(d.x² + d.y²)`
    /// with `r = acos(d.z)/π`, image centre +Z, the edge of the unit circle
    /// −Z, +Y toward the top row; `a = 2s − 1`, `b = 1 − 2t`.
    ///
    /// `dω/dp = 4·π sin(πr)/r` inside the unit circle (`π²·4` at its
    /// centre), 0 outside.
    Angular,
    /// Six square faces +X, −X, +Y, −Y, +Z, −Z, each oriented as in OpenGL's
    /// cube maps, row 0 at the top: a face's `(sc, tc)` in `[−1, 1]²` are
    /// `(2s − 1, 2t' − 1)` with `t'` the row fraction.
    ///
    /// `dω/dp = 4/(1 + sc² + tc²)^{3/2}`.
    Cube,
}

/// The faces of a cube map: major axis, and the directions that `sc` and
/// `tc` run along (OpenGL's table).
const CUBE_FACES: [(V3<f64>, V3<f64>, V3<f64>); 6] = [
    ([1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, -1.0, 0.0]),
    ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]),
    ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ([0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]),
    ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]),
    ([0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]),
];

impl Mapping {
    /// The name used in the Python API: `"latlong"`, `"angular"`, `"cube"`.
    pub fn name(self) -> &'static str {
        match self {
            Mapping::LatLong => "latlong",
            Mapping::Angular => "angular",
            Mapping::Cube => "cube",
        }
    }

    /// The mapping called `name` (see [`Mapping::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "latlong" => Some(Mapping::LatLong),
            "angular" => Some(Mapping::Angular),
            "cube" => Some(Mapping::Cube),
            _ => None,
        }
    }

    /// Upper bound of `t` (1, or 6 for the six faces of a cube map).
    pub fn t_max(self) -> f64 {
        match self {
            Mapping::Cube => 6.0,
            _ => 1.0,
        }
    }

    /// The unit direction at `p`. Points outside an angular map's circle
    /// give the direction at the same angle on its edge (−Z).
    #[inline]
    pub fn to_dir(self, p: [f64; 2]) -> V3<f64> {
        self.to_dir_and_sin(p).0
    }

    /// [`Mapping::to_dir`], and the sine of the direction's angle to the
    /// polar axis of the mapping's sampling table (+Y for lat-long, +Z for
    /// angular; 0 for cube maps, which have none), as the direction's
    /// formula has it (`sin(π t)`, `sin(π r)`).
    #[inline(always)]
    pub fn to_dir_and_sin<F: Real>(self, p: [F; 2]) -> (V3<F>, F) {
        let [s, t] = p;
        let (zero, one, two, half) = (F::zero(), F::one(), F::c(2.0), F::c(0.5));
        match self {
            Mapping::LatLong => {
                let (sin_theta, cos_theta) = sin_cos_turn(half * t);
                let (sin_phi, cos_phi) = sin_cos_turn(s);
                let d = [sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta];
                (d, sin_theta)
            }
            Mapping::Angular => {
                let (a, b) = (two * s - one, one - two * t);
                let r = (a * a + b * b).sqrt();
                if r == zero {
                    return ([zero, zero, one], zero);
                }
                let (sin_theta, cos_theta) = sin_cos_turn(half * r.min(one));
                ([a / r * sin_theta, b / r * sin_theta, cos_theta], sin_theta)
            }
            Mapping::Cube => {
                let (face, sc, tc) = cube_face(p);
                let (major, s_axis, t_axis) = CUBE_FACES[face];
                let v: V3<F> = std::array::from_fn(|k| {
                    F::c(major[k]) + sc * F::c(s_axis[k]) + tc * F::c(t_axis[k])
                });
                let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                (v.map(|x| x / norm), zero)
            }
        }
    }

    /// The point of the domain that looks along `d` (of any length, the
    /// zero vector giving a valid point), computed in `F`. Every formula
    /// is of ratios of `d`'s components (`atan2`, [`polar_angle`], a cube
    /// face's `d_s/|d_major|`), so `d` is not normalised first: its length
    /// only scales both sides of each ratio, as long as the squares in
    /// [`polar_angle`] stay normal floats (in `f32`, lengths from about
    /// 10⁻¹⁹ to 10¹⁹).
    #[inline(always)]
    pub fn from_dir<F: Real>(self, d: V3<F>) -> [F; 2] {
        let (zero, one) = (F::zero(), F::one());
        match self {
            Mapping::LatLong => {
                let s = atan2(d[0], -d[2]) * F::c(0.5 / PI);
                let s = if s < zero { s + one } else { s };
                // -0.0 and s + 1 rounding up to 1 both mean the start of the turn.
                let s = if s >= one { zero } else { s.abs() };
                [s, polar_angle(d[1], d[0], d[2]) * F::c(FRAC_1_PI)]
            }
            Mapping::Angular => {
                let rho = (d[0] * d[0] + d[1] * d[1]).sqrt();
                let r = polar_angle(d[2], d[0], d[1]) * F::c(FRAC_1_PI);
                let (a, b) = if rho > zero {
                    (d[0] * r / rho, d[1] * r / rho)
                } else {
                    // +Z at the centre; −Z anywhere on the edge (take +X's side).
                    (r, zero)
                };
                let half = F::c(0.5);
                [(a + one) * half, (one - b) * half]
            }
            Mapping::Cube => {
                let abs = d.map(F::abs);
                let axis = if abs[0] >= abs[1] && abs[0] >= abs[2] {
                    0
                } else if abs[1] >= abs[2] {
                    1
                } else {
                    2
                };
                let face = 2 * axis + usize::from(d[axis] < zero);
                let (_, s_axis, t_axis) = CUBE_FACES[face];
                let ma = abs[axis].max(F::min_positive_value());
                let dot =
                    |e: V3<f64>| (F::c(e[0]) * d[0] + F::c(e[1]) * d[1] + F::c(e[2]) * d[2]) / ma;
                let unit = |x: F| ((x + one) * F::c(0.5)).max(zero).min(one);
                let (s, t) = (unit(dot(s_axis)), unit(dot(t_axis)));
                [s, F::c(face as f64) + t.min(F::ONE_MINUS_EPSILON)]
            }
        }
    }

    /// `dω/dp` at `p`: solid angle per unit area of the domain (0 at the
    /// poles of a lat-long map and on or outside an angular map's circle).
    #[inline]
    pub fn jacobian<F: Real>(self, p: [F; 2]) -> F {
        let [s, t] = p;
        let (pi, one, two) = (F::PI(), F::one(), F::c(2.0));
        match self {
            Mapping::LatLong => two * pi * pi * (pi * t).sin().max(F::zero()),
            Mapping::Angular => {
                let (a, b) = (two * s - one, one - two * t);
                let r = (a * a + b * b).sqrt();
                if r >= one {
                    F::zero()
                } else if r < F::c(1e-8) {
                    F::c(4.0) * pi * pi
                } else {
                    F::c(4.0) * pi * (pi * r).sin() / r
                }
            }
            Mapping::Cube => {
                let (_, sc, tc) = cube_face(p);
                F::c(4.0) / (one + sc * sc + tc * tc).powf(F::c(1.5))
            }
        }
    }
}

/// The face of the cube-map point `p` and its coordinates on the face in
/// `[−1, 1]²`: `(2s − 1, 2(t − face) − 1)`.
#[inline(always)]
fn cube_face<F: Real>([s, t]: [F; 2]) -> (usize, F, F) {
    let face = t.floor_index(5);
    let (one, two) = (F::one(), F::c(2.0));
    (face, two * s - one, two * (t - F::c(face as f64)) - one)
}

/// The angle between a unit vector and an axis, from its component `c`
/// along the axis and the two others: `atan2(√(a² + b²), c)`, which unlike
/// `acos(c)` keeps its precision near the poles.
#[inline(always)]
pub fn polar_angle<F: Real>(c: F, a: F, b: F) -> F {
    atan2((a * a + b * b).sqrt(), c)
}

/// `d/|d|`, or `d` itself when it has length 0.
#[inline(always)]
pub fn normalized<F: Real>(d: V3<F>) -> V3<F> {
    let norm2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if norm2 > F::zero() {
        let inv = F::one() / norm2.sqrt();
        d.map(|x| x * inv)
    } else {
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Mapping; 3] = [Mapping::LatLong, Mapping::Angular, Mapping::Cube];

    fn close(a: V3<f64>, b: V3<f64>, tol: f64) -> bool {
        (0..3).all(|k| (a[k] - b[k]).abs() < tol)
    }

    #[test]
    fn latlong_axes_follow_mitsuba() {
        let m = Mapping::LatLong;
        assert!(close(m.to_dir([0.0, 0.5]), [0.0, 0.0, -1.0], 1e-15));
        assert!(close(m.to_dir([0.25, 0.5]), [1.0, 0.0, 0.0], 1e-15));
        assert!(close(m.to_dir([0.5, 0.5]), [0.0, 0.0, 1.0], 1e-15));
        assert!(close(m.to_dir([0.3, 0.0]), [0.0, 1.0, 0.0], 1e-15));
        assert_eq!(m.from_dir([1.0, 0.0, 0.0]), [0.25, 0.5]);
    }

    #[test]
    fn angular_centre_is_plus_z_and_top_is_plus_y() {
        let m = Mapping::Angular;
        assert!(close(m.to_dir([0.5, 0.5]), [0.0, 0.0, 1.0], 1e-15));
        // Half way up from the centre: θ = π/2 toward +Y.
        assert!(close(m.to_dir([0.5, 0.25]), [0.0, 1.0, 0.0], 1e-15));
        assert!(close(m.to_dir([0.75, 0.5]), [1.0, 0.0, 0.0], 1e-15));
        assert!(close(m.to_dir([1.0, 0.5]), [0.0, 0.0, -1.0], 1e-15));
    }

    #[test]
    fn cube_faces_follow_opengl() {
        let m = Mapping::Cube;
        let centres = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        for (face, c) in centres.iter().enumerate() {
            assert!(close(m.to_dir([0.5, face as f64 + 0.5]), *c, 1e-15));
        }
        // +Z face: row 0 (top) looks up (+Y), column 0 (left) toward −X.
        let top = m.to_dir([0.5, 4.0]);
        assert!(top[1] > 0.0 && top[0].abs() < 1e-15);
        let left = m.to_dir([0.0, 4.5]);
        assert!(left[0] < 0.0);
    }

    #[test]
    fn round_trips() {
        for m in ALL {
            for i in 0..=40 {
                for j in 0..=40 {
                    let s = (i as f64 + 0.37) / 41.0;
                    let t = (j as f64 + 0.61) / 41.0 * m.t_max();
                    let p = [s, t];
                    if m == Mapping::Angular && m.jacobian(p) == 0.0 {
                        continue;
                    }
                    let d = m.to_dir(p);
                    let back = m.from_dir(d);
                    let dd = m.to_dir(back);
                    assert!(close(d, dd, 1e-12), "{m:?}: {p:?} -> {d:?} -> {back:?}");
                    assert!((back[0] - s).abs() < 1e-12 && (back[1] - t).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn jacobians_integrate_to_the_sphere() {
        // Midpoint rule over the domain: ∫ dω/dp dp = 4π.
        for m in ALL {
            let n = 1000;
            let rows = (n as f64 * m.t_max()) as usize;
            let mut total = 0.0;
            for i in 0..n {
                for j in 0..rows {
                    let p = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                    total += m.jacobian(p);
                }
            }
            total /= (n * n) as f64;
            assert!((total / (4.0 * PI) - 1.0).abs() < 2e-3, "{m:?}: {total}");
        }
    }
}

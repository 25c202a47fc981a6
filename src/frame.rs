//! Orthonormal frames: the local shading frame (normal = +z) around a
//! world-space normal.

use crate::math::{Real, V3, cross, dot};

/// An orthonormal basis `(s, t, n)`: `to_local` gives a vector's
/// coordinates along `s`, `t`, `n`; `to_world` maps them back.
///
/// Built from a unit normal without a branch that breaks near ±z (Duff et
/// al.): with `σ = sign(n_z)` (+1 for `n_z = ±0`), `a = −1/(σ + n_z)`,
/// `b = n_x n_y a`,
/// `s = (1 + σ n_x² a, σ b, −σ n_x)`, `t = (b, σ + n_y² a, −n_y)`.
/// The basis is right-handed: `s × t = n`.
///
/// # References
/// T. Duff, J. Burgess, P. Christensen, C. Hery, A. Kensler, M. Liani,
/// R. Villemin, "Building an Orthonormal Basis, Revisited", Journal of
/// Computer Graphics Techniques 6(1), 2017.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame<F> {
    /// First tangent.
    pub s: V3<F>,
    /// Second tangent.
    pub t: V3<F>,
    /// The normal.
    pub n: V3<F>,
}

impl<F: Real> Frame<F> {
    /// The frame around the unit vector `n`.
    #[inline(always)]
    pub fn from_normal(n: V3<F>) -> Self {
        let sign = F::one().copysign(n[2]);
        let a = -F::one() / (sign + n[2]);
        let b = n[0] * n[1] * a;
        Frame {
            s: [F::one() + sign * n[0] * n[0] * a, sign * b, -sign * n[0]],
            t: [b, sign + n[1] * n[1] * a, -n[1]],
            n,
        }
    }

    /// The frame around the unit vector `n` whose first axis follows the
    /// tangent `dpdu` (Mitsuba's `SurfaceInteraction::initialize_sh_frame`):
    /// `s = normalize(dpdu − n (n·dpdu))`, `t = n × s`; or
    /// [`Frame::from_normal`]'s when `dpdu` is zero or (nearly) along `n`.
    #[inline]
    pub fn from_normal_and_tangent(n: V3<F>, dpdu: V3<F>) -> Self {
        let along = dot(n, dpdu);
        let s: V3<F> = std::array::from_fn(|k| dpdu[k] - n[k] * along);
        let len2 = dot(s, s);
        if !(len2 > F::c(1e-12) && len2 > F::c(1e-6) * dot(dpdu, dpdu)) {
            return Self::from_normal(n);
        }
        let s = s.map(|c| c / len2.sqrt());
        Frame {
            s,
            t: cross(n, s),
            n,
        }
    }

    /// Coordinates of `v` in this frame: `(v·s, v·t, v·n)`.
    #[inline(always)]
    pub fn to_local(&self, v: V3<F>) -> V3<F> {
        [dot(v, self.s), dot(v, self.t), dot(v, self.n)]
    }

    /// The vector with local coordinates `v`: `v_x s + v_y t + v_z n`.
    #[inline(always)]
    pub fn to_world(&self, v: V3<F>) -> V3<F> {
        std::array::from_fn(|k| v[0] * self.s[k] + v[1] * self.t[k] + v[2] * self.n[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn check(n: V3<f64>) {
        check_frame(Frame::from_normal(n), n);
    }

    /// `f` is orthonormal, right-handed, about `n`.
    fn check_frame(f: Frame<f64>, n: V3<f64>) {
        for (name, v) in [("s", f.s), ("t", f.t)] {
            assert!(
                (dot(v, v) - 1.0).abs() < 1e-12,
                "|{name}| != 1 for n = {n:?}"
            );
            assert!(
                dot(v, n).abs() < 1e-12,
                "{name} not orthogonal to n = {n:?}"
            );
        }
        assert!(dot(f.s, f.t).abs() < 1e-12);
        let c = cross(f.s, f.t);
        assert!(
            (0..3).all(|k| (c[k] - n[k]).abs() < 1e-12),
            "left-handed at {n:?}"
        );
        let v = [0.3, -0.5, 0.8];
        let back = f.to_world(f.to_local(v));
        assert!((0..3).all(|k| (back[k] - v[k]).abs() < 1e-12));
        assert_eq!(f.to_local(n)[2], dot(n, n));
    }

    #[test]
    fn orthonormal_at_the_poles_and_near_them() {
        for n in [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [-0.0, -0.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ] {
            check(n);
        }
        for eps in [1e-3, 1e-8, 1e-12] {
            for z in [1.0, -1.0f64] {
                let (x, y): (f64, f64) = (eps, -eps);
                let zz = z * (1.0 - x * x - y * y).sqrt();
                check([x, y, zz]);
            }
        }
    }

    /// A tangent frame's first axis is the tangent made orthogonal to
    /// `n`; no tangent, or one along `n`, gives Duff's frame.
    #[test]
    fn a_tangent_turns_the_frame_about_the_normal() {
        let n = [0.6, 0.0, 0.8];
        let f = Frame::from_normal_and_tangent(n, [0.0, 2.0, 1.0]);
        check_frame(f, n);
        // [0, 2, 1] − n (n·[0, 2, 1]) = [−0.48, 2, 0.36], of length 2.088.
        let want = [-0.48, 2.0, 0.36].map(|c| c / (0.48f64 * 0.48 + 4.0 + 0.36 * 0.36).sqrt());
        assert!(
            (0..3).all(|k| (f.s[k] - want[k]).abs() < 1e-12),
            "{:?}",
            f.s
        );
        for none in [[0.0; 3], [1.2, 0.0, 1.6], [1e-9, 0.0, 0.0]] {
            assert_eq!(
                Frame::from_normal_and_tangent(n, none),
                Frame::from_normal(n)
            );
        }
    }

    proptest! {
        #[test]
        fn orthonormal_everywhere(phi in 0.0..std::f64::consts::TAU, z in -1.0..=1.0f64) {
            let r = (1.0 - z * z).sqrt();
            let n = [r * phi.cos(), r * phi.sin(), z];
            check(n);
            // A sphere's azimuth tangent, as `SurfacePoint::dpdu`.
            let f = Frame::from_normal_and_tangent(n, [-n[1], n[0], 0.0]);
            check_frame(f, n);
        }
    }
}

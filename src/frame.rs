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

    /// The frame around the unit vector `n` whose first axis runs along
    /// the azimuth about the z axis, as a sphere's `∂p/∂u` (Mitsuba's
    /// sphere): `s = (−n_y, n_x, 0)/√(n_x² + n_y²)`, `t = n × s`. It turns
    /// smoothly everywhere but at the poles `n = ±z`, where
    /// [`Frame::from_normal`]'s (which jumps across `n_z = 0`) takes over
    /// (`n_x² + n_y² ≤ 10⁻¹²`).
    #[inline]
    pub fn azimuthal(n: V3<F>) -> Self {
        Self::around(n, true)
    }

    /// [`Frame::azimuthal`] of `n` where `azimuthal` holds, else
    /// [`Frame::from_normal`]: both computed and one selected, without a
    /// branch, for kernels over many normals at SIMD width.
    #[inline(always)]
    pub fn around(n: V3<F>, azimuthal: bool) -> Self {
        let normal = Self::from_normal(n);
        let r2 = n[0] * n[0] + n[1] * n[1];
        let inv = F::one() / r2.sqrt();
        let s = [-n[1] * inv, n[0] * inv, F::zero()];
        let t = cross(n, s);
        // (A NaN `r2` is not above the bound either.)
        let turns = azimuthal & (r2 > F::c(1e-12));
        Frame {
            s: if turns { s } else { normal.s },
            t: if turns { t } else { normal.t },
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

    /// The azimuthal frame's first axis is horizontal and turns smoothly
    /// across the equator, where Duff's jumps; at the poles it is Duff's.
    #[test]
    fn the_azimuthal_frame_turns_smoothly_across_the_equator() {
        let n = [0.6, 0.8, 0.0];
        let f = Frame::azimuthal(n);
        check_frame(f, n);
        assert!(
            (0..3).all(|k| (f.s[k] - [-0.8, 0.6, 0.0][k]).abs() < 1e-12),
            "{:?}",
            f.s
        );
        let near = |z: f64| {
            let r = (1.0 - z * z).sqrt();
            [0.6 * r, 0.8 * r, z]
        };
        let gap =
            |a: Frame<f64>, b: Frame<f64>| (0..3).map(|k| (a.s[k] - b.s[k]).abs()).sum::<f64>();
        let (above, below) = (near(1e-6), near(-1e-6));
        assert!(gap(Frame::azimuthal(above), Frame::azimuthal(below)) < 1e-5);
        assert!(gap(Frame::from_normal(above), Frame::from_normal(below)) > 0.5);
        for pole in [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1e-9, 0.0, 1.0]] {
            assert_eq!(Frame::azimuthal(pole), Frame::from_normal(pole));
        }
    }

    proptest! {
        #[test]
        fn orthonormal_everywhere(phi in 0.0..std::f64::consts::TAU, z in -1.0..=1.0f64) {
            let r = (1.0 - z * z).sqrt();
            let n = [r * phi.cos(), r * phi.sin(), z];
            check(n);
            check_frame(Frame::azimuthal(n), n);
        }
    }
}

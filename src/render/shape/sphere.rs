//! Spheres: intersection (in `f64`), and sampling by area or by the cone a
//! sphere subtends from a point outside it.

use glam::{DVec3, Vec3A};

use super::{Candidate, Ray, SurfacePoint};
use crate::warp;

/// A sphere; its normal points outward unless `flip`.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Centre.
    pub center: DVec3,
    /// Radius (> 0).
    pub radius: f64,
    /// Normals point inward.
    pub flip: bool,
}

impl Sphere {
    /// The roots of `|o + t d − c|² = r²` as `[disc, q, a, k]`: they are
    /// `q/a` and `k/q`, with `a = d·d`, `h = (o − c)·d`, `k = |o − c|² − r²`
    /// and `q = −(h + sign(h)·√disc)`, the form without cancellation, when
    /// the discriminant `disc = h² − a k` is not negative (otherwise the
    /// ray's line misses the sphere, and `q` is NaN). `disc` is computed
    /// as `a r² − |(o − c) × d|²` (Lagrange's identity), accurate for rays
    /// far from the sphere. In `f64`, without branches (for a batch of
    /// rays at SIMD width as for one).
    #[inline(always)]
    fn terms(&self, o: [f32; 3], d: [f32; 3]) -> [f64; 4] {
        let (o, d, a, disc) = self.discriminant(o, d);
        let h = o.dot(d);
        let q = -(h + h.signum() * disc.sqrt());
        [disc, q, a, o.length_squared() - self.radius * self.radius]
    }

    /// The origin relative to the centre, the direction (in `f64`), `a =
    /// d·d` and the discriminant `disc` of [`Sphere::terms`].
    #[inline(always)]
    fn discriminant(&self, o: [f32; 3], d: [f32; 3]) -> (DVec3, DVec3, f64, f64) {
        let o = DVec3::from_array(o.map(f64::from)) - self.center;
        let d = DVec3::from_array(d.map(f64::from));
        let a = d.length_squared();
        let disc = a * (self.radius * self.radius) - o.cross(d).length_squared();
        (o, d, a, disc)
    }

    /// Whether the line of the ray from `o` along `d` meets the sphere
    /// (the discriminant `h² − a k` of the intersection's quadratic is not
    /// negative, with the same bits as the hit tests compute it): where it
    /// does not, [`Sphere::hit_branchless`] and
    /// [`Sphere::occludes_branchless`] are false. Cheaper than either (no
    /// square root, no division), so that a batch can skip a sphere that
    /// no ray of a block comes near.
    #[inline(always)]
    pub fn line_meets(&self, o: [f32; 3], d: [f32; 3]) -> bool {
        self.discriminant(o, d).3 >= 0.0
    }

    /// [`Sphere::terms`] of `ray` as `(q, a, k)`; `None` when its line
    /// misses the sphere (the common case, which then costs no division).
    #[inline(always)]
    fn roots(&self, ray: &Ray) -> Option<(f64, f64, f64)> {
        let [disc, q, a, k] = self.terms(ray.o.to_array(), ray.d.to_array());
        (disc >= 0.0).then_some((q, a, k))
    }

    /// Whether the nearer root `t` of `(q, a, k)` in `(0, ∞)` lies below
    /// `tmax`, and `t`.
    #[inline(always)]
    fn nearer_root(q: f64, a: f64, k: f64, tmax: f32) -> (bool, f32) {
        let (t0, t1) = (q / a, k / q);
        let (near, far) = (t0.min(t1), t0.max(t1));
        let t = if near > 0.0 { near } else { far };
        (t > 0.0 && t < f64::from(tmax), t as f32)
    }

    /// Whether a root of `(q, a, k)` lies in `(0, tmax)`, without
    /// dividing: `q/a` does when `0 < q < a·tmax`, and `k/q` when `0 < σk <
    /// |q|·tmax` with `σ` the sign of `q` (`a > 0`).
    #[inline(always)]
    fn root_within(q: f64, a: f64, k: f64, tmax: f32) -> bool {
        let tmax = f64::from(tmax);
        let sk = q.signum() * k;
        (q > 0.0 && q < a * tmax) | (sk > 0.0 && sk < q.abs() * tmax)
    }

    /// The nearer root in `(0, tmax)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Candidate> {
        let (q, a, k) = self.roots(ray)?;
        let (hit, t) = Self::nearer_root(q, a, k, ray.tmax);
        hit.then_some(Candidate { t, bary: [0.0; 2] })
    }

    /// Whether a root lies in `(0, tmax)`, tested without a division (so
    /// no branch is needed to skip one).
    #[inline(always)]
    pub fn occludes(&self, ray: &Ray) -> bool {
        self.occludes_branchless(ray.o.to_array(), ray.d.to_array(), ray.tmax)
    }

    /// [`Sphere::intersect`] of the ray from `o` along `d` without
    /// branches, for a batch of rays at SIMD width: whether it meets the
    /// sphere in `(0, tmax)`, and where (the same bits as `intersect`).
    #[inline(always)]
    pub fn hit_branchless(&self, o: [f32; 3], d: [f32; 3], tmax: f32) -> (bool, f32) {
        let [disc, q, a, k] = self.terms(o, d);
        let (hit, t) = Self::nearer_root(q, a, k, tmax);
        ((disc >= 0.0) & hit, t)
    }

    /// Whether a root of the ray from `o` along `d` lies in `(0, tmax)`,
    /// without branches ([`Sphere::hit_branchless`]).
    #[inline(always)]
    pub fn occludes_branchless(&self, o: [f32; 3], d: [f32; 3], tmax: f32) -> bool {
        let [disc, q, a, k] = self.terms(o, d);
        (disc >= 0.0) & Self::root_within(q, a, k, tmax)
    }

    /// The point on the sphere nearest to `p` (a hit point, snapped back onto
    /// the surface), with its normal.
    #[inline]
    pub fn point(&self, p: Vec3A) -> SurfacePoint {
        let n = (p.as_dvec3() - self.center).normalize();
        let snapped = self.center + self.radius * n;
        let n = if self.flip { -n } else { n };
        let n = Vec3A::from(n.as_vec3());
        SurfacePoint {
            p: Vec3A::from(snapped.as_vec3()),
            ng: n,
            ns: n,
        }
    }

    /// Area `4π r²`.
    pub fn area(&self) -> f64 {
        4.0 * std::f64::consts::PI * self.radius * self.radius
    }

    /// A point drawn uniformly by area (density `1/(4π r²)`).
    pub fn sample(&self, u: [f32; 2]) -> SurfacePoint {
        let d = warp::square_to_uniform_sphere([f64::from(u[0]), f64::from(u[1])]);
        let p = self.center + self.radius * DVec3::from_array(d);
        self.point(Vec3A::from(p.as_vec3()))
    }

    /// The cone of directions in which the sphere is seen from `x`: its
    /// unit axis (toward the centre), `sin² θmax = r²/|c − x|²` and
    /// `1 − cos θmax` (as `sin² θmax / (1 + cos θmax)`, without
    /// cancellation for small spheres far away). `None` when `x` is not
    /// clearly outside the sphere: inside it, or on its surface to within
    /// rounding (a shading point on the sphere itself, which may round to
    /// either side).
    #[inline]
    fn cone(&self, x: Vec3A) -> Option<(DVec3, f64, f64)> {
        let to_center = self.center - x.as_dvec3();
        let dc2 = to_center.length_squared();
        let r2 = self.radius * self.radius;
        if dc2.is_nan() || dc2 <= r2 * (1.0 + 1e-4) {
            return None;
        }
        let sin2_max = r2 / dc2;
        let one_minus_cos_max = sin2_max / (1.0 + (1.0 - sin2_max).sqrt());
        Some((to_center / dc2.sqrt(), sin2_max, one_minus_cos_max))
    }

    /// Density per steradian of [`Sphere::sample_cone`] from `x` (for any
    /// direction toward the sphere): `1 / (2π (1 − cos θmax))`. `None` when
    /// `x` is not outside the sphere.
    #[inline]
    pub fn cone_pdf(&self, x: Vec3A) -> Option<f32> {
        let (_, _, one_minus_cos_max) = self.cone(x)?;
        Some(uniform_cone_density(one_minus_cos_max))
    }

    /// The point of the sphere that `x` (outside it) sees along a direction
    /// drawn uniformly in the cone the sphere subtends, with that density
    /// per steradian ([`Sphere::cone_pdf`]); `None` when `x` is not outside
    /// the sphere (sample by area then).
    ///
    /// # Density
    /// `p(ω) = 1 / (2π (1 − cos θmax))` for the directions that meet the
    /// sphere, `sin θmax = r / |c − x|`; the point is the nearer hit, so
    /// every sample is visible from `x`.
    ///
    /// # Method
    /// `1 − cos θ = u₀ (1 − cos θmax)` and `φ = 2π u₁` around the axis; the
    /// point is placed by its angle `α` at the centre (from the axis back
    /// toward `x`), `cos α = sin² θ / sin θmax + cos θ √(1 − sin² θ /
    /// sin² θmax)`, so that it lies on the sphere to rounding.
    ///
    /// # References
    /// M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th
    /// ed., §6.2.4 (sampling a sphere by the cone it subtends).
    pub fn sample_cone(&self, x: Vec3A, u: [f32; 2]) -> Option<(SurfacePoint, f32)> {
        let (axis, sin2_max, one_minus_cos_max) = self.cone(x)?;
        let omc = f64::from(u[0]) * one_minus_cos_max;
        let cos_theta = 1.0 - omc;
        let sin2_theta = omc * (2.0 - omc);
        let cos_alpha = sin2_theta / sin2_max.sqrt()
            + cos_theta * (1.0 - sin2_theta / sin2_max).max(0.0).sqrt();
        let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * f64::from(u[1]);
        let (s, t) = axis.any_orthonormal_pair();
        let n = -cos_alpha * axis + sin_alpha * (phi.cos() * s + phi.sin() * t);
        let p = self.center + self.radius * n;
        let n = Vec3A::from((if self.flip { -n } else { n }).as_vec3());
        let point = SurfacePoint {
            p: Vec3A::from(p.as_vec3()),
            ng: n,
            ns: n,
        };
        Some((point, uniform_cone_density(one_minus_cos_max)))
    }

    /// Bounds.
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        let r = DVec3::splat(self.radius);
        (
            Vec3A::from((self.center - r).as_vec3()),
            Vec3A::from((self.center + r).as_vec3()),
        )
    }
}

/// The density per steradian of directions uniform in a cone of solid angle
/// `2π (1 − cos θmax)`.
#[inline]
fn uniform_cone_density(one_minus_cos_max: f64) -> f32 {
    (1.0 / (2.0 * std::f64::consts::PI * one_minus_cos_max)) as f32
}

//! The shapes of a scene: triangles, spheres and disks, their ray
//! intersection and their uniform sampling by area.
//!
//! Geometry is single precision (the BVH's rays are `f32`), except the
//! sphere's quadratic, solved in `f64` so that its roots stay accurate far
//! from the origin.

use std::ops::{Add, BitAnd, Div, Mul, Sub};

use glam::{Affine3A, BVec4A, DVec3, Vec3A, Vec4};

use crate::warp;

/// A ray `o + t d` for `t` in `(0, tmax)`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Ray {
    /// Origin.
    pub o: Vec3A,
    /// Direction (unit length).
    pub d: Vec3A,
    /// Farthest distance.
    pub tmax: f32,
}

/// Where a ray meets a primitive, before shading (the [`SurfacePoint`] follows
/// from it).
#[derive(Clone, Copy, Debug)]
pub struct Candidate {
    /// Distance along the ray.
    pub t: f32,
    /// Barycentric `(b1, b2)` for triangles (unused otherwise).
    pub bary: [f32; 2],
}

/// A surface point, as a shading point or an emitter sample.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Position.
    pub p: Vec3A,
    /// Geometric normal (unit, outward / the front side).
    pub ng: Vec3A,
    /// Shading normal (interpolated vertex normal, else `ng`).
    pub ns: Vec3A,
}

/// A triangle `p0 + b1 e1 + b2 e2` of a mesh.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// First vertex.
    pub p0: Vec3A,
    /// `p1 − p0`.
    pub e1: Vec3A,
    /// `p2 − p0`.
    pub e2: Vec3A,
    /// Vertex normals, when the mesh has them.
    pub normals: Option<[Vec3A; 3]>,
}

impl Triangle {
    /// Möller–Trumbore: the distance and barycentrics of the hit in
    /// `(0, tmax)`, if any (see [`moller_trumbore`]).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Candidate> {
        let [o, d, p0, e1, e2] = [ray.o, ray.d, self.p0, self.e1, self.e2].map(|v| v.to_array());
        let scaled = moller_trumbore(o, d, p0, e1, e2);
        if !scaled.inside {
            return None;
        }
        let (ahead, t, bary) = scaled.hit(ray.tmax);
        ahead.then_some(Candidate { t, bary })
    }

    /// Area, `|e1 × e2| / 2`.
    pub fn area(&self) -> f32 {
        0.5 * self.e1.cross(self.e2).length()
    }

    /// The surface point at barycentrics `bary`: face normal
    /// `normalize(e1 × e2)` (counter-clockwise vertices face the viewer), and
    /// the barycentric blend of the vertex normals as shading normal.
    #[inline]
    pub fn point(&self, bary: [f32; 2]) -> SurfacePoint {
        let [b1, b2] = bary;
        let p = self.p0 + b1 * self.e1 + b2 * self.e2;
        let ng = self.e1.cross(self.e2).normalize_or_zero();
        let ns = match self.normals {
            Some([n0, n1, n2]) => ((1.0 - b1 - b2) * n0 + b1 * n1 + b2 * n2).normalize_or(ng),
            None => ng,
        };
        SurfacePoint { p, ng, ns }
    }

    /// A point drawn uniformly by area (density `1/area`), `u ∈ [0, 1]²`.
    pub fn sample(&self, u: [f32; 2]) -> SurfacePoint {
        let [b1, b2] = warp::square_to_uniform_triangle(u);
        self.point([b1, b2])
    }
}

/// Numbers that Möller–Trumbore runs on: one `f32` (one triangle), or a
/// `Vec4` (four triangles at once, one per lane).
pub trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// Per-lane truth values.
    type Mask: Copy + BitAnd<Output = Self::Mask>;
    /// `x` in every lane.
    fn splat(x: f32) -> Self;
    /// `±1` by the sign bit.
    fn signum(self) -> Self;
    /// `|x|`.
    fn abs(self) -> Self;
    /// `self < other`.
    fn lt(self, other: Self) -> Self::Mask;
    /// `self <= other`.
    fn le(self, other: Self) -> Self::Mask;
}

impl Lanes for f32 {
    type Mask = bool;
    fn splat(x: f32) -> Self {
        x
    }
    fn signum(self) -> Self {
        f32::signum(self)
    }
    fn abs(self) -> Self {
        f32::abs(self)
    }
    fn lt(self, other: Self) -> bool {
        self < other
    }
    fn le(self, other: Self) -> bool {
        self <= other
    }
}

impl Lanes for Vec4 {
    type Mask = BVec4A;
    fn splat(x: f32) -> Self {
        Vec4::splat(x)
    }
    fn signum(self) -> Self {
        Vec4::signum(self)
    }
    fn abs(self) -> Self {
        Vec4::abs(self)
    }
    fn lt(self, other: Self) -> BVec4A {
        self.cmplt(other)
    }
    fn le(self, other: Self) -> BVec4A {
        self.cmple(other)
    }
}

/// Möller–Trumbore's quantities, scaled by the determinant made positive,
/// `|det|`: `b1 |det|`, `b2 |det|` and `t |det|`. The inside test runs on
/// them, so that a miss costs no division.
pub struct Scaled<L: Lanes> {
    /// Whether `det` is finite and not 0 and the barycentrics lie in the
    /// triangle.
    pub inside: L::Mask,
    det: L,
    b1: L,
    b2: L,
    t: L,
}

impl<L: Lanes> Scaled<L> {
    /// Whether the hit lies in `(0, tmax)`, its distance and barycentrics.
    #[inline(always)]
    pub fn hit(&self, tmax: f32) -> (L::Mask, L, [L; 2]) {
        let inv = L::splat(1.0) / self.det;
        let t = self.t * inv;
        let ahead = L::splat(0.0).lt(t) & t.lt(L::splat(tmax));
        (ahead, t, [self.b1 * inv, self.b2 * inv])
    }
}

/// Möller–Trumbore for the ray `o + t d` and the triangle `p0 + b1 e1 +
/// b2 e2` (in lanes: several triangles, one ray splatted), as vectors of
/// components:
///
/// ```text
/// p = d × e2,  det = e1 · p,  s = o − p0,  q = s × e1,
/// b1 = (s · p) / det,  b2 = (d · q) / det,  t = (e2 · q) / det
/// ```
#[inline(always)]
pub fn moller_trumbore<L: Lanes>(
    o: [L; 3],
    d: [L; 3],
    p0: [L; 3],
    e1: [L; 3],
    e2: [L; 3],
) -> Scaled<L> {
    let cross = |a: [L; 3], b: [L; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [L; 3], b: [L; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let p = cross(d, e2);
    let det = dot(e1, p);
    let s = [o[0] - p0[0], o[1] - p0[1], o[2] - p0[2]];
    let q = cross(s, e1);
    let sign = det.signum();
    let (det, b1, b2) = (det.abs(), sign * dot(s, p), sign * dot(d, q));
    let zero = L::splat(0.0);
    let inside = zero.lt(det)
        & det.lt(L::splat(f32::INFINITY))
        & zero.le(b1)
        & b1.le(det)
        & zero.le(b2)
        & (b1 + b2).le(det);
    Scaled {
        inside,
        det,
        b1,
        b2,
        t: sign * dot(e2, q),
    }
}

/// Up to four triangles side by side, component by component, tested
/// against one ray at once (unused lanes hold a degenerate triangle, which
/// nothing hits).
#[derive(Clone, Copy, Debug)]
pub struct Triangles4 {
    p0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
}

impl Triangles4 {
    /// At most four triangles, in lane order.
    pub fn new(triangles: &[Triangle]) -> Self {
        let mut pack = Triangles4 {
            p0: [Vec4::ZERO; 3],
            e1: [Vec4::ZERO; 3],
            e2: [Vec4::ZERO; 3],
        };
        for (lane, t) in triangles.iter().take(4).enumerate() {
            for k in 0..3 {
                pack.p0[k][lane] = t.p0[k];
                pack.e1[k][lane] = t.e1[k];
                pack.e2[k][lane] = t.e2[k];
            }
        }
        pack
    }

    /// Möller–Trumbore for all four lanes: which lanes the ray hits in
    /// `(0, tmax)` (bit `l` for lane `l`), the distances and barycentrics.
    #[inline(always)]
    fn hits(&self, ray: &Ray) -> (u32, Vec4, [Vec4; 2]) {
        let scaled = moller_trumbore::<Vec4>(
            ray.o.to_array().map(Vec4::splat),
            ray.d.to_array().map(Vec4::splat),
            self.p0,
            self.e1,
            self.e2,
        );
        if !scaled.inside.any() {
            return (0, Vec4::ZERO, [Vec4::ZERO; 2]);
        }
        let (ahead, t, bary) = scaled.hit(ray.tmax);
        ((scaled.inside & ahead).bitmask(), t, bary)
    }

    /// The nearest hit in `(0, tmax)` among the four: its lane and
    /// candidate.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<(usize, Candidate)> {
        let (hits, t, [b1, b2]) = self.hits(ray);
        let lane = (0..4)
            .filter(|l| hits & (1 << l) != 0)
            .min_by(|&a, &b| t[a].total_cmp(&t[b]))?;
        Some((
            lane,
            Candidate {
                t: t[lane],
                bary: [b1[lane], b2[lane]],
            },
        ))
    }

    /// Whether any of the four lies on the ray in `(0, tmax)`.
    #[inline]
    pub fn occludes(&self, ray: &Ray) -> bool {
        self.hits(ray).0 != 0
    }
}

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
    /// The roots of `|o + t d − c|² = r²` as `(q, a, k)`: they are `q/a`
    /// and `k/q`, with `a = d·d`, `h = (o − c)·d`, `k = |o − c|² − r²` and
    /// `q = −(h + sign(h)·√(h² − a k))`, the form without cancellation. The
    /// discriminant is `h² − a k = a r² − |(o − c) × d|²` (Lagrange's
    /// identity), accurate for rays far from the sphere, and needs no
    /// division, so that a miss (the common case) costs none. `None` when
    /// the ray's line misses the sphere. In `f64`.
    #[inline(always)]
    fn roots(&self, ray: &Ray) -> Option<(f64, f64, f64)> {
        let o = ray.o.as_dvec3() - self.center;
        let d = ray.d.as_dvec3();
        let a = d.length_squared();
        let r2 = self.radius * self.radius;
        let disc = a * r2 - o.cross(d).length_squared();
        if disc < 0.0 {
            return None;
        }
        let h = o.dot(d);
        let q = -(h + h.signum() * disc.sqrt());
        Some((q, a, o.length_squared() - r2))
    }

    /// The nearer root in `(0, tmax)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Candidate> {
        let (q, a, k) = self.roots(ray)?;
        let (t0, t1) = (q / a, k / q);
        let (near, far) = (t0.min(t1), t0.max(t1));
        let t = if near > 0.0 { near } else { far };
        (t > 0.0 && t < f64::from(ray.tmax)).then_some(Candidate {
            t: t as f32,
            bary: [0.0; 2],
        })
    }

    /// Whether a root lies in `(0, tmax)`, without dividing: `q/a` does
    /// when `0 < q < a·tmax`, and `k/q` when `0 < σk < |q|·tmax` with `σ`
    /// the sign of `q` (`a > 0`).
    #[inline]
    pub fn occludes(&self, ray: &Ray) -> bool {
        let Some((q, a, k)) = self.roots(ray) else {
            return false;
        };
        let tmax = f64::from(ray.tmax);
        let sk = q.signum() * k;
        (q > 0.0 && q < a * tmax) || (sk > 0.0 && sk < q.abs() * tmax)
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

/// The unit disk `x² + y² ≤ 1, z = 0` (normal +z), placed by an affine
/// `to_world` as Mitsuba's `disk`.
#[derive(Clone, Copy, Debug)]
pub struct Disk {
    /// Local to world.
    pub to_world: Affine3A,
    /// World to local.
    pub to_local: Affine3A,
    /// World normal (unit): the local +z through the inverse transpose.
    pub normal: Vec3A,
    /// `π |Mx × My|`: the image of the unit disk's area.
    pub area: f32,
}

impl Disk {
    /// A disk placed by `to_world`, or `None` if that matrix is singular on
    /// the disk's plane.
    pub fn new(to_world: Affine3A) -> Option<Self> {
        let m = to_world.matrix3;
        let cross = m.x_axis.cross(m.y_axis);
        let det = m.determinant();
        if cross.length() == 0.0 || det == 0.0 || !det.is_finite() {
            return None;
        }
        let to_local = to_world.inverse();
        let normal = (to_local.matrix3.transpose() * Vec3A::Z).normalize();
        Some(Disk {
            to_world,
            to_local,
            normal,
            area: std::f32::consts::PI * cross.length(),
        })
    }

    /// The hit in `(0, tmax)`, solved in the disk's local frame (the
    /// distance is the same in both frames, as the direction is mapped
    /// without renormalising).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Candidate> {
        let o = self.to_local.transform_point3a(ray.o);
        let d = self.to_local.transform_vector3a(ray.d);
        if d.z == 0.0 {
            return None;
        }
        let t = -o.z / d.z;
        let (x, y) = (o.x + t * d.x, o.y + t * d.y);
        (t > 0.0 && t < ray.tmax && x * x + y * y <= 1.0).then_some(Candidate { t, bary: [0.0; 2] })
    }

    /// The point of the disk at world position `p` (on its plane).
    #[inline]
    pub fn point(&self, p: Vec3A) -> SurfacePoint {
        SurfacePoint {
            p,
            ng: self.normal,
            ns: self.normal,
        }
    }

    /// A point drawn uniformly by area (density `1/area`; the map is affine,
    /// so uniform on the unit disk stays uniform).
    pub fn sample(&self, u: [f32; 2]) -> SurfacePoint {
        let [x, y] = warp::square_to_uniform_disk_concentric(u);
        self.point(self.to_world.transform_point3a(Vec3A::new(x, y, 0.0)))
    }

    /// Bounds: the image of the square `[−1, 1]² × {0}`.
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, y)| self.to_world.transform_point3a(Vec3A::new(x, y, 0.0)));
        let lo = corners.iter().fold(Vec3A::INFINITY, |a, &c| a.min(c));
        let hi = corners.iter().fold(Vec3A::NEG_INFINITY, |a, &c| a.max(c));
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray {
            o: Vec3A::from(o),
            d: Vec3A::from(d).normalize(),
            tmax: f32::INFINITY,
        }
    }

    #[test]
    fn triangle_hit_and_normals() {
        let tri = Triangle {
            p0: Vec3A::new(0.0, 0.0, 0.0),
            e1: Vec3A::new(1.0, 0.0, 0.0),
            e2: Vec3A::new(0.0, 1.0, 0.0),
            normals: None,
        };
        let hit = tri
            .intersect(&ray([0.25, 0.25, 2.0], [0.0, 0.0, -1.0]))
            .unwrap();
        assert!((hit.t - 2.0).abs() < 1e-6);
        let sp = tri.point(hit.bary);
        assert!((sp.p - Vec3A::new(0.25, 0.25, 0.0)).length() < 1e-6);
        assert_eq!(sp.ng, Vec3A::Z);
        assert!(
            tri.intersect(&ray([0.75, 0.75, 2.0], [0.0, 0.0, -1.0]))
                .is_none()
        );
        assert!((tri.area() - 0.5).abs() < 1e-7);
    }

    /// Four triangles tested at once give the nearest of the hits each
    /// gives alone (and its barycentrics), on rays that hit none, one or
    /// several of them; three triangles leave a padding lane that nothing
    /// hits.
    #[test]
    fn four_triangles_at_once_agree_with_one_at_a_time() {
        let tri = |p0: [f32; 3], e1: [f32; 3], e2: [f32; 3]| Triangle {
            p0: Vec3A::from(p0),
            e1: Vec3A::from(e1),
            e2: Vec3A::from(e2),
            normals: None,
        };
        let tris = [
            tri([-1.0, -1.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
            tri([-1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [2.0, 0.0, 0.0]),
            tri([0.0, -2.0, -3.0], [0.0, 4.0, 0.0], [0.0, 0.0, 4.0]),
            tri([0.3, -0.5, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.2]),
        ];
        for count in [3, 4] {
            let pack = Triangles4::new(&tris[..count]);
            let mut nearest_lanes = [0; 4];
            for i in 0..400 {
                let (a, b) = ((i % 20) as f32 / 10.0 - 1.0, (i / 20) as f32 / 10.0 - 1.0);
                let r = ray([a, b, 2.0], [0.3 * b, -0.2, -1.0]);
                let nearest = tris[..count]
                    .iter()
                    .enumerate()
                    .filter_map(|(l, t)| t.intersect(&r).map(|c| (l, c)))
                    .min_by(|x, y| x.1.t.total_cmp(&y.1.t));
                let packed = pack.intersect(&r);
                assert_eq!(packed.map(|p| p.0), nearest.map(|n| n.0), "ray {i}");
                if let (Some((_, p)), Some((_, n))) = (packed, nearest) {
                    assert_eq!((p.t, p.bary), (n.t, n.bary), "ray {i}");
                }
                assert_eq!(pack.occludes(&r), nearest.is_some());
                if let Some((l, _)) = nearest {
                    nearest_lanes[l] += 1;
                }
            }
            assert!(
                nearest_lanes[..count].iter().all(|&n| n > 0),
                "{nearest_lanes:?}"
            );
        }
    }

    #[test]
    fn sphere_hit_from_outside_and_inside() {
        let s = Sphere {
            center: DVec3::new(0.0, 0.0, -5.0),
            radius: 1.0,
            flip: false,
        };
        let outside = s
            .intersect(&ray([0.0, 0.0, 0.0], [0.0, 0.0, -1.0]))
            .unwrap();
        assert!((outside.t - 4.0).abs() < 1e-6);
        let inside = s
            .intersect(&ray([0.0, 0.0, -5.0], [1.0, 0.0, 0.0]))
            .unwrap();
        assert!((inside.t - 1.0).abs() < 1e-6);
        assert!(
            s.intersect(&ray([0.0, 2.0, 0.0], [0.0, 0.0, -1.0]))
                .is_none()
        );
        let sp = s.point(Vec3A::new(0.0, 0.0, -4.0));
        assert!((sp.ng - Vec3A::Z).length() < 1e-6);
    }

    #[test]
    fn sphere_occlusion_agrees_with_the_nearest_hit() {
        let s = Sphere {
            center: DVec3::new(0.2, -0.1, -3.0),
            radius: 0.8,
            flip: false,
        };
        let (mut hits, mut misses) = (0, 0);
        for i in 0..2000 {
            let k = i as f32;
            // Origins outside, inside and just off the surface (as a shadow
            // ray leaves it); directions all around; finite and infinite
            // tmax.
            let start = match i % 3 {
                0 => [0.0, 0.0, 0.0],
                1 => [0.3, -0.2, -3.1],
                _ => {
                    let n = Vec3A::new((k * 0.37).sin(), (k * 0.71).cos(), (k * 0.13).sin())
                        .normalize();
                    (s.center.as_vec3a() + n * (0.8 + 1e-4)).to_array()
                }
            };
            let mut r = ray(start, [(k * 1.3).sin(), (k * 0.9).cos(), -(k * 0.5).cos()]);
            r.tmax = [f32::INFINITY, 0.5, 2.0, 4.0][i % 4];
            let hit = s.intersect(&r).is_some();
            assert_eq!(s.occludes(&r), hit, "ray {i}: {r:?}");
            (hits, misses) = (hits + usize::from(hit), misses + usize::from(!hit));
        }
        assert!(hits > 300 && misses > 300, "{hits} hits, {misses} misses");
    }

    #[test]
    fn disk_hit_area_and_normal() {
        let m = Affine3A::from_scale_rotation_translation(
            glam::Vec3::new(2.0, 2.0, 1.0),
            glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            glam::Vec3::new(0.0, 1.0, 0.0),
        );
        let disk = Disk::new(m).unwrap();
        assert!((disk.area - 4.0 * std::f32::consts::PI).abs() < 1e-4);
        assert!((disk.normal - Vec3A::new(0.0, -1.0, 0.0)).length() < 1e-6);
        let hit = disk
            .intersect(&ray([1.5, 5.0, 0.0], [0.0, -1.0, 0.0]))
            .unwrap();
        assert!((hit.t - 4.0).abs() < 1e-5);
        assert!(
            disk.intersect(&ray([2.5, 5.0, 0.0], [0.0, -1.0, 0.0]))
                .is_none()
        );
    }
}

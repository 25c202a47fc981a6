//! Triangles of meshes: Möller–Trumbore intersection, one at a time or four
//! at once, and uniform sampling by area.

use std::ops::{Add, BitAnd, Div, Mul, Sub};

use glam::{BVec4A, Vec3A, Vec4};

use super::{Candidate, Ray, SurfacePoint};
use crate::warp;

/// A triangle `p0 + b1 e1 + b2 e2` of a mesh.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// First vertex.
    pub p0: Vec3A,
    /// `p1 − p0`.
    pub e1: Vec3A,
    /// `p2 − p0`.
    pub e2: Vec3A,
    /// The indices of the vertex normals in its mesh's table (the
    /// `normals` argument of [`Triangle::point`]), when the mesh has
    /// them.
    pub normals: Option<[u32; 3]>,
}

impl Triangle {
    /// Möller–Trumbore: the distance and barycentrics of the hit in
    /// `(0, tmax)`, if any (see [`moller_trumbore`]).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Candidate> {
        let [p0, e1, e2] = [self.p0, self.e1, self.e2].map(|v| v.to_array());
        triangle_hit(ray, p0, e1, e2)
    }

    /// Area, `|e1 × e2| / 2`.
    pub fn area(&self) -> f32 {
        0.5 * self.e1.cross(self.e2).length()
    }

    /// The surface point at barycentrics `bary`: face normal
    /// `normalize(e1 × e2)` (counter-clockwise vertices face the viewer), and
    /// the barycentric blend of the vertex normals (`normals[i]` for the
    /// indices `i` of [`Triangle::normals`]) as shading normal.
    #[inline]
    pub fn point(&self, bary: [f32; 2], normals: &[Vec3A]) -> SurfacePoint {
        let [b1, b2] = bary;
        let p = self.p0 + b1 * self.e1 + b2 * self.e2;
        let ng = self.e1.cross(self.e2).normalize_or_zero();
        let ns = match self.normals {
            Some(i) => {
                let [n0, n1, n2] = i.map(|i| normals[i as usize]);
                ((1.0 - b1 - b2) * n0 + b1 * n1 + b2 * n2).normalize_or(ng)
            }
            None => ng,
        };
        SurfacePoint { p, ng, ns }
    }

    /// A point drawn uniformly by area (density `1/area`), `u ∈ [0, 1]²`
    /// (`normals` as for [`Triangle::point`]).
    pub fn sample(&self, u: [f32; 2], normals: &[Vec3A]) -> SurfacePoint {
        let [b1, b2] = warp::square_to_uniform_triangle(u);
        self.point([b1, b2], normals)
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

/// The hit of `ray` in `(0, ray.tmax)` on the triangle `p0 + b1 e1 + b2
/// e2` ([`moller_trumbore`] for one ray), if any.
#[inline(always)]
pub fn triangle_hit(ray: &Ray, p0: [f32; 3], e1: [f32; 3], e2: [f32; 3]) -> Option<Candidate> {
    let scaled = moller_trumbore(ray.o.to_array(), ray.d.to_array(), p0, e1, e2);
    if !scaled.inside {
        return None;
    }
    let (ahead, t, bary) = scaled.hit(ray.tmax);
    ahead.then_some(Candidate { t, bary })
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

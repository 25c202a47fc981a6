//! The shapes of a scene: triangles, spheres and disks, their ray
//! intersection and their uniform sampling by area.
//!
//! Geometry is single precision (the BVH's rays are `f32`), except the
//! sphere's quadratic, solved in `f64` so that its roots stay accurate far
//! from the origin.

use glam::{Affine3A, DVec3, Vec3A};

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

/// Where a ray meets a primitive, before shading ([`Intersection`] follows
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
    /// `(0, tmax)`, if any. The tests run on the barycentrics and distance
    /// scaled by the determinant (made positive), so that a miss costs no
    /// division.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Candidate> {
        let pvec = ray.d.cross(self.e2);
        let det = self.e1.dot(pvec);
        if !(det != 0.0 && det.is_finite()) {
            return None;
        }
        let tvec = ray.o - self.p0;
        let qvec = tvec.cross(self.e1);
        let sign = det.signum();
        let (det, b1, b2) = (det.abs(), sign * tvec.dot(pvec), sign * ray.d.dot(qvec));
        if !(b1 >= 0.0 && b1 <= det && b2 >= 0.0 && b1 + b2 <= det) {
            return None;
        }
        let inv = 1.0 / det;
        let t = sign * self.e2.dot(qvec) * inv;
        (t > 0.0 && t < ray.tmax).then_some(Candidate {
            t,
            bary: [b1 * inv, b2 * inv],
        })
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
    /// The nearer root of `|o + t d − c|² = r²` in `(0, tmax)`, solved in
    /// `f64` in the numerically stable form (no cancellation).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Candidate> {
        let o = ray.o.as_dvec3() - self.center;
        let d = ray.d.as_dvec3();
        let a = d.length_squared();
        let inv_a = 1.0 / a;
        let od = o.dot(d);
        // The discriminant as b² − 4ac = 4a(r² − |o − (o·d/a) d|²), which
        // stays accurate for rays far from the sphere.
        let f = o - (od * inv_a) * d;
        let r2 = self.radius * self.radius;
        let disc = 4.0 * a * (r2 - f.length_squared());
        if disc < 0.0 {
            return None;
        }
        let b = 2.0 * od;
        let c = o.length_squared() - r2;
        let q = -0.5 * (b + b.signum() * disc.sqrt());
        let (mut t0, mut t1) = (q * inv_a, c / q);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        let tmax = f64::from(ray.tmax);
        let t = if t0 > 0.0 { t0 } else { t1 };
        (t > 0.0 && t < tmax).then_some(Candidate {
            t: t as f32,
            bary: [0.0; 2],
        })
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

    /// Bounds.
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        let r = DVec3::splat(self.radius);
        (
            Vec3A::from((self.center - r).as_vec3()),
            Vec3A::from((self.center + r).as_vec3()),
        )
    }
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

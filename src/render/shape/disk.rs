//! Mitsuba's `disk`: the unit disk placed by an affine map, its intersection
//! and uniform sampling by area.

use glam::{Affine3A, Vec3A};

use super::{Candidate, Ray, SurfacePoint};
use crate::warp;

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

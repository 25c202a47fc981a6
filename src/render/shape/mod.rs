//! The shapes of a scene: triangles, spheres and disks, their ray
//! intersection and their sampling (uniform by area, and a sphere seen from
//! outside by the cone it subtends), one file each.
//!
//! Geometry is single precision (the BVH's rays are `f32`), except the
//! sphere, solved in `f64` so that its roots stay accurate far from the
//! origin.

mod disk;
mod sphere;
mod triangle;

pub use disk::Disk;
pub use sphere::Sphere;
pub use triangle::{Lanes, Scaled, Triangle, Triangles4, moller_trumbore, triangle_hit};

use glam::Vec3A;

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

#[cfg(test)]
mod tests;

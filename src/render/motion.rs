//! Motion blur: a transform that changes during the shutter interval.
//!
//! A moving shape or camera has its transform `M₀` at `shutter_open` and
//! `M₁` at `shutter_close`; at the normalised time `τ ∈ [0, 1]` between
//! them it is `M(τ) = T(τ) R(τ) S(τ)`, with each of `M₀`, `M₁` split into a
//! translation `T`, a rotation `R` and a symmetric stretch `S` (the polar
//! decomposition of the linear part, `A = R S`), `T` and `S` interpolated
//! linearly and `R` by spherical linear interpolation of its quaternion
//! (as pbrt's animated transforms). A map that reflects (`det A < 0`) is
//! split as `A = (−R)(−S)`, so that `−R` is a rotation; both ends must then
//! reflect. A moving shape is traced in a BVH of its own ([`Mover`]).

use glam::{Affine3A, DAffine3, DMat3, DQuat, DVec3, Vec3A};

use super::accel::{Accel, Hit};
use super::geometry::affine_f32;
use super::shape::{Ray, SurfacePoint};

use crate::error::{Error, Result};

/// An affine map as translation, rotation and stretch.
#[derive(Clone, Copy, Debug)]
struct Parts {
    translation: DVec3,
    rotation: DQuat,
    stretch: DMat3,
    /// Whether the linear part is `−R S` (the map reflects).
    reflects: bool,
}

impl Parts {
    /// The parts of `m`, or `None` when its linear part is singular, not
    /// finite, or too far from a rotation for the iteration to converge in
    /// 100 steps (scales beyond about 2^±90).
    fn new(m: DAffine3) -> Option<Self> {
        let det = m.matrix3.determinant();
        if !(det.is_finite() && det != 0.0) {
            return None;
        }
        let reflects = det < 0.0;
        let a = if reflects { -m.matrix3 } else { m.matrix3 };
        // Polar decomposition by Newton's iteration `R ← (R + R⁻ᵀ)/2`,
        // which converges quadratically to the rotation nearest to `a`.
        let mut r = a;
        let mut converged = false;
        for _ in 0..100 {
            let next = (r + r.inverse().transpose()) * 0.5;
            let change = (next - r)
                .to_cols_array()
                .iter()
                .map(|v| v.abs())
                .sum::<f64>();
            r = next;
            if change < 1e-12 {
                converged = true;
                break;
            }
        }
        // Scales beyond about 2^±90 need more steps: refused as singular.
        if !converged {
            return None;
        }
        Some(Parts {
            translation: m.translation,
            rotation: DQuat::from_mat3(&r).normalize(),
            stretch: r.transpose() * a,
            reflects,
        })
    }
}

/// A transform moving from `start` (at `τ = 0`) to `end` (at `τ = 1`).
#[derive(Clone, Copy, Debug)]
pub struct Motion {
    start: Parts,
    end: Parts,
}

impl Motion {
    /// The motion from `start` to `end`.
    ///
    /// # Errors
    /// [`Error::Argument`] naming `arg` when either map is singular (or
    /// scales by more than about 2^±90), or when one reflects and the
    /// other does not (no rotation turns one into the other).
    pub fn new(arg: &'static str, start: DAffine3, end: DAffine3) -> Result<Self> {
        let (Some(s), Some(e)) = (Parts::new(start), Parts::new(end)) else {
            return Err(Error::Argument {
                arg,
                message: format!("{arg}: a transform at either end of the shutter is singular"),
            });
        };
        if s.reflects != e.reflects {
            return Err(Error::Argument {
                arg,
                message: format!(
                    "{arg}: one end of the motion mirrors the shape and the other does not"
                ),
            });
        }
        Ok(Motion { start: s, end: e })
    }

    /// A sphere holding, at every time, where the points of the sphere
    /// `(center, radius)` at `τ = 0` go. With `p = M(0)⁻¹ x` (so
    /// `|p| ≤ |M(0)⁻¹ c| + ‖L(0)⁻¹‖ r`, `L` the linear part) and
    /// `M(τ) p = T(τ) ± R(τ) S(τ) p`: `T(τ)` runs along the segment of its
    /// ends and `‖S(τ)‖ ≤ max(‖S(0)‖, ‖S(1)‖)` (a norm is convex and `S` is
    /// linear in `τ`), Frobenius norms bounding the operator norm.
    pub fn bounding_sphere(&self, center: DVec3, radius: f64) -> (DVec3, f64) {
        let start = self.at(0.0).inverse();
        let frobenius = |m: DMat3| m.to_cols_array().iter().map(|v| v * v).sum::<f64>().sqrt();
        let p = start.transform_point3(center).length() + frobenius(start.matrix3) * radius;
        let (a, b) = (&self.start, &self.end);
        let stretch = frobenius(a.stretch).max(frobenius(b.stretch));
        (
            0.5 * (a.translation + b.translation),
            0.5 * (b.translation - a.translation).length() + stretch * p,
        )
    }

    /// `M(τ) = T(τ) R(τ) S(τ)`.
    pub fn at(&self, tau: f64) -> DAffine3 {
        let (a, b) = (&self.start, &self.end);
        let rotation = DMat3::from_quat(a.rotation.slerp(b.rotation, tau));
        let stretch = a.stretch * (1.0 - tau) + b.stretch * tau;
        let linear = rotation * stretch;
        DAffine3 {
            matrix3: if a.reflects { -linear } else { linear },
            translation: a.translation.lerp(b.translation, tau),
        }
    }
}

/// A shape that moves during the shutter, traced in a BVH of its own: its
/// primitives where they are at `shutter_open` (transform `M₀`), met by the
/// ray mapped through `D(τ)⁻¹`, with `D(τ) = M(τ) M₀⁻¹` taking them to
/// where they are at time `τ`. The direction is mapped without
/// renormalising, so distances along the ray are the same in both frames;
/// normals go back through the inverse transpose of `D(τ)`.
pub struct Mover {
    accel: Accel,
    motion: Motion,
    start_inverse: DAffine3,
    /// The number of its first primitive in the scene's [`Hit`]s: they
    /// follow the still shapes' and those of the moving shapes before it.
    first: u32,
}

impl Mover {
    /// The shape of primitives `accel` (where they are at `shutter_open`)
    /// moving by `motion`.
    pub fn new(accel: Accel, motion: Motion) -> Self {
        Mover {
            accel,
            motion,
            start_inverse: motion.at(0.0).inverse(),
            first: 0,
        }
    }

    /// Its primitives and their BVH, where they are at `shutter_open`.
    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    /// Numbers its primitives from `first` in the scene's hits; returns the
    /// number after its last.
    pub fn number_from(&mut self, first: u32) -> u32 {
        self.first = first;
        first + self.accel.primitives().len() as u32
    }

    /// The number of its first primitive.
    pub fn first(&self) -> u32 {
        self.first
    }

    /// A sphere around the shape at every time ([`Motion::bounding_sphere`]
    /// of the sphere around its box at `shutter_open`); `None` when it has
    /// no primitives.
    pub fn bounding_sphere(&self) -> Option<(Vec3A, f32)> {
        let (lo, hi) = self.accel.bounds()?;
        let (c, r) = self.motion.bounding_sphere(
            (0.5 * (lo + hi)).as_dvec3(),
            f64::from(0.5 * (hi - lo).length()),
        );
        // Rounded outward to f32.
        Some((c.as_vec3a(), (r * (1.0 + 1e-6)) as f32))
    }

    /// `D(τ)` and `D(τ)⁻¹`.
    #[inline]
    fn relative(&self, tau: f32) -> (Affine3A, Affine3A) {
        let d = self.motion.at(f64::from(tau)) * self.start_inverse;
        (affine_f32(d), affine_f32(d.inverse()))
    }

    /// `ray` in the frame of the shape's `shutter_open` position.
    #[inline]
    fn local(ray: &Ray, inverse: &Affine3A) -> Ray {
        Ray {
            o: inverse.transform_point3a(ray.o),
            d: inverse.transform_vector3a(ray.d),
            tmax: ray.tmax,
        }
    }

    /// Its hit at time `tau` if nearer than `best`, else `best`.
    pub fn intersect(&self, ray: &Ray, tau: f32, best: Option<Hit>) -> Option<Hit> {
        let mut local = Self::local(ray, &self.relative(tau).1);
        if let Some(h) = best {
            local.tmax = h.t;
        }
        match self.accel.intersect(&local) {
            Some(h) => Some(Hit {
                primitive: self.first + h.primitive,
                ..h
            }),
            None => best,
        }
    }

    /// Whether it lies on `ray` at time `tau`.
    pub fn occludes(&self, ray: &Ray, tau: f32) -> bool {
        self.accel
            .occluded(&Self::local(ray, &self.relative(tau).1))
    }

    /// Its shape and surface point at `hit` (one of its own, found at time
    /// `tau`).
    pub fn surface(&self, ray: &Ray, hit: &Hit, tau: f32) -> (u32, SurfacePoint) {
        let own = hit.primitive - self.first;
        let (forward, inverse) = self.relative(tau);
        let local = Self::local(ray, &inverse);
        let primitive = &self.accel.primitives()[own as usize];
        let sp = primitive.point(local.o + local.d * hit.t, hit.bary, self.accel.meshes());
        let normal = |n: Vec3A| (inverse.matrix3.transpose() * n).normalize();
        (
            self.accel.shape_of(own),
            SurfacePoint {
                p: forward.transform_point3a(sp.p),
                ng: normal(sp.ng),
                ns: normal(sp.ns),
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DAffine3, b: DAffine3) -> bool {
        a.abs_diff_eq(b, 1e-12)
    }

    #[test]
    fn ends_are_the_given_maps() {
        let start = DAffine3::from_scale_rotation_translation(
            DVec3::new(1.0, 2.0, 0.5),
            DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
            DVec3::new(1.0, -2.0, 3.0),
        );
        let end = DAffine3::from_cols_array(&[
            0.3, 0.1, -0.2, 0.0, 1.5, 0.4, 0.2, -0.1, 2.0, 5.0, 6.0, 7.0,
        ]);
        let m = Motion::new("to_world_end", start, end).unwrap();
        assert!(close(m.at(0.0), start), "{:?}", m.at(0.0));
        assert!(close(m.at(1.0), end), "{:?}", m.at(1.0));
        // A mirror at both ends.
        let flip = DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0));
        let m = Motion::new("m", flip, flip * start).unwrap();
        assert!(close(m.at(0.0), flip) && close(m.at(1.0), flip * start));
    }

    #[test]
    fn rotation_by_slerp_translation_and_scale_linearly() {
        let start = DAffine3::from_scale(DVec3::splat(1.0));
        let end = DAffine3::from_scale_rotation_translation(
            DVec3::splat(3.0),
            DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2),
            DVec3::new(2.0, 0.0, 0.0),
        );
        let m = Motion::new("m", start, end).unwrap();
        let half = DAffine3::from_scale_rotation_translation(
            DVec3::splat(2.0),
            DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4),
            DVec3::new(1.0, 0.0, 0.0),
        );
        assert!(close(m.at(0.5), half), "{:?}", m.at(0.5));
        // A point on the x axis turns on a circle as it grows (not along
        // the chord, as interpolating the matrices would).
        let p = m.at(0.25).transform_point3(DVec3::X);
        let angle = p.y.atan2(p.x - 0.5);
        assert!((angle - std::f64::consts::PI / 8.0).abs() < 1e-12, "{p}");
    }

    #[test]
    fn singular_and_mirror_to_rotation_refused() {
        let id = DAffine3::IDENTITY;
        let flat = DAffine3::from_scale(DVec3::new(1.0, 0.0, 1.0));
        assert!(Motion::new("to_world_end", id, flat).is_err());
        let huge = DAffine3::from_scale(DVec3::new(1e40, 1.0, 1.0));
        assert!(Motion::new("to_world_end", id, huge).is_err());
        let mirror = DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0));
        let e = Motion::new("to_world_end", id, mirror).unwrap_err();
        assert!(e.to_string().contains("mirrors"), "{e}");
    }

    #[test]
    fn the_bounding_sphere_holds_the_shape_at_every_time() {
        let start = DAffine3::from_scale_rotation_translation(
            DVec3::new(1.0, 2.0, 0.5),
            DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
            DVec3::new(1.0, -2.0, 3.0),
        );
        let end = DAffine3::from_scale_rotation_translation(
            DVec3::new(0.5, 3.0, 1.0),
            DQuat::from_axis_angle(DVec3::new(-1.0, 0.5, 0.2).normalize(), 2.5),
            DVec3::new(-4.0, 1.0, 0.0),
        );
        let m = Motion::new("m", start, end).unwrap();
        let (c0, r0) = (DVec3::new(1.0, -1.5, 3.5), 0.8);
        let (c, r) = m.bounding_sphere(c0, r0);
        let inverse = start.inverse();
        let mut farthest = 0.0f64;
        for i in 0..=64 {
            let tau = f64::from(i) / 64.0;
            let d = m.at(tau) * inverse;
            for j in 0..200 {
                // Points on the sphere at τ = 0 (a spiral over it).
                let z = 1.0 - 2.0 * (f64::from(j) + 0.5) / 200.0;
                let phi = 2.399_963 * f64::from(j);
                let rho = (1.0 - z * z).sqrt();
                let p = c0 + r0 * DVec3::new(rho * phi.cos(), rho * phi.sin(), z);
                farthest = farthest.max((d.transform_point3(p) - c).length());
            }
        }
        assert!(farthest <= r, "{farthest} > {r}");
        // Not wildly loose either.
        assert!(r < 4.0 * farthest, "{r} vs {farthest}");
    }
}

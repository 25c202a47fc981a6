//! Cameras as Mitsuba 3 defines them: `perspective` (a pinhole) and
//! `thinlens` (depth of field), looking down +z in camera space, placed by
//! `to_world` (usually `look_at`: camera +x is `up × dir`, the image's left).

use glam::{Affine3A, Vec2, Vec3A};

use super::shape::Ray;
use crate::error::{Error, Result};
use crate::simd;
use crate::warp;

/// Which image axis `fov` spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    /// Horizontal.
    X,
    /// Vertical.
    Y,
    /// The image diagonal.
    Diagonal,
    /// The shorter side.
    Smaller,
    /// The longer side.
    Larger,
}

impl FovAxis {
    /// The axis named as in Mitsuba.
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "x" => FovAxis::X,
            "y" => FovAxis::Y,
            "diagonal" => FovAxis::Diagonal,
            "smaller" => FovAxis::Smaller,
            "larger" => FovAxis::Larger,
            _ => return None,
        })
    }
}

/// A perspective or thin-lens camera with its film size.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    to_world: Affine3A,
    /// `tan(fov_x / 2)` and `tan(fov_y / 2)`.
    tan_half: Vec2,
    near_clip: f32,
    far_clip: f32,
    aperture_radius: f32,
    focus_distance: f32,
}

impl Camera {
    /// A camera with field of view `fov_degrees` along `axis`, for a film of
    /// `width × height` pixels. `aperture_radius = 0` is a pinhole.
    ///
    /// # Errors
    /// [`Error::Parameter`] for a field of view outside `(0, 180)` degrees,
    /// clip distances that are not `0 < near < far`, or a negative aperture
    /// or focus distance (the latter must be > 0 for a thin lens).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        to_world: Affine3A,
        fov_degrees: f64,
        axis: FovAxis,
        width: usize,
        height: usize,
        near_clip: f64,
        far_clip: f64,
        aperture_radius: f64,
        focus_distance: f64,
    ) -> Result<Self> {
        let bad = |arg, value, requirement| {
            Err(Error::Parameter {
                arg,
                value,
                requirement,
            })
        };
        if !(fov_degrees > 0.0 && fov_degrees < 180.0) {
            return bad("fov", fov_degrees, "must lie in (0, 180) degrees");
        }
        if !(near_clip > 0.0 && near_clip < far_clip && far_clip.is_finite()) {
            return bad(
                "near_clip",
                near_clip,
                "must satisfy 0 < near_clip < far_clip < inf",
            );
        }
        if !(aperture_radius >= 0.0 && aperture_radius.is_finite()) {
            return bad(
                "aperture_radius",
                aperture_radius,
                "must be finite and >= 0",
            );
        }
        if aperture_radius > 0.0 && !(focus_distance > 0.0 && focus_distance.is_finite()) {
            return bad("focus_distance", focus_distance, "must be finite and > 0");
        }
        let (w, h) = (width as f64, height as f64);
        let t = (fov_degrees.to_radians() / 2.0).tan();
        // tan of the half angle along x, from the one along `axis`.
        let tx = match axis {
            FovAxis::X => t,
            FovAxis::Y => t * w / h,
            FovAxis::Diagonal => t * w / (w * w + h * h).sqrt(),
            FovAxis::Smaller if w <= h => t,
            FovAxis::Smaller => t * w / h,
            FovAxis::Larger if w >= h => t,
            FovAxis::Larger => t * w / h,
        };
        Ok(Camera {
            to_world,
            tan_half: Vec2::new(tx as f32, (tx * h / w) as f32),
            near_clip: near_clip as f32,
            far_clip: far_clip as f32,
            aperture_radius: aperture_radius as f32,
            focus_distance: focus_distance as f32,
        })
    }

    /// The ray through the film position `film ∈ [0, 1]²` (x right, y down),
    /// through the lens point `lens ∈ [0, 1]²` (concentric disk) for a thin
    /// lens. In camera space the pinhole ray's direction is
    /// `v = ((1 − 2x) tan(fov_x/2), (1 − 2y) tan(fov_y/2), 1)`; the thin lens
    /// aims from the aperture point `a` at `v·focus_distance`. The ray starts
    /// where it crosses the near clip plane and ends at the far one, as in
    /// Mitsuba. Branch-free (both the pinhole and the lens are computed),
    /// so that [`Camera::rays_into`] vectorises.
    #[inline(always)]
    pub fn ray(&self, film: [f32; 2], lens: [f32; 2]) -> Ray {
        let v = Vec3A::new(
            (1.0 - 2.0 * film[0]) * self.tan_half.x,
            (1.0 - 2.0 * film[1]) * self.tan_half.y,
            1.0,
        );
        let [x, y] = warp::square_to_uniform_disk_concentric(lens);
        let aperture = Vec3A::new(x, y, 0.0) * self.aperture_radius;
        let thin = self.aperture_radius > 0.0;
        let (o, d) = if thin {
            (aperture, v * self.focus_distance - aperture)
        } else {
            (Vec3A::ZERO, v)
        };
        // Mitsuba clips along the final direction: the ray starts where it
        // crosses the near plane `z = near_clip` (in camera space), which is
        // `near/d.z` along `d` (`d.z > 0`), or `|d|·near/d.z` along `d/|d|`.
        let inv_z = 1.0 / d.z;
        let o = o + d * (self.near_clip * inv_z);
        Ray {
            o: self.to_world.transform_point3a(o),
            d: self.to_world.transform_vector3a(d).normalize(),
            tmax: (self.far_clip - self.near_clip) * d.length() * inv_z,
        }
    }

    /// `out[i]` the ray of `u[i] = (film x, film y, lens x, lens y)` (see
    /// [`Camera::ray`]) for a batch, at full SIMD width.
    pub fn rays_into(&self, u: &[[f32; 4]], out: &mut [Ray]) {
        let mut rows = [[0.0f32; 7]; BLOCK];
        let kernel = {
            #[inline(always)]
            |u: [f32; 4]| {
                let r = self.ray([u[0], u[1]], [u[2], u[3]]);
                [r.o.x, r.o.y, r.o.z, r.d.x, r.d.y, r.d.z, r.tmax]
            }
        };
        for (u, out) in u.chunks(BLOCK).zip(out.chunks_mut(BLOCK)) {
            let rows = &mut rows[..u.len()];
            simd::map_rows(rows, u, &kernel, |_| true, false);
            for (o, r) in out.iter_mut().zip(rows.iter()) {
                *o = Ray {
                    o: Vec3A::new(r[0], r[1], r[2]),
                    d: Vec3A::new(r[3], r[4], r[5]),
                    tmax: r[6],
                };
            }
        }
    }
}

/// Rays per block of [`Camera::rays_into`].
const BLOCK: usize = 256;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_down_z_and_corners_follow_mitsuba() {
        let cam = Camera::new(
            Affine3A::IDENTITY,
            90.0,
            FovAxis::X,
            200,
            100,
            1e-3,
            1e4,
            0.0,
            0.0,
        )
        .unwrap();
        let r = cam.ray([0.5, 0.5], [0.5, 0.5]);
        assert!((r.d - Vec3A::Z).length() < 1e-6);
        // The left edge of the image is camera +x, the top is +y.
        let r = cam.ray([0.0, 0.0], [0.5, 0.5]);
        let expected = Vec3A::new(1.0, 0.5, 1.0).normalize();
        assert!((r.d - expected).length() < 1e-6);
    }

    #[test]
    fn thin_lens_rays_meet_at_the_focus_distance() {
        let cam = Camera::new(
            Affine3A::IDENTITY,
            40.0,
            FovAxis::Y,
            64,
            64,
            1e-3,
            1e4,
            0.5,
            3.0,
        )
        .unwrap();
        for lens in [[0.1, 0.2], [0.9, 0.5], [0.5, 0.95]] {
            let r = cam.ray([0.3, 0.6], lens);
            let t = (3.0 - r.o.z) / r.d.z;
            let p = r.o + t * r.d;
            let pin = cam.ray([0.3, 0.6], [0.5, 0.5]);
            let q = pin.o + (3.0 - pin.o.z) / pin.d.z * pin.d;
            assert!((p - q).length() < 1e-4, "{p} {q}");
        }
    }
}

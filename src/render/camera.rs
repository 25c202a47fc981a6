//! Cameras as Mitsuba 3 defines them: `perspective` (a pinhole) and
//! `thinlens` (depth of field), looking down +z in camera space, placed by
//! `to_world` (usually `look_at`: camera +x is `up × dir`, the image's left).

use glam::{Affine3A, DAffine3, Vec2, Vec3A};

use super::geometry::affine_f32;
use super::motion::Motion;
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
    /// `to_world`'s columns (x, y, z axes and translation), as plain
    /// arrays: the ray kernel then runs one ray per SIMD lane.
    to_world: [[f32; 3]; 4],
    /// `tan(fov_x / 2)` and `tan(fov_y / 2)`.
    tan_half: Vec2,
    near_clip: f32,
    far_clip: f32,
    aperture_radius: f32,
    focus_distance: f32,
    /// How `to_world` changes during the shutter, for a moving camera.
    motion: Option<Motion>,
    /// The inverse of `to_world` (at `shutter_open`).
    to_local: Affine3A,
}

/// A connection from a point `x` to the camera, as Mitsuba's
/// `Sensor::sample_direction` makes it: the lens point (the pinhole, or a
/// point drawn uniformly on the aperture), where the ray from it through
/// `x` lands on the film, and the camera's importance.
#[derive(Clone, Copy, Debug)]
pub struct SensorSample {
    /// The film position in `[0, 1]²` (x right, y down).
    pub film: [f32; 2],
    /// Unit direction from `x` toward the lens point.
    pub d: Vec3A,
    /// Distance from `x` to the lens point.
    pub dist: f32,
    /// Density per steradian at `x` of the lens point: 1 for the pinhole
    /// (a delta, Mitsuba's convention), `dist² / (π R² cos θ)` for a lens
    /// of radius `R`, `θ` the angle of the ray to the optical axis.
    pub pdf: f32,
    /// The importance the connection carries, `1 / (A cos³θ dist²)` with
    /// `A = 4 tan(fov_x/2) tan(fov_y/2)` the image's area at distance 1 (the
    /// importance per unit solid angle, times the film's cosine, over the
    /// lens point's density by area).
    pub weight: f32,
    /// The lens point, in world space.
    pub lens: Vec3A,
}

/// The columns of an affine map as plain arrays.
fn columns(m: Affine3A) -> [[f32; 3]; 4] {
    let m = m.to_cols_array();
    std::array::from_fn(|c| std::array::from_fn(|r| m[3 * c + r]))
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
            to_local: to_world.inverse(),
            to_world: columns(to_world),
            tan_half: Vec2::new(tx as f32, (tx * h / w) as f32),
            near_clip: near_clip as f32,
            far_clip: far_clip as f32,
            aperture_radius: aperture_radius as f32,
            focus_distance: focus_distance as f32,
            motion: None,
        })
    }

    /// The camera moving from its `to_world` at `shutter_open` to `end` at
    /// `shutter_close` ([`Motion`]).
    ///
    /// # Errors
    /// As [`Motion::new`], naming `to_world_end`.
    pub fn with_motion(self, end: DAffine3) -> Result<Self> {
        let start = DAffine3::from_cols_array(&std::array::from_fn(|i| {
            f64::from(self.to_world[i / 3][i % 3])
        }));
        let motion = Motion::new("to_world_end", start, end)?;
        Ok(Camera {
            motion: Some(motion),
            ..self
        })
    }

    /// Whether the camera moves during the shutter.
    pub fn moves(&self) -> bool {
        self.motion.is_some()
    }

    /// The film position in `[0, 1]²` of camera-space point `p` seen from
    /// the pinhole: `v = p / p_z`, `x = (1 − v_x / tan(fov_x/2)) / 2`, and
    /// likewise `y`; `None` outside the film.
    fn film_of(&self, p: Vec3A) -> Option<[f32; 2]> {
        let (vx, vy) = (p.x / p.z, p.y / p.z);
        let film = [
            0.5 * (1.0 - vx / self.tan_half.x),
            0.5 * (1.0 - vy / self.tan_half.y),
        ];
        (p.z > 0.0 && film.iter().all(|f| (0.0..=1.0).contains(f))).then_some(film)
    }

    /// The camera's `to_world` and its inverse at time `tau` of the shutter.
    fn placed(&self, tau: f32) -> (Affine3A, Affine3A) {
        match &self.motion {
            Some(motion) => {
                let m = affine_f32(motion.at(f64::from(tau)));
                (m, m.inverse())
            }
            None => {
                let [x, y, z, w] = self.to_world.map(Vec3A::from);
                (Affine3A::from_cols(x, y, z, w), self.to_local)
            }
        }
    }

    /// A point on the aperture in camera space: the pinhole, or `u` on the
    /// lens disk (concentric mapping).
    fn lens_point(&self, u: [f32; 2]) -> Vec3A {
        if self.has_lens() {
            let [a, b] = warp::square_to_uniform_disk_concentric(u);
            Vec3A::new(a * self.aperture_radius, b * self.aperture_radius, 0.0)
        } else {
            Vec3A::ZERO
        }
    }

    /// Where the camera-space ray from lens point `lens` along the unit
    /// direction `local` lands on the film: through a thin lens, where its
    /// point on the focal plane is seen from the pinhole.
    fn film_through(&self, lens: Vec3A, local: Vec3A) -> Option<[f32; 2]> {
        if local.z <= 0.0 {
            return None;
        }
        if self.has_lens() {
            if !(self.near_clip..=self.far_clip).contains(&self.focus_distance) {
                return None;
            }
            self.film_of(lens + local * (self.focus_distance / local.z))
        } else {
            self.film_of(local)
        }
    }

    /// The world position at time `tau` of the lens point that `u` places
    /// (the pinhole, or a point of the thin lens's aperture).
    pub fn lens_point_at(&self, u: [f32; 2], tau: f32) -> Vec3A {
        self.placed(tau).0.transform_point3a(self.lens_point(u))
    }

    /// The density per steradian with which the camera at time `tau`,
    /// from its lens point `lens` (world), sends rays along the unit world
    /// direction `d`: `1 / (A cos³θ)` when the ray lands on the film, else
    /// 0 (Mitsuba's and pbrt's `pdf` of a perspective camera's direction,
    /// the film position drawn uniformly).
    pub fn pdf_direction(&self, lens: Vec3A, d: Vec3A, tau: f32) -> f32 {
        let to_local = self.placed(tau).1;
        let local = to_local.transform_vector3a(d).normalize();
        match self.film_through(to_local.transform_point3a(lens), local) {
            Some(_) => {
                let cos = local.z;
                1.0 / (4.0 * self.tan_half.x * self.tan_half.y * cos * cos * cos)
            }
            None => 0.0,
        }
    }

    /// The connection from world point `x` to the camera where it stands at
    /// time `tau` of the shutter (in `[0, 1]`), with `u` placing the point
    /// on a thin lens's aperture (concentric disk); `None` when `x` lies
    /// outside the clip range or the ray through it misses the film
    /// (Mitsuba's `sample_direction` of `perspective` and `thinlens`).
    pub fn sample_direction(&self, x: Vec3A, u: [f32; 2], tau: f32) -> Option<SensorSample> {
        let (to_world, to_local) = self.placed(tau);
        let p = to_local.transform_point3a(x);
        if !(p.z >= self.near_clip && p.z <= self.far_clip) {
            return None;
        }
        let lens = self.lens_point(u);
        let to_x = p - lens;
        let dist = to_x.length();
        let local = to_x / dist;
        let cos = local.z;
        let film = self.film_through(lens, local)?;
        let area = 4.0 * self.tan_half.x * self.tan_half.y;
        let world_lens = to_world.transform_point3a(lens);
        let pdf = if self.has_lens() {
            dist * dist / (std::f32::consts::PI * self.aperture_radius.powi(2) * cos)
        } else {
            1.0
        };
        Some(SensorSample {
            film,
            d: (world_lens - x) / dist,
            dist,
            pdf,
            weight: 1.0 / (area * cos * cos * cos * dist * dist),
            lens: world_lens,
        })
    }

    /// Whether rays start across a lens (a thin lens) rather than at a
    /// pinhole, which ignores the lens sample.
    pub fn has_lens(&self) -> bool {
        self.aperture_radius > 0.0
    }

    /// The ray through the film position `film ∈ [0, 1]²` (x right, y down),
    /// through the lens point `lens ∈ [0, 1]²` (concentric disk) for a thin
    /// lens. In camera space the pinhole ray's direction is
    /// `v = ((1 − 2x) tan(fov_x/2), (1 − 2y) tan(fov_y/2), 1)`; the thin lens
    /// aims from the aperture point `a` at `v·focus_distance`. The ray starts
    /// where it crosses the near clip plane and ends at the far one, as in
    /// Mitsuba. A moving camera is placed where it is at time `tau` of the
    /// shutter.
    #[inline]
    pub fn ray(&self, film: [f32; 2], lens: [f32; 2], tau: f32) -> Ray {
        let m = match &self.motion {
            Some(motion) => columns(affine_f32(motion.at(f64::from(tau)))),
            None => self.to_world,
        };
        let u = [film[0], film[1], lens[0], lens[1]];
        ray_from_row(self.ray_row(u, self.has_lens(), &m))
    }

    /// [`Camera::ray`] of `u = (film x, film y, lens x, lens y)` as the row
    /// `[o, d, tmax]`, for a pinhole or (`thin`) a thin lens placed by the
    /// columns `m` of its `to_world`: plain `f32` arithmetic without
    /// branches, so that a loop over rays runs one per SIMD lane.
    #[inline(always)]
    fn ray_row(&self, u: [f32; 4], thin: bool, m: &[[f32; 3]; 4]) -> [f32; 7] {
        let v = [
            (1.0 - 2.0 * u[0]) * self.tan_half.x,
            (1.0 - 2.0 * u[1]) * self.tan_half.y,
            1.0,
        ];
        let (o, d) = if thin {
            let [x, y] = warp::square_to_uniform_disk_concentric([u[2], u[3]]);
            let a = [x * self.aperture_radius, y * self.aperture_radius, 0.0];
            (
                a,
                std::array::from_fn(|k| v[k] * self.focus_distance - a[k]),
            )
        } else {
            ([0.0; 3], v)
        };
        // Mitsuba clips along the final direction: the ray starts where it
        // crosses the near plane `z = near_clip` (in camera space), which is
        // `near/d.z` along `d` (`d.z > 0`), or `|d|·near/d.z` along `d/|d|`.
        let inv_z = 1.0 / d[2];
        let o: [f32; 3] = std::array::from_fn(|k| o[k] + d[k] * (self.near_clip * inv_z));
        let wo: [f32; 3] =
            std::array::from_fn(|k| m[0][k] * o[0] + m[1][k] * o[1] + m[2][k] * o[2] + m[3][k]);
        let wd: [f32; 3] =
            std::array::from_fn(|k| m[0][k] * d[0] + m[1][k] * d[1] + m[2][k] * d[2]);
        let inv_len = 1.0 / (wd[0] * wd[0] + wd[1] * wd[1] + wd[2] * wd[2]).sqrt();
        let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        [
            wo[0],
            wo[1],
            wo[2],
            wd[0] * inv_len,
            wd[1] * inv_len,
            wd[2] * inv_len,
            (self.far_clip - self.near_clip) * length * inv_z,
        ]
    }

    /// `out[i]` the ray of `u[i] = (film x, film y, lens x, lens y)` (see
    /// [`Camera::ray`]) for a batch, at full SIMD width; a moving camera
    /// placed where it is at `times[i]` (of the shutter, in `[0, 1]`), one
    /// ray after the other.
    pub fn rays_into(&self, u: &[[f32; 4]], times: &[f32], out: &mut [Ray]) {
        let thin_lens = self.aperture_radius > 0.0;
        if let Some(motion) = &self.motion {
            for ((u, &tau), out) in u.iter().zip(times).zip(out.iter_mut()) {
                let m = columns(affine_f32(motion.at(f64::from(tau))));
                *out = ray_from_row(self.ray_row(*u, thin_lens, &m));
            }
            return;
        }
        let simd::OnLines(rows) = &mut simd::OnLines([[0.0f32; 7]; BLOCK]);
        let pinhole = {
            #[inline(always)]
            |u: [f32; 4]| self.ray_row(u, false, &self.to_world)
        };
        let thin = {
            #[inline(always)]
            |u: [f32; 4]| self.ray_row(u, true, &self.to_world)
        };
        for (u, out) in u.chunks(BLOCK).zip(out.chunks_mut(BLOCK)) {
            let rows = &mut rows[..u.len()];
            if thin_lens {
                simd::map_rows(rows, u, &thin, |_| true, false);
            } else {
                simd::map_rows(rows, u, &pinhole, |_| true, false);
            }
            for (o, r) in out.iter_mut().zip(rows.iter()) {
                *o = ray_from_row(*r);
            }
        }
    }
}

/// The ray of a row `[o, d, tmax]`.
#[inline(always)]
fn ray_from_row(r: [f32; 7]) -> Ray {
    Ray {
        o: Vec3A::new(r[0], r[1], r[2]),
        d: Vec3A::new(r[3], r[4], r[5]),
        tmax: r[6],
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
        let r = cam.ray([0.5, 0.5], [0.5, 0.5], 0.0);
        assert!((r.d - Vec3A::Z).length() < 1e-6);
        // The left edge of the image is camera +x, the top is +y.
        let r = cam.ray([0.0, 0.0], [0.5, 0.5], 0.0);
        let expected = Vec3A::new(1.0, 0.5, 1.0).normalize();
        assert!((r.d - expected).length() < 1e-6);
        // It starts on the near plane and ends on the far one: z from 1e-3
        // to 1e4 along (1, 0.5, 1), of length 1.5 per unit of z.
        assert!((r.o.z - 1e-3).abs() < 1e-9, "{}", r.o);
        let tmax = (1e4 - 1e-3) * 1.5;
        assert!((r.tmax - tmax).abs() < 1e-6 * tmax, "{}", r.tmax);
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
            let r = cam.ray([0.3, 0.6], lens, 0.0);
            let t = (3.0 - r.o.z) / r.d.z;
            let p = r.o + t * r.d;
            let pin = cam.ray([0.3, 0.6], [0.5, 0.5], 0.0);
            let q = pin.o + (3.0 - pin.o.z) / pin.d.z * pin.d;
            assert!((p - q).length() < 1e-4, "{p} {q}");
        }
    }
}

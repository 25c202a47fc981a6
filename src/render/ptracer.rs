//! Light tracing, as Mitsuba's `ptracer`: paths start on the lights and
//! each of their vertices is connected to the camera, splatting what it
//! sends there onto the film ([`splat`](super::splat)).
//!
//! Each sample index traces one path per pixel of the film (`N = n·P`
//! paths for `n` samples per pixel, `P` pixels), and each path first
//! connects a point of a light straight to the camera (the lights seen
//! directly, unless `hide_emitters`):
//!
//! ```text
//! area light:   c = Le cos θ_y / p_A(y) · W     (y drawn by area, p_A incl. the light's choice)
//! environment:  c = L(ω) / P_env                (ω along a camera ray through a uniform film point)
//! ```
//!
//! with `W` the camera's weight of [`Camera::sample_direction`](super::camera::Camera::sample_direction)
//! (importance over the lens point's density, `1/(A cos³θ dist²)` for a
//! pinhole) and `P_env` the probability of choosing the environment. The
//! environment is seen through the camera's own sampling rather than
//! its directions' (as Mitsuba's `ptracer` does): a direction drawn by the
//! environment lands in a given pixel about once in `1/(p(ω) dω_pixel)`
//! draws, far fewer than once per sample. Then
//! the light path: a ray from a point `y` of an area light in a
//! cosine-weighted direction (`β₀ = Le π / p_A(y)`), or from the
//! environment along `−ω` through a point drawn uniformly on the disk of
//! radius `R` facing `ω` at the scene's bounding sphere (`β₀ = L(ω) π R² /
//! p(ω)`); at each vertex `x` (while the path has fewer than `max_depth`
//! segments with the camera's) the connection
//!
//! ```text
//! c = β · f(ω_l, ω_c) |cos_s ω_c| · K · W,   K = |cos_s ω_l · (ω_c·n_g)| / |cos_s ω_c · (ω_l·n_g)|
//! ```
//!
//! (`ω_l` toward the light, `ω_c` toward the lens point; `K` is Veach's
//! correction of shading normals for the adjoint BSDF, 1 where shading and
//! geometric normals agree; directions on different sides of the two
//! normals carry nothing, against light leaks), then a BSDF sample `ω`,
//! `β ← β · f cos_s / p · K`, and Russian roulette past `rr_depth`
//! (survival `min(max β, 0.95)`). Occluded connections carry nothing; a
//! shadow ray runs from `x` to the lens point, so geometry nearer than the
//! near clip plane blocks it (as in Mitsuba; camera rays start at that
//! plane). With `hide_emitters`, only the lights seen directly are left
//! out (light reflected toward the camera by an area light's surface still
//! counts, as in Mitsuba).

use glam::Vec3A;

use super::Settings;
use super::camera::SensorSample;
use super::integrator::{offset, unoccluded};
use super::scene::{Emission, Scene};
use super::shape::{Ray, SurfacePoint};
use super::splat::Splat;
use super::splatting::Paths;
use crate::frame::Frame;
use crate::sampler::Stream;
use crate::warp;

/// The dimensions of a light path's sample, in this order: the time, the
/// light seen directly, the light path's start, then
/// [`dims::PER_VERTEX`] for each of its vertices ([`dims::vertex`]).
pub mod dims {
    /// The time within the shutter (drawn only when something moves).
    pub const TIME: u32 = 0;
    /// Which light is connected straight to the camera.
    pub const DIRECT_CHOICE: u32 = 1;
    /// Its point or direction (2D).
    pub const DIRECT_POSITION: u32 = 2;
    /// The lens point of that connection (2D).
    pub const DIRECT_LENS: u32 = 4;
    /// Which light the path starts on.
    pub const EMITTER_CHOICE: u32 = 6;
    /// The point on it, or the environment's direction (2D).
    pub const EMITTER_POSITION: u32 = 7;
    /// The direction of the first ray, or its point on the environment's
    /// disk (2D).
    pub const EMITTER_DIRECTION: u32 = 9;
    /// Dimensions before the first vertex.
    pub const START: u32 = 11;
    /// The lens point of a vertex's connection to the camera (2D).
    pub const LENS: u32 = 0;
    /// The BSDF sample (3D).
    pub const BSDF: u32 = 2;
    /// Russian roulette.
    pub const ROULETTE: u32 = 5;
    /// Dimensions of each vertex.
    pub const PER_VERTEX: u32 = 6;

    /// Dimension `offset` of vertex `k` (0: where the light's ray lands).
    #[inline]
    pub fn vertex(k: u32, offset: u32) -> u32 {
        START
            .saturating_add(PER_VERTEX.saturating_mul(k))
            .saturating_add(offset)
    }
}

/// Light tracing as a [`Paths`] integrator: the path of "pixel" `j` is
/// just the `j`-th light path of its sample index.
pub struct LightPaths<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The settings (`max_depth`, `rr_depth`, `hide_emitters`).
    pub settings: &'a Settings,
}

impl Paths for LightPaths<'_> {
    type Scratch = ();
    const PER_PATH: bool = true;

    fn scratch(&self) {}

    fn trace(&self, (): &mut (), stream: &mut Stream, _pixel: usize, out: &mut Vec<Splat>) {
        light_path(self.scene, self.settings, stream, out);
    }
}

/// One light path's splats, from `stream` at its current sample.
fn light_path(scene: &Scene, settings: &Settings, stream: &mut Stream, out: &mut Vec<Splat>) {
    let max_depth = settings.max_depth();
    if max_depth == 0 {
        return;
    }
    let tau = if scene.moves() {
        stream.get1(dims::TIME)
    } else {
        0.0
    };
    if !settings.hide_emitters {
        let u = [
            stream.get1(dims::DIRECT_CHOICE),
            stream.get1(dims::DIRECT_POSITION),
            stream.get1(dims::DIRECT_POSITION + 1),
        ];
        let lens = stream.get2(dims::DIRECT_LENS);
        if let Some(s) = seen_directly(scene, u, lens, tau) {
            out.push(s);
        }
    }
    let start = (
        dims::EMITTER_CHOICE,
        dims::EMITTER_POSITION,
        dims::EMITTER_DIRECTION,
    );
    let Some((_, mut ray, mut beta)) = start_light_path(scene, stream, start) else {
        return;
    };
    // Segments of the camera's path through the next vertex: the light's
    // ray, then the connection.
    let mut depth = 1u32;
    let mut k = 0u32;
    while depth < max_depth {
        let Some(hit) = scene.intersect(&ray, tau) else {
            break;
        };
        let (shape, sp) = scene.surface(&ray, &hit, tau);
        let to_light = -ray.d;
        let material = scene.material(shape);
        let ns = if material.two_sided && sp.ns.dot(to_light) < 0.0 {
            -sp.ns
        } else {
            sp.ns
        };
        let frame = Frame::from_normal(ns.to_array());
        let view = material.bsdf.view(frame.to_local(to_light.to_array()));
        let lens = stream.get2(dims::vertex(k, dims::LENS));
        if let Some(camera) = scene.camera().sample_direction(sp.p, lens, tau)
            && let Some(fix) = adjoint(&sp, to_light, camera.d)
            && visible(scene, sp.p, sp.ng, &camera, tau)
        {
            let wo = frame.to_local(camera.d.to_array());
            let (f, _) = view.eval_pdf_one(wo);
            let s = wo[2].abs() * fix * camera.weight;
            let value: [f32; 3] = std::array::from_fn(|c| beta[c] * f[c] * s);
            if value.iter().any(|&v| v != 0.0) {
                out.push(Splat {
                    film: camera.film,
                    value,
                    channel: 0,
                });
            }
        }
        let u = [
            stream.get1(dims::vertex(k, dims::BSDF)),
            stream.get1(dims::vertex(k, dims::BSDF + 1)),
            stream.get1(dims::vertex(k, dims::BSDF + 2)),
        ];
        let sample = view.sample_one(u);
        if sample.weight.iter().all(|&v| v <= 0.0) {
            break;
        }
        let d = Vec3A::from(frame.to_world(sample.wo)).normalize();
        let Some(fix) = adjoint(&sp, to_light, d) else {
            break;
        };
        beta = std::array::from_fn(|c| beta[c] * sample.weight[c] * fix);
        depth += 1;
        if depth > settings.rr_depth {
            let q = beta.iter().copied().fold(0.0f32, f32::max).min(0.95);
            if stream.get1::<f32>(dims::vertex(k, dims::ROULETTE)) >= q {
                break;
            }
            beta = beta.map(|b| b / q);
        }
        ray = Ray {
            o: offset(sp.p, sp.ng, d),
            d,
            tmax: f32::INFINITY,
        };
        k += 1;
    }
}

/// The start of a light path from `stream`: the light, and its point or
/// direction ([`Scene::sample_emission`]), drawn from dimensions `choice`
/// (1) and `position` (2), and the first ray with its weight
/// ([`emitted_ray`]) from dimensions `direction` (2).
pub(super) fn start_light_path(
    scene: &Scene,
    stream: &mut Stream,
    (choice, position, direction): (u32, u32, u32),
) -> Option<(Emission, Ray, [f32; 3])> {
    let u = [
        stream.get1(choice),
        stream.get1(position),
        stream.get1(position + 1),
    ];
    let emission = scene.sample_emission(u)?;
    let (ray, beta) = emitted_ray(scene, emission, stream.get2(direction));
    Some((emission, ray, beta))
}

/// The first ray of a light path and its weight `β₀` (see the module's
/// text), `u` drawing its direction (area light) or its point on the disk
/// (environment).
fn emitted_ray(scene: &Scene, emission: Emission, u: [f32; 2]) -> (Ray, [f32; 3]) {
    match emission {
        Emission::Surface {
            point,
            pdf,
            radiance,
            ..
        } => {
            let frame = Frame::from_normal(point.ng.to_array());
            let local = warp::square_to_cosine_hemisphere(u);
            let d = Vec3A::from(frame.to_world(local)).normalize();
            let s = std::f32::consts::PI / pdf;
            (
                Ray {
                    o: offset(point.p, point.ng, d),
                    d,
                    tmax: f32::INFINITY,
                },
                radiance.map(|l| l * s),
            )
        }
        Emission::Environment {
            d, pdf, radiance, ..
        } => {
            let (center, radius) = scene.bounding_sphere();
            let frame = Frame::from_normal(d.to_array());
            let [a, b] = warp::square_to_uniform_disk_concentric(u);
            let o = center + Vec3A::from(frame.to_world([a * radius, b * radius, radius]));
            let s = std::f32::consts::PI * radius * radius / pdf;
            (
                Ray {
                    o,
                    d: -d,
                    tmax: f32::INFINITY,
                },
                radiance.map(|l| l * s),
            )
        }
    }
}

/// A light seen directly, chosen with `u[0]`: a point of an area light
/// drawn with `u[1..3]`, connected to the camera through the lens point
/// `lens`; or the environment, seen along the camera ray of film position
/// `u[1..3]` and `lens`. `None` when the connection misses the film, faces
/// the light's back, or is blocked.
fn seen_directly(scene: &Scene, u: [f32; 3], lens: [f32; 2], tau: f32) -> Option<Splat> {
    let camera = scene.camera();
    match scene.sample_emission(u)? {
        Emission::Surface {
            point,
            pdf,
            radiance,
            ..
        } => {
            let c = camera.sample_direction(point.p, lens, tau)?;
            let cos = point.ng.dot(c.d);
            let s = cos / pdf * c.weight;
            (cos > 0.0 && visible(scene, point.p, point.ng, &c, tau)).then(|| Splat {
                film: c.film,
                value: radiance.map(|l| l * s),
                channel: 0,
            })
        }
        Emission::Environment { choice, .. } => {
            let film = [u[1], u[2]];
            let ray = camera.ray(film, lens, tau);
            let radiance = scene.environment()?.eval(ray.d);
            (!scene.occluded(&ray, tau)).then(|| Splat {
                film,
                value: radiance.map(|l| l / choice),
                channel: 0,
            })
        }
    }
}

/// Whether the lens point of `camera` is seen from surface point `p`
/// (geometric normal `ng`).
fn visible(scene: &Scene, p: Vec3A, ng: Vec3A, camera: &SensorSample, tau: f32) -> bool {
    unoccluded(scene, offset(p, ng, camera.d), camera.lens, tau)
}

/// Veach's correction `K` (see the module's text) at `sp` for light from
/// `to_light` leaving toward `out` ([`shading_correction`]).
#[inline]
fn adjoint(sp: &SurfacePoint, to_light: Vec3A, out: Vec3A) -> Option<f32> {
    shading_correction(sp.ns, sp.ng, to_light, out)
}

/// Veach's correction of the adjoint BSDF for shading normals at a point
/// with shading normal `ns` and geometric normal `ng`, for light arriving
/// from `from` and leaving toward `to` (unit vectors away from the point):
/// `|(ns·from)(ng·to)| / |(ns·to)(ng·from)|`; `None` when either direction
/// lies on different sides of the two normals (light leaks).
#[inline]
pub(super) fn shading_correction(ns: Vec3A, ng: Vec3A, from: Vec3A, to: Vec3A) -> Option<f32> {
    let (si, so) = (ns.dot(from), ns.dot(to));
    let (gi, go) = (ng.dot(from), ng.dot(to));
    (si * gi > 0.0 && so * go > 0.0).then(|| ((si * go) / (so * gi)).abs())
}

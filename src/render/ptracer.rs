//! Light tracing, as Mitsuba's `ptracer`: paths start on the lights and
//! each of their vertices is connected to the camera, splatting what it
//! sends there onto the film ([`splat`](super::splat)).
//!
//! Each sample index traces one path per pixel of the film (`N = n·P`
//! paths for `n` samples per pixel, `P` pixels): the light subpath of
//! bidirectional path tracing ([`bdpt`](super::bdpt)), each vertex joined
//! to the camera as its `t = 1` strategy (unweighted); and first, a point
//! of a light straight to the camera (the lights seen directly, unless
//! `hide_emitters`):
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

use super::Settings;
use super::bdpt::{Ctx, dims, light_subpath, to_camera};
use super::integrator::{offset, unoccluded};
use super::scene::{Emission, Scene};
use super::splat::Splat;
use super::splatting::Paths;
use crate::sampler::Stream;

/// Light tracing as a [`Paths`] integrator: the path of "pixel" `j` is
/// just the `j`-th light path of its sample index.
pub struct LightPaths<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The settings (`max_depth`, `rr_depth`, `hide_emitters`).
    pub settings: &'a Settings,
}

impl Paths for LightPaths<'_> {
    type Scratch = Vec<super::bdpt::Vertex>;
    const PER_PATH: bool = true;

    fn scratch(&self) -> Self::Scratch {
        Vec::new()
    }

    fn trace(
        &self,
        light: &mut Self::Scratch,
        stream: &mut Stream,
        _: usize,
        out: &mut Vec<Splat>,
    ) {
        let (scene, settings) = (self.scene, self.settings);
        if settings.max_depth() == 0 {
            return;
        }
        let tau = if scene.moves() {
            stream.get1(dims::TIME)
        } else {
            0.0
        };
        if !settings.hide_emitters {
            let u = stream.get1_then2(dims::DIRECT_CHOICE, dims::DIRECT_POSITION);
            let lens = stream.get2(dims::DIRECT_LENS);
            out.extend(seen_directly(scene, u, lens, tau));
        }
        let ctx = Ctx {
            scene,
            settings,
            tau,
        };
        light_subpath(&ctx, stream, light);
        for s in 2..=light.len() {
            if let Some((value, film, _)) = to_camera(&ctx, light, s, stream) {
                out.push(Splat {
                    film,
                    value,
                    channel: 0,
                });
            }
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
            let visible = unoccluded(scene, offset(point.p, point.ng, c.d), c.lens, tau);
            (cos > 0.0 && visible).then(|| Splat {
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

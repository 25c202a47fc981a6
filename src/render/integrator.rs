//! The integrators: direct illumination and unidirectional path tracing,
//! each by BSDF sampling, emitter sampling or MIS of the two.
//!
//! One loop serves both (direct lighting is a path of at most two segments):
//!
//! ```text
//! L = Σ_k β_k · w_k · Le_k,   β_{k+1} = β_k · f_r cos θ / p_bsdf   (÷ q past rr_depth)
//! ```
//!
//! Emission found by a BSDF-sampled ray is weighted by `w = h(p_bsdf, p_light)`
//! under MIS, 1 under BSDF sampling and 0 under emitter sampling (which
//! counts it through next-event estimation instead); next-event estimation
//! adds `β f_r cos θ Le / p_light · h(p_light, p_bsdf)`, with `h = 1` under
//! emitter sampling. Emission seen straight from the camera counts unless
//! `hide_emitters`.
//! Path lengths follow Mitsuba's `max_depth`: 1 is emission only, 2 direct
//! illumination, −1 unbounded. The loop runs over a batch of paths at once,
//! one bounce at a time ([`super::wavefront`]).
//!
//! Every random decision of a sample has its own dimension of the pixel's
//! [`Stream`](crate::sampler::Stream) ([`dims`]): a stratified or low-discrepancy sampler then
//! stratifies each decision across the pixel's samples.

use glam::Vec3A;

use super::accel::Hit;
use super::scene::{EnvDensity, Scene};
use super::shape::{Ray, SurfacePoint};
use crate::alloc;
use crate::frame::Frame;
use crate::phong::PhongView;
use crate::sampler::Sampler;

/// The dimensions of a sample, in this order: the camera's, then
/// [`dims::PER_BOUNCE`] for each shading point along the path
/// ([`dims::bounce`]). 2D requests take two consecutive dimensions.
pub mod dims {
    /// The position on the film within the pixel (2D).
    pub const FILM: u32 = 0;
    /// The position on the lens (2D; for a pinhole camera only the
    /// independent sampler draws it, to keep its order of draws).
    pub const LENS: u32 = 2;
    /// The time within the shutter interval (drawn only when something in
    /// the scene moves).
    pub const TIME: u32 = 4;
    /// Dimensions of the camera sample.
    pub const CAMERA: u32 = 5;
    /// Which lobe of the BSDF is sampled.
    pub const BSDF_COMPONENT: u32 = 0;
    /// The direction the BSDF samples (2D).
    pub const BSDF_DIRECTION: u32 = 1;
    /// Which light is sampled.
    pub const LIGHT_CHOICE: u32 = 3;
    /// The position on the light (2D).
    pub const LIGHT_POSITION: u32 = 4;
    /// Russian roulette.
    pub const ROULETTE: u32 = 6;
    /// Dimensions of each shading point.
    pub const PER_BOUNCE: u32 = 7;

    /// Dimension `offset` (one of the constants above) of the shading
    /// point at path depth `depth` (0: where the camera ray lands):
    /// `CAMERA + PER_BOUNCE·depth + offset`.
    #[inline(always)]
    pub fn bounce(depth: u32, offset: u32) -> u32 {
        CAMERA
            .saturating_add(PER_BOUNCE.saturating_mul(depth))
            .saturating_add(offset)
    }
}

/// Which light transport to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Emitted and direct light (paths of at most two segments).
    Direct,
    /// Paths of any length (up to `max_depth`), with Russian roulette.
    Path,
    /// Light tracing ([`super::ptracer`]): paths from the lights, each
    /// vertex connected to the camera.
    Ptracer,
    /// Bidirectional path tracing ([`super::bdpt`]).
    Bdpt,
}

/// How light is found at each shading point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Only by sampling the BSDF and following the ray.
    Bsdf,
    /// Only by sampling the emitters (next-event estimation).
    Emitter,
    /// Both, weighted by the MIS heuristic.
    Mis,
}

pub use crate::mis::Heuristic;

/// What to render and how.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Direct or path.
    pub integrator: Integrator,
    /// BSDF, emitter or MIS.
    pub strategy: Strategy,
    /// The MIS heuristic.
    pub heuristic: Heuristic,
    /// Longest path in segments (Mitsuba's `max_depth`); `None`: unbounded.
    /// The direct integrator uses 2.
    pub max_depth: Option<u32>,
    /// Russian roulette starts at this depth (not for the direct
    /// integrator).
    pub rr_depth: u32,
    /// Whether emitters seen straight from the camera are left out, as by
    /// Mitsuba's `hide_emitters`: under the direct and path integrators,
    /// camera rays pass through area lights ([`skip_emitters`]) and see no
    /// environment; under light tracing and bidirectional path tracing,
    /// as in Mitsuba's `ptracer`, only the light a camera ray or
    /// connection receives straight from a light is left out (area lights
    /// still block and reflect light).
    pub hide_emitters: bool,
    /// Where each pixel's random numbers come from.
    pub sampler: Sampler,
    /// Bidirectional path tracing only: also render each strategy's image
    /// ([`super::bdpt::strategies`]).
    pub strategies: bool,
}

impl Settings {
    /// The density emitter sampling draws the environment by: compensated
    /// under MIS in the direct and path integrators (whose BSDF samples
    /// cover what it leaves out), complete otherwise.
    pub(super) fn env_density(&self) -> EnvDensity {
        let bsdf_paths = matches!(self.integrator, Integrator::Direct | Integrator::Path);
        if bsdf_paths && self.strategy == Strategy::Mis {
            EnvDensity::Compensated
        } else {
            EnvDensity::Complete
        }
    }

    pub(super) fn weight(&self, pdf_a: f32, pdf_b: f32) -> f32 {
        self.heuristic.weight(pdf_a, pdf_b)
    }

    pub(super) fn max_depth(&self) -> u32 {
        match self.integrator {
            Integrator::Direct => 2,
            Integrator::Path | Integrator::Ptracer | Integrator::Bdpt => {
                self.max_depth.unwrap_or(u32::MAX)
            }
        }
    }
}

/// Offset of a ray origin off a surface, as Mitsuba's: `(1 + max |p_i|) ε`
/// with `ε = 1500 · 2⁻²⁴`.
#[inline]
pub(super) fn offset(p: Vec3A, n: Vec3A, toward: Vec3A) -> Vec3A {
    let eps = (1.0 + p.abs().max_element()) * (1500.0 / 16_777_216.0);
    if n.dot(toward) >= 0.0 {
        p + n * eps
    } else {
        p - n * eps
    }
}

/// The shadow ray from a surface point `p` (geometric normal `n`) toward
/// a light sample along the unit `d`, whose light is at `point` on an area
/// light, or the environment (`None`). Toward an area light it runs
/// between the two points, each moved off its own surface toward the other
/// by [`offset`], so that neither the receiver nor the light itself can
/// block it (a ray kept along `d` from the moved origin would cross the
/// light's surface before its end at grazing angles); toward the
/// environment it is unbounded.
#[inline]
pub(crate) fn shadow_ray(p: Vec3A, n: Vec3A, d: Vec3A, point: Option<&SurfacePoint>) -> Ray {
    let o = offset(p, n, d);
    match point {
        None => Ray {
            o,
            d,
            tmax: f32::INFINITY,
        },
        Some(y) => ray_to(o, y, d),
    }
}

/// The ray from `o` to the surface point `y`, which lies along `d` from
/// `o`: it ends at `y` moved off its surface toward `o` by [`offset`], so
/// that `y`'s own surface cannot block it.
#[inline]
pub(crate) fn ray_to(o: Vec3A, y: &SurfacePoint, d: Vec3A) -> Ray {
    let to = offset(y.p, y.ng, -d) - o;
    let tmax = to.length();
    Ray {
        o,
        d: if tmax > 0.0 { to / tmax } else { d },
        tmax,
    }
}

/// The shading frame at a point of shape `shape` with shading normal `ns`
/// seen from the unit direction `from` (a two-sided material turns its
/// front toward it; seen from the back, a one-sided material is black),
/// and the BSDF's view of `from` in that frame, for a BSDF sampled under
/// `sampler`.
///
/// A stratified pattern is laid over the frame, so a frame that jumps
/// within a pixel mixes two layouts of it: the frame of the normal alone
/// ([`Frame::from_normal`], Duff's) jumps across `n_z = 0`, which crosses
/// every sphere. So under the samplers other than the independent one a
/// sphere shades in the frame of its azimuth ([`Frame::azimuthal`], as
/// Mitsuba's sphere), which turns smoothly but at its poles: the demo's
/// multijitter relMSE at 64 spp went from 1.016 to 0.998 × Mitsuba's
/// (benches/README.md). The independent sampler's directions are alike in
/// any turn of the frame: it keeps the frame of the normal, and its renders
/// their bits. The BSDF is isotropic, so a caller that only evaluates it
/// may pass any sampler.
#[inline]
pub(super) fn shading(
    scene: &Scene,
    shape: u32,
    ns: Vec3A,
    from: Vec3A,
    sampler: Sampler,
) -> (Frame<f32>, PhongView<f32>) {
    let frame = shading_frame(scene, shape, ns, from, sampler);
    let view = scene
        .material(shape)
        .bsdf
        .view(frame.to_local(from.to_array()));
    (frame, view)
}

/// The shading frame of [`shading`].
#[inline]
pub(super) fn shading_frame(
    scene: &Scene,
    shape: u32,
    ns: Vec3A,
    from: Vec3A,
    sampler: Sampler,
) -> Frame<f32> {
    let n = facing_normal(scene, shape, ns, from).to_array();
    if turns_with_azimuth(scene, shape, sampler) {
        Frame::azimuthal(n)
    } else {
        Frame::from_normal(n)
    }
}

/// The normal of [`shading_frame`]: `ns` of a point of `shape`, turned
/// toward `from` when its material is two-sided.
#[inline]
pub(super) fn facing_normal(scene: &Scene, shape: u32, ns: Vec3A, from: Vec3A) -> Vec3A {
    if scene.material(shape).two_sided && ns.dot(from) < 0.0 {
        -ns
    } else {
        ns
    }
}

/// Whether [`shading_frame`] at a point of `shape` under `sampler` is
/// [`Frame::azimuthal`] (a sphere's, under the samplers other than the
/// independent one) rather than [`Frame::from_normal`].
#[inline]
pub(super) fn turns_with_azimuth(scene: &Scene, shape: u32, sampler: Sampler) -> bool {
    sampler != Sampler::Independent && scene.is_sphere(shape)
}

/// Whether nothing blocks the segment from `o` to `end` at time `tau`
/// (the caller moves either end off its surface).
pub(super) fn unoccluded(scene: &Scene, o: Vec3A, end: Vec3A, tau: f32) -> bool {
    let to = end - o;
    let tmax = to.length();
    tmax > 0.0
        && !scene.occluded(
            &Ray {
                o,
                d: to / tmax,
                tmax,
            },
            tau,
        )
}

#[inline]
pub(super) fn mul(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}

#[inline]
pub(super) fn add_scaled(acc: &mut [f32; 3], a: [f32; 3], b: [f32; 3], s: f32) {
    for k in 0..3 {
        acc[k] += a[k] * b[k] * s;
    }
}

/// Rays that left the scene, whose environment light is looked up for a
/// whole batch of samples at once ([`add_escaped`]): those lookups (the
/// most frequent work in an environment-lit scene) then run in vectorised
/// loops whose texel and table reads overlap.
#[derive(Debug, Default)]
pub struct Escaped {
    /// World directions (apart: the lookups read them as one array).
    dir: Vec<[f32; 3]>,
    /// What the light each ray finds is added to.
    to: Vec<EscapedTo>,
    /// Scratch for the batch: radiance and environment densities.
    radiance: Vec<[f32; 3]>,
    light_pdf: Vec<f32>,
}

/// Where the light an escaped ray finds goes, and its weights.
#[derive(Clone, Copy, Debug)]
struct EscapedTo {
    /// The sample (index in the batch) the ray belongs to.
    slot: u32,
    /// The path throughput `β`.
    beta: [f32; 3],
    /// The BSDF density that drew the ray, where the MIS weight against
    /// environment sampling remains to be applied.
    bsdf_pdf: Option<f32>,
}

impl Escaped {
    /// Room for `n` rays (the samples of a batch: a path escapes once).
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the memory cannot be had.
    pub fn reserve(&mut self, n: usize) -> crate::Result<()> {
        alloc::reserve_each!(n, "the batch's escaped rays";
            self.dir, self.to, self.radiance, self.light_pdf)
    }

    /// Forgets every ray (keeping the memory).
    pub fn clear(&mut self) {
        self.dir.clear();
        self.to.clear();
        self.radiance.clear();
        self.light_pdf.clear();
    }

    /// Records a ray that left the scene with throughput `beta`; `bsdf_pdf`
    /// when its MIS weight against environment sampling remains to apply.
    #[inline]
    pub(super) fn push(&mut self, slot: u32, d: Vec3A, beta: [f32; 3], bsdf_pdf: Option<f32>) {
        self.dir.push(d.to_array());
        self.to.push(EscapedTo {
            slot,
            beta,
            bsdf_pdf,
        });
    }
}

/// Adds the environment light of every ray in `escaped` to the radiance of
/// its sample, `l[slot]`.
pub fn add_escaped(scene: &Scene, settings: &Settings, escaped: &mut Escaped, l: &mut [[f32; 3]]) {
    let Some(env) = scene.environment() else {
        return;
    };
    let n = escaped.dir.len();
    escaped.radiance.resize(n, [0.0; 3]);
    env.eval_into(&escaped.dir, &mut escaped.radiance);
    // The densities from the first ray whose MIS weight remains to apply:
    // the camera's rays, which come first, need none.
    if let Some(first) = escaped.to.iter().position(|to| to.bsdf_pdf.is_some()) {
        escaped.light_pdf.resize(n, 0.0);
        scene.environment_pdf_into(
            &escaped.dir[first..],
            &mut escaped.light_pdf[first..],
            settings.env_density(),
        );
    }
    let light_pdf = &escaped.light_pdf;
    for (i, (to, &radiance)) in escaped.to.iter().zip(&escaped.radiance).enumerate() {
        let w = to
            .bsdf_pdf
            .map_or(1.0, |p| settings.weight(p, light_pdf[i]));
        add_scaled(&mut l[to.slot as usize], to.beta, radiance, w);
    }
}

/// The first hit of the camera ray `ray` (whose first hit is `hit`) that
/// is not on an area light: the ray passes through them (re-spawned past
/// each, as Mitsuba's `hide_emitters` does), and `ray` is updated to the
/// last spawn. Only a light's surface point is computed (for the spawn):
/// whether a hit is on one is known from its primitive
/// ([`Scene::hits_emitter`]).
pub fn skip_emitters(scene: &Scene, ray: &mut Ray, mut hit: Option<Hit>, time: f32) -> Option<Hit> {
    while let Some(h) = hit {
        if !scene.hits_emitter(&h) {
            break;
        }
        let (_, sp) = scene.surface(ray, &h, time);
        ray.o = offset(sp.p, sp.ng, ray.d);
        hit = scene.intersect(ray, time);
    }
    hit
}

/// Whether a path's vertex at `depth` ends after its light sample: under
/// emitter sampling the next vertex's emission is not counted, so when it
/// would be the last, the path stops there (drawing no BSDF sample).
#[inline]
pub(super) fn ends_after_light(settings: &Settings, depth: u32) -> bool {
    settings.strategy == Strategy::Emitter && depth + 2 >= settings.max_depth()
}

/// The weight of emission found at path depth `depth` (0: seen from the
/// camera) after a BSDF sample of density `bsdf_pdf`; `light_pdf` gives the
/// density emitter sampling would have had for it.
#[inline]
pub(super) fn emission_weight(
    settings: &Settings,
    depth: u32,
    bsdf_pdf: f32,
    light_pdf: impl FnOnce() -> f32,
) -> f32 {
    if depth == 0 {
        return 1.0;
    }
    match settings.strategy {
        Strategy::Bsdf => 1.0,
        Strategy::Emitter => 0.0,
        Strategy::Mis => settings.weight(bsdf_pdf, light_pdf()),
    }
}

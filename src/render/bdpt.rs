//! Bidirectional path tracing (Veach 1997, ch. 10; as pbrt-v4's `bdpt`):
//! for each sample, a camera subpath `z₀ z₁ …` (from the lens through a
//! uniform point of the pixel, then BSDF sampling) and a light subpath
//! `y₀ y₁ …` (from a light as in [`ptracer`](super::ptracer)), and every
//! way `(s, t)` of joining the first `s` light vertices to the first `t`
//! camera vertices into a path of `s + t − 1 ≤ max_depth` segments:
//!
//! ```text
//! s = 0:   the camera subpath ends on a light:       C = β_t Le
//! t = 1:   y_{s−1} connected to a new lens point:    C = β_s f_s |cos| K W   (splatted where it lands)
//! s = 1:   z_{t−1} connected to a point drawn on a light (next-event estimation):
//!                                                    C = β_t f_t |cos| Le / p_ω
//! else:    y_{s−1} joined to z_{t−1}:                C = β_s f_s K · f_t β_t |cos_s| |cos_t| / d²
//! ```
//!
//! (`β` the subpaths' throughputs, `f` the BSDFs at the joined vertices,
//! `K` the shading-normal correction of the light side as in light
//! tracing; `(1, 1)`, a light point joined to the lens, is not used). Each
//! contribution is weighted by the MIS heuristic over every strategy that
//! could have made the same path (`w = 1 / Σ_i (p_i / p_{s,t})^β`, `β` = 1
//! for the balance heuristic, 2 for the power heuristic), from the
//! densities with which each vertex is sampled from either side, per unit
//! area (per steradian for an environment vertex): `p→` as the subpath
//! made it, `p←` as the other side would make it. Camera rays are drawn
//! with density `1 / (A cos³θ)` per steradian over the whole film (one
//! per pixel, uniform in it: together, uniform over the film), light
//! subpaths as in light tracing (area lights by area then cosine; the
//! environment by its direction density, then uniformly on the disk of
//! radius `R` across the scene's bounding sphere: `1 / (π R²)`).
//! Russian roulette ends either subpath past `rr_depth` (survival
//! `min(max β, 0.95)`). The camera paths' contributions and the light
//! connections land on the film by the same normalised splat
//! ([`splat`](super::splat)); each pixel's variance is that of its
//! per-sample totals.

use glam::Vec3A;

use super::Settings;
use super::integrator::{offset, shadow_ray};
use super::ptracer::emitted_ray;
use super::scene::{Emission, Scene};
use super::shape::Ray;
use super::splat::Splat;
use super::splatting::Paths;
use crate::frame::Frame;
use crate::mis::Heuristic;
use crate::phong::PhongView;
use crate::sampler::Stream;

/// The dimensions of a sample, in this order: the camera's, the light
/// subpath's start, then [`dims::PER_DEPTH`] per depth `k` ([`dims::at`]):
/// the camera subpath's `k`-th vertex, then the light subpath's.
pub mod dims {
    /// Film position in the pixel (2D).
    pub const FILM: u32 = 0;
    /// Lens position (2D).
    pub const LENS: u32 = 2;
    /// Time in the shutter (drawn only when something moves).
    pub const TIME: u32 = 4;
    /// The light the light subpath starts on.
    pub const EMITTER_CHOICE: u32 = 5;
    /// Its point, or the environment's direction (2D).
    pub const EMITTER_POSITION: u32 = 6;
    /// The first ray's direction, or its point on the disk (2D).
    pub const EMITTER_DIRECTION: u32 = 8;
    /// Dimensions before depth 0.
    pub const START: u32 = 10;
    /// Camera vertex: the BSDF sample (3D).
    pub const CAMERA_BSDF: u32 = 0;
    /// Camera vertex: next-event estimation's light and point (3D).
    pub const CAMERA_LIGHT: u32 = 3;
    /// Camera vertex: Russian roulette.
    pub const CAMERA_ROULETTE: u32 = 6;
    /// Light vertex: the lens point of its connection to the camera (2D).
    pub const LIGHT_LENS: u32 = 7;
    /// Light vertex: the BSDF sample (3D).
    pub const LIGHT_BSDF: u32 = 9;
    /// Light vertex: Russian roulette.
    pub const LIGHT_ROULETTE: u32 = 12;
    /// Dimensions per depth.
    pub const PER_DEPTH: u32 = 13;

    /// Dimension `offset` at depth `k` (the camera's vertex `z_{k+1}`,
    /// the light's `y_k`).
    #[inline]
    pub fn at(k: u32, offset: u32) -> u32 {
        START
            .saturating_add(PER_DEPTH.saturating_mul(k))
            .saturating_add(offset)
    }
}

/// What a vertex is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// The lens point.
    Camera,
    /// A point on a surface of shape `shape` (which may emit).
    Surface { shape: u32 },
    /// The point a light subpath starts from on an area light of shape
    /// `shape` (no BSDF: it only emits).
    Light { shape: u32 },
    /// The environment, in direction `p` (a unit vector toward it).
    Environment,
}

/// A vertex of a subpath.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    kind: Kind,
    /// Position (for the environment: the unit direction toward it).
    p: Vec3A,
    ng: Vec3A,
    ns: Vec3A,
    /// The throughput of the subpath up to this vertex.
    beta: [f32; 3],
    /// Density of this vertex as its subpath sampled it (per area, per
    /// steradian for the environment).
    pdf_fwd: f32,
    /// Density of this vertex as the other subpath would sample it.
    pdf_rev: f32,
}

impl Vertex {
    fn on_surface(&self) -> bool {
        matches!(self.kind, Kind::Surface { .. } | Kind::Light { .. })
    }
}

/// What the walks and connections need.
struct Ctx<'a> {
    scene: &'a Scene,
    settings: &'a Settings,
    tau: f32,
}

/// Bidirectional path tracing as a [`Paths`] integrator.
pub struct Bidirectional<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The settings (`max_depth`, `rr_depth`, `heuristic`).
    pub settings: &'a Settings,
}

/// One thread's subpaths.
#[derive(Default)]
pub struct Subpaths {
    camera: Vec<Vertex>,
    light: Vec<Vertex>,
}

impl Paths for Bidirectional<'_> {
    type Scratch = Subpaths;
    const PER_PATH: bool = false;

    fn scratch(&self) -> Subpaths {
        Subpaths::default()
    }

    fn trace(&self, sub: &mut Subpaths, stream: &mut Stream, pixel: usize, out: &mut Vec<Splat>) {
        let scene = self.scene;
        let max_depth = self.settings.max_depth();
        if max_depth == 0 {
            return;
        }
        let (width, height) = scene.film();
        let [fx, fy] = stream.get2::<f32>(dims::FILM);
        let lens = stream.get2(dims::LENS);
        let tau = if scene.moves() {
            stream.get1(dims::TIME)
        } else {
            0.0
        };
        let film = [
            ((pixel % width) as f32 + fx) / width as f32,
            ((pixel / width) as f32 + fy) / height as f32,
        ];
        let ctx = Ctx {
            scene,
            settings: self.settings,
            tau,
        };
        camera_subpath(&ctx, film, lens, stream, &mut sub.camera);
        light_subpath(&ctx, stream, &mut sub.light);
        connect_all(&ctx, sub, film, stream, out);
    }
}

/// The camera subpath: `z₀` on the lens, then up to `max_depth` vertices
/// (the last may be the environment).
fn camera_subpath(
    ctx: &Ctx,
    film: [f32; 2],
    lens: [f32; 2],
    stream: &mut Stream,
    out: &mut Vec<Vertex>,
) {
    out.clear();
    let camera = ctx.scene.camera();
    let z0 = camera.lens_point_at(lens, ctx.tau);
    let ray = camera.ray(film, lens, ctx.tau);
    out.push(Vertex {
        kind: Kind::Camera,
        p: z0,
        ng: ray.d,
        ns: ray.d,
        beta: [1.0; 3],
        pdf_fwd: 1.0,
        pdf_rev: 0.0,
    });
    let pdf = camera.pdf_direction(z0, ray.d, ctx.tau);
    walk(ctx, ray, [1.0; 3], pdf, (stream, false), out);
}

/// The light subpath: `y₀` on a light (or the environment), then up to
/// `max_depth − 1` vertices.
fn light_subpath(ctx: &Ctx, stream: &mut Stream, out: &mut Vec<Vertex>) {
    out.clear();
    let scene = ctx.scene;
    let u = [
        stream.get1(dims::EMITTER_CHOICE),
        stream.get1(dims::EMITTER_POSITION),
        stream.get1(dims::EMITTER_POSITION + 1),
    ];
    let Some(emission) = scene.sample_emission(u) else {
        return;
    };
    let (ray, beta) = emitted_ray(scene, emission, stream.get2(dims::EMITTER_DIRECTION));
    match emission {
        Emission::Surface {
            shape, point, pdf, ..
        } => {
            out.push(Vertex {
                kind: Kind::Light { shape },
                p: point.p,
                ng: point.ng,
                ns: point.ng,
                beta: [1.0; 3],
                pdf_fwd: pdf,
                pdf_rev: 0.0,
            });
            // The cosine-weighted direction's density.
            let pdf_dir = point.ng.dot(ray.d).max(0.0) * std::f32::consts::FRAC_1_PI;
            walk(ctx, ray, beta, pdf_dir, (stream, true), out);
        }
        Emission::Environment { d, pdf, .. } => {
            out.push(Vertex {
                kind: Kind::Environment,
                p: d,
                ng: -d,
                ns: -d,
                beta: [1.0; 3],
                pdf_fwd: pdf,
                pdf_rev: 0.0,
            });
            let (_, radius) = scene.bounding_sphere();
            let planar = 1.0 / (std::f32::consts::PI * radius * radius);
            walk(ctx, ray, beta, planar, (stream, true), out);
            // y₁'s density is the disk's, projected on its surface.
            if let Some(y1) = out.get_mut(1) {
                y1.pdf_fwd = planar * y1.ng.dot(d).abs();
            }
        }
    }
}

/// Extends a subpath from its last vertex along `ray` (drawn with density
/// `pdf` per steradian, or per area of the disk for the environment's
/// first ray: [`light_subpath`] corrects that vertex) with throughput
/// `beta`, by BSDF sampling, up to its length limit; `light` for a light
/// subpath (the adjoint BSDF: the shading-normal correction, light leaks
/// refused).
fn walk(
    ctx: &Ctx,
    mut ray: Ray,
    mut beta: [f32; 3],
    mut pdf: f32,
    (stream, light): (&mut Stream, bool),
    path: &mut Vec<Vertex>,
) {
    let scene = ctx.scene;
    // Vertices a subpath may hold: z₀ … z_max (the camera's) or y₀ …
    // y_{max−1} (the light's).
    let limit = ctx.settings.max_depth().saturating_add(u32::from(!light)) as usize;
    loop {
        if path.len() >= limit {
            return;
        }
        let k = path.len() as u32 - 1;
        let Some(hit) = scene.intersect(&ray, ctx.tau) else {
            if !light && scene.environment().is_some() {
                path.push(Vertex {
                    kind: Kind::Environment,
                    p: ray.d,
                    ng: -ray.d,
                    ns: -ray.d,
                    beta,
                    pdf_fwd: pdf,
                    pdf_rev: 0.0,
                });
            }
            return;
        };
        let (shape, sp) = scene.surface(&ray, &hit, ctx.tau);
        let prev = path[path.len() - 1];
        let mut v = Vertex {
            kind: Kind::Surface { shape },
            p: sp.p,
            ng: sp.ng,
            ns: sp.ns,
            beta,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
        };
        v.pdf_fwd = convert(pdf, &prev, &v);
        path.push(v);
        if path.len() >= limit {
            return;
        }
        let from = -ray.d;
        let (frame, view) = bsdf(scene, &v, shape, from);
        let (bsdf_u, rr_u) = if light {
            (dims::LIGHT_BSDF, dims::LIGHT_ROULETTE)
        } else {
            (dims::CAMERA_BSDF, dims::CAMERA_ROULETTE)
        };
        let u = [
            stream.get1(dims::at(k, bsdf_u)),
            stream.get1(dims::at(k, bsdf_u + 1)),
            stream.get1(dims::at(k, bsdf_u + 2)),
        ];
        let s = view.sample_one(u);
        if s.weight.iter().all(|&w| w <= 0.0) {
            return;
        }
        let d = Vec3A::from(frame.to_world(s.wo)).normalize();
        let fix = if light {
            match adjoint(&v, from, d) {
                Some(fix) => fix,
                None => return,
            }
        } else {
            1.0
        };
        beta = std::array::from_fn(|c| beta[c] * s.weight[c] * fix);
        // The density of sampling `from` had the walk come the other way.
        let rev = bsdf(scene, &v, shape, d)
            .1
            .eval_pdf_one(frame_local(&frame, from))
            .1;
        let n = path.len();
        path[n - 2].pdf_rev = convert(rev, &v, &path[n - 2]);
        if n as u32 - 1 > ctx.settings.rr_depth {
            let q = beta.iter().copied().fold(0.0f32, f32::max).min(0.95);
            if stream.get1::<f32>(dims::at(k, rr_u)) >= q {
                return;
            }
            beta = beta.map(|b| b / q);
        }
        pdf = s.pdf;
        ray = Ray {
            o: offset(sp.p, sp.ng, d),
            d,
            tmax: f32::INFINITY,
        };
    }
}

/// `v` in the local coordinates of `frame`.
fn frame_local(frame: &Frame<f32>, v: Vec3A) -> [f32; 3] {
    frame.to_local(v.to_array())
}

/// The shading frame and the BSDF at surface vertex `v` of shape `shape`
/// seen from `from` (a two-sided material faces it).
fn bsdf(scene: &Scene, v: &Vertex, shape: u32, from: Vec3A) -> (Frame<f32>, PhongView<f32>) {
    let material = scene.material(shape);
    let ns = if material.two_sided && v.ns.dot(from) < 0.0 {
        -v.ns
    } else {
        v.ns
    };
    let frame = Frame::from_normal(ns.to_array());
    let view = material.bsdf.view(frame_local(&frame, from));
    (frame, view)
}

/// Veach's shading-normal correction at `v` for light arriving from
/// `from` and leaving toward `to` ([`ptracer`](super::ptracer)); `None`
/// for directions on different sides of the two normals.
fn adjoint(v: &Vertex, from: Vec3A, to: Vec3A) -> Option<f32> {
    let (si, so) = (v.ns.dot(from), v.ns.dot(to));
    let (gi, go) = (v.ng.dot(from), v.ng.dot(to));
    (si * gi > 0.0 && so * go > 0.0).then(|| ((si * go) / (so * gi)).abs())
}

/// A density per steradian at `from` toward `to`, per unit area at `to`
/// (`|cos θ_to| / d²`; no cosine at the lens), kept per steradian toward
/// the environment.
fn convert(pdf: f32, from: &Vertex, to: &Vertex) -> f32 {
    if to.kind == Kind::Environment {
        return pdf;
    }
    let w = to.p - from.p;
    let d2 = w.length_squared();
    if d2.is_nan() || d2 <= 0.0 {
        return 0.0;
    }
    let cos = if to.on_surface() {
        to.ng.dot(w).abs() / d2.sqrt()
    } else {
        1.0
    };
    pdf * cos / d2
}

/// The unit direction from vertex `a` to vertex `b`.
fn direction(a: &Vertex, b: &Vertex) -> Vec3A {
    match (a.kind, b.kind) {
        (_, Kind::Environment) => b.p,
        (Kind::Environment, _) => -a.p,
        _ => (b.p - a.p).normalize_or_zero(),
    }
}

/// The density (per area at `next`) with which vertex `v`, reached from
/// `prev`, samples `next` ([`convert`] of its density per steradian).
fn pdf(ctx: &Ctx, v: &Vertex, prev: Option<&Vertex>, next: &Vertex) -> f32 {
    let to = direction(v, next);
    let per_sr = match v.kind {
        Kind::Camera => ctx.scene.camera().pdf_direction(v.p, to, ctx.tau),
        Kind::Surface { shape } => {
            let Some(prev) = prev else {
                return pdf_light(ctx, v, next);
            };
            let from = direction(v, prev);
            let (frame, view) = bsdf(ctx.scene, v, shape, from);
            view.eval_pdf_one(frame_local(&frame, to)).1
        }
        Kind::Light { .. } | Kind::Environment => return pdf_light(ctx, v, next),
    };
    convert(per_sr, v, next)
}

/// The density (per area at `next`) with which a light subpath starting at
/// `v` (on an area light, or the environment) reaches `next` with its
/// first ray: `cos θ / π` per steradian from an area light's front side;
/// `1 / (π R²)` per area across the environment's rays, `|cos θ_next|`
/// at `next`.
fn pdf_light(ctx: &Ctx, v: &Vertex, next: &Vertex) -> f32 {
    if v.kind == Kind::Environment {
        let (_, radius) = ctx.scene.bounding_sphere();
        let cos = if next.on_surface() {
            next.ng.dot(v.p).abs()
        } else {
            1.0
        };
        return cos / (std::f32::consts::PI * radius * radius);
    }
    let to = direction(v, next);
    convert(v.ng.dot(to).max(0.0) * std::f32::consts::FRAC_1_PI, v, next)
}

/// The density with which a light subpath starts at `v`: per area on an
/// area light, per steradian for the environment (the light's choice
/// included).
fn pdf_light_origin(ctx: &Ctx, v: &Vertex) -> f32 {
    match v.kind {
        Kind::Environment => ctx.scene.environment_pdf(v.p),
        Kind::Surface { shape } | Kind::Light { shape } => ctx.scene.emission_pdf(shape),
        Kind::Camera => 0.0,
    }
}

/// The radiance vertex `v` (a light, or a surface of an area light) emits
/// toward `toward`.
fn emitted(ctx: &Ctx, v: &Vertex, toward: &Vertex) -> Option<[f32; 3]> {
    match v.kind {
        Kind::Environment => ctx.scene.environment().map(|env| env.eval(v.p)),
        Kind::Surface { shape } | Kind::Light { shape } => {
            ctx.scene.emitted(shape, v.ng, direction(v, toward))
        }
        Kind::Camera => None,
    }
}

/// `f · |cos θ_out|` at surface vertex `v` for light between `prev` and
/// `next` (`light`: on a light subpath, light arrives from `prev`, with
/// the shading-normal correction; else from `next`).
fn scatter(ctx: &Ctx, v: &Vertex, prev: &Vertex, next: &Vertex, light: bool) -> [f32; 3] {
    let Kind::Surface { shape } = v.kind else {
        return [0.0; 3];
    };
    let (from, to) = (direction(v, prev), direction(v, next));
    let fix = if light {
        match adjoint(v, from, to) {
            Some(fix) => fix,
            None => return [0.0; 3],
        }
    } else {
        1.0
    };
    let (frame, view) = bsdf(ctx.scene, v, shape, from);
    let wo = frame_local(&frame, to);
    let f = view.eval_pdf_one(wo).0;
    let s = wo[2].abs() * fix;
    f.map(|x| x * s)
}

/// Every strategy `(s, t)` of the subpaths in `sub`, splatted to `out`
/// (camera paths' at `film`).
fn connect_all(
    ctx: &Ctx,
    sub: &Subpaths,
    film: [f32; 2],
    stream: &mut Stream,
    out: &mut Vec<Splat>,
) {
    let max_depth = ctx.settings.max_depth();
    let (cam, light) = (&sub.camera[..], &sub.light[..]);
    let mut total = [0.0f32; 3];
    for t in 1..=cam.len() {
        for s in 0..=light.len() {
            let segments = (s + t) as u32 - 1;
            let hidden = ctx.settings.hide_emitters && s == 0 && t == 2;
            if (s == 1 && t == 1) || s + t < 2 || segments > max_depth || hidden {
                continue;
            }
            if let Some((value, splat_at)) = connect(ctx, cam, light, s, t, stream) {
                match splat_at {
                    Some(at) => out.push(Splat { film: at, value }),
                    None => total = std::array::from_fn(|c| total[c] + value[c]),
                }
            }
        }
    }
    if total.iter().any(|&v| v != 0.0) {
        out.push(Splat { film, value: total });
    }
}

/// Strategy `(s, t)`: its weighted contribution and, for `t = 1`, where
/// on the film it lands.
fn connect(
    ctx: &Ctx,
    cam: &[Vertex],
    light: &[Vertex],
    s: usize,
    t: usize,
    stream: &mut Stream,
) -> Option<([f32; 3], Option<[f32; 2]>)> {
    let scene = ctx.scene;
    let pt = &cam[t - 1];
    // A camera path that left the scene joins nothing.
    if t > 1 && s != 0 && pt.kind == Kind::Environment {
        return None;
    }
    let mut sampled = None;
    let mut at = None;
    let value: [f32; 3] = if s == 0 {
        let le = emitted(ctx, pt, &cam[t - 2])?;
        std::array::from_fn(|c| le[c] * pt.beta[c])
    } else if t == 1 {
        let qs = &light[s - 1];
        if !matches!(qs.kind, Kind::Surface { .. }) {
            return None;
        }
        let k = s as u32 - 2;
        let u = stream.get2(dims::at(k, dims::LIGHT_LENS));
        let c = scene.camera().sample_direction(qs.p, u, ctx.tau)?;
        let lens = Vertex {
            kind: Kind::Camera,
            p: c.lens,
            ng: -c.d,
            ns: -c.d,
            beta: [c.weight; 3],
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
        };
        let f = scatter(ctx, qs, &light[s - 2], &lens, true);
        if f.iter().all(|&v| v == 0.0) || !visible(scene, qs, &lens, ctx.tau) {
            return None;
        }
        sampled = Some(lens);
        at = Some(c.film);
        std::array::from_fn(|i| qs.beta[i] * f[i] * c.weight)
    } else if s == 1 {
        if !matches!(pt.kind, Kind::Surface { .. }) {
            return None;
        }
        let k = t as u32 - 2;
        let u = [
            stream.get1(dims::at(k, dims::CAMERA_LIGHT)),
            stream.get1(dims::at(k, dims::CAMERA_LIGHT + 1)),
            stream.get1(dims::at(k, dims::CAMERA_LIGHT + 2)),
        ];
        let ls = scene.sample_light(pt.p, u, None::<fn() -> u64>)?;
        let mut y = match ls.point {
            Some((point, shape)) => Vertex {
                kind: Kind::Light { shape },
                p: point.p,
                ng: point.ng,
                ns: point.ng,
                beta: [1.0; 3],
                pdf_fwd: 0.0,
                pdf_rev: 0.0,
            },
            None => Vertex {
                kind: Kind::Environment,
                p: ls.d,
                ng: -ls.d,
                ns: -ls.d,
                beta: [1.0; 3],
                pdf_fwd: 0.0,
                pdf_rev: 0.0,
            },
        };
        y.pdf_fwd = pdf_light_origin(ctx, &y);
        let f = scatter(ctx, pt, &cam[t - 2], &y, false);
        if f.iter().all(|&v| v == 0.0) || scene.occluded(&shadow_ray(pt.p, pt.ng, &ls), ctx.tau) {
            return None;
        }
        sampled = Some(y);
        std::array::from_fn(|c| pt.beta[c] * f[c] * ls.radiance[c] / ls.pdf)
    } else {
        let qs = &light[s - 1];
        if !matches!(pt.kind, Kind::Surface { .. }) || !matches!(qs.kind, Kind::Surface { .. }) {
            return None;
        }
        let fq = scatter(ctx, qs, &light[s - 2], pt, true);
        let fp = scatter(ctx, pt, &cam[t - 2], qs, false);
        let d2 = (qs.p - pt.p).length_squared();
        let value: [f32; 3] = std::array::from_fn(|c| qs.beta[c] * fq[c] * fp[c] * pt.beta[c] / d2);
        if d2.is_nan()
            || d2 <= 0.0
            || value.iter().all(|&v| v == 0.0)
            || !visible(scene, qs, pt, ctx.tau)
        {
            return None;
        }
        value
    };
    if value.iter().all(|&v| v == 0.0) {
        return None;
    }
    let w = mis_weight(ctx, cam, light, sampled, s, t);
    Some((value.map(|v| v * w), at))
}

/// Whether surface vertex `a` sees vertex `b` (a surface or the lens).
fn visible(scene: &Scene, a: &Vertex, b: &Vertex, tau: f32) -> bool {
    let d = direction(a, b);
    let o = offset(a.p, a.ng, d);
    let end = if b.on_surface() {
        offset(b.p, b.ng, -d)
    } else {
        b.p
    };
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

/// The MIS weight of strategy `(s, t)` (`sampled`: the vertex that the
/// `s = 1` or `t = 1` strategy drew in place of `y₀` or `z₀`): one over
/// the sum, over the strategies that make the same path, of their density
/// relative to this one's (each ratio to the heuristic's power), the
/// ratios being products of `p← / p→` along the subpaths from the
/// connection.
fn mis_weight(
    ctx: &Ctx,
    cam: &[Vertex],
    light: &[Vertex],
    sampled: Option<Vertex>,
    s: usize,
    t: usize,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    // The joined vertices and their predecessors, with the densities
    // this connection gives them.
    let mut qs = match (s, sampled) {
        (0, _) => None,
        (1, Some(v)) => Some(v),
        _ => Some(light[s - 1]),
    };
    let mut pt = match (t, sampled) {
        (1, Some(v)) => v,
        _ => cam[t - 1],
    };
    let mut qs_minus = (s > 1).then(|| light[s - 2]);
    let mut pt_minus = (t > 1).then(|| cam[t - 2]);
    pt.pdf_rev = match &qs {
        Some(q) => pdf(ctx, q, qs_minus.as_ref(), &pt),
        None => pdf_light_origin(ctx, &pt),
    };
    if let Some(pm) = &mut pt_minus {
        pm.pdf_rev = match &qs {
            Some(q) => pdf(ctx, &pt, Some(q), pm),
            None => pdf_light(ctx, &pt, pm),
        };
    }
    if let Some(q) = &mut qs {
        q.pdf_rev = pdf(ctx, &pt, pt_minus.as_ref(), q);
    }
    if let (Some(qm), Some(q)) = (&mut qs_minus, &qs) {
        qm.pdf_rev = pdf(ctx, q, Some(&pt), qm);
    }
    let power = |x: f32| match ctx.settings.heuristic {
        Heuristic::Balance => x,
        Heuristic::Power => x * x,
    };
    let ratio = |v: &Vertex| {
        if v.pdf_fwd > 0.0 {
            power(v.pdf_rev / v.pdf_fwd)
        } else {
            0.0
        }
    };
    let mut sum = 0.0f32;
    let mut r = 1.0f32;
    for i in (1..t).rev() {
        let v = if i == t - 1 {
            &pt
        } else if i == t - 2 {
            pt_minus.as_ref().unwrap_or(&cam[i])
        } else {
            &cam[i]
        };
        r *= ratio(v);
        sum += r;
    }
    r = 1.0;
    for i in (0..s).rev() {
        let v = if i == s - 1 {
            qs.as_ref().unwrap_or(&light[i])
        } else if i == s - 2 {
            qs_minus.as_ref().unwrap_or(&light[i])
        } else {
            &light[i]
        };
        r *= ratio(v);
        sum += r;
    }
    1.0 / (1.0 + sum)
}

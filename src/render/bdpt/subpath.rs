//! The vertices of bidirectional path tracing's subpaths, how the
//! subpaths are made, and the densities with which either side samples a
//! vertex (per unit area; per steradian for the environment).

use glam::Vec3A;

use super::super::integrator::{offset, shading};
use super::super::scene::{Emission, Scene};
use super::super::shape::Ray;
use super::{Ctx, dims};
use crate::frame::Frame;
use crate::sampler::{Sampler, Stream};
use crate::warp;

/// What a vertex is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
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
pub struct Vertex {
    pub(super) kind: Kind,
    /// Position (for the environment: the unit direction toward it).
    pub(super) p: Vec3A,
    pub(super) ng: Vec3A,
    pub(super) ns: Vec3A,
    /// The throughput of the subpath up to this vertex.
    pub(super) beta: [f32; 3],
    /// Density of this vertex as its subpath sampled it (per area, per
    /// steradian for the environment).
    pub(super) pdf_fwd: f32,
    /// Density of this vertex as the other subpath would sample it.
    pub(super) pdf_rev: f32,
}

impl Vertex {
    pub(super) fn on_surface(&self) -> bool {
        matches!(self.kind, Kind::Surface { .. } | Kind::Light { .. })
    }
}

/// The camera subpath: `z₀` on the lens, then up to `max_depth` vertices
/// (the last may be the environment).
pub(super) fn camera_subpath(
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
pub(in crate::render) fn light_subpath(ctx: &Ctx, stream: &mut Stream, out: &mut Vec<Vertex>) {
    out.clear();
    let scene = ctx.scene;
    let start = (
        dims::EMITTER_CHOICE,
        dims::EMITTER_POSITION,
        dims::EMITTER_DIRECTION,
    );
    let Some((emission, ray, beta)) = start_light_path(scene, stream, start) else {
        return;
    };
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
pub(super) fn walk(
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
        let (frame, view) = shading(scene, shape, v.ns, from, stream.sampler());
        let (bsdf_u, rr_u) = if light {
            (dims::LIGHT_BSDF, dims::LIGHT_ROULETTE)
        } else {
            (dims::CAMERA_BSDF, dims::CAMERA_ROULETTE)
        };
        let u = stream.get2(dims::at(k, bsdf_u));
        let s = view.sample_one(stream.get1(dims::at(k, bsdf_u + 2)), u);
        if s.weight.iter().all(|&w| w <= 0.0) {
            return;
        }
        let d = Vec3A::from(frame.to_world(s.wo)).normalize();
        let Some(fix) = side_factor(&v, from, d, light) else {
            return;
        };
        beta = std::array::from_fn(|c| beta[c] * s.weight[c] * fix);
        // The density of sampling `from` had the walk come the other way.
        let (back, view_back) = shading(scene, shape, v.ns, d, stream.sampler());
        let rev = view_back.eval_pdf_one(frame_local(&back, from)).1;
        let n = path.len();
        path[n - 2].pdf_rev = convert(rev, &v, &path[n - 2]);
        // Past vertex `rr_depth` (`v` is vertex `n − 1`).
        if n as u32 > ctx.settings.rr_depth {
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
pub(super) fn frame_local(frame: &Frame<f32>, v: Vec3A) -> [f32; 3] {
    frame.to_local(v.to_array())
}

/// The factor of the BSDF at `v` for light between `from` and `to`: on a
/// light subpath Veach's correction `K` ([`shading_correction`]), on a
/// camera subpath 1; `None` for a direction on different sides of the
/// shading and the geometric normal (a light leak, refused on both
/// subpaths alike, so that every strategy agrees on which paths exist).
fn side_factor(v: &Vertex, from: Vec3A, to: Vec3A, light: bool) -> Option<f32> {
    let k = shading_correction(v.ns, v.ng, from, to)?;
    Some(if light { k } else { 1.0 })
}

/// A density per steradian at `from` toward `to`, per unit area at `to`
/// (`|cos θ_to| / d²`; no cosine at the lens), kept per steradian toward
/// the environment.
pub(super) fn convert(pdf: f32, from: &Vertex, to: &Vertex) -> f32 {
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
pub(super) fn direction(a: &Vertex, b: &Vertex) -> Vec3A {
    match (a.kind, b.kind) {
        (_, Kind::Environment) => b.p,
        (Kind::Environment, _) => -a.p,
        _ => (b.p - a.p).normalize_or_zero(),
    }
}

/// The density (per area at `next`) with which vertex `v`, reached from
/// `prev`, samples `next` ([`convert`] of its density per steradian).
pub(super) fn pdf(ctx: &Ctx, v: &Vertex, prev: Option<&Vertex>, next: &Vertex) -> f32 {
    let to = direction(v, next);
    let per_sr = match v.kind {
        Kind::Camera => ctx.scene.camera().pdf_direction(v.p, to, ctx.tau),
        Kind::Surface { shape } => {
            let Some(prev) = prev else {
                return pdf_light(ctx, v, next);
            };
            let from = direction(v, prev);
            // Only evaluated: any frame serves.
            let (frame, view) = shading(ctx.scene, shape, v.ns, from, Sampler::Independent);
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
pub(super) fn pdf_light(ctx: &Ctx, v: &Vertex, next: &Vertex) -> f32 {
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
pub(super) fn pdf_light_origin(ctx: &Ctx, v: &Vertex) -> f32 {
    match v.kind {
        Kind::Environment => ctx.scene.environment_pdf(v.p),
        Kind::Surface { shape } | Kind::Light { shape } => ctx.scene.emission_pdf(shape),
        Kind::Camera => 0.0,
    }
}

/// The radiance vertex `v` (a light, or a surface of an area light) emits
/// toward `toward`.
pub(super) fn emitted(ctx: &Ctx, v: &Vertex, toward: &Vertex) -> Option<[f32; 3]> {
    match v.kind {
        Kind::Environment => ctx.scene.environment().map(|env| env.eval(v.p)),
        Kind::Surface { shape } | Kind::Light { shape } => {
            ctx.scene.emitted(shape, v.ng, direction(v, toward))
        }
        Kind::Camera => None,
    }
}

/// `f · |cos θ_out|` at surface vertex `v` for light between `prev` and
/// `next`, times [`side_factor`] (`light`: on a light subpath, where light
/// arrives from `prev`; else it arrives from `next`).
pub(super) fn scatter(
    ctx: &Ctx,
    v: &Vertex,
    prev: &Vertex,
    next: &Vertex,
    light: bool,
) -> [f32; 3] {
    let Kind::Surface { shape } = v.kind else {
        return [0.0; 3];
    };
    let (from, to) = (direction(v, prev), direction(v, next));
    let Some(fix) = side_factor(v, from, to, light) else {
        return [0.0; 3];
    };
    // Only evaluated: any frame serves.
    let (frame, view) = shading(ctx.scene, shape, v.ns, from, Sampler::Independent);
    let wo = frame_local(&frame, to);
    let f = view.eval_pdf_one(wo).0;
    let s = wo[2].abs() * fix;
    f.map(|x| x * s)
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
    let u = stream.get1_then2(choice, position);
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

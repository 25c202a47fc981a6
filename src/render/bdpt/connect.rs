//! Bidirectional path tracing's strategies: each way `(s, t)` of joining
//! the subpaths, its contribution and its MIS weight.

use super::super::integrator::{offset, shadow_ray, unoccluded};
use super::super::scene::Scene;
use super::super::splat::Splat;
use super::subpath::{Kind, Vertex, direction, emitted, pdf, pdf_light, pdf_light_origin, scatter};
use super::{Ctx, Subpaths, dims, strategy_index};
use crate::mis::Heuristic;
use crate::sampler::Stream;

/// Every strategy `(s, t)` of the subpaths in `sub`, splatted to `out`
/// (camera paths' at `film`); with [`Settings::strategies`], each also to
/// its weighted and unweighted images.
pub(super) fn connect_all(
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
            let Some((value, w, at)) = connect(ctx, cam, light, s, t, stream) else {
                continue;
            };
            let weighted = value.map(|v| v * w);
            match at {
                Some(at) => out.push(Splat {
                    film: at,
                    value: weighted,
                    channel: 0,
                }),
                None => total = std::array::from_fn(|c| total[c] + weighted[c]),
            }
            if ctx.settings.strategies {
                let channel = 1 + 2 * strategy_index(s, t) as u32;
                let film = at.unwrap_or(film);
                out.push(Splat {
                    film,
                    value: weighted,
                    channel,
                });
                out.push(Splat {
                    film,
                    value,
                    channel: channel + 1,
                });
            }
        }
    }
    if total.iter().any(|&v| v != 0.0) {
        out.push(Splat {
            film,
            value: total,
            channel: 0,
        });
    }
}

/// Strategy `(s, t)`: its contribution, its MIS weight and, for `t = 1`,
/// where on the film it lands.
pub(super) fn connect(
    ctx: &Ctx,
    cam: &[Vertex],
    light: &[Vertex],
    s: usize,
    t: usize,
    stream: &mut Stream,
) -> Option<([f32; 3], f32, Option<[f32; 2]>)> {
    let scene = ctx.scene;
    let pt = &cam[t - 1];
    let mut sampled = None;
    let mut at = None;
    let value: [f32; 3] = if s == 0 {
        let le = emitted(ctx, pt, &cam[t - 2])?;
        std::array::from_fn(|c| le[c] * pt.beta[c])
    } else if t == 1 {
        let (value, film, lens) = to_camera(ctx, light, s, stream)?;
        sampled = Some(lens);
        at = Some(film);
        value
    } else if s == 1 {
        if !matches!(pt.kind, Kind::Surface { .. }) {
            return None;
        }
        let k = t as u32 - 2;
        let u = stream.get1_then2(
            dims::at(k, dims::CAMERA_LIGHT),
            dims::at(k, dims::CAMERA_LIGHT + 1),
        );
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
        if f.iter().all(|&v| v == 0.0)
            || scene.occluded(&shadow_ray(pt.p, pt.ng, ls.d, ls.end()), ctx.tau)
        {
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
    Some((value, mis_weight(ctx, cam, light, sampled, s, t), at))
}

/// The `t = 1` strategy for light vertex `y_{s−1}` (`s ≥ 2`): a lens point
/// drawn for it, the light it sends there (`β_s f |cos| K W`, not weighted),
/// where on the film it lands, and the lens point as a camera vertex.
/// Light tracing is this strategy alone.
pub(in crate::render) fn to_camera(
    ctx: &Ctx,
    light: &[Vertex],
    s: usize,
    stream: &mut Stream,
) -> Option<([f32; 3], [f32; 2], Vertex)> {
    let qs = &light[s - 1];
    if !matches!(qs.kind, Kind::Surface { .. }) {
        return None;
    }
    let u = stream.get2(dims::at(s as u32 - 2, dims::LIGHT_LENS));
    let c = ctx.scene.camera().sample_direction(qs.p, u, ctx.tau)?;
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
    if f.iter().all(|&v| v == 0.0) || !visible(ctx.scene, qs, &lens, ctx.tau) {
        return None;
    }
    Some((
        std::array::from_fn(|i| qs.beta[i] * f[i] * c.weight),
        c.film,
        lens,
    ))
}

/// Whether surface vertex `a` sees vertex `b` (a surface or the lens).
pub(super) fn visible(scene: &Scene, a: &Vertex, b: &Vertex, tau: f32) -> bool {
    let d = direction(a, b);
    let end = if b.on_surface() {
        offset(b.p, b.ng, -d)
    } else {
        b.p
    };
    unoccluded(scene, offset(a.p, a.ng, d), end, tau)
}

/// The MIS weight of strategy `(s, t)` (`sampled`: the vertex that the
/// `s = 1` or `t = 1` strategy drew in place of `y₀` or `z₀`): one over
/// the sum, over the strategies that make the same path, of their density
/// relative to this one's (each ratio to the heuristic's power), the
/// ratios being products of `p← / p→` along the subpaths from the
/// connection.
pub(super) fn mis_weight(
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
    // In f64: products of many ratios (squared for the power heuristic)
    // overflow f32.
    let power = |x: f64| match ctx.settings.heuristic {
        Heuristic::Balance => x,
        Heuristic::Power => x * x,
    };
    let ratio = |v: &Vertex| {
        if v.pdf_fwd > 0.0 {
            power(f64::from(v.pdf_rev) / f64::from(v.pdf_fwd))
        } else {
            0.0
        }
    };
    let mut sum = 0.0f64;
    let mut r = 1.0f64;
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
    // A path no other strategy can make has weight 1; one that others make
    // infinitely more likely, weight 0 (never NaN).
    let w = 1.0 / (1.0 + sum);
    if w.is_finite() { w as f32 } else { 0.0 }
}

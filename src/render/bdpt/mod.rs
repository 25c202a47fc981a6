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

mod connect;
mod subpath;

use super::Settings;
use super::scene::Scene;
use super::splat::Splat;
use super::splatting::Paths;
use crate::sampler::Stream;
use connect::connect_all;
pub(super) use connect::to_camera;
use subpath::camera_subpath;
pub(super) use subpath::{Vertex, light_subpath};

/// The dimensions of a sample, in this order: the camera's, the light
/// subpath's start, light tracing's connection of a light to the camera
/// (light tracing only), then [`dims::PER_DEPTH`] per depth `k`
/// ([`dims::at`]): the camera subpath's vertex `z_{k+1}`, then the light
/// subpath's `y_{k+1}`. Light tracing ([`ptracer`](super::ptracer)) takes
/// the same dimensions for its light subpaths.
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
    /// Light tracing: the light joined straight to the camera.
    pub const DIRECT_CHOICE: u32 = 10;
    /// Light tracing: its point, or the film point for the environment (2D).
    pub const DIRECT_POSITION: u32 = 11;
    /// Light tracing: the lens point of that connection (2D).
    pub const DIRECT_LENS: u32 = 13;
    /// Dimensions before depth 0.
    pub const START: u32 = 15;
    /// Camera vertex: the BSDF sample (3D: its direction, 2D, then its
    /// part).
    pub const CAMERA_BSDF: u32 = 0;
    /// Camera vertex: next-event estimation's light (1D) and point (2D).
    pub const CAMERA_LIGHT: u32 = 3;
    /// Camera vertex: Russian roulette.
    pub const CAMERA_ROULETTE: u32 = 6;
    /// Light vertex: the lens point of its connection to the camera (2D).
    pub const LIGHT_LENS: u32 = 7;
    /// Light vertex: the BSDF sample (3D: its direction, 2D, then its
    /// part).
    pub const LIGHT_BSDF: u32 = 9;
    /// Light vertex: Russian roulette.
    pub const LIGHT_ROULETTE: u32 = 12;
    /// Dimensions per depth.
    pub const PER_DEPTH: u32 = 13;

    /// Dimension `offset` at depth `k` (the camera's vertex `z_{k+1}`,
    /// the light's `y_{k+1}`).
    #[inline]
    pub fn at(k: u32, offset: u32) -> u32 {
        START
            .saturating_add(PER_DEPTH.saturating_mul(k))
            .saturating_add(offset)
    }
}

/// The strategies `(s, t)` of paths of at most `max_depth` segments (at
/// most 64), in the order of their images: by length `s + t − 1`
/// segments, then by `s`.
pub fn strategies(max_depth: u32) -> Vec<(u32, u32)> {
    (0..max_depth.min(64))
        .flat_map(|k| (0..=k + 1).map(move |s| (s, k + 2 - s)))
        .filter(|&st| st != (1, 1))
        .collect()
}

/// The position of strategy `(s, t)` in [`strategies`]: with `k = s + t
/// − 2`, the first of length `k + 1` is preceded by `Σ_{j<k} (j + 2) − 1`
/// (the `(1, 1)` strategy left out).
fn strategy_index(s: usize, t: usize) -> usize {
    let k = s + t - 2;
    if k == 0 { 0 } else { k * (k + 3) / 2 - 1 + s }
}

/// What the walks and connections need.
pub(super) struct Ctx<'a> {
    /// The scene.
    pub(super) scene: &'a Scene,
    /// The settings.
    pub(super) settings: &'a Settings,
    /// The sample's time in the shutter.
    pub(super) tau: f32,
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

    /// The render, then with [`Settings::strategies`] each strategy's
    /// weighted and unweighted image.
    fn channels(&self) -> u32 {
        if self.settings.strategies {
            1 + 2 * strategies(self.settings.max_depth()).len() as u32
        } else {
            1
        }
    }

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strategies_are_numbered_by_depth_then_s() {
        let all = strategies(5);
        assert_eq!(all[..4], [(0, 2), (0, 3), (1, 2), (2, 1)]);
        for (i, &(s, t)) in all.iter().enumerate() {
            assert_eq!(strategy_index(s as usize, t as usize), i, "{s} {t}");
        }
        // Depth 0 has one, depth k ≥ 1 has k + 2.
        assert_eq!(all.len(), 1 + 3 + 4 + 5 + 6);
    }
}

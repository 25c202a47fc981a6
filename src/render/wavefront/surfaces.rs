//! The surface points of a bounce's hits ([`Wavefront::find_surfaces`]).

use super::{Path, Wavefront};
#[cfg(doc)]
use crate::render::accel::Accel;
use crate::render::accel::Ahead;
use crate::render::scene::Scene;

/// The fewest primitives for which the surface points' reads are asked
/// for ahead ([`Accel::prefetch_point`]): smaller tables stay in the
/// caches.
const PREFETCH_MIN: usize = 1 << 14;

/// How many hits ahead each step of [`Accel::prefetch_point`] runs.
const AHEAD: [(usize, Ahead); 3] = [(30, Ahead::Entry), (20, Ahead::Face), (10, Ahead::Vertices)];

impl Wavefront {
    /// The shape and surface point of each path's hit (`depth`: the
    /// paths' bounces), into `self.surfaces`, in a loop of their own: the
    /// reads of the hit primitives overlap.
    pub(super) fn find_surfaces(&mut self, scene: &Scene, depth: u32) {
        self.surfaces.clear();
        let hits = self.paths.iter().zip(&self.hits);
        if scene.has_movers() {
            let surface = |(path, hit): (&Path, _)| scene.surface(&path.ray, hit, path.time);
            self.surfaces.extend(hits.map(surface));
            return;
        }
        // Without the moving shapes' call in the loop: its result,
        // returned through memory, was merged with the still shapes'
        // through the stack, where a 4-byte store read back by a 16-byte
        // load stalled every path (1.8 % of the plane's direct render).
        let surface = |(path, hit): (&Path, _)| scene.still_surface(&path.ray, hit);
        let accel = scene.accel();
        if depth == 0 || accel.primitives().len() < PREFETCH_MIN {
            self.surfaces.extend(hits.map(surface));
            return;
        }
        // Tables beyond the caches, and hits scattered over them (the
        // camera rays' lie close together): each hit's primitive, face and
        // vertices asked for ahead, in three steps.
        for (k, vertex) in hits.enumerate() {
            for (distance, step) in AHEAD {
                if let Some(h) = self.hits.get(k + distance) {
                    accel.prefetch_point(h.primitive, step);
                }
            }
            self.surfaces.push(surface(vertex));
        }
    }
}

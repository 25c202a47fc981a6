//! The direct and path integrators ([`super::integrator`]) over a batch of
//! camera samples at once, one bounce at a time (a wavefront):
//!
//! ```text
//! loop while paths remain:
//!   surface each path's shape and surface point at its hit (on large
//!           tables, the reads of the hits ahead prefetched)
//!   numbers the numbers the shading below will ask for, drawn together
//!           (samplers other than the independent one: `sampler::batch`)
//!   begin   each path at its hit, in one pass: its emission; its light
//!           sample (an area light's drawn there, the environment map's
//!           queued) and its BSDF sample's numbers; its row of the BSDF
//!           kernel. Then the queued environment samples together
//!           (`CellSampler::sample_many`, or by inversion
//!           `EnvMap::sample_into` for the other samplers), written into
//!           their rows
//!   shade   the BSDF kernel over every row at SIMD width (`shade`: the
//!           frame, the BRDF toward the light sample and its MIS weight,
//!           the BSDF sample), then each path's light sample's light kept
//!           with its shadow ray, its next ray, roulette
//!   occlude every shadow ray of the batch, one stream; add the light of
//!           those that reach it
//!   trace   every next ray, one stream; rays that leave the scene go to
//!           the batch's escaped rays ([`Escaped`]). Toward the last
//!           vertex, where only an area light's emission counts, a ray
//!           that meets another shape ends its path: when the scene's
//!           area lights are a few primitives, the nearest of them on
//!           the ray is found alone, and the ray is tested as shadow
//!           rays are, up to it (or without end)
//! ```
//!
//! Each ray tracer call then serves hundreds of rays: Embree's streams, and
//! loops whose memory reads (the hit primitives', the light tables')
//! overlap from one path to the next.
//!
//! The image is the one the same paths give traced one at a time: each
//! path draws its numbers from its pixel's stream in its own order (the
//! independent sampler's generator travels with the path), and adds its
//! light to its sample in the same order (the emission found at a vertex,
//! then that vertex's light sample, then the next vertex's).

use glam::Vec3A;

use super::accel::{Hit, Subset};
use super::embree;
use super::integrator::{Escaped, Settings, Strategy, add_scaled, dims, ends_after_light, ray_to};
use super::numbers::{Numbers, bounce_dims, draws_light_choice};
use super::scene::{InvertedSamples, LightSample, Scene};
use super::shape::{Ray, SurfacePoint};
use crate::alloc;
use crate::envmap::EnvSample;
use crate::error::Result;
use crate::rng::Rng;
use crate::sampler::batch::{Dim, Drawn};
use crate::sampler::{Sampler, Stream};
use shade::{Begun, Bounce, KernelRows};

/// A path between two bounces.
#[derive(Clone, Debug)]
struct Path {
    /// Its sample's index in the batch (where its light goes).
    slot: u32,
    /// Its pixel's stream, among the batch's.
    pixel: u32,
    /// Its sample's index in the pixel's sequence.
    index: u32,
    /// Shading points so far (0: the camera ray's).
    depth: u32,
    /// The ray toward the next shading point.
    ray: Ray,
    /// The shading point the ray left (emitter sampling's densities are
    /// seen from there).
    from: Vec3A,
    /// The throughput `β`.
    beta: [f32; 3],
    /// The density of the BSDF sample that made `ray`.
    bsdf_pdf: f32,
    /// The time of the sample within the shutter.
    time: f32,
    /// The independent sampler's generator, where the path left it.
    rng: Option<Rng>,
}

/// Light of a light sample, added to sample `slot` when its shadow ray is
/// clear: `β · fc · s`.
#[derive(Clone, Copy, Debug)]
struct Unshadowed {
    slot: u32,
    time: f32,
    beta: [f32; 3],
    fc: [f32; 3],
    s: f32,
}

/// A camera sample that starts a path.
#[derive(Clone, Debug)]
pub struct CameraSample {
    /// Its index in the batch (where its light goes).
    pub slot: u32,
    /// Its pixel's stream, among the batch's.
    pub pixel: u32,
    /// Its index in the pixel's sequence.
    pub index: u32,
    /// The camera ray.
    pub ray: Ray,
    /// Where the camera ray first meets the scene.
    pub hit: Option<Hit>,
    /// The time of the sample within the shutter.
    pub time: f32,
    /// The independent sampler's generator after the camera's draws
    /// (`None` for the other samplers).
    pub rng: Option<Rng>,
}

/// One thread's paths in flight and their rays (reused from batch to
/// batch).
#[derive(Default)]
pub struct Wavefront {
    paths: Vec<Path>,
    /// Where each path's ray meets the scene, and the shape and surface
    /// point there.
    hits: Vec<Hit>,
    surfaces: Vec<(u32, SurfacePoint)>,
    /// What the stream of next rays found (toward the last vertex, the
    /// nearest emitter on each: [`Wavefront::last_vertices`]).
    found: Vec<Option<Hit>>,
    rays: Vec<Ray>,
    shadows: Vec<Unshadowed>,
    shadow_rays: Vec<Ray>,
    blocked: Vec<bool>,
    /// The paths whose environment-map light samples are drawn together,
    /// by the map's cell sampler (its bits and the point's numbers) or by
    /// inversion (the numbers).
    by_cells: Waiting<(u64, [f32; 2])>,
    by_inversion: Waiting<[f64; 2]>,
    env_samples: Vec<EnvSample<f32>>,
    inverted: InvertedSamples,
    /// The points on area lights of the bounce's light samples (those of
    /// the paths whose [`Begun::to_point`] holds, in the paths' order):
    /// where their shadow rays end.
    light_points: Vec<SurfacePoint>,
    /// What each path that goes on past [`Bounce::begin`] at this bounce
    /// keeps for [`Bounce::finish`].
    begun: Vec<Begun>,
    /// Those paths' rows into the BSDF kernels, and their rows out.
    kernel_rows: KernelRows,
    /// The numbers of the bounce drawn beforehand (the samplers other than
    /// the independent one): the dimensions every path's vertex asks for,
    /// and their values, path after path.
    dims: Vec<Dim>,
    drawn: Drawn,
    stream: embree::Stream,
    /// The rays of the batch that left the scene.
    pub escaped: Escaped,
}

impl Wavefront {
    /// Room for the paths of `n` camera samples, every path and ray of the
    /// last batch forgotten.
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the memory cannot be had.
    pub fn start(&mut self, n: usize) -> Result<()> {
        const WHAT: &str = "a batch of paths";
        macro_rules! clear_and_reserve {
            ($($v:expr),*) => {{
                $($v.clear();)*
                alloc::reserve_each!(n, WHAT; $($v),*)
            }};
        }
        clear_and_reserve!(
            self.paths,
            self.hits,
            self.surfaces,
            self.found,
            self.rays,
            self.shadows,
            self.shadow_rays,
            self.blocked,
            self.by_cells.at,
            self.by_cells.draws,
            self.by_inversion.at,
            self.by_inversion.draws,
            self.env_samples,
            self.light_points,
            self.begun
        )?;
        self.kernel_rows.reserve(n, WHAT)?;
        self.escaped.clear();
        self.escaped.reserve(n)
    }

    /// Starts the path of camera sample `c`: none when it leaves the scene
    /// (its ray goes to the escaped rays, unless emitters are hidden), nor
    /// when the paths end at its hit (`max_depth` 1) and that hit is not on
    /// an area light.
    #[inline]
    pub fn push(&mut self, scene: &Scene, settings: &Settings, c: CameraSample) {
        if settings.max_depth() == 0 {
            return;
        }
        let Some(hit) = c.hit else {
            if scene.environment().is_some() && !settings.hide_emitters {
                self.escaped.push(c.slot, c.ray.d, [1.0; 3], None);
            }
            return;
        };
        // Paths that end at the camera ray's hit (`max_depth` 1) count only
        // an area light's emission there, as at any last vertex: the
        // others need no surface point.
        if settings.max_depth() == 1 && !scene.hits_emitter(&hit) {
            return;
        }
        self.paths.push(Path {
            slot: c.slot,
            pixel: c.pixel,
            index: c.index,
            depth: 0,
            ray: c.ray,
            from: c.ray.o,
            beta: [1.0; 3],
            bsdf_pdf: 0.0,
            time: c.time,
            rng: c.rng,
        });
        self.hits.push(hit);
    }

    /// Traces every path pushed since [`Wavefront::start`] to its end,
    /// adding its light to `l[slot]` (`streams[pixel]` giving its numbers),
    /// except the environment's: that of the rays that left the scene is
    /// added by [`super::integrator::add_escaped`] of
    /// [`Wavefront::escaped`].
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the ray streams' memory cannot be had;
    /// the paths left are then meaningless ([`Wavefront::start`] again
    /// before the next `trace`).
    pub fn trace(
        &mut self,
        scene: &Scene,
        settings: &Settings,
        streams: &mut [Stream],
        l: &mut [[f32; 3]],
    ) -> Result<()> {
        while !self.paths.is_empty() {
            self.rays.clear();
            self.shadows.clear();
            self.shadow_rays.clear();
            // The paths in flight have all made as many bounces.
            let depth = self.paths.first().map_or(0, |p| p.depth);
            debug_assert!(self.paths.iter().all(|p| p.depth == depth));
            self.find_surfaces(scene, depth);
            // The numbers the shading will ask for, drawn together.
            self.dims.clear();
            self.drawn.values.clear();
            if streams
                .first()
                .is_some_and(|s| s.sampler() != Sampler::Independent)
            {
                let many = scene.chooses_among_lights();
                bounce_dims(settings, many, depth, &mut self.dims);
                let samples = self.paths.iter().map(|p| (p.pixel, p.index));
                self.drawn.draw(streams, samples, &self.dims)?;
            }
            self.begin_vertices(scene, settings, (streams, depth), l);
            self.shade(scene, settings, (streams, depth));
            self.blocked.clear();
            scene
                .accel()
                .occluded_many(&self.shadow_rays, &mut self.stream, &mut self.blocked)?;
            for ((u, ray), &blocked) in self
                .shadows
                .iter()
                .zip(&self.shadow_rays)
                .zip(&self.blocked)
            {
                let blocked = blocked || scene.moves() && scene.movers_occlude(ray, u.time);
                if !blocked {
                    add_scaled(&mut l[u.slot as usize], u.beta, u.fc, u.s);
                }
            }
            // The next rays lead to the last vertex: only an area light's
            // emission counts there, and whether a ray reaches one (or
            // leaves the scene) is a shadow ray's test when the scene's
            // emitters are few (`Scene::emitters`); else by the nearest
            // hit, below.
            let last = depth + 2 >= settings.max_depth();
            if let Some(emitters) = scene.emitters().filter(|_| last) {
                self.last_vertices(scene, settings, emitters)?;
                continue;
            }
            self.found.clear();
            scene
                .accel()
                .intersect_many(&self.rays, false, &mut self.stream, &mut self.found)?;
            // The paths whose next ray meets the scene stay, with their
            // hits (toward the last vertex, only those on an area light);
            // the others' rays go to the escaped rays.
            debug_assert_eq!(self.found.len(), self.paths.len());
            self.hits.clear();
            let mut stream_hits = self.found.iter();
            self.paths.retain(|path| {
                let Some(&found) = stream_hits.next() else {
                    debug_assert!(false, "a path without its ray's hit");
                    return false;
                };
                let hit = if scene.moves() {
                    scene.intersect_movers(&path.ray, path.time, found)
                } else {
                    found
                };
                if let Some(hit) = hit {
                    // Another shape at the last vertex: the path ends
                    // without its surface point.
                    if last && !scene.hits_emitter(&hit) {
                        return false;
                    }
                    self.hits.push(hit);
                    return true;
                }
                escape(scene, settings, &mut self.escaped, path);
                false
            });
        }
        Ok(())
    }

    /// The first step of shading every path in flight at its hit (at
    /// bounce `depth`), in one pass: its emission added to `l[slot]`; then,
    /// unless the vertex is the last (whose shading ends there: every path
    /// is removed), its light sample (none under BSDF sampling; the point
    /// of an area light's into `self.light_points`), the numbers of its
    /// BSDF sample, and its row of the BSDF kernel ([`Bounce::begin`]).
    /// The light's choice and position numbers (then, for an environment
    /// map's cell sampler, 64 random bits) are the first the vertex asks
    /// for, the BSDF sample's next.
    /// The environment map's samples are drawn together after the pass
    /// (their table reads overlap, and their directions are computed at
    /// SIMD width), and written into their rows then.
    fn begin_vertices(
        &mut self,
        scene: &Scene,
        settings: &Settings,
        (streams, depth): (&mut [Stream], u32),
        l: &mut [[f32; 3]],
    ) {
        let Wavefront {
            paths,
            hits,
            surfaces,
            dims: wanted,
            drawn,
            by_cells,
            by_inversion,
            env_samples,
            inverted,
            light_points,
            begun,
            kernel_rows,
            ..
        } = self;
        debug_assert_eq!(hits.len(), paths.len());
        debug_assert_eq!(surfaces.len(), paths.len());
        light_points.clear();
        by_cells.clear();
        by_inversion.clear();
        begun.clear();
        kernel_rows.clear();
        // (Every pixel's stream is of the render's sampler.)
        let sampler = streams
            .first()
            .map_or(Sampler::Independent, Stream::sampler);
        let bounce = Bounce { scene, settings };
        let last = depth + 1 >= settings.max_depth();
        let lights = settings.strategy != Strategy::Bsdf;
        let ends = ends_after_light(settings, depth);
        let many = scene.chooses_among_lights();
        let density = settings.env_density();
        let drawn = (&wanted[..], &drawn.values[..]);
        let vertices = paths.iter_mut().zip(hits.iter().zip(&*surfaces));
        for (k, (path, (hit, (shape, sp)))) in vertices.enumerate() {
            bounce.emit(path, (hit.t, (*shape, sp)), &mut l[path.slot as usize]);
            if last {
                continue;
            }
            // An area light's sample (drawn here; the environment map's are
            // drawn together below).
            let mut ls = None;
            let bsdf_numbers = with_numbers(streams, drawn, (k, path), |numbers| {
                if lights {
                    let choice = if draws_light_choice(many, numbers.stream.sampler()) {
                        numbers.get1(dims::bounce(depth, dims::LIGHT_CHOICE))
                    } else {
                        0.0
                    };
                    let u = numbers.get2(dims::bounce(depth, dims::LIGHT_POSITION));
                    // The independent sampler picks environment cells from
                    // extra random bits (an alias table); the others by
                    // inversion, which keeps their stratification.
                    if let Some(light) = scene.choose_light(choice, density) {
                        let bits = light
                            .cells()
                            .and(numbers.independent())
                            .map(|r| r.next_u64());
                        match bits {
                            // A map's cell: drawn with the bounce's others.
                            Some(bits) => by_cells.push(k, (bits, u)),
                            // A map by inversion (the other samplers, or a
                            // map without cells): likewise.
                            None if light.is_environment() && scene.environment_map().is_some() => {
                                by_inversion.push(k, u.map(f64::from));
                            }
                            None => ls = scene.sample_chosen(light, sp.p, u, None),
                        }
                    }
                }
                // The direction from the 2D request, the part from the 1D
                // one (drawn in this order, the independent sampler's
                // numbers are those of `PhongView::sample`'s `[u0, u1,
                // part]`).
                if ends {
                    ([0.0; 2], 0.0)
                } else {
                    let u = numbers.get2(dims::bounce(depth, dims::BSDF_DIRECTION));
                    (u, numbers.get1(dims::bounce(depth, dims::BSDF_COMPONENT)))
                }
            });
            let (b, row) = bounce.begin(
                (k, path),
                (*shape, sp),
                (ls.as_ref(), bsdf_numbers),
                sampler,
            );
            light_points.extend(ls.as_ref().and_then(LightSample::end));
            begun.push(Begun {
                row: kernel_rows.push(b.diffuse, row),
                ..b
            });
        }
        if last {
            paths.clear();
            return;
        }
        let mut light = |k: u32, ls: Option<LightSample>| {
            // (Every path has its row here: `begun[k]` is path `k`'s.)
            debug_assert!(begun.get(k as usize).is_some_and(|b| b.k == k));
            if let (Some(ls), Some(b)) = (&ls, begun.get(k as usize)) {
                kernel_rows.set_light(b, ls);
            }
        };
        scene.sample_environment_cells(&by_cells.draws, env_samples, density, |i, ls| {
            light(by_cells.at[i], ls);
        });
        scene.sample_environment_inverted(&by_inversion.draws, inverted, density, |i, ls| {
            light(by_inversion.at[i], ls);
        });
    }

    /// The last two steps of shading every path in flight (at bounce
    /// `depth`, begun by [`Wavefront::begin_vertices`]): the BSDF kernel
    /// over every row, then each path's light sample's light kept with its
    /// shadow ray (`self.shadows`, `self.shadow_rays`; up to its point in
    /// `self.light_points` if on an area light) and its next ray
    /// (`self.rays`). The paths that end are removed; the others keep their
    /// order, so that they line up with their rays.
    fn shade(
        &mut self,
        scene: &Scene,
        settings: &Settings,
        (streams, depth): (&mut [Stream], u32),
    ) {
        let Wavefront {
            paths,
            surfaces,
            light_points,
            dims: wanted,
            drawn,
            begun,
            kernel_rows,
            shadows,
            shadow_rays,
            rays,
            ..
        } = self;
        debug_assert_eq!(begun.len(), paths.len());
        let bounce = Bounce { scene, settings };
        let drawn = (&wanted[..], &drawn.values[..]);
        let mut points = light_points.iter();
        kernel_rows.run(settings, depth);
        let mut rows_out = kernel_rows.out(begun);
        paths.retain_mut(|path| {
            let Some((b, rows)) = rows_out.next() else {
                debug_assert!(false, "a path without its BSDF sample");
                return false;
            };
            let k = b.k as usize;
            let roulette = |path: &mut Path, dim| {
                with_numbers(streams, drawn, (k, path), |numbers| numbers.get1(dim))
            };
            let vertex = (b, &surfaces[k].1, rows);
            let point = if b.to_point { points.next() } else { None };
            debug_assert!(
                !b.to_point || point.is_some(),
                "a path without its light's point"
            );
            let next = bounce.finish(path, vertex, point, (shadows, shadow_rays), roulette);
            let Some(ray) = next else {
                return false;
            };
            rays.push(ray);
            true
        });
        debug_assert!(points.next().is_none(), "a light's point without its path");
    }

    /// The last vertex of every path in flight, where only an area
    /// light's emission counts. A path whose ray meets one of the
    /// `emitters` (the nearest of them) with nothing before it keeps that
    /// hit (its emission is added at the next step); one whose ray leaves
    /// the scene goes to the escaped rays; the others end. Each ray is
    /// tested as a shadow ray is (an any-hit test, cheaper than finding the
    /// nearest hit): toward its emitter's point, moved off that surface
    /// ([`ray_to`]), or without end.
    ///
    /// # Errors
    /// [`crate::Error::Memory`] as [`Wavefront::trace`].
    fn last_vertices(
        &mut self,
        scene: &Scene,
        settings: &Settings,
        emitters: &Subset,
    ) -> Result<()> {
        self.found.clear();
        self.found.resize(self.rays.len(), None);
        emitters.intersect_many(&self.rays, &mut self.found);
        for ((ray, path), found) in self.rays.iter_mut().zip(&self.paths).zip(&self.found) {
            if let Some(hit) = found {
                let (_, y) = scene.surface(ray, hit, path.time);
                *ray = ray_to(ray.o, &y, ray.d);
            }
        }
        self.blocked.clear();
        scene
            .accel()
            .occluded_many(&self.rays, &mut self.stream, &mut self.blocked)?;
        self.hits.clear();
        let mut tests = self.rays.iter().zip(&self.blocked).zip(&self.found);
        self.paths.retain(|path| {
            let Some(((ray, &blocked), &found)) = tests.next() else {
                debug_assert!(false, "a path without its ray");
                return false;
            };
            if blocked || scene.moves() && scene.movers_occlude(ray, path.time) {
                return false;
            }
            match found {
                Some(hit) => self.hits.push(hit),
                None => escape(scene, settings, &mut self.escaped, path),
            }
            found.is_some()
        });
        Ok(())
    }
}

/// Keeps the ray of `path`, which leaves the scene, with the batch's
/// `escaped` rays when BSDF sampling counts the environment's light.
#[inline]
fn escape(scene: &Scene, settings: &Settings, escaped: &mut Escaped, path: &Path) {
    if scene.environment().is_some() && settings.strategy != Strategy::Emitter {
        let pdf = (settings.strategy == Strategy::Mis).then_some(path.bsdf_pdf);
        escaped.push(path.slot, path.ray.d, path.beta, pdf);
    }
}

/// `f` of the numbers of `path`'s vertex (`k`: its index among the
/// bounce's paths, whose numbers `drawn` were drawn beforehand), its
/// pixel's stream set to its sample. The independent sampler draws from a
/// copy of the generator the path carries, in the stream, and the path
/// then goes on from where the copy left ([`Rng::resume`]).
#[inline(always)]
fn with_numbers<T>(
    streams: &mut [Stream],
    drawn: (&[Dim], &[[f32; 2]]),
    (k, path): (usize, &mut Path),
    f: impl FnOnce(&mut Numbers) -> T,
) -> T {
    let stream = &mut streams[path.pixel as usize];
    stream.start(path.index);
    if let (Some(rng), Some(own)) = (stream.independent(), &path.rng) {
        rng.clone_from(own);
    }
    let mut numbers = Numbers::new(stream, drawn, k);
    let out = f(&mut numbers);
    if let (Some(rng), Some(own)) = (numbers.stream.independent(), path.rng.as_mut()) {
        own.resume(rng);
    }
    out
}

/// The paths (their indices in the bounce) whose environment-map light
/// samples are drawn together, with the numbers of each draw.
#[derive(Debug)]
struct Waiting<D> {
    at: Vec<u32>,
    draws: Vec<D>,
}

impl<D> Default for Waiting<D> {
    fn default() -> Self {
        Waiting {
            at: Vec::new(),
            draws: Vec::new(),
        }
    }
}

impl<D> Waiting<D> {
    fn clear(&mut self) {
        self.at.clear();
        self.draws.clear();
    }

    fn push(&mut self, path: usize, draw: D) {
        self.at.push(path as u32);
        self.draws.push(draw);
    }
}

mod shade;
mod surfaces;
#[cfg(test)]
mod tests;

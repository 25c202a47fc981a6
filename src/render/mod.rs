//! A compact renderer for envmap- and area-lit scenes: shapes in a BVH,
//! Phong and diffuse materials, a perspective or thin-lens camera, a film
//! with Mitsuba's box or Gaussian filter, motion blur of shapes and camera
//! ([`motion`]: each sample draws a time in the shutter, at which all its
//! rays are traced), and direct or path integrators by BSDF sampling,
//! emitter sampling or MIS ([`integrator`]).
//!
//! Pixel `(x, y)` is the mean of `spp` samples of its own: at uniform
//! positions inside it for the box filter (radius ½, as Mitsuba's `box`),
//! or drawn around its centre on the filter and weighted ([`filter`]); its
//! variance is that of the mean, `s² / spp` with `s²` the unbiased sample
//! variance, both from
//! sums that merge exactly ([`film`]). Each pixel draws from its own
//! [`Stream`] of the settings' [`Sampler`] (keyed by `seed` and the pixel
//! index), and each sample of the independent sampler from a PCG32
//! generator of its own (keyed by the pixel's key and the sample's index),
//! so the image does not depend on the thread count, on the order in which
//! rows are rendered, or on which samples were rendered before: a render of
//! samples `k .. k + n` ([`Samples`]) is a chunk of a larger one. The dimensions each random
//! decision takes are listed in [`integrator::dims`].
//!
//! Samples are rendered in batches of about `BATCH` (whole pixels of one
//! row): each sample's film and lens positions are drawn first, the
//! camera rays of the batch are made at SIMD width, the paths are traced
//! together one bounce at a time, in groups of at most `BATCH`
//! ([`wavefront`]: every shadow ray and every next ray of a group in one
//! stream), and the light
//! of every ray of a group that left the scene is looked up at its end
//! (vectorised, with the texel reads overlapping). The draws of a pixel
//! thus come in a fixed order, whatever the batch size or thread. The
//! samplers other than the independent one give a value that depends only
//! on the sample and the dimension, so the numbers the camera samples of a
//! batch, and then each bounce of its paths, will ask for are drawn
//! together beforehand at SIMD width ([`crate::sampler::batch`], the same
//! bits as one at a time). The independent sampler's camera numbers are
//! too: each sample starts a generator of its own, whose first draws they
//! are ([`crate::rng::first_floats`]); its paths' numbers are drawn as
//! they are asked for.
//!
//! Emitter sampling draws an environment map with the density of its own
//! [`crate::envmap::EnvMap::pdf`] (under MIS in the direct and path
//! integrators, of its compensated twin,
//! [`crate::envmap::EnvMap::compensated`]: [`scene::EnvDensity`]), but by
//! its [`crate::envmap::CellSampler`] (an alias table over the sampling
//! table's cells, in `f32`), all of a bounce's draws together: a cell costs
//! one load and no search of the table's running sums.

pub mod accel;
pub mod bdpt;
pub mod camera;
pub mod embree;
pub mod environment;
pub mod film;
pub mod filter;
pub mod geometry;
pub mod integrator;
pub mod mesh;
pub mod mesh_file;
pub mod motion;
mod numbers;
pub mod ptracer;
pub mod scene;
pub mod shape;
pub mod splat;
pub mod splatting;
#[cfg(test)]
mod tests;
pub mod wavefront;

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use rayon::prelude::*;

pub use integrator::{Heuristic, Integrator, Settings, Strategy, dims};
pub use scene::Scene;

use crate::alloc;
use crate::error::Result;
use crate::parallel;
use crate::rng::Rng;
use crate::sampler::batch::Drawn;
use crate::sampler::zorder::ZOrder;
use crate::sampler::{Sampler, Stream};
use accel::Hit;
use film::{Block, Sums};
use numbers::{camera_dims, camera_values};
use shape::Ray;
use wavefront::{CameraSample, Wavefront};

/// A finished (or stopped) render.
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Mean radiance per pixel, row-major RGB, row 0 at the top.
    pub mean: Vec<f32>,
    /// Variance of each pixel's mean per channel (`s²/spp`; infinite for
    /// `spp = 1`).
    pub variance: Vec<f32>,
    /// Variance of each pixel's mean luminance (Rec. 709 Y of the samples),
    /// which accounts for the correlation between channels.
    pub luminance_variance: Vec<f32>,
    /// The samples rendered: their blocks ([`film`]), the same for every
    /// pixel.
    pub blocks: Vec<Block>,
    /// The [`Sums`] of each pixel's blocks, pixel by pixel (row-major, then
    /// block), when [`Samples::keep_sums`] asked for them; else empty.
    pub sums: Vec<f64>,
    /// Whether `cancel` stopped the render before every row was done.
    pub cancelled: bool,
}

/// Which samples of each pixel's sequence a render takes.
#[derive(Clone, Copy, Debug)]
pub struct Samples {
    /// The first sample's index in the sequence.
    pub first: u64,
    /// Samples per pixel.
    pub count: u32,
    /// Length of the sequence (at least `first + count`): the count that
    /// the stratified and Sobol' samplers lay their patterns over.
    pub total: u64,
    /// Whether to return each pixel's [`Sums`] (to merge chunks later).
    pub keep_sums: bool,
}

impl Samples {
    /// All `spp` samples of a sequence of `spp`, sums not kept.
    pub fn all(spp: u32) -> Self {
        Samples {
            first: 0,
            count: spp,
            total: u64::from(spp),
            keep_sums: false,
        }
    }
}

/// Moves `stream` (of the pixel with index `pixel` and key `key`) to
/// sample `index`. The independent sampler restarts from a PCG32 generator
/// of the sample's own (seeded by the pixel's key and `index`, on stream
/// `pixel`): the numbers of a sample do not depend on which samples were
/// rendered before it, so a chunk of samples draws what a whole render
/// draws.
#[inline]
fn start_sample(stream: &mut Stream, key: u64, pixel: u64, index: u64) {
    // Other samplers index their patterns with it (their sequences have at
    // most u32::MAX samples, `Sampler::max_count`).
    stream.start(index as u32);
    if let Some(rng) = stream.independent() {
        let (seed, stream) = sample_seed(key, pixel, index);
        *rng = Rng::new(seed, stream);
    }
}

/// The seed and stream of the independent generator of sample `index` of
/// pixel `pixel`, whose stream's key is `key`.
#[inline(always)]
fn sample_seed(key: u64, pixel: u64, index: u64) -> (u64, u64) {
    (mix(key, index), pixel)
}

/// [`sample_seed`] of `count` samples in a row whose pixels have `spp`
/// samples each, from sample `start.1 < spp` of pixel `start.0` on (pixel
/// `p`'s `(pixel, key)` in `keys[p]`; sample `k`'s index `first_index +
/// k`), appended to `out`: one pixel's run at a time, each at SIMD width
/// (three 64-bit products per sample).
fn sample_seeds(
    keys: &[(u64, u64)],
    (mut p, mut k): (usize, usize),
    (count, spp): (usize, usize),
    first_index: u64,
    out: &mut Vec<(u64, u64)>,
) {
    crate::simd::dispatch(
        #[inline(always)]
        |_| {
            let mut left = count;
            while left > 0 {
                let run = (spp - k).min(left);
                let Some(&(pixel, key)) = keys.get(p) else {
                    debug_assert!(false, "samples past the row's pixels");
                    return;
                };
                let from = first_index + k as u64;
                out.extend((from..from + run as u64).map(|i| sample_seed(key, pixel, i)));
                (p, k, left) = (p + 1, 0, left - run);
            }
        },
    );
}

/// State shared with whoever watches a render from another thread.
#[derive(Debug, Default)]
pub struct Progress {
    /// Samples computed so far.
    pub samples: AtomicU64,
    /// Set to stop the render; rows not yet finished stay black.
    pub cancel: AtomicBool,
}

/// Camera samples per batch (at least one pixel's), and paths traced
/// together ([`wavefront`], in groups of at most this many, whose escaped
/// rays' environment light is looked up together:
/// [`integrator::add_escaped`]). Larger groups keep the later bounces'
/// streams and kernels wide as paths end. Against 256 (min of 7 renders,
/// two rounds alternated): the sphere on a plane (256², 64 spp), direct
/// MIS 287 → 275 ms and path 373–377 → 343 ms; the 2·10^5-triangle mesh,
/// direct 488–503 → 474–485 ms and path 839–884 → 800–806 ms. At 2048
/// and 4096 the plane's direct MIS took 290 and 301 ms.
const BATCH: usize = 1024;

/// One thread's buffers for a batch of camera samples (reused from batch
/// to batch).
#[derive(Default)]
struct Batch {
    paths: Wavefront,
    /// Radiance of each sample, pixel after pixel.
    radiance: Vec<[f32; 3]>,
    /// Film and lens positions of each sample.
    camera_u: Vec<[f32; 4]>,
    /// The reconstruction filter's weight of each sample (empty for the
    /// box filter, whose weights are 1).
    weights: Vec<f32>,
    /// The time of each sample within the shutter, in `[0, 1]` (empty, and
    /// 0 for every sample, in a scene where nothing moves).
    times: Vec<f32>,
    /// The independent sampler's generator of each sample after its camera
    /// draws.
    resume: Vec<Rng>,
    /// The seed and stream of each sample's generator, `BATCH` at a time.
    starts: Vec<(u64, u64)>,
    rays: Vec<Ray>,
    /// Where each camera ray first meets the scene.
    hits: Vec<Option<Hit>>,
    /// Embree's records of the camera rays.
    stream: embree::Stream,
    /// The camera's numbers drawn beforehand, `BATCH` samples at a time:
    /// the `j`-th sample's are the `(j mod BATCH)`-th of the batch.
    drawn: Drawn,
    /// One pixel's sums per block at a time.
    block_sums: Vec<Sums>,
}

impl Batch {
    /// The `spp` samples of each pixel `(x, y)`, `x` in `pixels`, into
    /// [`Batch::radiance`]: film and lens positions first (from the pixel's
    /// own stream, or, under the independent sampler, from each sample's
    /// own generator, which its path then carries), the camera rays of the
    /// whole batch at SIMD width, then the paths bounce by bounce in groups
    /// of at most `BATCH`, each group's escaped rays' light looked up
    /// together at its end.
    fn run(
        &mut self,
        scene: &Scene,
        settings: &Settings,
        seed: u64,
        samples: Samples,
        y: usize,
        pixels: std::ops::Range<usize>,
    ) -> Result<()> {
        let spp = samples.count;
        let (width, height) = scene.film();
        let (inv_width, inv_height) = (1.0 / width as f32, 1.0 / height as f32);
        let filter = scene.filter();
        let moves = scene.moves();
        self.radiance.clear();
        self.camera_u.clear();
        self.weights.clear();
        self.times.clear();
        self.resume.clear();
        // Reserved up front (samples grow with spp): a batch too big for
        // memory is an error, not an abort.
        let n = pixels.len() * spp.max(1) as usize;
        const WHAT: &str = "a batch of samples";
        alloc::reserve_each!(n, WHAT;
            self.camera_u, self.weights, self.times, self.resume, self.rays, self.hits, self.radiance)?;
        let mut streams: Vec<Stream> = alloc::with_capacity(pixels.len(), WHAT)?;
        let mut keys: Vec<(u64, u64)> = alloc::with_capacity(pixels.len(), WHAT)?;
        for x in pixels.clone() {
            let pixel = (y * width + x) as u64;
            let key = mix(seed, pixel);
            keys.push((pixel, key));
            streams.push(Stream::new(
                settings.sampler,
                key,
                Rng::new(key, pixel),
                samples.total,
                ZOrder::new((x, y), (width, height), samples.total, seed),
            ));
        }
        // A pinhole ignores the lens: only the independent sampler,
        // whose draws come in order, must draw it. A still scene draws no
        // time (likewise).
        let independent = settings.sampler == Sampler::Independent;
        let lens_drawn = scene.camera().has_lens() || independent;
        let camera = camera_dims((lens_drawn, moves));
        let spp = spp.max(1) as usize;
        let index = |k: usize| samples.first + k as u64;
        // The camera's numbers drawn together, BATCH samples at a time (a
        // pixel may have many more). `start`: the pixel (from the row's
        // first) and the number in it of the batch's first sample.
        for first in (0..n).step_by(BATCH) {
            let start = (first / spp, first % spp);
            let count = (first + BATCH).min(n) - first;
            let mut at = start;
            let batch = (0..count).map(|_| {
                let sample = at;
                at = next_sample(at, spp);
                sample
            });
            if independent {
                // Each sample's own generator, seeded as `start_sample`
                // seeds it; the paths go on from where these draws leave
                // it.
                self.starts.clear();
                sample_seeds(&keys, start, (count, spp), index(0), &mut self.starts);
                self.drawn.draw_fresh(&self.starts, &camera)?;
                self.resume.extend_from_slice(&self.drawn.generators);
            } else {
                let samples = batch.map(|(p, k)| (p as u32, index(k) as u32));
                self.drawn.draw(&mut streams, samples, &camera)?;
            }
            // Written in place (the room is reserved): no capacity check
            // per sample.
            let values = self.drawn.values.chunks_exact(camera.len());
            let base = self.camera_u.len();
            self.camera_u.resize(base + values.len(), [0.0; 4]);
            let mut sample = start;
            for (u, values) in self.camera_u[base..].iter_mut().zip(values) {
                let (film, lens, time) = camera_values(values, (lens_drawn, moves));
                let ([px, py], weight) = filter.sample((pixels.start + sample.0, y), film);
                *u = [px * inv_width, py * inv_height, lens[0], lens[1]];
                if filter.weighted() {
                    self.weights.push(weight);
                }
                if moves {
                    self.times.push(time);
                }
                sample = next_sample(sample, spp);
            }
        }
        self.rays.resize(self.camera_u.len(), Ray::default());
        scene
            .camera()
            .rays_into(&self.camera_u, &self.times, &mut self.rays);
        self.hits.clear();
        let times = &self.times;
        let time = |i: usize| if moves { times[i] } else { 0.0 };
        // The still shapes' hits as one coherent stream (the camera rays of
        // each pixel lie close together), then the moving shapes'.
        scene
            .accel()
            .intersect_many(&self.rays, true, &mut self.stream, &mut self.hits)?;
        for (i, (ray, hit)) in self.rays.iter_mut().zip(&mut self.hits).enumerate() {
            if moves {
                *hit = scene.intersect_movers(ray, time(i), *hit);
            }
            if settings.hide_emitters {
                *hit = integrator::skip_emitters(scene, ray, *hit, time(i));
            }
        }
        self.radiance.resize(self.rays.len(), [0.0; 3]);
        // The paths in groups of at most BATCH (a pixel's samples may be
        // many more): the memory of the paths in flight stays bounded.
        for first in (0..self.rays.len()).step_by(BATCH) {
            let slots = first..(first + BATCH).min(self.rays.len());
            self.paths.start(slots.len())?;
            // Slot `s` is sample `s mod spp` of pixel `s / spp`.
            let mut sample = (first / spp, first % spp);
            for slot in slots {
                let (pixel, k) = sample;
                self.paths.push(
                    scene,
                    settings,
                    CameraSample {
                        slot: slot as u32,
                        pixel: pixel as u32,
                        index: index(k) as u32,
                        ray: self.rays[slot],
                        hit: self.hits[slot],
                        time: time(slot),
                        // The path goes on from where the sample's camera
                        // draws left its numbers.
                        rng: self.resume.get(slot).cloned(),
                    },
                );
                sample = next_sample(sample, spp);
            }
            self.paths
                .trace(scene, settings, &mut streams, &mut self.radiance)?;
            integrator::add_escaped(scene, settings, &mut self.paths.escaped, &mut self.radiance);
        }
        for (l, w) in self.radiance.iter_mut().zip(&self.weights) {
            *l = l.map(|v| v * w);
        }
        Ok(())
    }
}

/// The sample after `(p, k)` (sample `k` of pixel `p`) in a row whose
/// pixels have `spp` samples each: the samples counted along, pixel after
/// pixel, without a division for each.
#[inline(always)]
fn next_sample((p, k): (usize, usize), spp: usize) -> (usize, usize) {
    if k + 1 == spp { (p + 1, 0) } else { (p, k + 1) }
}

/// SplitMix64's finaliser: a well-mixed 64-bit state from the seed and the
/// pixel index.
fn mix(seed: u64, pixel: u64) -> u64 {
    let mut z = seed ^ pixel.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Renders samples `samples.first ..` (`samples.count` per pixel) of
/// `scene`, rows in parallel on mcsample's thread pool. `progress` counts
/// samples as rows finish and is polled for cancellation once per pixel.
///
/// # Errors
/// [`crate::Error::Integer`] naming `spp` when the sampler cannot make a
/// sequence of `samples.total` samples per pixel ([`Sampler::max_count`],
/// [`ZOrder::check`]), or when `samples.first + samples.count` exceeds it;
/// [`crate::Error::Memory`] when the film does not fit in memory; and
/// when the thread pool cannot start.
pub fn render(
    scene: &Scene,
    samples: Samples,
    seed: u64,
    settings: &Settings,
    progress: &Progress,
) -> Result<Image> {
    let (width, height) = scene.film();
    let arg = if samples.total == u64::from(samples.count) {
        "spp"
    } else {
        "total_spp"
    };
    settings.sampler.check_count(arg, samples.total)?;
    if samples.first.saturating_add(u64::from(samples.count)) > samples.total {
        return Err(crate::Error::Integer {
            arg: "first_sample",
            value: samples.first.to_string(),
            requirement: format!(
                "first_sample + spp must be at most total_spp = {}",
                samples.total
            ),
        });
    }
    if settings.sampler == Sampler::ZSobol {
        ZOrder::check((width, height), samples.total)?;
    }
    match settings.integrator {
        Integrator::Ptracer => {
            let paths = ptracer::LightPaths { scene, settings };
            return splatting::render(scene, samples, (seed, settings), progress, &paths);
        }
        Integrator::Bdpt => {
            let paths = bdpt::Bidirectional { scene, settings };
            return splatting::render(scene, samples, (seed, settings), progress, &paths);
        }
        Integrator::Direct | Integrator::Path => {}
    }
    let spp = samples.count.max(1) as usize;
    let blocks = film::blocks(samples.first, u64::from(samples.count));
    let pixels = width * height;
    let mut mean = alloc::filled(pixels * 3, 0.0f32, "the film's means")?;
    let mut variance = alloc::filled(pixels * 3, 0.0f32, "the film's variances")?;
    let mut luminance_variance = alloc::filled(pixels, 0.0f32, "the film's variances")?;
    let sums_per_pixel = if samples.keep_sums {
        blocks.len() * 8
    } else {
        0
    };
    let mut sums = alloc::filled(pixels * sums_per_pixel, 0.0f64, "the film's sums")?;
    // Each row's share of the sums (empty when they are not kept).
    let mut sums_rows: Vec<&mut [f64]> = alloc::with_capacity(height, "the film's rows")?;
    if sums_per_pixel > 0 {
        sums_rows.extend(sums.chunks_mut(width * sums_per_pixel));
    } else {
        sums_rows.extend((0..height).map(|_| &mut [][..]));
    }
    // Pixels per batch: about BATCH samples, at least one pixel.
    let group = (BATCH / spp).max(1);
    parallel::install(|| {
        mean.par_chunks_mut(width * 3)
            .zip(variance.par_chunks_mut(width * 3))
            .zip(luminance_variance.par_chunks_mut(width))
            .zip(sums_rows.into_par_iter())
            .enumerate()
            .try_for_each_init(
                Batch::default,
                |batch, (y, (((mean_row, var_row), lum_row), sums_row))| {
                    for x0 in (0..width).step_by(group) {
                        if progress.cancel.load(Ordering::Relaxed) {
                            return Ok(());
                        }
                        let pixels = x0..(x0 + group).min(width);
                        batch.run(scene, settings, seed, samples, y, pixels.clone())?;
                        let Batch {
                            radiance,
                            block_sums,
                            ..
                        } = batch;
                        for (x, pixel_samples) in pixels.zip(radiance.chunks(spp)) {
                            block_sums.clear();
                            film::block_sums(pixel_samples, &blocks, block_sums);
                            let sums_out = &mut sums_row[x * sums_per_pixel..][..sums_per_pixel];
                            film::finish_pixel(
                                block_sums,
                                u64::from(samples.count),
                                (
                                    &mut mean_row[3 * x..3 * x + 3],
                                    &mut var_row[3 * x..3 * x + 3],
                                ),
                                &mut lum_row[x],
                                sums_out,
                            );
                        }
                    }
                    progress
                        .samples
                        .fetch_add(width as u64 * u64::from(samples.count), Ordering::Relaxed);
                    Ok(())
                },
            )
    })??;
    Ok(Image {
        width,
        height,
        mean,
        variance,
        luminance_variance,
        blocks,
        sums,
        cancelled: progress.cancel.load(Ordering::Relaxed),
    })
}

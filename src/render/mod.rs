//! A compact renderer for envmap- and area-lit scenes: shapes in a BVH,
//! Phong and diffuse materials, a perspective or thin-lens camera, a box-
//! filtered film, and direct or path integrators by BSDF sampling, emitter
//! sampling or MIS ([`integrator`]).
//!
//! Pixel `(x, y)` is the mean of `spp` samples at uniform positions inside
//! it (a box filter of radius ½, as Mitsuba's `box`); its variance is that of
//! the mean, `s² / spp` with `s²` the unbiased sample variance. Each pixel
//! draws from its own [`Stream`] of the settings' [`Sampler`] (keyed by
//! `seed` and the pixel index; the independent sampler's PCG32 stream is
//! seeded the same way), so the image does not depend on the thread count
//! or on the order in which rows are rendered. The dimensions each random
//! decision takes are listed in [`integrator::dims`].
//!
//! Samples are rendered in batches of about `BATCH` (whole pixels of one
//! row): each pixel's film and lens positions are drawn first, the camera
//! rays of the batch are made at SIMD width, each path is traced, and the
//! light of every ray that left the scene is looked up for the whole batch
//! at the end (vectorised, with the texel reads overlapping). The draws of a
//! pixel thus come in a fixed order, whatever the batch size or thread.
//!
//! Emitter sampling draws an environment map with the density of its own
//! [`crate::envmap::EnvMap::pdf`], but by its
//! [`crate::envmap::CellSampler`] (an alias table over the sampling table's
//! cells, in `f32`): one draw at a time between other work, a search of the
//! table's running sums would wait on each of its loads in turn.

pub mod accel;
pub mod camera;
pub mod geometry;
pub mod integrator;
pub mod mesh_file;
pub mod scene;
pub mod shape;
#[cfg(test)]
mod tests;

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use rayon::prelude::*;

pub use integrator::{Heuristic, Integrator, Settings, Strategy, dims};
pub use scene::Scene;

use crate::alloc;
use crate::error::Result;
use crate::math::luminance;
use crate::parallel;
use crate::rng::Rng;
use crate::sampler::zorder::ZOrder;
use crate::sampler::{Sampler, Stream};
use accel::Hit;
use integrator::Escaped;
use shape::Ray;

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
    /// Whether `cancel` stopped the render before every row was done.
    pub cancelled: bool,
}

/// State shared with whoever watches a render from another thread.
#[derive(Debug, Default)]
pub struct Progress {
    /// Samples computed so far.
    pub samples: AtomicU64,
    /// Set to stop the render; rows not yet finished stay black.
    pub cancel: AtomicBool,
}

/// Camera samples per batch: their escaped rays' environment light is
/// looked up together ([`integrator::add_escaped`]).
const BATCH: usize = 256;

/// One thread's buffers for a batch of camera samples (reused from batch
/// to batch).
#[derive(Default)]
struct Batch {
    escaped: Escaped,
    /// Radiance of each sample, pixel after pixel.
    radiance: Vec<[f32; 3]>,
    /// Film and lens positions of each sample.
    camera_u: Vec<[f32; 4]>,
    rays: Vec<Ray>,
    /// Where each camera ray first meets the scene.
    hits: Vec<Option<Hit>>,
}

impl Batch {
    /// The `spp` samples of each pixel `(x, y)`, `x` in `pixels`, into
    /// [`Batch::radiance`]: film and lens positions first (from the pixel's
    /// own stream, which then drives its paths), the camera rays of the
    /// whole batch at SIMD width, the paths one by one, and last the light
    /// of every ray that left the scene, looked up together.
    fn run(
        &mut self,
        scene: &Scene,
        settings: &Settings,
        seed: u64,
        spp: u32,
        y: usize,
        pixels: std::ops::Range<usize>,
    ) -> Result<()> {
        let (width, height) = scene.film();
        let (inv_width, inv_height) = (1.0 / width as f32, 1.0 / height as f32);
        self.escaped.clear();
        self.radiance.clear();
        self.camera_u.clear();
        // Reserved up front (samples grow with spp): a batch too big for
        // memory is an error, not an abort.
        let n = pixels.len() * spp.max(1) as usize;
        const WHAT: &str = "a batch of samples";
        alloc::reserve(&mut self.camera_u, n, WHAT)?;
        alloc::reserve(&mut self.rays, n, WHAT)?;
        alloc::reserve(&mut self.hits, n, WHAT)?;
        alloc::reserve(&mut self.radiance, n, WHAT)?;
        self.escaped.reserve(n)?;
        let mut streams = alloc::with_capacity(pixels.len(), WHAT)?;
        for x in pixels {
            let pixel = (y * width + x) as u64;
            let key = mix(seed, pixel);
            let mut stream = Stream::new(
                settings.sampler,
                key,
                Rng::new(key, pixel),
                u64::from(spp),
                ZOrder::new((x, y), (width, height), u64::from(spp), seed),
            );
            // A pinhole ignores the lens: only the independent sampler,
            // whose draws come in order, must draw it.
            let lens_drawn = scene.camera().has_lens() || stream.independent().is_some();
            for i in 0..spp {
                stream.start(i);
                let film = stream.get2::<f32>(dims::FILM);
                let lens = if lens_drawn {
                    stream.get2(dims::LENS)
                } else {
                    [0.5; 2]
                };
                let film_x = (x as f32 + film[0]) * inv_width;
                let film_y = (y as f32 + film[1]) * inv_height;
                self.camera_u.push([film_x, film_y, lens[0], lens[1]]);
            }
            streams.push(stream);
        }
        self.rays.resize(self.camera_u.len(), Ray::default());
        scene.camera().rays_into(&self.camera_u, &mut self.rays);
        self.hits.clear();
        self.hits.extend(self.rays.iter_mut().map(|ray| {
            let hit = scene.accel().intersect(ray);
            if settings.hide_emitters {
                integrator::skip_emitters(scene, ray, hit)
            } else {
                hit
            }
        }));
        let spp = spp.max(1) as usize;
        let per_pixel = self.rays.chunks(spp).zip(self.hits.chunks(spp));
        for (mut stream, (rays, hits)) in streams.into_iter().zip(per_pixel) {
            for (i, (ray, hit)) in (0..).zip(rays.iter().zip(hits)) {
                stream.start(i);
                let slot = self.radiance.len() as u32;
                let l = integrator::radiance(
                    scene,
                    *ray,
                    *hit,
                    &mut stream,
                    settings,
                    &mut self.escaped,
                    slot,
                );
                self.radiance.push(l);
            }
        }
        integrator::add_escaped(scene, settings, &mut self.escaped, &mut self.radiance);
        Ok(())
    }
}

/// A pixel's estimate from its samples.
struct Moments {
    /// Mean per channel.
    mean: [f32; 3],
    /// Variance of the mean per channel, `s²/n` (infinite for fewer than 2
    /// samples).
    variance: [f32; 3],
    /// Variance of the mean luminance.
    luminance_variance: f32,
}

/// Mean and variances of a pixel's `samples`, accumulated in `f64`.
fn moments(samples: &[[f32; 3]]) -> Moments {
    let n = samples.len() as f64;
    let variance_of_mean = |sum: f64, sum_sq: f64| -> f32 {
        if samples.len() > 1 {
            (((sum_sq - sum * sum / n) / (n - 1.0)).max(0.0) / n) as f32
        } else {
            f32::INFINITY
        }
    };
    let mut sum = [0.0f64; 3];
    let mut sum_sq = [0.0f64; 3];
    let (mut sum_y, mut sum_y_sq) = (0.0f64, 0.0f64);
    for l in samples {
        let l = l.map(f64::from);
        for k in 0..3 {
            sum[k] += l[k];
            sum_sq[k] += l[k] * l[k];
        }
        let y = luminance(l);
        sum_y += y;
        sum_y_sq += y * y;
    }
    Moments {
        mean: sum.map(|s| (s / n.max(1.0)) as f32),
        variance: std::array::from_fn(|k| variance_of_mean(sum[k], sum_sq[k])),
        luminance_variance: variance_of_mean(sum_y, sum_y_sq),
    }
}

/// SplitMix64's finaliser: a well-mixed 64-bit state from the seed and the
/// pixel index.
fn mix(seed: u64, pixel: u64) -> u64 {
    let mut z = seed ^ pixel.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Renders `scene` with `spp` samples per pixel, rows in parallel on
/// mcsample's thread pool. `progress` counts samples as rows finish and is
/// polled for cancellation once per pixel.
///
/// # Errors
/// [`crate::Error::Integer`] naming `spp` when the sampler cannot make that
/// many samples per pixel ([`Sampler::max_count`], [`ZOrder::check`]), and
/// when the thread pool cannot start.
pub fn render(
    scene: &Scene,
    spp: u32,
    seed: u64,
    settings: &Settings,
    progress: &Progress,
) -> Result<Image> {
    let (width, height) = scene.film();
    settings.sampler.check_count("spp", u64::from(spp))?;
    if settings.sampler == Sampler::ZSobol {
        ZOrder::check((width, height), u64::from(spp))?;
    }
    let mut mean = alloc::filled(width * height * 3, 0.0f32, "the film's means")?;
    let mut variance = alloc::filled(width * height * 3, 0.0f32, "the film's variances")?;
    let mut luminance_variance = alloc::filled(width * height, 0.0f32, "the film's variances")?;
    // Pixels per batch: about BATCH samples, at least one pixel.
    let group = (BATCH / spp.max(1) as usize).max(1);
    parallel::install(|| {
        mean.par_chunks_mut(width * 3)
            .zip(variance.par_chunks_mut(width * 3))
            .zip(luminance_variance.par_chunks_mut(width))
            .enumerate()
            .try_for_each_init(
                Batch::default,
                |batch, (y, ((mean_row, var_row), lum_row))| {
                    for x0 in (0..width).step_by(group) {
                        if progress.cancel.load(Ordering::Relaxed) {
                            return Ok(());
                        }
                        let pixels = x0..(x0 + group).min(width);
                        batch.run(scene, settings, seed, spp, y, pixels.clone())?;
                        let per_pixel = batch.radiance.chunks(spp.max(1) as usize);
                        for (x, samples) in pixels.zip(per_pixel.chain(std::iter::repeat(&[][..])))
                        {
                            let m = moments(samples);
                            mean_row[3 * x..3 * x + 3].copy_from_slice(&m.mean);
                            var_row[3 * x..3 * x + 3].copy_from_slice(&m.variance);
                            lum_row[x] = m.luminance_variance;
                        }
                    }
                    progress
                        .samples
                        .fetch_add(width as u64 * u64::from(spp), Ordering::Relaxed);
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
        cancelled: progress.cancel.load(Ordering::Relaxed),
    })
}

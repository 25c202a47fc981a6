//! A compact renderer for envmap- and area-lit scenes: shapes in a BVH,
//! Phong and diffuse materials, a perspective or thin-lens camera, a box-
//! filtered film, and direct or path integrators by BSDF sampling, emitter
//! sampling or MIS ([`integrator`]).
//!
//! Pixel `(x, y)` is the mean of `spp` samples at uniform positions inside
//! it (a box filter of radius ½, as Mitsuba's `box`); its variance is that of
//! the mean, `s² / spp` with `s²` the unbiased sample variance. Each pixel
//! draws from its own PCG32 stream (seeded from `seed` and the pixel index),
//! so the image does not depend on the thread count or on the order in which
//! rows are rendered.

pub mod accel;
pub mod camera;
pub mod integrator;
pub mod mesh_file;
pub mod scene;
pub mod shape;

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use rayon::prelude::*;

pub use integrator::{Heuristic, Integrator, Settings, Strategy};
pub use scene::Scene;

use crate::error::Result;
use crate::math::luminance;
use crate::parallel;
use crate::rng::Rng;

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
/// Only when the thread pool cannot start.
pub fn render(
    scene: &Scene,
    spp: u32,
    seed: u64,
    settings: &Settings,
    progress: &Progress,
) -> Result<Image> {
    let (width, height) = scene.film();
    let mut mean = vec![0.0f32; width * height * 3];
    let mut variance = vec![0.0f32; width * height * 3];
    let mut luminance_variance = vec![0.0f32; width * height];
    let n = f64::from(spp.max(1));
    let variance_of_mean = |sum: f64, sum_sq: f64| -> f32 {
        if spp > 1 {
            (((sum_sq - sum * sum / n) / (n - 1.0)).max(0.0) / n) as f32
        } else {
            f32::INFINITY
        }
    };
    parallel::install(|| {
        mean.par_chunks_mut(width * 3)
            .zip(variance.par_chunks_mut(width * 3))
            .zip(luminance_variance.par_chunks_mut(width))
            .enumerate()
            .for_each(|(y, ((mean_row, var_row), lum_row))| {
                for x in 0..width {
                    if progress.cancel.load(Ordering::Relaxed) {
                        return;
                    }
                    let pixel = (y * width + x) as u64;
                    let mut rng = Rng::new(mix(seed, pixel), pixel);
                    let mut sum = [0.0f64; 3];
                    let mut sum_sq = [0.0f64; 3];
                    let (mut sum_y, mut sum_y_sq) = (0.0f64, 0.0f64);
                    for _ in 0..spp {
                        let film = [
                            (x as f32 + rng.next_float::<f32>()) / width as f32,
                            (y as f32 + rng.next_float::<f32>()) / height as f32,
                        ];
                        let lens = [rng.next_float(), rng.next_float()];
                        let ray = scene.camera().ray(film, lens);
                        let l = integrator::radiance(scene, ray, &mut rng, settings);
                        let l = l.map(f64::from);
                        for k in 0..3 {
                            sum[k] += l[k];
                            sum_sq[k] += l[k] * l[k];
                        }
                        let y = luminance(l);
                        sum_y += y;
                        sum_y_sq += y * y;
                    }
                    for k in 0..3 {
                        mean_row[3 * x + k] = (sum[k] / n) as f32;
                        var_row[3 * x + k] = variance_of_mean(sum[k], sum_sq[k]);
                    }
                    lum_row[x] = variance_of_mean(sum_y, sum_y_sq);
                }
                progress
                    .samples
                    .fetch_add(width as u64 * u64::from(spp), Ordering::Relaxed);
            });
    })?;
    Ok(Image {
        width,
        height,
        mean,
        variance,
        luminance_variance,
        cancelled: progress.cancel.load(Ordering::Relaxed),
    })
}

//! The render loop of the integrators whose samples land anywhere on the
//! film (light tracing, bidirectional path tracing): for each sample
//! index, one path per pixel, traced in parallel in fixed chunks whose
//! splats are added to the film in order, so the image has the same bits
//! at any thread count ([`splat`](super::splat)).

use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::Ordering;

use super::scene::Scene;
use super::splat::{Entry, Splat, SplatFilm, Splatter};
use super::{Image, Progress, Samples, Settings, mix, start_sample};
use crate::error::Result;
use crate::parallel;
use crate::rng::Rng;
use crate::sampler::Stream;
use crate::sampler::zorder::ZOrder;

/// An integrator that splats: path `pixel` of each sample index (drawn
/// from the stream of that pixel) returns values at film positions.
pub trait Paths: Sync {
    /// One thread's buffers.
    type Scratch: Send;
    /// Whether the paths of a sample index are independent and alike, so
    /// that each pixel's variance is taken over all paths (light tracing:
    /// no path belongs to a pixel); else over the sample indices (a
    /// camera path contributes to its own pixel only).
    const PER_PATH: bool;
    /// Images the paths splat onto ([`Splat::channel`]): 1, the render.
    fn channels(&self) -> u32 {
        1
    }
    /// Fresh buffers.
    fn scratch(&self) -> Self::Scratch;
    /// Appends the splats of path `pixel`, drawing from `stream` (at the
    /// path's sample).
    fn trace(
        &self,
        scratch: &mut Self::Scratch,
        stream: &mut Stream,
        pixel: usize,
        out: &mut Vec<Splat>,
    );
}

/// Paths per parallel task.
const CHUNK: usize = 512;

/// Tasks whose entries are held at once (about 32,768 paths).
const BATCH: usize = 64;

/// Renders samples `samples.first ..` of `scene` with `paths`;
/// [`Progress::samples`] counts paths, and the render stops between
/// sample indices when cancelled.
///
/// # Errors
/// As [`super::render`].
pub fn render<P: Paths>(
    scene: &Scene,
    samples: Samples,
    (seed, settings): (u64, &Settings),
    progress: &Progress,
    paths: &P,
) -> Result<Image> {
    let (width, height) = scene.film();
    let pixels = width * height;
    let chunks: Vec<Range<usize>> = (0..pixels)
        .step_by(CHUNK)
        .map(|a| a..(a + CHUNK).min(pixels))
        .collect();
    // Entries index a pixel of a channel in 32 bits.
    let channels = paths.channels() as usize;
    let Some(values) = pixels
        .checked_mul(channels)
        .filter(|&n| n <= u32::MAX as usize)
    else {
        return Err(crate::Error::Argument {
            arg: "film",
            message: format!(
                "{channels} images of {pixels} pixels are too many for one render: ask for \
                 fewer (a smaller film, or fewer strategy images)"
            ),
        });
    };
    let mut film = SplatFilm::new(values, P::PER_PATH);
    let scale = if P::PER_PATH { pixels as f32 } else { 1.0 };
    let channels = channels as u32;
    parallel::install(|| -> Result<()> {
        for index in samples.first..samples.first + u64::from(samples.count) {
            let mut leaf = film.leaf()?;
            // A bounded batch of chunks at a time: their entries are held
            // until added to the leaf, in chunk order.
            for batch in chunks.chunks(BATCH) {
                let parts: Vec<Vec<Entry>> = batch
                    .par_iter()
                    .map_init(
                        || {
                            let filter = scene.filter().filter();
                            let splatter = Splatter::new(filter, scene.film(), channels, scale);
                            (paths.scratch(), splatter, Vec::new())
                        },
                        |(scratch, splatter, splats), range| {
                            let mut out = Vec::new();
                            if progress.cancel.load(Ordering::Relaxed) {
                                return out;
                            }
                            for j in range.clone() {
                                let mut stream =
                                    stream_of(scene, settings.sampler, (seed, samples.total), j);
                                start_sample(&mut stream, mix(seed, j as u64), j as u64, index);
                                splats.clear();
                                paths.trace(scratch, &mut stream, j, splats);
                                splatter.path(splats, &mut out);
                            }
                            out
                        },
                    )
                    .collect();
                parts.iter().for_each(|part| leaf.add(part));
            }
            if progress.cancel.load(Ordering::Relaxed) {
                break;
            }
            film.push(index, leaf)?;
            progress.samples.fetch_add(pixels as u64, Ordering::Relaxed);
        }
        Ok(())
    })??;
    let per_sample = if P::PER_PATH { pixels as u64 } else { 1 };
    let developed = film.develop(per_sample, samples.keep_sums)?;
    Ok(Image {
        width,
        height,
        mean: developed.mean,
        variance: developed.variance,
        luminance_variance: developed.luminance_variance,
        blocks: developed.blocks,
        sums: developed.sums,
        cancelled: progress.cancel.load(Ordering::Relaxed),
    })
}

/// The stream of path `j` (keyed as pixel `j` of a camera render).
fn stream_of(
    scene: &Scene,
    sampler: crate::sampler::Sampler,
    (seed, total): (u64, u64),
    j: usize,
) -> Stream {
    let (width, height) = scene.film();
    let key = mix(seed, j as u64);
    Stream::new(
        sampler,
        key,
        Rng::new(key, j as u64),
        total,
        ZOrder::new((j % width, j / width), (width, height), total, seed),
    )
}

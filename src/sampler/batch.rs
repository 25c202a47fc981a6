//! Many requests of a batch of samples drawn together: what each would
//! get from [`Stream::get1`] or [`Stream::get2`], bit for bit, at SIMD width
//! for the Sobol' family.
//!
//! A request of the Sobol' family ([`Sampler::Sobol`],
//! [`Sampler::LowDiscrepancy`], [`Sampler::ZSobol`]) is a chain of
//! integer hashes (the index permutation or z-order shuffle, the second
//! dimension's matrix, two scrambles, a bit reversal) whose latency a
//! scalar caller waits on between its other work. Here each stream first
//! gives its cached key per request, then the hashes run over all the
//! requests in loops the compiler vectorises ([`crate::simd::dispatch`]):
//! the Kensler step of every shuffled index (all but [`Sampler::ZSobol`]), the cycle walk
//! and rotation (no step when the count is a power of two above 1), then
//! the scrambled points. The other samplers' requests are drawn one by one,
//! but for the independent sampler's first requests of samples that each
//! start a generator of their own ([`Drawn::draw_fresh`]: the camera's).
//!
//! A 1D request of the Sobol' family is the first coordinate of the 2D
//! request of the same dimension ([`Stream::get1`] scrambles the same first
//! coordinate with the same seed), so every request is drawn as a pair.

use super::{Sampler, Stream, randomized_pair, zorder};
use crate::alloc;
use crate::error::Result;
use crate::math::Real;
use crate::qmc::patterns::{kensler_step, rotate, walk};
use crate::rng::{Rng, first_floats};
use crate::simd::dispatch;

/// A coordinate every sample of a step asks for: `dim` (and `dim + 1`
/// when `two`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dim {
    /// The (first) dimension.
    pub dim: u32,
    /// A 2D request ([`Stream::get2`]) rather than 1D ([`Stream::get1`]).
    pub two: bool,
}

/// The values of a batch's requests (each of its samples asking for the
/// same dimensions), and the scratch they are drawn in
/// (kept between batches, so drawing allocates only while the batches
/// grow).
#[derive(Clone, Debug, Default)]
pub struct Drawn {
    /// `values[s · d + k]`: coordinates `dims[k]` of sample `s`, when each
    /// asks for `d` dimensions (a 1D request's in `[0]`, `[1]` then
    /// meaningless).
    pub values: Vec<[f32; 2]>,
    /// The Sobol' index of each request: the sample's index until the
    /// permutation of [`Sampler::Sobol`] or [`Sampler::LowDiscrepancy`] replaces it.
    index: Vec<u64>,
    /// The scrambles' seeds (low half the first coordinate's).
    seed: Vec<u64>,
    /// [`Sampler::Sobol`], [`Sampler::LowDiscrepancy`]: the permutation's seed, its rotation and the
    /// stream's count.
    permutation: Vec<[u32; 3]>,
    /// [`Drawn::draw_fresh`]: each sample's generator after its draws.
    pub generators: Vec<Rng>,
}

impl Drawn {
    /// Draws `dims` for each of `samples` (a stream of `streams` and a
    /// sample's index in it): `values[s · dims.len() + k]` is what
    /// `streams[stream].start(index)` followed by `get1::<f32>` or
    /// `get2::<f32>` of `dims[k]` gives. Nothing is drawn for
    /// [`Sampler::Independent`], whose numbers depend on the order they
    /// are asked in (but see [`Drawn::draw_fresh`]). The streams of the
    /// samplers other than Sobol's are left at the last sample
    /// ([`Stream::start`] them again before asking).
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the memory for the values cannot be
    /// had.
    ///
    /// # Panics
    /// When a sample names a stream out of `streams`.
    pub fn draw<I>(&mut self, streams: &mut [Stream], samples: I, dims: &[Dim]) -> Result<()>
    where
        I: ExactSizeIterator<Item = (u32, u32)>,
    {
        const WHAT: &str = "a batch of sample numbers";
        let n = samples.len() * dims.len();
        self.values.clear();
        alloc::reserve(&mut self.values, n, WHAT)?;
        let Some(sampler) = streams.first().map(Stream::sampler) else {
            return Ok(());
        };
        if sampler == Sampler::Independent {
            return Ok(());
        }
        if !matches!(
            sampler,
            Sampler::Sobol | Sampler::LowDiscrepancy | Sampler::ZSobol
        ) {
            for (stream, index) in samples {
                let stream = &mut streams[stream as usize];
                stream.start(index);
                self.values.extend(dims.iter().map(|d| {
                    if d.two {
                        stream.get2(d.dim)
                    } else {
                        [stream.get1(d.dim), 0.0]
                    }
                }));
            }
            return Ok(());
        }
        let Drawn {
            values,
            index,
            seed,
            permutation,
            ..
        } = self;
        // Sized first, then written through slices (no length kept up to
        // date per request).
        for v in [&mut *index, &mut *seed] {
            v.clear();
            alloc::reserve(v, n, WHAT)?;
            v.resize(n, 0);
        }
        permutation.clear();
        if sampler != Sampler::ZSobol {
            alloc::reserve(permutation, n, WHAT)?;
            permutation.resize(n, [0; 3]);
        }
        values.resize(n, [0.0; 2]);
        let per_sample = dims.len().max(1);
        let keyed = index
            .chunks_exact_mut(per_sample)
            .zip(seed.chunks_exact_mut(per_sample));
        if sampler == Sampler::ZSobol {
            for ((stream, at), (i, s)) in samples.zip(keyed) {
                let stream = &mut streams[stream as usize];
                stream.start(at);
                for ((d, i), s) in dims.iter().zip(i).zip(s) {
                    let (index, key) = stream.sobol_index(d.dim);
                    (*i, *s) = (index, key.seed);
                }
            }
        } else {
            let keyed = keyed.zip(permutation.chunks_exact_mut(per_sample));
            for ((stream, at), ((i, s), p)) in samples.zip(keyed) {
                let stream = &mut streams[stream as usize];
                for (((d, i), s), p) in dims.iter().zip(i).zip(s).zip(p) {
                    let key = stream.key(d.dim);
                    (*i, *s) = (u64::from(at), key.seed);
                    let (seed, rotation) = key.permutation();
                    *p = [seed, rotation, stream.count];
                }
            }
        }
        dispatch(
            #[inline(always)]
            |_| {
                for (i, &[seed, _, count]) in index.iter_mut().zip(&*permutation) {
                    *i = u64::from(kensler_step(*i as u32, count, seed));
                }
                for (i, &[seed, rotation, count]) in index.iter_mut().zip(&*permutation) {
                    *i = u64::from(rotate(walk(*i as u32, count, seed), count, rotation));
                }
                for ((v, &i), &seed) in values.iter_mut().zip(&*index).zip(&*seed) {
                    let pair = randomized_pair(sampler, zorder::sobol01_reversed(i), seed);
                    *v = pair.map(f32::from_random_bits);
                }
            },
        );
        Ok(())
    }

    /// The independent sampler's requests `dims` of samples that each start
    /// a generator of their own, `Rng::new(seed, stream)` for each of
    /// `starts`: what asking them in order of that generator gives, laid out
    /// as [`Drawn::draw`] lays them out, drawn at SIMD width
    /// ([`crate::rng::first_floats`]). [`Drawn::generators`] holds each
    /// sample's generator after them.
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the memory for the values cannot be
    /// had.
    pub fn draw_fresh(&mut self, starts: &[(u64, u64)], dims: &[Dim]) -> Result<()> {
        const WHAT: &str = "a batch of sample numbers";
        let n = starts.len();
        self.values.clear();
        self.generators.clear();
        alloc::reserve(&mut self.values, n * dims.len(), WHAT)?;
        alloc::reserve(&mut self.generators, n, WHAT)?;
        self.values.resize(n * dims.len(), [0.0; 2]);
        self.generators.resize(n, Rng::new(0, 0));
        // Each request's floats, at their places in its sample's values.
        let at: Vec<usize> = (dims.iter().enumerate())
            .flat_map(|(k, d)| [2 * k, 2 * k + 1].into_iter().take(1 + usize::from(d.two)))
            .collect();
        first_floats(
            starts,
            &at,
            self.values.as_flattened_mut(),
            &mut self.generators,
        );
        Ok(())
    }
}

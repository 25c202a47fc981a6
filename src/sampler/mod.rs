//! Sample generators for the estimators and the renderer: where the uniform
//! numbers of each sample come from.
//!
//! A [`Stream`] holds the samples `0 .. count` of one pixel (or of one
//! estimate); sample `i`'s coordinate `dim` is asked for by
//! [`Stream::get1`] and [`Stream::get2`] after [`Stream::start`]`(i)`. The
//! callers give every random decision a fixed dimension (the renderer's
//! order is in [`crate::render::integrator`]), so that a stratified or
//! low-discrepancy sampler stratifies each decision across the samples:
//!
//! - [`Sampler::Independent`]: PCG32 numbers in the order they are asked
//!   for, dimensions ignored (the bits of every earlier release; the
//!   renderer gives each sample a generator of its own);
//! - [`Sampler::Stratified`] and [`Sampler::MultiJitter`]: each 1D request a
//!   jittered stratum of `1/count`, each 2D request a point of a jittered
//!   grid or of Kensler's correlated multi-jittered pattern
//!   ([`crate::qmc::Pattern`]), a pattern of its own (hashed from the
//!   stream's key and the dimension) per request, as Mitsuba's samplers;
//! - [`Sampler::Sobol`]: padded Owen-scrambled Sobol' (pbrt-v4's
//!   `PaddedSobolSampler`): every request the first one or two Sobol'
//!   dimensions (a (0, m, 2)-net for every power-of-two prefix, which
//!   consecutive higher dimensions are not) at the sample's index shuffled
//!   by a permutation of `0 .. count`, Owen-scrambled (Vegdahl's
//!   Laine–Karras hash, pbrt-v4's `FastOwenScrambler`), each with its own
//!   seeds per pixel and dimension;
//! - [`Sampler::LowDiscrepancy`]: the same padded Sobol' points as
//!   [`Sampler::Sobol`], each request's shuffled index as there, randomised
//!   by a random XOR of its bits (a digital shift; pbrt-v4's
//!   `PermuteDigits` in base 2) in place of Owen's scramble: Mitsuba's
//!   `ldsampler` (Kollig and Keller's scrambled (0, 2)-sequence, shuffled
//!   per dimension), with seeds of its own per pixel and dimension;
//! - [`Sampler::ZSobol`]: Ahmed and Wronski's (2020) z-ordered Sobol', as
//!   pbrt-v4's `ZSobolSampler` ([`zorder`]): every request the first two
//!   Sobol' dimensions at the pixel's Morton index, shuffled by base-4
//!   digit permutations per dimension, Owen-scrambled per dimension, so that
//!   the error is spread as blue noise across the screen.
//!
//! Every value is uniform on `[0, 1)` over the seed (a scrambled net is
//! uniform point by point), so every estimator stays unbiased whatever the
//! sampler.

pub mod batch;
pub mod zorder;

use crate::error::{Error, Result};
use crate::math::Real;
use crate::qmc::patterns::{Layout, Pattern, mix64, permute_rotated};
use crate::qmc::sobol::owen_reversed_pair;
use crate::rng::Rng;
use zorder::ZOrder;

/// Which generator a [`Stream`] draws from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampler {
    /// Independent uniform numbers (PCG32).
    Independent,
    /// Jittered strata per request (Mitsuba's `stratified`).
    Stratified,
    /// Correlated multi-jittered patterns per request (Mitsuba's
    /// `multijitter`).
    MultiJitter,
    /// Padded Owen-scrambled Sobol', seeded per pixel.
    Sobol,
    /// Padded Sobol' randomised by a digital shift (Mitsuba's
    /// `ldsampler`), seeded per pixel.
    LowDiscrepancy,
    /// Z-ordered, Owen-scrambled Sobol' (pbrt-v4's `ZSobolSampler`).
    ZSobol,
}

impl Sampler {
    /// Every sampler with its Python name.
    pub const NAMES: &'static [(&'static str, Sampler)] = &[
        ("independent", Sampler::Independent),
        ("stratified", Sampler::Stratified),
        ("multijitter", Sampler::MultiJitter),
        ("sobol", Sampler::Sobol),
        ("ldsampler", Sampler::LowDiscrepancy),
        ("zsobol", Sampler::ZSobol),
    ];

    /// The most samples one stream may hold: Sobol' indices are below
    /// `2^32` (and a stream's count, which its index permutation runs over,
    /// is a `u32`), and a stratified grid's `⌈√n⌉²` strata are counted in
    /// 32 bits.
    pub fn max_count(self) -> u64 {
        match self {
            Sampler::Independent => u64::MAX,
            Sampler::Stratified | Sampler::MultiJitter => crate::qmc::PATTERN_MAX_POINTS,
            Sampler::Sobol | Sampler::LowDiscrepancy | Sampler::ZSobol => u64::from(u32::MAX),
        }
    }

    /// Checks that a stream of `count` samples fits (argument `arg`).
    ///
    /// # Errors
    /// [`Error::Integer`] naming `arg` when `count` exceeds [`Sampler::max_count`].
    pub fn check_count(self, arg: &'static str, count: u64) -> Result<()> {
        if count <= self.max_count() {
            return Ok(());
        }
        let name = Sampler::NAMES
            .iter()
            .find(|(_, s)| *s == self)
            .map_or("?", |(n, _)| n);
        Err(Error::Integer {
            arg,
            value: count.to_string(),
            requirement: format!(
                "must be at most {} with sampler=\"{name}\"",
                self.max_count()
            ),
        })
    }
}

/// Dimensions whose [`DimKey`] a stream keeps once computed (a direct-
/// lighting sample uses 12, each bounce of a path 7 more).
const CACHED: usize = 32;

/// Samples a stream must have for its patterns' layouts to be kept (a
/// layout costs a few divisions, and the table of them an allocation:
/// worth it when each is read many times).
const LAID_OUT_MIN: u32 = 16;

/// What a dimension's values need besides the sample index.
#[derive(Clone, Copy, Debug, Default)]
struct DimKey {
    /// The 64-bit seed of the dimension's scrambles or pattern.
    seed: u64,
    /// [`Sampler::ZSobol`]: the shuffled digits above the pixel's samples
    /// ([`ZOrder::block`]); [`Sampler::Sobol`] and
    /// [`Sampler::LowDiscrepancy`]: the index permutation's
    /// seed (low half) and the rotation that ends it, that seed modulo the
    /// stream's count (high half).
    block: u64,
}

impl DimKey {
    /// [`Sampler::Sobol`], [`Sampler::LowDiscrepancy`]: the index
    /// permutation's seed and rotation.
    #[inline(always)]
    fn permutation(self) -> (u32, u32) {
        (self.block as u32, (self.block >> 32) as u32)
    }
}

/// The samples `0 .. count` of one pixel or one estimate.
#[derive(Clone, Debug)]
pub struct Stream {
    sampler: Sampler,
    /// The independent numbers (also the source of
    /// [`Sampler::Independent`]'s draws).
    rng: Rng,
    /// Seeds the scrambles and patterns of this stream.
    key: u64,
    count: u32,
    index: u32,
    zorder: ZOrder,
    /// The keys of dimensions below [`CACHED`], where bit `dim` of
    /// `cached` is set.
    keys: [DimKey; CACHED],
    cached: u32,
    /// [`Sampler::Stratified`] and [`Sampler::MultiJitter`]: the patterns
    /// of dimensions below [`CACHED`] once laid out (bit `dim` of
    /// `laid_out`), allocated at the first.
    layouts: Vec<Layout>,
    laid_out: u32,
}

impl Stream {
    /// A stream of `count` samples (`1 ≤ count ≤` [`Sampler::max_count`],
    /// which the caller checks) keyed by `key`; `rng` feeds
    /// [`Sampler::Independent`]. `zorder` places the stream's samples in
    /// the z-ordered sequence of [`Sampler::ZSobol`].
    pub fn new(sampler: Sampler, key: u64, rng: Rng, count: u64, zorder: ZOrder) -> Self {
        Stream {
            sampler,
            rng,
            key,
            count: count.clamp(1, u64::from(u32::MAX)) as u32,
            index: 0,
            zorder,
            keys: [DimKey::default(); CACHED],
            cached: 0,
            layouts: Vec::new(),
            laid_out: 0,
        }
    }

    /// This stream with its independent numbers advanced by `draws` (where
    /// a thread's share of an estimate starts).
    pub fn jumped(&self, draws: u64) -> Self {
        Stream {
            rng: self.rng.jumped(draws),
            ..self.clone()
        }
    }

    /// The sampler.
    pub fn sampler(&self) -> Sampler {
        self.sampler
    }

    /// Moves to sample `index` (`< count`).
    #[inline(always)]
    pub fn start(&mut self, index: u32) {
        self.index = index;
    }

    /// The independent generator, for [`Sampler::Independent`] only: its
    /// callers may draw extra bits (an alias table's) that a stratified
    /// sampler would waste.
    #[inline(always)]
    pub fn independent(&mut self) -> Option<&mut Rng> {
        (self.sampler == Sampler::Independent).then_some(&mut self.rng)
    }

    /// The key of dimension `dim`: its seed is a hash of the stream's key
    /// and `dim` ([`Sampler::ZSobol`]: of the sampler's seed and `dim`, the
    /// same for every pixel, as the z-order decorrelates them).
    #[inline(always)]
    fn key(&mut self, dim: u32) -> DimKey {
        let Some(slot) = self.keys.get(dim as usize) else {
            return self.make_key(dim);
        };
        if self.cached >> dim & 1 == 1 {
            return *slot;
        }
        let key = self.make_key(dim);
        self.keys[dim as usize] = key;
        self.cached |= 1 << dim;
        key
    }

    fn make_key(&self, dim: u32) -> DimKey {
        let dim = mix64(u64::from(dim));
        if self.sampler == Sampler::ZSobol {
            let seed = mix64(self.zorder.seed() ^ dim);
            DimKey {
                seed,
                block: self.zorder.block(seed),
            }
        } else {
            let seed = mix64(self.key ^ dim);
            let permutation = mix64(seed) as u32;
            let rotation = permutation % self.count;
            DimKey {
                seed,
                block: u64::from(rotation) << 32 | u64::from(permutation),
            }
        }
    }

    /// The 2D pattern of [`Sampler::Stratified`] (else Kensler's).
    fn pattern(&self) -> Pattern {
        if self.sampler == Sampler::Stratified {
            Pattern::Stratified
        } else {
            Pattern::MultiJitter
        }
    }

    /// The pattern of dimension `dim` ([`Sampler::Stratified`] and
    /// [`Sampler::MultiJitter`]), laid out once for dimensions below
    /// [`CACHED`] of a stream of at least [`LAID_OUT_MIN`] samples.
    #[inline]
    fn layout(&mut self, dim: u32) -> Layout {
        let (p, pairs) = ((self.key(dim).seed >> 32) as u32, self.pattern());
        let slot = dim as usize;
        if slot >= CACHED || self.count < LAID_OUT_MIN {
            return Layout::new(self.count, p, pairs);
        }
        if self.laid_out >> dim & 1 == 0 {
            if self.layouts.is_empty() {
                self.layouts.resize(CACHED, Layout::default());
            }
            self.layouts[slot] = Layout::new(self.count, p, pairs);
            self.laid_out |= 1 << dim;
        }
        self.layouts[slot]
    }

    /// Coordinate `dim` of the current sample, in `[0, 1)`.
    #[inline(always)]
    pub fn get1<F: Real>(&mut self, dim: u32) -> F {
        if self.sampler == Sampler::Independent {
            self.rng.next_float()
        } else {
            self.stratified1(dim)
        }
    }

    /// Coordinates `dim` and `dim + 1` of the current sample, stratified
    /// together.
    #[inline(always)]
    pub fn get2<F: Real>(&mut self, dim: u32) -> [F; 2] {
        if self.sampler == Sampler::Independent {
            [self.rng.next_float(), self.rng.next_float()]
        } else {
            self.stratified2(dim)
        }
    }

    /// A 1D request at `one`, then a 2D one at `two`, as three numbers
    /// `[u(one), u(two), u(two + 1)]` (a light's choice and a point on it).
    #[inline]
    pub fn get1_then2<F: Real>(&mut self, one: u32, two: u32) -> [F; 3] {
        let a = self.get1(one);
        let [b, c] = self.get2(two);
        [a, b, c]
    }

    /// [`Stream::get1`] of the samplers other than the independent one.
    fn stratified1<F: Real>(&mut self, dim: u32) -> F {
        let unit = |x: f64| F::c(x).min(F::ONE_MINUS_EPSILON);
        match self.sampler {
            Sampler::Independent => self.rng.next_float(),
            Sampler::Stratified | Sampler::MultiJitter => {
                unit(self.layout(dim).single(self.index, false))
            }
            Sampler::Sobol | Sampler::LowDiscrepancy | Sampler::ZSobol => {
                let (i, k) = self.sobol_index(dim);
                let [x, _] = randomized_pair(self.sampler, zorder::sobol01_reversed(i), k.seed);
                F::from_random_bits(x)
            }
        }
    }

    /// [`Stream::get2`] of the samplers other than the independent one.
    fn stratified2<F: Real>(&mut self, dim: u32) -> [F; 2] {
        let unit = |x: f64| F::c(x).min(F::ONE_MINUS_EPSILON);
        match self.sampler {
            Sampler::Independent => [self.rng.next_float(), self.rng.next_float()],
            Sampler::Stratified | Sampler::MultiJitter => {
                let (x, y) = self.layout(dim).pair(self.index, self.pattern());
                [unit(x), unit(y)]
            }
            Sampler::Sobol | Sampler::LowDiscrepancy | Sampler::ZSobol => {
                let (i, k) = self.sobol_index(dim);
                randomized_pair(self.sampler, zorder::sobol01_reversed(i), k.seed)
                    .map(F::from_random_bits)
            }
        }
    }

    /// The Sobol' index of the current sample for dimension `dim`, and
    /// the dimension's key: shuffled by a permutation of `0 .. count`
    /// ([`Sampler::Sobol`], [`Sampler::LowDiscrepancy`]) or z-ordered
    /// ([`Sampler::ZSobol`]).
    #[inline]
    fn sobol_index(&mut self, dim: u32) -> (u64, DimKey) {
        let k = self.key(dim);
        let i = if self.sampler == Sampler::ZSobol {
            k.block | self.zorder.within(self.index, k.seed)
        } else {
            let (seed, rotation) = k.permutation();
            u64::from(permute_rotated(self.index, self.count, seed, rotation))
        };
        (i, k)
    }
}

/// The first two Sobol' dimensions `(x, y)` of an index (32 bits each,
/// reversed, as [`zorder::sobol01_reversed`] gives them) randomised by
/// `sampler`'s scramble with a half of `seed` each (the low half the first
/// coordinate's): Owen's ([`owen_reversed_pair`]), or for
/// [`Sampler::LowDiscrepancy`] a digital shift (`x ⊕ seed`), as 32 bits
/// each. Its first coordinate is every 1D request's.
#[inline(always)]
fn randomized_pair(sampler: Sampler, (x, y): (u32, u32), seed: u64) -> [u32; 2] {
    let seeds = [seed as u32, (seed >> 32) as u32];
    if sampler == Sampler::LowDiscrepancy {
        [x.reverse_bits() ^ seeds[0], y.reverse_bits() ^ seeds[1]]
    } else {
        owen_reversed_pair([x, y], seeds)
    }
}

#[cfg(test)]
mod tests;

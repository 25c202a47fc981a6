//! PCG32 random numbers with jump-ahead.
//!
//! [`Rng`] is O'Neill's `pcg32_random_r` (64-bit LCG state, XSH-RR output)
//! seeded as `pcg32_srandom_r(seed, stream)` does, the generator Mitsuba 3
//! and Dr.Jit use. Floats in `[0, 1)` are made from one 32-bit output each,
//! as Dr.Jit's `next_float32` / `next_float64` make them
//! ([`Real::from_random_bits`]), so a stream of floats equals Dr.Jit's for
//! the same seed and stream.
//!
//! [`Rng::advance`] jumps `n` outputs ahead in `O(log n)` (Brown, "Random
//! number generation with arbitrary strides", 1994). Batch fills give each
//! chunk of the batch a copy advanced to the chunk's first index, so a batch
//! is bit-identical to drawing its numbers one after another, on any number
//! of threads.
//!
//! The generator's two words are its own (not `rand_pcg`'s, which the tests
//! check it against) so that [`first_floats`] steps many generators at SIMD
//! width with the same two functions (`step`, `output`), and so that a
//! path's generator is handed back to it by its state alone
//! ([`Rng::resume`]).

use crate::error::Result;
use crate::math::Real;
use crate::parallel;

/// The largest stream id: PCG32 uses `2·stream + 1` as its increment, so
/// the top bit of a 64-bit stream id would be lost.
pub const MAX_STREAM: u64 = (1 << 63) - 1;

/// PCG32's multiplier (O'Neill's `PCG_DEFAULT_MULTIPLIER_64`).
const MULTIPLIER: u64 = 6_364_136_223_846_793_005;

/// The LCG's step: `s·a + c` (multiplier `a`, increment `c`).
#[inline(always)]
fn step(state: u64, increment: u64) -> u64 {
    state.wrapping_mul(MULTIPLIER).wrapping_add(increment)
}

/// XSH-RR, the output of state `s`: `((s ⊕ s ≫ 18) ≫ 27) as u32` rotated
/// right by `s ≫ 59`.
#[inline(always)]
fn output(state: u64) -> u32 {
    let xsh = (((state >> 18) ^ state) >> 27) as u32;
    xsh.rotate_right((state >> 59) as u32)
}

/// A PCG32 generator: the LCG's state, and its increment `2·stream + 1`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rng {
    state: u64,
    increment: u64,
}

impl Rng {
    /// Seeds as `pcg32_srandom_r(seed, stream)`: the state
    /// `(seed + c)·a + c`. `stream` is taken modulo 2^63 (see
    /// [`MAX_STREAM`]); callers reject larger values.
    #[inline]
    pub fn new(seed: u64, stream: u64) -> Self {
        let increment = (stream << 1) | 1;
        Rng {
            state: step(seed.wrapping_add(increment), increment),
            increment,
        }
    }

    /// The next 32-bit output: that of the state, which then steps.
    #[inline(always)]
    pub fn next_u32(&mut self) -> u32 {
        let state = self.state;
        self.state = step(state, self.increment);
        output(state)
    }

    /// The next 64 bits: two 32-bit outputs, the first the low half.
    #[inline(always)]
    pub fn next_u64(&mut self) -> u64 {
        let low = u64::from(self.next_u32());
        (u64::from(self.next_u32()) << 32) | low
    }

    /// The next float in `[0, 1)`, from one 32-bit output.
    #[inline(always)]
    pub fn next_float<F: Real>(&mut self) -> F {
        F::from_random_bits(self.next_u32())
    }

    /// Goes on from where `copy`, a copy of this generator, left its
    /// draws: only the state is copied (one word, which the draws wrote
    /// last; a copy of both would wait on those writes).
    #[inline(always)]
    pub fn resume(&mut self, copy: &Rng) {
        debug_assert_eq!(self.increment, copy.increment, "not a copy");
        self.state = copy.state;
    }

    /// Skips `delta` outputs in `O(log delta)`: `delta` steps compose into
    /// one affine map `s ↦ A·s + C`, built by squaring.
    pub fn advance(&mut self, delta: u64) {
        let (mut a, mut c) = (1u64, 0u64);
        let (mut square_a, mut square_c) = (MULTIPLIER, self.increment);
        let mut left = delta;
        while left > 0 {
            if left & 1 == 1 {
                a = a.wrapping_mul(square_a);
                c = c.wrapping_mul(square_a).wrapping_add(square_c);
            }
            square_c = square_a.wrapping_add(1).wrapping_mul(square_c);
            square_a = square_a.wrapping_mul(square_a);
            left >>= 1;
        }
        self.state = a.wrapping_mul(self.state).wrapping_add(c);
    }

    /// This generator advanced by `delta` outputs (self is unchanged).
    pub fn jumped(&self, delta: u64) -> Self {
        let mut r = self.clone();
        r.advance(delta);
        r
    }

    /// Fills `out` with the next `out.len()` floats of this stream, on all
    /// cores, and advances past them.
    ///
    /// # Errors
    /// Only if the thread count cannot be determined.
    pub fn fill<F: Real>(&mut self, out: &mut [F]) -> Result<()> {
        self.fill_with(out, Self::next_float)
    }

    /// Fills `out` with the next `out.len()` 32-bit outputs and advances past
    /// them.
    ///
    /// # Errors
    /// As [`Rng::fill`].
    pub fn fill_u32(&mut self, out: &mut [u32]) -> Result<()> {
        self.fill_with(out, Self::next_u32)
    }

    /// `out[i]` = `next` of the stream advanced by `i` (one draw each), on
    /// all cores; then advances past them.
    fn fill_with<T: Send>(
        &mut self,
        out: &mut [T],
        next: impl Fn(&mut Self) -> T + Sync,
    ) -> Result<()> {
        let n = out.len();
        let base = &*self;
        parallel::for_each_chunk(n, out, |range, chunk| {
            let mut rng = base.jumped(range.start as u64);
            chunk.iter_mut().for_each(|x| *x = next(&mut rng));
            true
        })?;
        self.advance(n as u64);
        Ok(())
    }
}

/// For each `(seed, stream)` of `starts`, the first `at.len()` floats of
/// `Rng::new(seed, stream)`, float `k` at `row[at[k]]` of the sample's row
/// of `out` (`out.len() / starts.len()` floats), and that generator after
/// them in `after`: bit for bit [`Rng::new`] and [`Rng::next_float`], at
/// SIMD width.
///
/// Each sample's generator is seeded by [`Rng::new`] and stepped in one
/// lane (`step`, `output`).
///
/// # Panics
/// When `out.len()` is not a multiple of `starts.len()`, an offset is not
/// within a row, or `after` is not as long as `starts`.
pub fn first_floats(starts: &[(u64, u64)], at: &[usize], out: &mut [f32], after: &mut [Rng]) {
    let Some(stride) = out.len().checked_div(starts.len()) else {
        return;
    };
    assert!(out.len() == stride * starts.len() && after.len() == starts.len());
    assert!(at.iter().all(|&k| k < stride));
    const BLOCK: usize = crate::simd::BLOCK;
    crate::simd::dispatch(
        #[inline(always)]
        |_| {
            let blocks = starts.chunks(BLOCK).zip(after.chunks_mut(BLOCK));
            for (b, (starts, after)) in blocks.enumerate() {
                let first = b * BLOCK * stride;
                let rows = &mut out[first..first + starts.len() * stride];
                let (mut c, mut s) = ([0; BLOCK], [0; BLOCK]);
                for ((&(seed, stream), c), s) in starts.iter().zip(&mut c).zip(&mut s) {
                    let rng = Rng::new(seed, stream);
                    (*c, *s) = (rng.increment, rng.state);
                }
                for &k in at {
                    let mut column = [0.0; BLOCK];
                    for ((column, s), c) in column.iter_mut().zip(&mut s).zip(&c) {
                        *column = f32::from_random_bits(output(*s));
                        *s = step(*s, *c);
                    }
                    for (row, &v) in rows.chunks_exact_mut(stride).zip(&column) {
                        row[k] = v;
                    }
                }
                for ((a, &state), &increment) in after.iter_mut().zip(&s).zip(&c) {
                    *a = Rng { state, increment };
                }
            }
        },
    );
}

/// `n × dim` uniform floats in `[0, 1)`, row-major: the first `n·dim` floats
/// of `Rng::new(seed, 0)`.
///
/// # Errors
/// [`crate::Error::Memory`] when the memory cannot be had; if the thread
/// count cannot be determined.
pub fn uniform<F: Real>(n: usize, dim: usize, seed: u64) -> Result<Vec<F>> {
    let len = n.saturating_mul(dim);
    let mut out = crate::alloc::filled(len, F::zero(), "the uniform values")?;
    Rng::new(seed, 0).fill(&mut out)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first outputs of `pcg32_srandom_r(42, 54)`, as printed by the
    /// reference implementation's demo program (pcg-c-basic).
    const REFERENCE_42_54: [u32; 6] = [
        0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e,
    ];

    #[test]
    fn matches_the_reference_implementation() {
        let mut rng = Rng::new(42, 54);
        let got: Vec<u32> = (0..6).map(|_| rng.next_u32()).collect();
        assert_eq!(got, REFERENCE_42_54);
    }

    #[test]
    fn first_floats_are_the_generators_draws() {
        let starts: Vec<(u64, u64)> = (0..150u64)
            .map(|i| (i.wrapping_mul(0x9E37_79B9_7F4A_7C15), i % 7 + (i << 40)))
            .chain([(u64::MAX, MAX_STREAM), (0, 0)])
            .collect();
        let layouts: [(&[usize], usize); 4] = [
            (&[], 2),
            (&[0], 1),
            (&[0, 1, 2, 3], 4),
            (&[4, 0, 1, 2, 3], 6),
        ];
        for (at, stride) in layouts {
            let mut out = vec![-1.0; starts.len() * stride];
            let mut after = vec![Rng::new(0, 0); starts.len()];
            first_floats(&starts, at, &mut out, &mut after);
            for ((&(seed, stream), after), row) in
                starts.iter().zip(&mut after).zip(out.chunks(stride))
            {
                let mut rng = Rng::new(seed, stream);
                let mut expected = vec![-1.0; stride];
                for &k in at {
                    expected[k] = rng.next_float();
                }
                assert_eq!(row, &expected[..], "seed {seed}, stream {stream}");
                assert_eq!(
                    after.next_u64(),
                    rng.next_u64(),
                    "seed {seed}, stream {stream}"
                );
            }
        }
    }

    #[test]
    fn matches_drjit_default_seed_floats() {
        // Dr.Jit's PCG32() with its default state and stream; its test suite
        // pins next_float32 / next_float64 of the first output.
        let (state, stream) = (0x853c49e6748fea9b, 0xda3e39cb94b95bdb);
        assert_eq!(
            Rng::new(state, stream).next_float::<f32>(),
            0.108_378_65_f32
        );
        assert_eq!(
            Rng::new(state, stream).next_float::<f64>(),
            0.108_378_705_102_950_33
        );
    }

    #[test]
    fn equals_rand_pcg() {
        use rand_core::Rng as _;
        let seeds = [0, 1, 42, u64::MAX, 0x853c_49e6_748f_ea9b];
        let streams = [0, 1, 54, MAX_STREAM, u64::MAX];
        for (&seed, &stream) in seeds
            .iter()
            .flat_map(|s| streams.iter().map(move |t| (s, t)))
        {
            let (mut ours, mut theirs) =
                (Rng::new(seed, stream), rand_pcg::Pcg32::new(seed, stream));
            for _ in 0..100 {
                assert_eq!(ours.next_u32(), theirs.next_u32());
            }
            assert_eq!(ours.next_u64(), theirs.next_u64());
            for delta in [0, 1, 2, 1000, 1 << 40, u64::MAX] {
                ours.advance(delta);
                theirs.advance(delta);
                assert_eq!(ours.next_u32(), theirs.next_u32(), "advance({delta})");
            }
        }
    }

    #[test]
    fn resumes_where_its_copy_left() {
        let mut rng = Rng::new(9, 4);
        let mut copy = rng.clone();
        let drawn: Vec<u32> = (0..3).map(|_| copy.next_u32()).collect();
        assert_ne!(rng, copy);
        rng.resume(&copy);
        assert_eq!(rng, copy);
        let mut fresh = Rng::new(9, 4);
        assert_eq!((0..3).map(|_| fresh.next_u32()).collect::<Vec<_>>(), drawn);
        assert_eq!(rng.next_u32(), fresh.next_u32());
    }

    #[test]
    fn advance_equals_stepping() {
        let mut a = Rng::new(7, 3);
        let mut b = a.clone();
        for _ in 0..1000 {
            a.next_u32();
        }
        b.advance(1000);
        assert_eq!(a.next_u32(), b.next_u32());
    }

    #[test]
    fn batch_fill_is_the_sequential_stream_for_any_thread_count() {
        let n = 3 * parallel::CHUNK + 11;
        let mut seq = Rng::new(5, 0);
        let expected: Vec<f64> = (0..n).map(|_| seq.next_float()).collect();
        let mut rng = Rng::new(5, 0);
        let mut got = vec![0.0; n];
        rng.fill(&mut got).unwrap();
        assert_eq!(got, expected);
        assert_eq!(
            rng.next_u32(),
            seq.next_u32(),
            "fill advances past the batch"
        );
        assert_eq!(
            uniform::<f64>(n / 2, 2, 5).unwrap()[..],
            expected[..n / 2 * 2]
        );
    }

    #[test]
    fn floats_lie_in_the_half_open_interval() {
        assert_eq!(f32::from_random_bits(0), 0.0);
        assert!(f32::from_random_bits(u32::MAX) < 1.0);
        assert!(f64::from_random_bits(u32::MAX) < 1.0);
    }
}

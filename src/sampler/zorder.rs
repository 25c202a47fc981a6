//! Z-ordered Sobol' indices (Ahmed and Wronski, "Screen-space blue-noise
//! diffusion of Monte Carlo sampling error via hierarchical ordering of
//! pixels", 2020), the index pbrt-v4's `ZSobolSampler` draws with.
//!
//! Sample `s` of pixel `(x, y)` has the global index
//! `m = morton(x, y)·2^k + s` (`2^k ≥ spp`, pixels in Morton order on a
//! square of side `2^r ≥ max(width, height)`). Read in base 4 from the top,
//! each digit of `m` is replaced by its image under one of the 24
//! permutations of `{0, 1, 2, 3}`, chosen by a hash of the digits above it
//! and of the dimension (an odd `k` leaves a last binary digit, flipped by
//! such a hash). That is a random permutation of the 4-ary tree of
//! indices that keeps every subtree whole, so a pixel's `spp` samples are
//! one aligned block of `2^k` indices of the Sobol' sequence (stratified
//! like any such block), and the blocks of neighbouring pixels are
//! neighbouring quadrants of larger blocks: their errors are negatively
//! correlated, which is blue noise on screen.

use crate::error::{Error, Result};
use crate::qmc::patterns::mix64;

/// The 24 permutations of `{0, 1, 2, 3}`, in lexicographic order.
const PERMUTATIONS: [[u8; 4]; 24] = permutations();

const fn permutations() -> [[u8; 4]; 24] {
    let mut out = [[0u8; 4]; 24];
    let mut k = 0;
    let mut code = 0;
    while code < 256 {
        let p = [code & 3, (code >> 2) & 3, (code >> 4) & 3, (code >> 6) & 3];
        let seen = (1u8 << p[0]) | (1 << p[1]) | (1 << p[2]) | (1 << p[3]);
        if seen == 0b1111 {
            out[k] = [p[0] as u8, p[1] as u8, p[2] as u8, p[3] as u8];
            k += 1;
        }
        code += 1;
    }
    out
}

/// The first Sobol' dimension (van der Corput's) of index `i`, as 32
/// bits reversed (which are the index's low 32 bits).
#[inline(always)]
pub fn sobol0_reversed(i: u64) -> u32 {
    i as u32
}

/// The first two Sobol' dimensions of index `i` (natural order), as 32
/// bits each, reversed.
///
/// The second dimension's generator matrix is Pascal's triangle mod 2:
/// digit `r` of the value is the parity of the index bits `b` with
/// `binom(b, r)` odd, which by Lucas is `r & !b = 0` (the positions `b`
/// whose bits include those of `r`). That sum over supersets is six
/// shift-and-xor steps, one per bit of a position, on the index itself.
#[inline]
pub fn sobol01_reversed(i: u64) -> (u32, u32) {
    const LOW_HALVES: [u64; 6] = [
        0x5555_5555_5555_5555,
        0x3333_3333_3333_3333,
        0x0f0f_0f0f_0f0f_0f0f,
        0x00ff_00ff_00ff_00ff,
        0x0000_ffff_0000_ffff,
        0x0000_0000_ffff_ffff,
    ];
    let mut y = i;
    for (k, mask) in LOW_HALVES.iter().enumerate() {
        y ^= (y >> (1 << k)) & mask;
    }
    (sobol0_reversed(i), y as u32)
}

/// The z-order of one pixel's samples (the default: a single pixel).
#[derive(Clone, Copy, Debug, Default)]
pub struct ZOrder {
    /// `morton(x, y)·2^k`.
    base: u64,
    /// `k = ⌈log2 spp⌉`.
    log2_count: u32,
    /// Base-4 digits of the index (`r + ⌈k/2⌉`).
    digits: u32,
    seed: u64,
}

/// Spreads the low 32 bits of `v` to the even bits.
fn spread(v: u64) -> u64 {
    let mut v = v & 0xffff_ffff;
    v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
    v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
    v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
    v = (v | (v << 2)) & 0x3333_3333_3333_3333;
    (v | (v << 1)) & 0x5555_5555_5555_5555
}

impl ZOrder {
    /// Checks that the global index of `count` samples per pixel on a
    /// film of `width × height` fits in 64 bits.
    ///
    /// # Errors
    /// [`Error::Integer`] naming `spp` when it would not
    /// (`2·⌈log2 max(width, height)⌉ + ⌈log2 spp⌉ > 64`).
    pub fn check(film: (usize, usize), count: u64) -> Result<()> {
        let (log2_side, log2_count) = Self::log2_sizes(film, count);
        if 2 * log2_side + log2_count > 64 {
            return Err(Error::Integer {
                arg: "spp",
                value: count.to_string(),
                requirement: format!(
                    "with sampler=\"zsobol\" on a film of width {} and height {}, 2·⌈log2 max(width, height)⌉ + ⌈log2 spp⌉ must be at most 64",
                    film.0, film.1
                ),
            });
        }
        Ok(())
    }

    fn log2_sizes(film: (usize, usize), count: u64) -> (u32, u32) {
        let side = film.0.max(film.1).max(1).next_power_of_two();
        (
            side.trailing_zeros(),
            count.max(1).next_power_of_two().trailing_zeros(),
        )
    }

    /// The order of pixel `(x, y)`'s `count` samples on a film of
    /// `width × height`, from `seed` ([`ZOrder::check`]ed by the caller).
    pub fn new(pixel: (usize, usize), film: (usize, usize), count: u64, seed: u64) -> Self {
        let (log2_side, log2_count) = Self::log2_sizes(film, count);
        let morton = spread(pixel.0 as u64) | (spread(pixel.1 as u64) << 1);
        ZOrder {
            base: morton.checked_shl(log2_count).unwrap_or(0),
            log2_count,
            digits: log2_side + log2_count.div_ceil(2),
            seed,
        }
    }

    /// The sampler's seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The shuffled global index of sample `s` for the dimension whose
    /// hashed seed is `h`: [`ZOrder::block`] `|` [`ZOrder::within`].
    #[inline]
    pub fn sample_index(&self, s: u32, h: u64) -> u64 {
        self.block(h) | self.within(s, h)
    }

    /// The shuffled digits above the pixel's samples (the same for all of
    /// them): where the pixel's block of `2^k` indices went.
    pub fn block(&self, h: u64) -> u64 {
        let first = self.log2_count.div_ceil(2);
        self.shuffle(self.base, h, first..self.digits)
    }

    /// The shuffled digits of sample `s` within its pixel's block.
    #[inline]
    pub fn within(&self, s: u32, h: u64) -> u64 {
        let m = self.base | u64::from(s);
        let odd = self.log2_count & 1;
        let mut out = self.shuffle(m, h, odd..self.log2_count.div_ceil(2));
        if odd == 1 {
            out |= (m & 1) ^ (mix64((m >> 1) ^ h) & 1);
        }
        out
    }

    /// The base-4 digits `digits` of `m` (digit `i` at bit `2i − (k mod
    /// 2)`), each replaced by its image under the permutation that a hash
    /// of the digits above it and `h` picks.
    #[inline]
    fn shuffle(&self, m: u64, h: u64, digits: std::ops::Range<u32>) -> u64 {
        let odd = self.log2_count & 1;
        let mut out = 0u64;
        for i in digits.rev() {
            let shift = 2 * i - odd;
            let digit = ((m >> shift) & 3) as usize;
            let higher = m.checked_shr(shift + 2).unwrap_or(0);
            let p = ((mix64(higher ^ h) >> 32) % 24) as usize;
            out |= u64::from(PERMUTATIONS[p][digit]) << shift;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qmc::directions::columns;

    #[test]
    fn the_second_dimension_is_pascals_triangle() {
        // The map is linear over GF(2), so the unit indices settle it: the
        // Joe–Kuo columns below bit 32, Lucas's rule above.
        let v = columns(2)[1].map(u32::reverse_bits);
        for b in 0..64 {
            let column = sobol01_reversed(1 << b).1;
            let lucas = (0..32).filter(|r| r & !b == 0).fold(0, |c, r| c | 1 << r);
            assert_eq!(column, v.get(b).copied().unwrap_or(lucas), "bit {b}");
            assert_eq!(column, lucas, "bit {b}");
        }
    }

    #[test]
    fn permutations_are_distinct() {
        let mut p = PERMUTATIONS.to_vec();
        p.sort();
        p.dedup();
        assert_eq!(p.len(), 24);
    }

    #[test]
    fn a_pixel_gets_one_aligned_block() {
        // Every pixel's samples map to one aligned block of 2^k indices,
        // and the pixels' blocks tile the sequence.
        for spp in [1u64, 2, 4, 8, 16] {
            let (w, h) = (5, 3);
            let mut blocks = Vec::new();
            for y in 0..h {
                for x in 0..w {
                    let z = ZOrder::new((x, y), (w, h), spp, 7);
                    let idx: Vec<u64> = (0..spp as u32).map(|s| z.sample_index(s, 99)).collect();
                    let block = idx[0] / spp;
                    assert!(idx.iter().all(|i| i / spp == block), "spp {spp}");
                    let mut low: Vec<u64> = idx.iter().map(|i| i % spp).collect();
                    low.sort();
                    assert_eq!(low, (0..spp).collect::<Vec<_>>());
                    blocks.push(block);
                }
            }
            blocks.sort();
            blocks.dedup();
            assert_eq!(blocks.len(), w * h);
        }
    }

    #[test]
    fn too_many_bits_is_an_error() {
        assert!(ZOrder::check((1 << 16, 1 << 16), 1 << 32).is_ok());
        assert!(ZOrder::check((1 << 16, 1 << 16), (1 << 32) + 1).is_err());
        assert!(ZOrder::check(((1 << 16) + 1, 1), 1 << 31).is_err());
    }
}

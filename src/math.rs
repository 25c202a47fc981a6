//! Scalar type abstraction and small numeric helpers shared by all kernels.
//!
//! Every kernel is written once, generic over [`Real`], and instantiated for
//! `f32` (fast path: float32 in, float32 out) and `f64`.

use num_traits::{Float, FloatConst};
use std::fmt::Debug;

/// A point of the unit square or a planar domain.
pub type P2<F> = [F; 2];
/// A direction (unit vector) or a 3D point.
pub type V3<F> = [F; 3];

/// The dot product `a · b`.
#[inline(always)]
pub fn dot<F: Real>(a: V3<F>, b: V3<F>) -> F {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The cross product `a × b`.
#[inline(always)]
pub fn cross<F: Real>(a: V3<F>, b: V3<F>) -> V3<F> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A floating-point type a kernel can run in: `f32` or `f64`.
pub trait Real: Float + FloatConst + Debug + Default + Send + Sync + 'static {
    /// The largest value below 1; `u = 1.0` is clamped to it where a kernel
    /// needs a half-open interval.
    const ONE_MINUS_EPSILON: Self;

    /// Converts an `f64` constant (rounding to nearest for `f32`).
    fn c(x: f64) -> Self;

    /// Converts to `f64` exactly.
    fn f64(self) -> f64;

    /// Maps 32 random bits to `[0, 1)` as Dr.Jit's `PCG32` does: `f32` keeps
    /// the top 23 bits (`next_float32`), `f64` all 32 (`next_float64`), by
    /// filling the mantissa of a number in `[1, 2)` and subtracting 1.
    fn from_random_bits(bits: u32) -> Self;

    /// `(sin x, cos x)` for `|x| ≤ π/4` by polynomials good to this type's
    /// precision (minimax to x⁷/x⁶ in `f32`, Taylor to x¹⁷/x¹⁶ in `f64`):
    /// branch-free and without library calls, so loops over it vectorise.
    fn sin_cos_octant(x: Self) -> (Self, Self);

    /// `(sin 2πt, cos 2πt)` for `t` in `[0, 1]` (a fraction of a turn), see
    /// [`sin_cos_turn`].
    fn sin_cos_turn(t: Self) -> (Self, Self);

    /// `xʸ` for finite `x ≥ 0` and `y ≥ 0` with `xʸ < 2¹⁰²³` (the callers
    /// have `x ≤ 1`: cosines, uniform numbers), as `2^(y·log₂x)` with
    /// polynomials (no branches, no library calls, so loops vectorise):
    /// relative error below 2e-13 (computed in `f64` for both types); exact at
    /// `x = 1` and `y = 0`; 0 for `x = 0` (or a subnormal `x`) unless
    /// `y = 0`, and 0 where the result underflows.
    fn pow_positive(x: Self, y: Self) -> Self;
    /// `atan r` for `|r| ≤ tan(π/8)`: in `f64` by its Taylor series
    /// `Σ (−1)ᵏ r²ᵏ⁺¹/(2k+1)` cut where the next term is below the precision
    /// (21 terms); in `f32` by a fitted polynomial of 6 terms (`ATAN_F32`,
    /// where the series needs 10: a fifth of `EnvMap.pdf`'s time). Evaluated
    /// by Estrin's scheme: branch-free, without library calls.
    fn atan_reduced(r: Self) -> Self;

    /// `ln(1 − u)` for `u ∈ [0, 1]` (`−∞` at 1) in this type's precision:
    /// [`ln_one_minus`] in `f64`, the same series cut at this type's
    /// precision in `f32` (vectorised at twice the width).
    fn ln_one_minus(u: Self) -> Self;
    /// `ln x` for a positive `x` (`−∞` for 0) in this type's precision:
    /// [`ln_positive`] in `f64` (for a normal `x`), the same series cut at
    /// this type's precision in `f32` (for any positive `x`, subnormals
    /// too).
    fn ln_positive(x: Self) -> Self;

    /// `⌊x⌋` as an index clamped to `[0, last]` (0 for NaN; in `f32` at
    /// most `2³¹ − 128`, the largest `f32` below 2³¹), in `u32`, which
    /// takes fewer instructions than `usize`; clamped as a float and then
    /// converted, so that a loop of it vectorises.
    fn floor_u32(self, last: u32) -> u32;

    /// [`Real::floor_u32`] as a `usize`, for `last` below 2³² (a larger
    /// one is taken as `u32::MAX`).
    #[inline(always)]
    fn floor_index(self, last: usize) -> usize {
        self.floor_u32(u32::try_from(last).unwrap_or(u32::MAX)) as usize
    }
}

/// The first `N` Taylor coefficients of `atan r / r` in powers of `r²`:
/// `(−1)ᵏ/(2k+1)`.
const fn atan_series<const N: usize>() -> [f64; N] {
    let mut c = [0.0; N];
    let mut k = 0;
    while k < N {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        c[k] = sign / (2 * k + 1) as f64;
        k += 1;
    }
    c
}

/// `atan r / r ≈ Σ cₖ r²ᵏ` on `|r| ≤ tan(π/8)` for `f32`: a fit of degree
/// 5 in `r²` that brings the relative error to 6·10⁻¹⁰ (nearly minimax;
/// weighted least squares at Chebyshev nodes), where the Taylor series
/// needs 10 terms for `f32`'s precision.
const ATAN_F32: [f64; 6] = [
    0.999_999_999_396_665_1,
    -0.333_333_076_257_264_5,
    0.199_982_169_422_475_65,
    -0.142_400_829_207_627_98,
    0.105_734_792_222_187_48,
    -0.060_347_889_954_566_23,
];

/// Estrin's evaluation of `c[0] + c[1] y + c[2] y² + …`: neighbouring terms
/// paired as `c[2i] + c[2i+1] y`, then the pairs in `y²`, and so on, so the
/// chain of dependent operations is `log₂ N` long instead of Horner's `N`
/// (what a single evaluation waits for). Plain multiply and add, as
/// [`horner`].
#[inline(always)]
fn estrin<F: Real, const N: usize>(y: F, c: &[f64; N]) -> F {
    let mut terms: [F; N] = std::array::from_fn(|i| F::c(c[i]));
    let (mut len, mut power) = (N, y);
    while len > 1 {
        let half = len.div_ceil(2);
        for i in 0..half {
            let high = if 2 * i + 1 < len {
                terms[2 * i + 1] * power
            } else {
                F::zero()
            };
            terms[i] = terms[2 * i] + high;
        }
        len = half;
        power = power * power;
    }
    terms[0]
}

/// Horner evaluation of `c[0] + c[1] y + c[2] y² + …`, from the last
/// coefficient (a fold from 0 costs a multiply and an add that the compiler
/// may not drop: `0·y` is not 0 for an infinite `y`). Plain multiply and
/// add (no `mul_add`, which becomes a library call wherever the code is not
/// compiled for FMA hardware): the same bits on every path.
#[inline(always)]
fn horner<F: Real>(y: F, c: &[f64]) -> F {
    match c.split_last() {
        Some((&last, rest)) => rest
            .iter()
            .rev()
            .fold(F::c(last), |acc, &k| acc * y + F::c(k)),
        None => F::zero(),
    }
}

/// [`Real::sin_cos_turn`] for one float type and its same-width unsigned
/// integer. Adding `1.5·2^(p−1)` (p mantissa digits) to `4t` rounds it to
/// the nearest whole number `k` and leaves `k` in the low mantissa bits,
/// which give the quadrant without a float-to-integer conversion. The
/// reduction `4t − k` is exact.
macro_rules! sin_cos_turn {
    ($F:ty, $U:ty) => {
        #[inline(always)]
        fn sin_cos_turn(t: $F) -> ($F, $F) {
            let magic = 1.5 * (1u64 << (<$F>::MANTISSA_DIGITS - 1)) as $F;
            let four_t = 4.0 * t;
            let rounded = four_t + magic;
            let k = rounded.to_bits();
            let (s, c) = Self::sin_cos_octant((four_t - (rounded - magic)) * Self::FRAC_PI_2());
            // Quadrant k mod 4: 0 → (s, c), 1 → (c, −s), 2 → (−s, −c),
            // 3 → (−c, s): a swap for odd k, then sign flips on the bits.
            let swap = k & 1 != 0;
            let (s, c) = (if swap { c } else { s }, if swap { s } else { c });
            let shift = <$U>::BITS - 2;
            let s_sign = (k & 2) << shift;
            let c_sign = (k.wrapping_add(1) & 2) << shift;
            (
                <$F>::from_bits(s.to_bits() ^ s_sign),
                <$F>::from_bits(c.to_bits() ^ c_sign),
            )
        }
    };
}

/// `xʸ` in `f64` (see [`Real::pow_positive`]).
///
/// `log₂x = e + log₂m` with `x = m·2ᵉ`, `m ∈ [√½, √2)`, and
/// `log₂m = (2/ln 2)·atanh(s)`, `s = (m − 1)/(m + 1)` (odd series in `s`);
/// `2ᵗ = 2ᵏ·e^(f·ln 2)` with `k` the whole number nearest `t` (ties to
/// odd) and `|f| ≤ ½` (Taylor series), `2ᵏ` built from its bits. Both
/// polynomials are evaluated by Estrin's scheme: the loops that call `pow`
/// (the cosine-power warp, Phong) wait on the chain of dependent
/// operations, and Horner's is 24 steps long (Estrin's: 8), at the same
/// accuracy. The whole numbers `e` and `k` stay floats: a biased exponent
/// field is read as a float by placing it in the mantissa of `2⁵²` (and
/// written back from the low mantissa bits of `t + 1.5·2⁵² + 1023`),
/// because AVX2 has no conversion between `f64` and 64-bit integers and a
/// loop that needs one runs one lane at a time.
#[inline(always)]
fn pow_unit(x: f64, y: f64) -> f64 {
    const MANTISSA_BITS: u32 = 52;
    const BIAS: f64 = 1023.0;
    /// `1.5·2⁵² + BIAS`: `t + ROUNDER` (`−2⁵¹ − BIAS ≤ t < 2⁵¹ − BIAS`; here
    /// `−1022 ≤ t < 1023`) lies in `[2⁵², 2⁵³)`, where the sum rounds to a
    /// whole number: `k`, `t` rounded to the nearest whole number, ties to
    /// the odd one (`ROUNDER` is odd, the sum rounds ties to even), with
    /// `2⁵¹ + k + BIAS` in the mantissa. One addition, no rounding
    /// instruction (`floor` would be a library call in code built for
    /// baseline x86-64, such as bidirectional path tracing's Phong draws).
    const ROUNDER: f64 = 1.5 * (1u64 << MANTISSA_BITS) as f64 + BIAS;
    let (m, e) = mantissa_exponent(x);
    let s = (m - 1.0) / (m + 1.0);
    let log2_m = s * estrin(s * s, &ATANH_OVER_S) * (2.0 * std::f64::consts::LOG2_E);
    let t = (y * (e + log2_m)).max(1.0 - BIAS);
    let rounded = t + ROUNDER;
    let k = rounded - ROUNDER;
    let p = estrin((t - k) * std::f64::consts::LN_2, &EXP);
    // k + BIAS in [1, 2046] (results below 2¹⁰²³): the low mantissa bits
    // of `rounded`, shifted into the exponent field.
    let scale = f64::from_bits(rounded.to_bits() << MANTISSA_BITS);
    let result = p * scale;
    // x = 0 or subnormal: 0ʸ (1 for y = 0); underflow: 0.
    let tiny = x < f64::MIN_POSITIVE;
    let underflow = t <= 1.0 - BIAS;
    if y == 0.0 {
        1.0
    } else if tiny | underflow {
        0.0
    } else {
        result
    }
}

/// `x = m·2ᵉ` for a positive normal `x`, with `m ∈ [√½, √2)` and the whole
/// number `e` as a float (read from the exponent field by way of the
/// mantissa of `2⁵²`, as `pow_unit` explains).
#[inline(always)]
fn mantissa_exponent(x: f64) -> (f64, f64) {
    const MANTISSA_BITS: u32 = 52;
    const SHIFTER: f64 = (1u64 << MANTISSA_BITS) as f64;
    let bits = x.to_bits();
    let field = f64::from_bits((bits >> MANTISSA_BITS) | SHIFTER.to_bits()) - SHIFTER;
    let m = f64::from_bits((bits & ((1 << MANTISSA_BITS) - 1)) | 1.0f64.to_bits());
    let big = m > std::f64::consts::SQRT_2;
    (
        if big { 0.5 * m } else { m },
        field - 1023.0 + if big { 1.0 } else { 0.0 },
    )
}

/// `e·ln 2 + ln m` with `ln m = 2 atanh(s)`, `s = (m − 1)/(m + 1)`.
#[inline(always)]
fn ln_from_parts(e: f64, s: f64) -> f64 {
    e * std::f64::consts::LN_2 + 2.0 * s * estrin(s * s, &ATANH_OVER_S)
}

/// `ln x` for `x > 0` (normal) in `f64`, `−∞` for `x = 0`: `x = m·2ᵉ`,
/// `ln x = e·ln 2 + 2 atanh((m − 1)/(m + 1))` (the series of
/// `pow_positive`), without library calls, so loops over it vectorise.
#[inline(always)]
pub fn ln_positive(x: f64) -> f64 {
    let (m, e) = mantissa_exponent(x);
    let ln = ln_from_parts(e, (m - 1.0) / (m + 1.0));
    if x > 0.0 { ln } else { f64::NEG_INFINITY }
}

/// `ln(1 − u)` for `u ∈ [0, 1]` in `f64` (`−∞` at 1), as [`ln_positive`] but keeping
/// the relative precision near `u = 0` that `1 − u` loses: there
/// (`u < 1 − √½`, where `1 − u` is its own mantissa) `s = −u/(2 − u)`
/// directly.
#[inline(always)]
pub fn ln_one_minus(u: f64) -> f64 {
    let (m, e) = mantissa_exponent(1.0 - u);
    let near = u < 1.0 - std::f64::consts::FRAC_1_SQRT_2;
    // The operands chosen, then one division for both cases.
    let (num, den) = if near {
        (-u, 2.0 - u)
    } else {
        (m - 1.0, m + 1.0)
    };
    let ln = ln_from_parts(if near { 0.0 } else { e }, num / den);
    if u < 1.0 { ln } else { f64::NEG_INFINITY }
}

/// `x = m·2ᵉ` for a positive normal `f32` `x`, `m ∈ [√½, √2)` and the
/// whole number `e` as a float, read from its bits.
#[inline(always)]
fn mantissa_exponent_f32(x: f32) -> (f32, f32) {
    const MANTISSA: u32 = (1 << 23) - 1;
    let bits = x.to_bits();
    let field = ((bits >> 23) as i32 - 127) as f32;
    let m = f32::from_bits((bits & MANTISSA) | 1.0f32.to_bits());
    if m > std::f32::consts::SQRT_2 {
        (0.5 * m, field + 1.0)
    } else {
        (m, field)
    }
}

/// `e·ln 2 + 2 atanh(s)` in `f32`: `|s| ≤ 3 − 2√2`, so five terms of the
/// series reach `f32` precision (the sixth, `s¹⁰/11`, is below `2·10⁻⁹` of
/// the sum).
#[inline(always)]
fn ln_from_parts_f32(e: f32, s: f32) -> f32 {
    e * std::f32::consts::LN_2 + 2.0 * s * estrin(s * s, &ATANH_OVER_S_F32)
}

/// [`ln_positive`] in `f32`: `x = m·2ᵉ`, `s = (m − 1)/(m + 1)`; a
/// subnormal `x` is scaled by `2²⁴` first (and `e` lowered by 24), so
/// every positive `f32` has its logarithm.
#[inline(always)]
fn ln_positive_f32(x: f32) -> f32 {
    let subnormal = x < f32::MIN_POSITIVE;
    let scaled = if subnormal { x * 16_777_216.0 } else { x };
    let (m, e) = mantissa_exponent_f32(scaled);
    let e = if subnormal { e - 24.0 } else { e };
    let ln = ln_from_parts_f32(e, (m - 1.0) / (m + 1.0));
    if x > 0.0 { ln } else { f32::NEG_INFINITY }
}

/// [`ln_one_minus`] in `f32`: `1 − u = m·2ᵉ` read from its bits, `s = (m −
/// 1)/(m + 1)`, or `s = −u/(2 − u)` for `u < 1 − √½`.
#[inline(always)]
fn ln_one_minus_f32(u: f32) -> f32 {
    let (m, e) = mantissa_exponent_f32(1.0 - u);
    let near = u < 1.0 - std::f32::consts::FRAC_1_SQRT_2;
    // The operands chosen, then one division for both cases.
    let (num, den, e) = if near {
        (-u, 2.0 - u, 0.0)
    } else {
        (m - 1.0, m + 1.0, e)
    };
    let ln = ln_from_parts_f32(e, num / den);
    if u < 1.0 { ln } else { f32::NEG_INFINITY }
}

/// The first five terms of [`ATANH_OVER_S`], for [`ln_from_parts_f32`].
const ATANH_OVER_S_F32: [f64; 5] = [1.0, 1.0 / 3.0, 1.0 / 5.0, 1.0 / 7.0, 1.0 / 9.0];

/// `1/(2k + 1)`: the series of `atanh(s)/s` in `s²`.
const ATANH_OVER_S: [f64; 10] = [
    1.0,
    1.0 / 3.0,
    1.0 / 5.0,
    1.0 / 7.0,
    1.0 / 9.0,
    1.0 / 11.0,
    1.0 / 13.0,
    1.0 / 15.0,
    1.0 / 17.0,
    1.0 / 19.0,
];

/// `1/k!`: the series of `eᶻ`.
const EXP: [f64; 14] = [
    1.0,
    1.0,
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5040.0,
    1.0 / 40_320.0,
    1.0 / 362_880.0,
    1.0 / 3_628_800.0,
    1.0 / 39_916_800.0,
    1.0 / 479_001_600.0,
    1.0 / 6_227_020_800.0,
];

/// Minimax coefficients (fitted for this crate by Lawson's iteration on
/// `|x| ≤ π/4`) of `sin x = x + x·y·(s₁ + s₂y + s₃y²)` and
/// `cos x = 1 + y·(c₁ + c₂y + c₃y²)`, `y = x²`: within 4e-8 and 1e-7 of
/// the true values in `f32` arithmetic.
const SIN_F32: [f64; 3] = [
    -0.166_666_509_243_536_54,
    0.008_331_989_733_128_929,
    -0.000_194_967_814_174_672,
];
const COS_F32: [f64; 3] = [
    -0.499_998_960_395_355_63,
    0.041_656_353_407_869_19,
    -0.001_359_846_284_213_661,
];

/// Taylor coefficients of `sin x / x` and `cos x` in powers of `x²` (the
/// `f64` polynomials).
const SIN_OVER_X: [f64; 9] = [
    1.0,
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
    1.0 / 355_687_428_096_000.0,
];
const COS: [f64; 9] = [
    1.0,
    -1.0 / 2.0,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
];

impl Real for f32 {
    const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;
    #[inline(always)]
    fn sin_cos_octant(x: f32) -> (f32, f32) {
        let y = x * x;
        let s = x * y * horner(y, &SIN_F32) + x;
        let c = y * horner(y, &COS_F32) + 1.0;
        (s, c)
    }
    sin_cos_turn!(f32, u32);
    /// Computed in `f64`: in `f32`, `y·log₂x` would lose the result's
    /// precision for large `y`.
    #[inline(always)]
    fn pow_positive(x: f32, y: f32) -> f32 {
        pow_unit(x as f64, y as f64) as f32
    }
    #[inline(always)]
    fn atan_reduced(r: f32) -> f32 {
        r * estrin(r * r, &ATAN_F32)
    }
    #[inline(always)]
    fn ln_one_minus(u: f32) -> f32 {
        ln_one_minus_f32(u)
    }
    #[inline(always)]
    fn ln_positive(x: f32) -> f32 {
        ln_positive_f32(x)
    }
    #[inline(always)]
    fn c(x: f64) -> f32 {
        x as f32
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn floor_u32(self, last: u32) -> u32 {
        // Clamped in floats first (`max` takes NaN to 0) to the largest
        // `f32` below 2³¹, so that the conversion needs no saturation: one
        // instruction at SIMD width, where the saturating `as` is scalar;
        // then to `last` in integers (`last as f32` would round). (Not
        // `clamp`, which keeps NaN.)
        #[allow(clippy::manual_clamp)]
        let x = self.max(0.0).min(2_147_483_520.0);
        #[allow(unsafe_code)]
        // SAFETY: `x` is finite and in `[0, 2³¹)`, which `i32` holds.
        let i = unsafe { x.to_int_unchecked::<i32>() };
        (i as u32).min(last)
    }
    #[inline(always)]
    fn from_random_bits(bits: u32) -> f32 {
        f32::from_bits((bits >> 9) | 0x3f80_0000) - 1.0
    }
}

impl Real for f64 {
    const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;
    #[inline(always)]
    fn sin_cos_octant(x: f64) -> (f64, f64) {
        let y = x * x;
        (x * horner(y, &SIN_OVER_X), horner(y, &COS))
    }
    sin_cos_turn!(f64, u64);
    #[inline(always)]
    fn pow_positive(x: f64, y: f64) -> f64 {
        pow_unit(x, y)
    }
    #[inline(always)]
    fn atan_reduced(r: f64) -> f64 {
        r * estrin(r * r, &const { atan_series::<21>() })
    }
    #[inline(always)]
    fn ln_one_minus(u: f64) -> f64 {
        ln_one_minus(u)
    }
    #[inline(always)]
    fn ln_positive(x: f64) -> f64 {
        ln_positive(x)
    }
    #[inline(always)]
    fn c(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn floor_u32(self, last: u32) -> u32 {
        // Clamped in floats first (`max` takes NaN to 0) to `u32::MAX`,
        // which `f64` holds exactly, so that the conversion needs no
        // saturation: one instruction at SIMD width on AVX-512, where the
        // saturating `as` converts lane by lane. The same values as `as`.
        #[allow(clippy::manual_clamp)]
        let x = self.max(0.0).min(f64::from(u32::MAX));
        #[allow(unsafe_code)]
        // SAFETY: `x` is finite and in `[0, 2³² − 1]`, which `u32` holds.
        let i = unsafe { x.to_int_unchecked::<u32>() };
        i.min(last)
    }
    #[inline(always)]
    fn from_random_bits(bits: u32) -> f64 {
        f64::from_bits(((bits as u64) << 20) | 0x3ff0_0000_0000_0000) - 1.0
    }
}

/// `sqrt(max(x, 0))`: a square root that never returns NaN for round-off
/// negatives.
#[inline(always)]
pub fn safe_sqrt<F: Real>(x: F) -> F {
    x.max(F::zero()).sqrt()
}

/// `(sin 2πt, cos 2πt)` for `t` in `[0, 1]` (a fraction of a turn):
/// reduced exactly to the nearest quarter turn `k` (`4t − k` is exact), then
/// [`Real::sin_cos_octant`], and a swap and sign flips for the quadrant,
/// all without branches or library calls.
#[inline(always)]
pub fn sin_cos_turn<F: Real>(t: F) -> (F, F) {
    F::sin_cos_turn(t)
}

/// `atan2(y, x)` in `(−π, π]` (the library's signs and values at ±0 and
/// on the axes), branch-free and without library calls, so that loops over
/// it vectorise: with `lo = min(|x|, |y|)`, `hi = max(|x|, |y|)`,
/// `r = lo/hi` in `[0, tan(π/8)]`, or, where `lo > (√2 − 1)·hi`,
/// `r = (lo − hi)/(lo + hi)` (`atan(lo/hi) = π/4 + atan r`): one division
/// of the chosen numerator and denominator, which holds subnormal inputs
/// too. Then [`Real::atan_reduced`] and the octant's reflections. Within 3
/// ulp of the library's in `f64` and 4 in `f32`. Inputs are finite.
#[inline(always)]
pub fn atan2<F: Real>(y: F, x: F) -> F {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let big = lo > F::c(std::f64::consts::SQRT_2 - 1.0) * hi;
    // (lo − hi)/(lo + hi) from lo and hi directly: one rounding fewer than
    // from lo/hi. (0/1 at the origin.)
    let (num, den) = if big { (lo - hi, lo + hi) } else { (lo, hi) };
    let r = num / if hi > F::zero() { den } else { F::one() };
    let a = F::atan_reduced(r);
    let a = if big { a + F::FRAC_PI_4() } else { a };
    let a = if ay > ax { F::FRAC_PI_2() - a } else { a };
    let a = if x.is_sign_negative() { F::PI() - a } else { a };
    a.copysign(y)
}

/// Whether `x` lies in the closed unit interval (false for NaN).
#[inline(always)]
pub fn in_unit_interval<F: Real>(x: F) -> bool {
    x >= F::zero() && x <= F::one()
}

/// Rec. 709 luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B`.
#[inline(always)]
pub fn luminance<F: Real>(rgb: [F; 3]) -> F {
    F::c(0.2126) * rgb[0] + F::c(0.7152) * rgb[1] + F::c(0.0722) * rgb[2]
}

#[cfg(test)]
mod tests;

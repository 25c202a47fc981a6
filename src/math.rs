//! Scalar type abstraction and small numeric helpers shared by all kernels.
//!
//! Every kernel is written once, generic over [`Real`], and instantiated for
//! `f32` (fast path: float32 in, float32 out) and `f64`.

use num_traits::{Float, FloatConst};
use std::fmt::Debug;

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
}

impl Real for f32 {
    const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;
    #[inline(always)]
    fn c(x: f64) -> f32 {
        x as f32
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn from_random_bits(bits: u32) -> f32 {
        f32::from_bits((bits >> 9) | 0x3f80_0000) - 1.0
    }
}

impl Real for f64 {
    const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;
    #[inline(always)]
    fn c(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self
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
mod tests {
    use super::*;

    #[test]
    fn one_minus_epsilon_is_the_float_below_one() {
        assert_eq!(f32::ONE_MINUS_EPSILON.to_bits() + 1, 1.0f32.to_bits());
        assert_eq!(f64::ONE_MINUS_EPSILON.to_bits() + 1, 1.0f64.to_bits());
    }

    #[test]
    fn helpers() {
        assert_eq!(safe_sqrt(-1e-12f64), 0.0);
        assert!(!in_unit_interval(f64::NAN));
        assert!(in_unit_interval(1.0f32));
        assert!((luminance([1.0f64, 1.0, 1.0]) - 1.0).abs() < 1e-12);
    }
}

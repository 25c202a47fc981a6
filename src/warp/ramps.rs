//! Tents and linear ramps by inversion, as Mitsuba 3's `mi.warp`: the tent
//! on `[−1, 1]` (and its product on the square), the tent with its peak
//! anywhere in `[a, c]`, and the linear density between two end values.

use super::P2;
use crate::math::{Real, safe_sqrt};

/// The tent `1 − |x|` on `[−1, 1]` by inversion: `s = u − ½`,
/// `x = sign(s)·(1 − √(1 − 2|s|))`. Density per unit length.
///
/// # Density
/// `p(x) = 1 − |x|` on `[−1, 1]` ([`square_to_tent_pdf`] is the product
/// of two).
///
/// # Inverse
/// [`tent_to_interval`]: `u = ½·(x·(2 − |x|) + 1)`.
#[inline(always)]
pub fn interval_to_tent<F: Real>(u: F) -> F {
    let s = u - F::c(0.5);
    let x = F::one() - safe_sqrt(F::one() - F::c(2.0) * s.abs());
    if s < F::zero() { -x } else { x }
}

/// Inverse of [`interval_to_tent`].
#[inline(always)]
pub fn tent_to_interval<F: Real>(x: F) -> F {
    F::c(0.5) * (x * (F::c(2.0) - x.abs()) + F::one())
}

/// [`interval_to_tent`] in each coordinate: the tent
/// `(1 − |x|)(1 − |y|)` on `[−1, 1]²`. Density per unit area.
///
/// # Density
/// [`square_to_tent_pdf`].
///
/// # Inverse
/// [`tent_to_square`].
#[inline(always)]
pub fn square_to_tent<F: Real>(u: P2<F>) -> P2<F> {
    u.map(interval_to_tent)
}

/// Inverse of [`square_to_tent`].
#[inline(always)]
pub fn tent_to_square<F: Real>(p: P2<F>) -> P2<F> {
    p.map(tent_to_interval)
}

/// Density of [`square_to_tent`]: `(1 − |x|)(1 − |y|)` on `[−1, 1]²`
/// (its edges included), else 0.
#[inline(always)]
pub fn square_to_tent_pdf<F: Real>(p: P2<F>) -> F {
    if p[0].abs() <= F::one() && p[1].abs() <= F::one() {
        (F::one() - p[0].abs()) * (F::one() - p[1].abs())
    } else {
        F::zero()
    }
}

/// The tent on `[a, c]` with its peak at `b` (`a ≤ b ≤ c`, `a < c`), as
/// Mitsuba's `interval_to_nonuniform_tent`: for `u·(c − a) < b − a` the
/// rising side, `x = b + (a − b)(1 − √(u·(a − c)/(a − b)))`; else the
/// falling side, `x = b + (c − b)(1 − √(s'))` with
/// `s' = (a − c)/(b − c)·(u − (a − b)/(a − c))` (so `u = 1` gives `b`:
/// the map runs down from `c` on that side). Density per unit length.
///
/// # Density
/// `p(x) = 2(x − a)/((c − a)(b − a))` for `a ≤ x ≤ b`,
/// `2(c − x)/((c − a)(c − b))` for `b ≤ x ≤ c`, else 0.
///
/// For `b = c` the falling side is empty, and `u = 1` stays on the rising
/// side (where Mitsuba's formula divides 0 by 0).
#[inline(always)]
pub fn interval_to_nonuniform_tent<F: Real>(a: F, b: F, c: F, u: F) -> F {
    let rising = u * (c - a) < b - a || b == c;
    let (factor, s) = if rising {
        (a - b, u * ((a - c) / (a - b)))
    } else {
        (c - b, ((a - c) / (b - c)) * (u - (a - b) / (a - c)))
    };
    factor * (F::one() - safe_sqrt(s)) + b
}

/// The linear density on `[0, 1]` from `v0` at 0 to `v1` at 1 (`v0, v1 ≥
/// 0`, not both 0) by inversion: `x = (v0 − √m)/(v0 − v1)` with
/// `m = (1 − u)·v0² + u·v1²`, computed as `u·(v0 + v1)/(v0 + √m)`, or
/// `x = u` when the ends agree to `10⁻⁴` (Mitsuba's test).
/// Density per unit length.
///
/// # Density
/// `p(x) = 2((1 − x)·v0 + x·v1)/(v0 + v1)` on `[0, 1]`.
///
/// # Inverse
/// [`linear_to_interval`]: `u = x·(x·v1 + (2 − x)·v0)/(v0 + v1)`.
#[inline(always)]
pub fn interval_to_linear<F: Real>(v0: F, v1: F, u: F) -> F {
    if (v0 - v1).abs() > F::c(1e-4) * (v0 + v1) {
        // Mitsuba's quotient times (v0 + √m)/(v0 + √m): the same x without
        // the cancellation of v0 − √m when the ends are close.
        let mix = v0 * v0 - v0 * v0 * u + v1 * v1 * u;
        let denominator = v0 + safe_sqrt(mix);
        if denominator > F::zero() {
            (u * (v0 + v1) / denominator).min(F::one())
        } else {
            F::zero()
        }
    } else {
        u
    }
}

/// Inverse of [`interval_to_linear`].
#[inline(always)]
pub fn linear_to_interval<F: Real>(v0: F, v1: F, x: F) -> F {
    if (v0 - v1).abs() > F::c(1e-4) * (v0 + v1) {
        x * (x * v1 + (F::c(2.0) - x) * v0) / (v0 + v1)
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean of `f(sample(u))` over a midpoint grid of `u`.
    fn mean(sample: impl Fn(f64) -> f64, f: impl Fn(f64) -> f64) -> f64 {
        let n = 1_000_000;
        (0..n)
            .map(|k| f(sample((k as f64 + 0.5) / n as f64)))
            .sum::<f64>()
            / n as f64
    }

    /// Each warp's samples have its density's moments: the tent's `E[x] = 0`,
    /// `E[x²] = 1/6`; the nonuniform tent's mean `(a + b + c)/3` and
    /// variance `(a² + b² + c² − ab − ac − bc)/18`; the linear density's mean
    /// `(v0 + 2 v1)/(3 (v0 + v1))`.
    #[test]
    fn samples_have_their_densitys_moments() {
        assert!(mean(interval_to_tent, |x| x).abs() < 1e-9);
        assert!((mean(interval_to_tent, |x| x * x) - 1.0 / 6.0).abs() < 1e-9);
        for (a, b, c) in [
            (-1.0, 0.0, 2.0),
            (0.0, 0.8, 1.0),
            (0.0, 1.0, 1.0),
            (2.0, 2.0, 5.0),
        ] {
            let tent = |u| interval_to_nonuniform_tent(a, b, c, u);
            let m = (a + b + c) / 3.0;
            let var = (a * a + b * b + c * c - a * b - a * c - b * c) / 18.0;
            // The map jumps from b to c where the sides meet, so a grid cell
            // there is off by up to (c − b)/n.
            assert!((mean(tent, |x| x) - m).abs() < 1e-5, "{a} {b} {c}");
            assert!((mean(tent, |x| (x - m) * (x - m)) - var).abs() < 1e-5);
            assert!((a..=c).contains(&tent(1.0)) && (a..=c).contains(&tent(0.0)));
        }
        for (v0, v1) in [(1.0, 3.0), (2.0, 0.0), (0.0, 1.0)] {
            let m = (v0 + 2.0 * v1) / (3.0 * (v0 + v1));
            assert!((mean(|u| interval_to_linear(v0, v1, u), |x| x) - m).abs() < 1e-8);
        }
    }

    #[test]
    fn inverses_undo_the_warps() {
        for k in 0..=100 {
            let u = k as f64 / 100.0;
            assert!((tent_to_interval(interval_to_tent(u)) - u).abs() < 1e-12);
            for (v0, v1) in [(1.0, 3.0), (2.0, 0.0), (0.0, 1.0), (1.0, 1.00001)] {
                let x = interval_to_linear(v0, v1, u);
                assert!((linear_to_interval(v0, v1, x) - u).abs() < 1e-12);
            }
        }
        assert_eq!(square_to_tent_pdf([0.0f64, 0.0]), 1.0);
        assert_eq!(square_to_tent_pdf([1.0f64, 0.5]), 0.0);
        assert_eq!(square_to_tent_pdf([-1.5f64, 0.0]), 0.0);
    }
}

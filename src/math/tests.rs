use super::*;

#[test]
fn one_minus_epsilon_is_the_float_below_one() {
    assert_eq!(f32::ONE_MINUS_EPSILON.to_bits() + 1, 1.0f32.to_bits());
    assert_eq!(f64::ONE_MINUS_EPSILON.to_bits() + 1, 1.0f64.to_bits());
}

/// The logarithms agree with the library's `ln` and `ln_1p` to a few
/// ulp, relatively, from 1e-300 to 1 (1e-12 in `f32`), and `ln_one_minus`
/// near 0, where `ln(1 − u)` would lose it all.
#[test]
fn logarithms_match_the_library() {
    let mut u = 1e-300f64;
    while u < 1.0 {
        for v in [u, 1.0 - u, 0.5 * u + 0.25] {
            let (got, want) = (ln_positive(v), v.ln());
            assert!(
                (got - want).abs() <= 4e-16 * want.abs().max(1e-300),
                "ln {v}"
            );
            if v < 1.0 {
                let (got, want) = (ln_one_minus(v), (-v).ln_1p());
                assert!((got - want).abs() <= 4e-16 * want.abs(), "ln(1 - {v})");
            }
        }
        u *= 1.37;
    }
    assert_eq!(ln_positive(0.0), f64::NEG_INFINITY);
    assert_eq!(ln_one_minus(0.0), 0.0);
    // In f32: within 2 units in the last place of the rounded
    // logarithm, for every u from 2^-40 to 1 − 2^-24.
    let mut u = 1e-12f32;
    while u < 1.0 {
        for v in [u, 1.0 - u, 0.5 * u + 0.25]
            .into_iter()
            .filter(|&v| v < 1.0)
        {
            let (got, want) = (f32::ln_one_minus(v), (-f64::from(v)).ln_1p());
            let ulp = f64::from(f32::EPSILON) * want.abs();
            assert!(
                (f64::from(got) - want).abs() <= 2.0 * ulp,
                "f32 ln(1 - {v})"
            );
            let (got, want) = (f32::ln_positive(v), f64::from(v).ln());
            let ulp = f64::from(f32::EPSILON) * want.abs();
            assert!((f64::from(got) - want).abs() <= 2.0 * ulp, "f32 ln {v}");
        }
        u *= 1.07;
    }
    assert_eq!(f32::ln_one_minus(0.0), 0.0);
    assert_eq!(f32::ln_one_minus(1.0), f32::NEG_INFINITY);
    assert_eq!(f32::ln_positive(0.0), f32::NEG_INFINITY);
    // Subnormals too (Beckmann's warp takes the log of 2·edge for an
    // edge as small as its input numbers).
    for v in [1e-45f32, 3e-42, 1e-40, 1.1e-38, f32::MIN_POSITIVE] {
        let (got, want) = (f32::ln_positive(v), f64::from(v).ln());
        let ulp = f64::from(f32::EPSILON) * want.abs();
        assert!((f64::from(got) - want).abs() <= 2.0 * ulp, "f32 ln {v}");
    }
    assert_eq!(f32::ln_positive(1.0), 0.0);
    assert_eq!(ln_one_minus(1.0), f64::NEG_INFINITY);
    assert_eq!(ln_positive(1.0), 0.0);
}

#[test]
fn sin_cos_match_the_library() {
    for k in 0..=100_000 {
        let t = k as f64 / 100_000.0;
        let (s, c) = sin_cos_turn(t);
        let (rs, rc) = (std::f64::consts::TAU * t).sin_cos();
        assert!((s - rs).abs() < 1e-15 && (c - rc).abs() < 1e-15, "t = {t}");
        let (s, c) = sin_cos_turn(t as f32);
        let (rs, rc) = (std::f64::consts::TAU * (t as f32) as f64).sin_cos();
        assert!(
            (s as f64 - rs).abs() < 2e-7 && (c as f64 - rc).abs() < 2e-7,
            "t = {t}"
        );
    }
}

#[test]
fn atan2_matches_the_library() {
    let ulps = |a: f64, b: f64| (a.to_bits() as i64 - b.to_bits() as i64).abs();
    let mut worst = 0;
    for i in -400..=400 {
        for j in -400..=400 {
            let (y, x) = (i as f64 * 0.0137, j as f64 * 0.0113);
            let (ours, lib) = (atan2(y, x), y.atan2(x));
            assert_eq!(ours.is_sign_negative(), lib.is_sign_negative(), "{y}, {x}");
            worst = worst.max(ulps(ours, lib));
            let (ours, lib) = (atan2(y as f32, x as f32), (y as f32).atan2(x as f32));
            assert!((ours - lib).abs() <= 4.0 * f32::EPSILON * lib.abs().max(1e-30));
        }
    }
    assert!(worst <= 3, "{worst} ulp");
    for (y, x) in [
        (0.0f64, 0.0f64),
        (-0.0, 0.0),
        (0.0, -0.0),
        (-0.0, -0.0),
        (1e-300, -1.0),
    ] {
        assert_eq!(
            atan2(y, x).to_bits(),
            f64::atan2(y, x).to_bits(),
            "{y}, {x}"
        );
    }
    assert_eq!(atan2(1.0, 0.0), std::f64::consts::FRAC_PI_2);
    assert_eq!(atan2(0.0, -1.0), std::f64::consts::PI);
    // Subnormal inputs, whose ratio is an ordinary number.
    for (y, x) in [
        (1e-40f32, 1e-40f32),
        (-3e-41, 2e-41),
        (1e-45, -1e-40),
        (4e-39, 1e-38),
    ] {
        let (ours, lib) = (atan2(y, x), y.atan2(x));
        assert!(
            (ours - lib).abs() <= 4.0 * f32::EPSILON * lib.abs(),
            "{y}, {x}: {ours} {lib}"
        );
    }
    for (y, x) in [(1e-310f64, 1e-310f64), (-3e-320, 2e-320), (5e-324, -1e-310)] {
        let (ours, lib) = (atan2(y, x), y.atan2(x));
        assert!(ulps(ours, lib) <= 3, "{y}, {x}: {ours} {lib}");
    }
}

#[test]
fn pow_matches_the_library() {
    let mut worst = (0.0f64, 0.0f64);
    for i in 0..=2000 {
        let x = (i as f64 / 2000.0).powi(3);
        for y in [
            0.0,
            1e-3,
            0.5,
            1.0 / 1001.0,
            1.0,
            2.0,
            10.0,
            101.0,
            1000.0,
            1e4,
        ] {
            let (got, want) = (f64::pow_positive(x, y), x.powf(y));
            let rel = if want > 1e-300 {
                (got - want).abs() / want
            } else {
                got
            };
            assert!(rel < 1e-12, "{x}^{y}: {got} vs {want}");
            worst.0 = worst.0.max(rel);
            let (got, want) = (
                f32::pow_positive(x as f32, y as f32) as f64,
                (x as f32 as f64).powf(y as f32 as f64),
            );
            let rel = if want > 1e-30 {
                (got - want).abs() / want
            } else {
                got
            };
            assert!(
                rel < 2e-7 || (got - want).abs() < 1e-37,
                "f32 {x}^{y}: {got} vs {want}"
            );
            worst.1 = worst.1.max(if want > 1e-30 { rel } else { 0.0 });
        }
    }
    assert_eq!(f64::pow_positive(1.0, 1234.5), 1.0);
    assert_eq!(f64::pow_positive(0.0, 0.0), 1.0);
    assert_eq!(f64::pow_positive(0.0, 2.0), 0.0);
    assert_eq!(f32::pow_positive(1.0, 7.0), 1.0);
    eprintln!("worst relative error: f64 {:e}, f32 {:e}", worst.0, worst.1);
}

#[test]
fn helpers() {
    assert_eq!(safe_sqrt(-1e-12f64), 0.0);
    assert!(!in_unit_interval(f64::NAN));
    assert!(in_unit_interval(1.0f32));
    assert!((luminance([1.0f64, 1.0, 1.0]) - 1.0).abs() < 1e-12);
}

#[test]
fn floor_index_floors_and_clamps() {
    for (x, last, want) in [
        (2.7, 10, 2),
        (3.0, 10, 3),
        (0.3, 10, 0),
        (-0.5, 10, 0),
        (-7.0, 10, 0),
        (f64::NAN, 10, 0),
        (10.5, 10, 10),
        (1e12, 10, 10),
        (f64::INFINITY, 10, 10),
        (4_294_967_294.5, u32::MAX as usize, 4_294_967_294),
    ] {
        assert_eq!(x.floor_index(last), want, "{x}");
        if x.abs() < 1e6 || !x.is_finite() {
            assert_eq!((x as f32).floor_index(last), want, "{x} in f32");
        }
    }
    // In f32, a last index with no float of its own (2²⁴ + 1 rounds to
    // 2²⁴) is still reached, and nothing passes it.
    let last = (1 << 24) + 1;
    for (x, want) in [
        (16_777_218.0f32, last),
        (16_777_216.0, 1 << 24),
        (1e30, last),
    ] {
        assert_eq!(x.floor_index(last), want, "{x} in f32");
        assert_eq!(x.floor_u32(last as u32), want as u32, "{x} in f32");
    }
}

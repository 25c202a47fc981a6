//! Unit tests of the luminance density: its row moments, cell weights,
//! density and placing.

use super::*;

/// `∫₀¹ (α + β t) sin(θ₀ + Δt) dt` by Simpson's rule.
fn simpson(alpha: f64, beta: f64, theta0: f64, delta: f64) -> f64 {
    let n = 2000;
    let f = |t: f64| (alpha + beta * t) * (theta0 + delta * t).sin();
    let h = 1.0 / n as f64;
    let inner: f64 = (1..n)
        .map(|k| f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    (f(0.0) + inner + f(1.0)) * h / 3.0
}

#[test]
fn angle_terms_agree_with_the_library() {
    for x in [1e-6, 1e-3, 0.1, 0.2, 0.2499, SERIES_BELOW, 1.0] {
        let (sin, cos) = f64::sin_cos(x);
        let [s, v, g] = angle_terms(x);
        assert!((s - sin).abs() <= 1e-15 * sin, "x={x}: {s} {sin}");
        // The library's forms lose ~ε/x² of their digits, the series none.
        assert!((v - (1.0 - cos)).abs() <= 1e-15 / (x * x) * v, "x={x}: {v}");
        assert!(
            (g - (sin - x * cos)).abs() <= 1e-15 / (x * x) * g,
            "x={x}: {g}"
        );
        if x < SERIES_BELOW {
            assert!(
                (v - 2.0 * (0.5 * x).sin().powi(2)).abs() <= 1e-15 * v,
                "x={x}: {v}"
            );
            // sin x − x cos x = Σ (−1)ⁿ⁺¹ 2n x²ⁿ⁺¹/(2n + 1)!, n ≥ 1.
            let series: f64 = (1..8)
                .map(|n| {
                    let sign = if n % 2 == 1 { 1.0 } else { -1.0 };
                    let factorial: f64 = (1..=2 * n + 1).map(f64::from).product();
                    sign * f64::from(2 * n) * x.powi(2 * n + 1) / factorial
                })
                .sum();
            assert!((g - series).abs() <= 2e-15 * g, "x={x}: {g} {series}");
        }
    }
}

#[test]
fn cell_weights_are_the_luminance_over_the_cell() {
    // Poles, equator, coarse and fine maps.
    for height in [3, 4, 17, 1025, 16385] {
        let delta = PI / (height - 1) as f64;
        for row in [0, (height - 1) / 2, height - 2] {
            let theta0 = row as f64 * delta;
            let (sin, cos) = theta0.sin_cos();
            let [i0, i1] = moments([sin.max(0.0), cos], delta);
            for (alpha, beta) in [(1.0, 0.0), (0.0, 2.0), (3.5, -3.5)] {
                let truth = simpson(alpha, beta, theta0, delta);
                let ours = alpha * i0 + beta * i1;
                assert!((ours - truth).abs() < 1e-10 * truth, "H={height} row={row}");
            }
        }
    }
}

#[test]
fn cells_are_drawn_by_their_light_and_points_by_the_luminance() {
    let (w, h) = (8, 5);
    let mut lum: Vec<f64> = (0..w * h).map(|k| (k % 7) as f64).collect();
    lum[2 * w + 3] = 40.0;
    let d = LuminanceDensity::new(Buffer::from_slice(&lum, "lum").unwrap(), w, h)
        .unwrap()
        .unwrap();
    // p_q integrates to 1 over the table (midpoint rule, exact for a
    // bilinear function), and follows Y within each cell.
    let n = 8;
    let mut total = 0.0;
    for k in 0..w * (h - 1) {
        let cell = (k / w, k % w);
        for a in 0..n {
            for b in 0..n {
                let f = [(a as f64 + 0.5) / n as f64, (b as f64 + 0.5) / n as f64];
                total += d.table_pdf(cell, f);
            }
        }
        let ratio = d.table_pdf(cell, [0.3, 0.6]) / bilerp(corners(&lum, w, k), 0.3, 0.6);
        let other = d.table_pdf(cell, [0.9, 0.1]) / bilerp(corners(&lum, w, k), 0.9, 0.1);
        assert!((ratio - other).abs() <= 1e-12 * ratio);
        let (f, pdf) = d.tables().place(cell, [0.25, 0.75]);
        assert!((pdf - d.table_pdf(cell, f)).abs() <= 1e-15 * pdf);
    }
    let area = 1.0 / (w * (h - 1)) as f64;
    assert!(
        (total * area / (n * n) as f64 - 1.0).abs() < 1e-12,
        "{total}"
    );
    assert!(
        LuminanceDensity::new(Buffer::zeroed(w * h, "lum").unwrap(), w, h)
            .unwrap()
            .is_none()
    );
}

//! Known values, round trips, normalisation and `u = 1` for every warp.

use super::*;
use std::f64::consts::PI;

/// A density on points of a warp's domain.
type Pdf = fn(&[f64]) -> f64;

/// A function on points of a warp's domain, to integrate.
type Integrand<'a> = &'a dyn Fn(&[f64]) -> f64;

/// A planar or spherical warp under test, in f64.
struct Case {
    name: &'static str,
    sample: fn([f64; 2]) -> Vec<f64>,
    pdf: Pdf,
    invert: fn(&[f64]) -> [f64; 2],
    /// Integral of a function over the warp's domain, by quadrature.
    integrate: fn(Integrand) -> f64,
}

/// Midpoint rule over `[-1, 1]²` with `n²` cells.
fn integrate_plane(pdf: Integrand) -> f64 {
    let n = 800;
    let h = 2.0 / n as f64;
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let p = [-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h];
            sum += pdf(&p);
        }
    }
    sum * h * h
}

/// Midpoint rule over the sphere in (φ, cos θ), which is area-preserving.
fn integrate_sphere(pdf: Integrand) -> f64 {
    crate::quadrature::integrate_sphere(|d| pdf(&d), 200, 4000)
}

const EXPONENTS: [f64; 5] = [0.0, 1.0, 10.0, 100.0, 1000.0];

/// The lunes between two faces whose normals, in the xy plane, are 72°
/// apart (θ = 36°): their edges are meridians at multiples of 1/200 of a
/// turn, edges of [`integrate_sphere`]'s cells, so that the midpoint rule
/// integrates the piecewise constant density exactly. (The Python
/// chi-square tests take normals in general position.)
fn lunes() -> Lunes<f64> {
    let (s, c) = 36f64.to_radians().sin_cos();
    Lunes::new([c, -s, 0.0], [c, s, 0.0]).expect("not parallel")
}

/// Corners of a bilinear density, mean 1.
const CORNERS: Corners<f64> = [0.2, 1.6, 0.8, 1.4];

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "uniform_disk",
            sample: |u| square_to_uniform_disk(u).to_vec(),
            pdf: |p| square_to_uniform_disk_pdf([p[0], p[1]]),
            invert: |p| uniform_disk_to_square([p[0], p[1]]),
            integrate: integrate_plane,
        },
        Case {
            name: "uniform_disk_concentric",
            sample: |u| square_to_uniform_disk_concentric(u).to_vec(),
            pdf: |p| square_to_uniform_disk_concentric_pdf([p[0], p[1]]),
            invert: |p| uniform_disk_to_square_concentric([p[0], p[1]]),
            integrate: integrate_plane,
        },
        Case {
            name: "uniform_triangle",
            sample: |u| square_to_uniform_triangle(u).to_vec(),
            pdf: |p| square_to_uniform_triangle_pdf([p[0], p[1]]),
            invert: |p| uniform_triangle_to_square([p[0], p[1]]),
            integrate: integrate_plane,
        },
        Case {
            name: "uniform_sphere",
            sample: |u| square_to_uniform_sphere(u).to_vec(),
            pdf: |d| square_to_uniform_sphere_pdf([d[0], d[1], d[2]]),
            invert: |d| uniform_sphere_to_square([d[0], d[1], d[2]]),
            integrate: integrate_sphere,
        },
        Case {
            name: "uniform_hemisphere",
            sample: |u| square_to_uniform_hemisphere(u).to_vec(),
            pdf: |d| square_to_uniform_hemisphere_pdf([d[0], d[1], d[2]]),
            invert: |d| uniform_hemisphere_to_square([d[0], d[1], d[2]]),
            integrate: integrate_sphere,
        },
        Case {
            name: "cosine_hemisphere",
            sample: |u| square_to_cosine_hemisphere(u).to_vec(),
            pdf: |d| square_to_cosine_hemisphere_pdf([d[0], d[1], d[2]]),
            invert: |d| cosine_hemisphere_to_square([d[0], d[1], d[2]]),
            integrate: integrate_sphere,
        },
        Case {
            name: "cosine_hemisphere_polar",
            sample: |u| square_to_cosine_hemisphere_polar(u).to_vec(),
            pdf: |d| square_to_cosine_hemisphere_pdf([d[0], d[1], d[2]]),
            invert: |d| cosine_hemisphere_to_square_polar([d[0], d[1], d[2]]),
            integrate: integrate_sphere,
        },
        Case {
            name: "cosine_power_hemisphere(10)",
            sample: |u| square_to_cosine_power_hemisphere(u, 10.0).to_vec(),
            pdf: |d| square_to_cosine_power_hemisphere_pdf([d[0], d[1], d[2]], 10.0),
            invert: |d| cosine_power_hemisphere_to_square([d[0], d[1], d[2]], 10.0),
            integrate: integrate_sphere,
        },
        Case {
            name: "uniform_cone(0.3)",
            sample: |u| square_to_uniform_cone(u, 0.3).to_vec(),
            pdf: |d| square_to_uniform_cone_pdf([d[0], d[1], d[2]], 0.3),
            invert: |d| uniform_cone_to_square([d[0], d[1], d[2]], 0.3),
            integrate: integrate_sphere,
        },
        Case {
            name: "beckmann(0.5)",
            sample: |u| square_to_beckmann(u, 0.5).to_vec(),
            pdf: |d| square_to_beckmann_pdf([d[0], d[1], d[2]], 0.5),
            invert: |d| beckmann_to_square([d[0], d[1], d[2]], 0.5),
            integrate: integrate_sphere,
        },
        Case {
            name: "von_mises_fisher(3)",
            sample: |u| square_to_von_mises_fisher(u, &VonMisesFisher::new(3.0)).to_vec(),
            pdf: |d| square_to_von_mises_fisher_pdf([d[0], d[1], d[2]], &VonMisesFisher::new(3.0)),
            invert: |d| von_mises_fisher_to_square([d[0], d[1], d[2]], &VonMisesFisher::new(3.0)),
            integrate: integrate_sphere,
        },
        Case {
            name: "spherical_lune",
            sample: |u| square_to_uniform_spherical_lune(u, &lunes()).to_vec(),
            pdf: |d| square_to_uniform_spherical_lune_pdf([d[0], d[1], d[2]], &lunes()),
            invert: |d| uniform_spherical_lune_to_square([d[0], d[1], d[2]], &lunes()),
            integrate: integrate_sphere,
        },
        Case {
            name: "bilinear",
            sample: |u| square_to_bilinear(CORNERS, u).0.to_vec(),
            pdf: |p| square_to_bilinear_pdf(CORNERS, [p[0], p[1]]),
            invert: |p| bilinear_to_square(CORNERS, [p[0], p[1]]).0,
            integrate: integrate_plane,
        },
    ]
}

/// An open grid `1e-6 .. 1 − 1e-6` plus points within 1e-12 of the edges.
fn grid() -> Vec<f64> {
    let mut g: Vec<f64> = (0..=40)
        .map(|i| 1e-6 + (1.0 - 2e-6) * i as f64 / 40.0)
        .collect();
    g.extend([1e-12, 1.0 - 1e-12, 0.5 - 1e-12, 0.5 + 1e-12]);
    g
}

#[test]
fn invert_of_sample_is_identity() {
    for case in cases() {
        for &a in &grid() {
            for &b in &grid() {
                let u = [a, b];
                let x = (case.sample)(u);
                let v = (case.invert)(&x);
                // u_x is an azimuth: it is undefined at a pole or the origin,
                // so only compare it where the point has a defined angle.
                let radial = x[0].hypot(x[1]);
                let tol = 1e-9;
                let ok_y = (v[1] - u[1]).abs() < tol;
                let ok_x = radial < 1e-6 || {
                    let d = (v[0] - u[0]).abs();
                    d < tol || (1.0 - d) < tol
                };
                assert!(ok_x && ok_y, "{}: u = {u:?} -> {x:?} -> {v:?}", case.name);
            }
        }
    }
}

#[test]
fn sample_of_invert_is_identity() {
    for case in cases() {
        for &a in &grid() {
            for &b in &grid() {
                let x = (case.sample)([a, b]);
                let u = (case.invert)(&x);
                // Beckmann's map stretches without bound at the square's edge
                // (the horizon): 1e-12 from it, the inverse's last-bit error
                // moves the point by 1e-8. Its other direction is checked.
                let edge = [a, b].iter().any(|&v| v.min(1.0 - v) < 1e-9);
                if edge && case.name.starts_with("beckmann") {
                    continue;
                }
                let y = (case.sample)(u);
                let err = x
                    .iter()
                    .zip(&y)
                    .map(|(p, q)| (p - q).abs())
                    .fold(0.0, f64::max);
                assert!(err < 1e-9, "{}: {x:?} -> {u:?} -> {y:?}", case.name);
            }
        }
    }
}

#[test]
fn pdfs_integrate_to_one_and_are_positive_on_samples() {
    for case in cases() {
        let total = (case.integrate)(&case.pdf);
        assert!(
            (total - 1.0).abs() < 5e-3,
            "{}: integral {total}",
            case.name
        );
        for &a in &grid() {
            for &b in &grid() {
                let x = (case.sample)([a, b]);
                assert!((case.pdf)(&x) > 0.0, "{}: pdf 0 at sample {x:?}", case.name);
            }
        }
    }
}

#[test]
fn cosine_power_normalised_for_every_exponent() {
    // cos^n lobes get sharp: integrate in cos θ directly, exactly enough.
    for n in EXPONENTS {
        let steps = 200_000;
        let h = 1.0 / steps as f64;
        let integral: f64 = (0..steps)
            .map(|j| {
                let z = (j as f64 + 0.5) * h;
                square_to_cosine_power_hemisphere_pdf([0.0, (1.0 - z * z).sqrt(), z], n)
            })
            .sum::<f64>()
            * h
            * 2.0
            * PI;
        assert!((integral - 1.0).abs() < 1e-4, "n = {n}: {integral}");
    }
}

#[test]
fn u_equal_one_stays_in_the_domain() {
    for case in cases() {
        for u in [[1.0, 1.0], [1.0, 0.0], [0.0, 1.0], [0.0, 0.0], [1.0, 0.5]] {
            let x = (case.sample)(u);
            assert!(
                x.iter().all(|v| v.is_finite()),
                "{}: {u:?} -> {x:?}",
                case.name
            );
            // The cosine and Beckmann lobes vanish on the rim z = 0, which
            // is still inside.
            let lobe = case.name.starts_with("cosine") || case.name.starts_with("beckmann");
            let on_rim = lobe && x[2] == 0.0;
            assert!(
                on_rim || (case.pdf)(&x) > 0.0,
                "{}: {u:?} -> {x:?} outside",
                case.name
            );
        }
    }
    assert!(interval_to_power(1.0f32, 3.0) <= 1.0);
}

#[test]
fn known_values() {
    assert_eq!(square_to_uniform_disk([0.5, 0.0]), [0.0, 0.0]);
    let c = square_to_uniform_disk_concentric([0.5, 0.5]);
    assert_eq!(c, [0.0, 0.0]);
    let d = square_to_uniform_disk_concentric([1.0, 0.5]);
    assert!((d[0] - 1.0f64).abs() < 1e-15 && d[1].abs() < 1e-15);
    assert_eq!(square_to_uniform_sphere([0.0, 0.0]), [0.0, 0.0, 1.0]);
    assert_eq!(square_to_cosine_hemisphere([0.5, 0.5]), [0.0, 0.0, 1.0]);
    assert_eq!(square_to_uniform_triangle([0.0, 0.7]), [0.0, 0.7]);
    assert_eq!(square_to_uniform_triangle([1.0, 0.7]), [1.0, 0.0]);
    assert_eq!(interval_to_power(0.25f64, 1.0), 0.5);
    assert!((interval_to_power_pdf(0.5f64, 2.0) - 0.75f64).abs() < 1e-15);
    assert_eq!(power_to_interval(0.5f64, 1.0), 0.25);
}

#[test]
fn pdfs_vanish_off_the_support() {
    assert_eq!(square_to_uniform_disk_pdf([1.0, 1.0]), 0.0);
    assert_eq!(square_to_uniform_hemisphere_pdf([0.0, 0.0, -1.0]), 0.0);
    assert_eq!(square_to_cosine_hemisphere_pdf([0.0, 0.6, -0.8]), 0.0);
    assert_eq!(
        square_to_cosine_power_hemisphere_pdf([1.0, 0.0, 0.0], 0.0),
        0.0
    );
    assert_eq!(square_to_uniform_cone_pdf([1.0, 0.0, 0.0], 0.5), 0.0);
    assert_eq!(square_to_uniform_triangle_pdf([0.8, 0.8]), 0.0);
    assert_eq!(interval_to_power_pdf(1.5f64, 2.0), 0.0);
}

/// The support tests allow a few ulps of round-off past the edge (so that
/// `u = 1` and rounded samples stay inside), and no more: a disk point 4 ε
/// outside the rim, and a cone direction 4 ε below its cutoff, still have
/// their density; 10⁻⁹ outside, none.
#[test]
fn support_edges_allow_a_few_ulps() {
    let eps = f64::EPSILON;
    assert!(square_to_uniform_disk_pdf([1.0 + 2.0 * eps, 0.0]) > 0.0);
    assert_eq!(square_to_uniform_disk_pdf([1.0 + 1e-9, 0.0]), 0.0);
    let c = 0.5;
    let below = |t: f64| [(1.0 - (c - t) * (c - t)).sqrt(), 0.0, c - t];
    assert!(square_to_uniform_cone_pdf(below(4.0 * eps), c) > 0.0);
    assert_eq!(square_to_uniform_cone_pdf(below(1e-9), c), 0.0);
    assert!(square_to_uniform_triangle_pdf([0.5 + 4.0 * eps, 0.5]) > 0.0);
    assert_eq!(square_to_uniform_triangle_pdf([0.5 + 1e-9, 0.5]), 0.0);
    // The triangle's vertex where the inverse would divide by 0.
    assert_eq!(uniform_triangle_to_square([1.0f64, 0.0]), [1.0, 0.0]);
}

#[test]
fn f32_agrees_with_f64() {
    for &a in &grid() {
        for &b in &grid() {
            let d64 = square_to_cosine_hemisphere([a, b]);
            let d32 = square_to_cosine_hemisphere([a as f32, b as f32]);
            // z = √(1 − r²) loses up to √ε₃₂ ≈ 3e-4 near the rim in f32.
            for k in 0..3 {
                assert!((d64[k] - d32[k] as f64).abs() < 1e-3, "{d64:?} vs {d32:?}");
            }
        }
    }
}

mod props {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn power_lobe_round_trip(n in 0.0f64..1e4, a in 0.0f64..1.0, b in 1e-3f64..1.0) {
            let d = square_to_cosine_power_hemisphere([a, b], n);
            let u = cosine_power_hemisphere_to_square(d, n);
            prop_assert!((u[1] - b).abs() < 1e-9 * (1.0 + n), "{b} -> {d:?} -> {u:?}");
        }

        #[test]
        fn cone_round_trip(c in -1.0f64..0.999, a in 1e-6f64..1.0, b in 1e-6f64..1.0) {
            let d = square_to_uniform_cone([a, b], c);
            prop_assert!(square_to_uniform_cone_pdf(d, c) > 0.0);
            let y = square_to_uniform_cone(uniform_cone_to_square(d, c), c);
            for k in 0..3 {
                prop_assert!((y[k] - d[k]).abs() < 1e-9, "{d:?} -> {y:?}");
            }
        }
    }
}

/// Each warp places its samples with its own density: the mean of a few
/// low moments (`x`, `y`, `z`, their squares and products) over samples of
/// a fine grid of `u` (a quadrature of `f ∘ sample` over the square) equals
/// `∫ f p` over the domain (a quadrature of the density). Catches samples
/// on the wrong part of the domain that the round trips cannot see (every
/// sample at a pole, where the azimuth is not compared).
#[test]
fn samples_have_the_moments_of_their_density() {
    let n = 400;
    for case in cases() {
        let samples: Vec<Vec<f64>> = (0..n * n)
            .map(|k| {
                let u = [(k % n) as f64 + 0.5, (k / n) as f64 + 0.5].map(|v| v / n as f64);
                (case.sample)(u)
            })
            .collect();
        let dims = samples[0].len();
        // x[a], and x[a] x[b] for b >= a.
        let mut moments: Vec<(usize, Option<usize>)> = Vec::new();
        for a in 0..dims {
            moments.push((a, None));
            moments.extend((a..dims).map(|b| (a, Some(b))));
        }
        for (k, &(a, b)) in moments.iter().enumerate() {
            let f = |x: &[f64]| x[a] * b.map_or(1.0, |b| x[b]);
            let mean = samples.iter().map(|x| f(x)).sum::<f64>() / samples.len() as f64;
            let expected = (case.integrate)(&|x: &[f64]| f(x) * (case.pdf)(x));
            assert!(
                (mean - expected).abs() < 5e-3,
                "{}: moment {k}: {mean} from samples, {expected} from the pdf",
                case.name
            );
        }
    }
}

/// The concentric square map keeps the square's measure: on a fine grid of
/// `u`, its points have the uniform square's moments, they stay in the
/// square, and the eight octants keep their order around the centre.
#[test]
fn square_concentric_preserves_the_measure() {
    let n = 1000;
    let (mut m, mut all_inside) = ([0.0; 4], true);
    for i in 0..n {
        for j in 0..n {
            let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
            let [phi, r2] = square_to_uniform_square_concentric(u);
            all_inside &= (0.0..=1.0).contains(&phi) && (0.0..=1.0).contains(&r2);
            for (acc, v) in m.iter_mut().zip([phi, r2, phi * phi, phi * r2]) {
                *acc += v / (n * n) as f64;
            }
        }
    }
    assert!(all_inside);
    for (got, want) in m.iter().zip([0.5, 0.5, 1.0 / 3.0, 0.25]) {
        assert!((got - want).abs() < 1e-5, "{m:?}");
    }
    assert_eq!(
        square_to_uniform_square_concentric([0.5f64, 0.5]),
        [0.0, 0.0]
    );
    // Right of the centre: angle 0 (a turn's start), radius² 1 at the edge.
    assert_eq!(
        square_to_uniform_square_concentric([1.0f64, 0.5]),
        [0.0, 1.0]
    );
    // Above: a quarter turn.
    assert_eq!(
        square_to_uniform_square_concentric([0.5f64, 1.0]),
        [0.25, 1.0]
    );
}

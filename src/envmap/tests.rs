//! Unit tests of the environment maps: sample / pdf agreement, densities
//! that integrate to 1, support, modes and conversions.

use super::*;
use crate::warp;
use std::ops::Range;

/// A smooth map with a bright spot, `w × h` (cube: faces of `w`).
pub(super) fn test_image(mapping: Mapping, w: usize, h: usize) -> Vec<f32> {
    let mut data = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let p = texel_centre(mapping, w, h, x, y);
            let d = mapping.to_dir(p);
            let spot = if d[0] * 0.6 + d[1] * 0.8 > 0.97 {
                40.0
            } else {
                0.0
            };
            let sky = 0.2 + 0.5 * d[1].max(0.0);
            data.extend([sky + spot, sky * 0.8 + spot, 0.3 * sky].map(|v| v as f32));
        }
    }
    data
}

fn map(mapping: Mapping, sampling: Sampling, rotated: bool) -> EnvMap {
    let (w, h) = match mapping {
        Mapping::LatLong => (32, 17),
        Mapping::Angular => (24, 24),
        Mapping::Cube => (8, 48),
    };
    let c = 0.8f64;
    let s = 0.6f64;
    let to_world = if rotated {
        [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
    } else {
        IDENTITY
    };
    let options = Options {
        mapping,
        to_world,
        scale: 2.0,
        sampling,
        compensate: false,
    };
    EnvMap::new(w, h, &test_image(mapping, w, h), options).unwrap()
}

pub(super) fn all_maps() -> Vec<EnvMap> {
    vec![
        map(Mapping::LatLong, Sampling::Piecewise, false),
        map(Mapping::LatLong, Sampling::Piecewise, true),
        map(Mapping::LatLong, Sampling::Mitsuba, true),
        map(Mapping::LatLong, Sampling::Luminance, true),
        map(Mapping::Angular, Sampling::Piecewise, true),
        map(Mapping::Cube, Sampling::Piecewise, false),
    ]
}

/// ∫ f dω over the sphere by the midpoint rule in (φ, cos θ), with the
/// poles on ±y (the lat-long map's).
fn integrate(f: impl Fn(V3<f64>) -> f64) -> f64 {
    crate::quadrature::integrate_sphere(|[x, y, z]| f([x, z, y]), 800, 800)
}

#[test]
fn pdfs_integrate_to_one() {
    for m in all_maps() {
        let total = integrate(|d| m.pdf(d));
        assert!((total - 1.0).abs() < 5e-3, "{:?}: {total}", m.options());
    }
}

#[test]
fn samples_carry_their_own_pdf_and_weight() {
    for m in all_maps() {
        let mut mismatches = 0;
        for i in 0..=60 {
            for j in 0..=60 {
                let u = [i as f64 / 60.0, j as f64 / 60.0];
                let s = m.sample(u);
                let norm = s.direction.iter().map(|x| x * x).sum::<f64>();
                assert!((norm - 1.0).abs() < 1e-12);
                // Mitsuba's density is 0 exactly on a pole (u[1] = 0 or 1).
                let pole =
                    m.options().sampling == Sampling::Mitsuba && (u[1] == 0.0 || u[1] == 1.0);
                assert!(s.pdf > 0.0 || pole, "{:?}: u = {u:?}", m.options());
                // On the edges of u, samples lie on cell boundaries, the seam
                // of a polar table, the rim of an angular map (one direction,
                // −Z, whose radiance depends on where on the rim it is looked
                // up) or a seam between cube faces: there a direction may find
                // the neighbouring cell or face.
                let seam = u.iter().any(|&x| x == 0.0 || x == 1.0);
                let pdf = m.pdf(s.direction);
                if (pdf - s.pdf).abs() > 1e-6 * s.pdf && !seam {
                    mismatches += 1;
                }
                let l = m.eval(s.direction);
                for k in (0..3).filter(|_| s.pdf > 0.0 && !seam) {
                    let diff = (s.weight[k] * s.pdf - l[k]).abs();
                    assert!(diff <= 1e-6 * l[k].max(1e-3), "{:?} {u:?}", m.options());
                    let diff = (s.radiance[k] - l[k]).abs();
                    assert!(diff <= 1e-6 * l[k].max(1e-3), "{:?} {u:?}", m.options());
                }
            }
        }
        // Only samples on a cell boundary may find the neighbouring cell.
        assert!(mismatches <= 4, "{:?}: {mismatches}", m.options());
    }
}

#[test]
fn polar_tables_give_the_table_pdf() {
    // The branch-free polar query (f64 and f32) against the table's own
    // density at the same point, on random directions.
    for env in all_maps() {
        let Some(table) = env.polar_table() else {
            continue;
        };
        let mut rng = crate::rng::Rng::new(7, 1);
        let (mut f32_misses, n) = (0, 20_000);
        for _ in 0..n {
            let u = [rng.next_float::<f64>(), rng.next_float::<f64>()];
            let d = warp::square_to_uniform_sphere(u);
            let expected = env.pdf_at(env.pdf_query(d));
            let q = table.query(d);
            let ours = table.density()[table.cell(q)] * q[2];
            assert!(
                (ours - expected).abs() <= 1e-12 * expected,
                "{d:?}: {ours} vs {expected}"
            );
            assert_eq!(env.pdf(d), ours);
            let q = table.query(d.map(|x| x as f32));
            let ours = table.density()[table.cell(q)] * q[2] as f64;
            f32_misses += usize::from((ours - expected).abs() > 1e-5 * expected);
        }
        // In f32 only directions within a few ulps of a cell edge may move.
        assert!(f32_misses < n / 1000, "{f32_misses} of {n}");
    }
}

#[test]
fn luminance_pdfs_in_f32_follow_f64s() {
    // The f32 batch computes p_q from the texels' L and the rows' moments in
    // f32 (and the one-at-a-time f32 density the same bits); the f64
    // density at the same (f32) direction is the reference. Directions
    // along the seam and at the poles (where cells wrap and clamp), then
    // uniform on the sphere and drawn from the map (its bright spot).
    let m = map(Mapping::LatLong, Sampling::Luminance, true);
    let mut rng = crate::rng::Rng::new(5, 1);
    let w = m.image.width() as f64;
    let seam = [0.0, 0.2 / w, 0.5 / w, 1.0 - 0.5 / w, 1.0 - 0.2 / w, 1.0];
    let edges = seam
        .iter()
        .flat_map(|&s| [0.0, 0.01, 0.3, 0.99, 1.0].map(|t| m.uv_to_dir([s, t])));
    let n = 20_000;
    let inside = (0..n).map(|k| {
        let u = [rng.next_float::<f64>(), rng.next_float::<f64>()];
        if k % 2 == 0 {
            warp::square_to_uniform_sphere(u)
        } else {
            m.sample(u).direction
        }
    });
    let d: Vec<[f32; 3]> = edges.chain(inside).map(|x| x.map(|v| v as f32)).collect();
    let mut ours = vec![-1.0f32; d.len()];
    assert!(m.pdf_into(&d, &mut ours, |_| true));
    let mut misses = 0;
    for (x, &o) in d.iter().zip(&ours) {
        let expected = m.pdf(x.map(f64::from));
        let error = (o as f64 - expected).abs() / expected;
        assert!(o.is_finite() && o > 0.0, "{x:?}: {o}");
        // Only directions within a few ulps of a cell edge may move cell
        // (a NaN fails here).
        assert!(error < 0.5, "{x:?}: {o} against {expected}");
        misses += usize::from(error > 1e-5);
    }
    assert!(misses < n / 1000, "{misses} of {n}");
}

#[test]
fn uv_round_trips_through_to_world() {
    for m in all_maps() {
        for i in 0..50 {
            let p = [(i as f64 + 0.3) / 50.0, ((i * 7 % 50) as f64 + 0.6) / 50.0];
            if m.options().mapping == Mapping::Angular && Mapping::Angular.jacobian(p) == 0.0 {
                continue;
            }
            let d = m.uv_to_dir(p);
            let back = m.dir_to_uv(d);
            assert!((back[0] - p[0]).abs() < 1e-12 && (back[1] - p[1]).abs() < 1e-12);
        }
    }
}

#[test]
fn one_bright_texel_is_covered_by_the_pdf() {
    for (mapping, w, h) in [
        (Mapping::LatLong, 16, 9),
        (Mapping::Angular, 16, 16),
        (Mapping::Cube, 4, 24),
    ] {
        // A texel near a pole / the rim too.
        for (x, y) in [(5, 3), (0, 0), (w - 1, h - 1), (w / 2, 0)] {
            let mut data = vec![0.0f32; w * h * 3];
            data[(y * w + x) * 3 + 1] = 100.0;
            let m = EnvMap::new(w, h, &data, Options::for_mapping(mapping)).unwrap();
            let lit = integrate(|d| f64::from(m.eval(d)[1] > 0.0 && m.pdf(d) == 0.0));
            assert_eq!(lit, 0.0, "{mapping:?} texel ({x}, {y})");
            // The estimator of ∫L by envmap sampling equals the quadrature.
            let truth = integrate(|d| m.eval(d)[1]);
            let n = 200;
            let mut est = 0.0;
            for i in 0..n {
                for j in 0..n {
                    est += m
                        .sample([(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64])
                        .weight[1];
                }
            }
            est /= (n * n) as f64;
            if truth > 1e-3 {
                assert!(
                    (est / truth - 1.0).abs() < 0.02,
                    "{mapping:?} ({x}, {y}): {est} vs {truth}"
                );
            }
        }
    }
}

#[test]
fn black_maps_sample_nothing() {
    let m = EnvMap::new(4, 3, &[0.0; 36], Options::default()).unwrap();
    let s = m.sample([0.3, 0.7]);
    assert_eq!((s.pdf, s.weight), (0.0, [0.0; 3]));
    assert!((s.direction.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-12);
    assert_eq!(m.pdf([0.0, 1.0, 0.0]), 0.0);
}

/// A 16 × 9 lat-long image of radiance 1 with a block of 50 on the texel
/// rows `rows` and columns `cols`.
pub(crate) fn dim_sky_with_block(rows: Range<usize>, cols: Range<usize>) -> Vec<f32> {
    let w = 16;
    let mut data = vec![1.0f32; w * 9 * 3];
    for y in rows {
        for x in cols.clone() {
            data[(y * w + x) * 3..(y * w + x) * 3 + 3].fill(50.0);
        }
    }
    data
}

#[test]
fn compensation_removes_the_mean() {
    // A floor of 1 with a 3 × 3 block of 50: compensated, the floor gets no
    // samples.
    let (w, h) = (16, 9);
    let data = dim_sky_with_block(3..6, 6..9);
    for sampling in [Sampling::Luminance, Sampling::Piecewise, Sampling::Mitsuba] {
        let options = Options {
            sampling,
            ..Options::default()
        };
        let compensated = Options {
            compensate: true,
            ..options
        };
        let m = EnvMap::new(w, h, &data, compensated).unwrap();
        let plain = EnvMap::new(w, h, &data, options).unwrap();
        let floor = m.uv_to_dir([0.1, 0.5]);
        assert_eq!(m.pdf(floor), 0.0);
        assert!(plain.pdf(floor) > 0.0);
        assert!((integrate(|d| m.pdf(d)) - 1.0).abs() < 5e-3);
        // The twin the renderer draws under MIS is that map.
        let twin = plain.compensated().unwrap().unwrap();
        assert_eq!(twin.options(), m.options());
        for p in [floor, m.uv_to_dir([0.45, 0.45]), m.uv_to_dir([0.5, 0.9])] {
            assert_eq!(twin.pdf(p), m.pdf(p));
            assert_eq!(twin.eval(p), plain.eval(p));
        }
        assert!(m.compensated().unwrap().is_none());
    }
    // A constant map is left as it is.
    let flat = EnvMap::new(
        w,
        h,
        &vec![2.0f32; w * h * 3],
        Options {
            compensate: true,
            ..Options::default()
        },
    );
    assert!(flat.unwrap().pdf([0.0, 0.0, 1.0]) > 0.0);
    // Nor does it get a twin.
    let flat = EnvMap::new(w, h, &vec![2.0f32; w * h * 3], Options::default()).unwrap();
    assert!(flat.compensated().unwrap().is_none());
}

#[test]
fn convert_round_trip_keeps_the_light() {
    let m = map(Mapping::LatLong, Sampling::Piecewise, true);
    for target in [Mapping::Cube, Mapping::Angular] {
        let (w, h) = if target == Mapping::Cube {
            (64, 384)
        } else {
            (128, 128)
        };
        let c = m.convert(target, w, h).unwrap();
        let back = c.convert(Mapping::LatLong, 32, 17).unwrap();
        let total = integrate(|d| m.eval(d)[0]);
        let err = integrate(|d| (back.eval(d)[0] - m.eval(d)[0]).abs());
        let bound = if target == Mapping::Cube { 0.05 } else { 0.1 };
        assert!(err / total < bound, "{target:?}: {}", err / total);
    }
}

/// `convert` checks the new shape before it asks for memory (a shape too
/// large is `TooLarge`, a wrong one `Shape`, neither a memory error), and
/// pads a tiny lat-long target as `EnvMap::new` pads one.
#[test]
fn convert_checks_the_shape_first_and_pads_tiny_maps() {
    let m = map(Mapping::LatLong, Sampling::Piecewise, true);
    let too_large = m.convert(Mapping::LatLong, 1 << 20, 1 << 20).unwrap_err();
    assert!(matches!(too_large, Error::TooLarge { .. }), "{too_large:?}");
    for (mapping, w, h) in [
        (Mapping::Cube, 4, 20),
        (Mapping::Angular, 4, 5),
        (Mapping::LatLong, 0, 3),
    ] {
        let e = m.convert(mapping, w, h).unwrap_err();
        assert!(
            matches!(e, Error::Shape { .. }),
            "{mapping:?} {w}x{h}: {e:?}"
        );
    }
    let tiny = m.convert(Mapping::LatLong, 1, 1).unwrap();
    let texel = tiny.image().texels()[0];
    let direct = EnvMap::new(1, 1, &texel, *m.options()).unwrap();
    assert_eq!((tiny.image().width(), tiny.image().height()), (2, 3));
    assert_eq!(tiny.image().texels(), direct.image().texels());
}

#[test]
fn bad_options_are_errors() {
    let data = [1.0f32; 36];
    let bad = |options: Options| EnvMap::new(4, 3, &data, options).unwrap_err().to_string();
    assert!(
        bad(Options {
            scale: -1.0,
            ..Options::default()
        })
        .starts_with("scale = -1")
    );
    let skew = [[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    assert!(
        bad(Options {
            to_world: skew,
            ..Options::default()
        })
        .starts_with("to_world")
    );
    let e = bad(Options::for_mapping(Mapping::Cube));
    assert!(e.contains("(6, R, R, 3)"), "{e}");
    let e = EnvMap::new(
        2,
        2,
        &data[..12],
        Options {
            mapping: Mapping::Angular,
            sampling: Sampling::Mitsuba,
            ..Options::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().starts_with("sampling = \"mitsuba\""), "{e}");
}

/// The cell sampler draws the table's density: each direction carries the
/// density and radiance that `pdf` and `eval` give it (in `f64`; in `f32`
/// to a few ulps), and the cells its directions fall in are hit as often
/// as the table's probabilities say (z-scores of every cell expected to
/// get 20 draws or more, fixed seed).
#[test]
fn cell_sampler_draws_the_table_density() {
    for m in all_maps() {
        let Some(cells) = CellSampler::new(&m).unwrap() else {
            assert_eq!(m.options().sampling, Sampling::Mitsuba);
            continue;
        };
        let table = match &m.distribution {
            Distribution::Piecewise(table) => table.table(),
            Distribution::Luminance(density) => density.cells(),
            _ => unreachable!("a cell sampler needs cells"),
        };
        let (rows, cols) = table.shape();
        // A luminance density's cells are the patches between texel
        // centres, as a piecewise lat-long table's.
        let floor = |x: f64, n: usize| ((x * n as f64) as usize).min(n - 1);
        let cell_of = |q: [f64; 2]| match &m.distribution {
            Distribution::Piecewise(table) => {
                table.cell_of(q).expect("a direction inside the table")
            }
            _ => (floor(q[1], rows), floor(q[0], cols)),
        };
        let mut counts = vec![0u32; rows * cols];
        let mut rng = crate::rng::Rng::new(7, 3);
        let n = 400_000;
        for _ in 0..n {
            let bits = rng.next_u64();
            let r: [f64; 2] = [rng.next_float(), rng.next_float()];
            let s = cells.sample(&m, bits, r);
            let (direction, s_pdf, radiance) = (s.direction, s.pdf, s.radiance);
            let pdf = m.pdf(direction);
            assert!((pdf - s_pdf).abs() <= 1e-9 * s_pdf, "{:?}", m.options());
            let l = m.eval(direction);
            for (a, l) in radiance.iter().zip(l) {
                assert!((a - l).abs() <= 1e-9 * l.max(1e-3));
            }
            let s32 = cells.sample(&m, bits, r.map(|x| x as f32));
            let (d32, pdf32) = (s32.direction, s32.pdf);
            for (a, b) in d32.iter().zip(direction) {
                assert!((f64::from(*a) - b).abs() < 1e-5);
            }
            // Near a pole, f32 places the point (and sin θ) to an ulp of
            // the table's extent: a relative error of about 1e-7 / sin θ.
            let d = m.to_local(direction);
            let sin = match m.options().mapping {
                Mapping::LatLong => d[0].hypot(d[2]),
                Mapping::Angular => d[0].hypot(d[1]),
                Mapping::Cube => 1.0,
            };
            let tol = 1e-5 + 1e-6 / sin;
            // Against the f64 draw of the same (rounded) numbers: the
            // luminance density varies within a cell, and where it is
            // nearly 0 a rounding of r moves the point far.
            let same_numbers = cells.sample(&m, bits, r.map(|x| f64::from(x as f32))).pdf;
            assert!(
                (f64::from(pdf32) - same_numbers).abs() <= tol * same_numbers,
                "{:?}",
                m.options()
            );
            let (row, col) = cell_of(m.table_point(d));
            counts[row * cols + col] += 1;
        }
        let sum = table.sum();
        let mut tested = 0;
        for (c, &count) in counts.iter().enumerate() {
            let expected = table.weights()[c] / sum * f64::from(n);
            if expected == 0.0 {
                assert_eq!(count, 0, "{:?}: a cell of weight 0 drawn", m.options());
            } else if expected >= 20.0 {
                let z = (f64::from(count) - expected) / expected.sqrt();
                assert!(z.abs() < 5.5, "{:?}: cell {c}, z = {z}", m.options());
                tested += 1;
            }
        }
        assert!(tested > 50, "{:?}: {tested} cells tested", m.options());
    }
}

/// The cell sampler's batch draws are its single draws, bit for bit, in
/// `f32` and `f64`, for every map that has one (and more draws than a
/// group).
#[test]
fn cell_sampler_batches_are_its_single_draws() {
    fn check<F: TableFloat>(m: &EnvMap, cells: &CellSampler, draws: &[(u64, [F; 2])]) {
        let mut many = Vec::new();
        cells.sample_many(m, draws, &mut many);
        assert_eq!(many.len(), draws.len());
        for (s, &(bits, r)) in many.iter().zip(draws) {
            let one = cells.sample(m, bits, r);
            let key = |s: &EnvSample<F>| {
                let parts = [s.direction, s.weight, s.radiance];
                (
                    s.pdf.f64().to_bits(),
                    parts.map(|v| v.map(|x| x.f64().to_bits())),
                )
            };
            assert_eq!(key(s), key(&one), "{:?}", m.options());
        }
    }
    let mut rng = crate::rng::Rng::new(5, 9);
    let draws: Vec<(u64, [f64; 2])> = (0..3 * crate::distr::GROUP + 7)
        .map(|_| (rng.next_u64(), [rng.next_float(), rng.next_float()]))
        .collect();
    let mut checked = 0;
    for m in all_maps() {
        if let Some(cells) = CellSampler::new(&m).unwrap() {
            check(&m, &cells, &draws);
            let draws32: Vec<_> = draws
                .iter()
                .map(|&(b, r)| (b, r.map(|x| x as f32)))
                .collect();
            check(&m, &cells, &draws32);
            checked += 1;
        }
    }
    assert!(checked >= 5, "{checked}");
}

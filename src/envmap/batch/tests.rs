//! Unit tests of the batch pipelines: `sample_into`, `pdf_into` and
//! `eval_into` against the one-at-a-time methods, bit for bit.

use super::BATCH_BLOCK;
use crate::envmap::tests::{all_maps, test_image};
use crate::envmap::*;
use crate::math::Real;
use crate::warp;

/// `m.sample_into(us)` as samples (radiance 0: a batch writes none).
fn batch<F: TableFloat>(m: &EnvMap, us: &[[F; 2]]) -> Vec<EnvSample<F>> {
    let n = us.len();
    let (mut direction, mut pdf, mut weight) = (
        vec![[F::zero(); 3]; n],
        vec![F::zero(); n],
        vec![[F::zero(); 3]; n],
    );
    let out = EnvSamples {
        direction: &mut direction,
        pdf: &mut pdf,
        weight: &mut weight,
    };
    m.sample_into(us, out);
    (0..n)
        .map(|k| EnvSample {
            direction: direction[k],
            pdf: pdf[k],
            weight: weight[k],
            radiance: [F::zero(); 3],
        })
        .collect()
}

#[test]
fn batch_sampling_agrees_with_single_draws() {
    let black = EnvMap::new(2, 2, &[0.0; 12], Options::default()).unwrap();
    for m in all_maps().into_iter().chain([black]) {
        // Not a multiple of the batch group; u = 0 and 1 included.
        let us: Vec<[f64; 2]> = (0..=300)
            .map(|k| [(k as f64 * 0.618_033_988_749_895).fract(), k as f64 / 300.0])
            .collect();
        let out = batch(&m, &us);
        for (&u, o) in us.iter().zip(&out) {
            let s = EnvSample {
                radiance: [0.0; 3],
                ..m.sample(u)
            };
            assert_eq!(*o, s, "{:?}: u = {u:?}", m.options());
        }
        // In f32: the same directions and densities to f32 precision, away
        // from the poles and seams (where rounding u may pick a neighbour).
        let u32s: Vec<[f32; 2]> = us.iter().map(|u| u.map(|x| x as f32)).collect();
        let out32 = batch(&m, &u32s);
        let mut far = 0;
        for (&u, o) in u32s.iter().zip(&out32) {
            let s = m.sample(u.map(f64::from));
            // sin θ from the lat-long (+Y) and the angular (+Z) pole.
            let d = m.to_local(s.direction);
            if d[0].hypot(d[2]).min(d[0].hypot(d[1])) < 1e-2 {
                continue;
            }
            let close = o
                .direction
                .iter()
                .zip(s.direction)
                .all(|(a, b)| (f64::from(*a) - b).abs() < 1e-4)
                && (f64::from(o.pdf) - s.pdf).abs() <= 1e-3 * s.pdf;
            far += usize::from(!close);
        }
        assert!(
            far == 0,
            "{:?}: {far} f32 samples away from f64's",
            m.options()
        );
    }
}

/// Batches that end anywhere around a group's boundary (the pipeline's
/// last group, part or whole, finished after the loop; two groups in
/// flight), and none, give each draw's own sample: in `f64` the bits of
/// [`EnvMap::sample`], in `f32` those of a batch of that draw alone.
#[test]
fn batches_of_every_length_about_a_group_are_the_single_draws() {
    fn bits<F: Real>(s: &EnvSample<F>) -> (u64, [[u64; 3]; 2]) {
        (
            s.pdf.f64().to_bits(),
            [s.direction, s.weight].map(|v| v.map(|x| x.f64().to_bits())),
        )
    }
    const GROUP: usize = crate::distr::GROUP;
    let mut rng = crate::rng::Rng::new(8, 3);
    for m in all_maps() {
        for n in [
            0,
            1,
            GROUP - 1,
            GROUP,
            GROUP + 1,
            2 * GROUP - 1,
            2 * GROUP,
            2 * GROUP + 1,
        ] {
            let us: Vec<[f64; 2]> = (0..n)
                .map(|_| [rng.next_float(), rng.next_float()])
                .collect();
            let out = batch(&m, &us);
            assert_eq!(out.len(), n);
            for (&u, o) in us.iter().zip(&out) {
                assert_eq!(bits(o), bits(&m.sample(u)), "{:?}: u = {u:?}", m.options());
            }
            let us32: Vec<[f32; 2]> = us.iter().map(|u| u.map(|x| x as f32)).collect();
            for (&u, o) in us32.iter().zip(&batch(&m, &us32)) {
                let one = batch(&m, &[u]);
                assert_eq!(bits(o), bits(&one[0]), "{:?}: u = {u:?}", m.options());
            }
        }
    }
}

/// Asserts that `m.eval_into(d)` gives, direction by direction, the bits
/// of `m.eval` (compared as `f64`, which holds every `f32` and its NaN
/// payload).
fn same_bits_as_single_evals<F: Real>(m: &EnvMap, d: &[[F; 3]]) {
    let mut out = vec![[-F::one(); 3]; d.len()];
    m.eval_into(d, &mut out, |_| true);
    let bits = |v: [F; 3]| v.map(|x| x.f64().to_bits());
    for (x, o) in d.iter().zip(&out) {
        assert_eq!(
            bits(*o),
            bits(m.eval(*x)),
            "{} x {}: {x:?}",
            m.image.width(),
            m.image.height()
        );
    }
}

/// A lat-long map's batch `eval` (its texels read by gathers) gives the
/// one-at-a-time values bit for bit, on padded maps and at NaN and
/// infinite directions too.
#[test]
fn lat_long_evals_in_blocks_are_the_single_ones_on_small_maps_and_odd_directions() {
    // Padded maps (1 × 1, 1 × 2, 2 × 1), a 3 × 3 one and the others'
    // 32 × 17; directions with NaN, infinite and zero parts before random
    // ones (the renderer passes its directions unchecked).
    let (nan, inf) = (f64::NAN, f64::INFINITY);
    let odd = [
        [nan, 0.0, 1.0],
        [0.0, nan, 0.0],
        [inf, 0.0, 0.0],
        [-inf, inf, 0.0],
        [0.0, 0.0, 0.0],
        [0.0, -inf, 1.0],
        [1e-30, 1.0, -1e-30],
        [0.0, -1.0, 0.0],
    ];
    let mut rng = crate::rng::Rng::new(3, 7);
    let random =
        (0..150).map(|_| warp::square_to_uniform_sphere([rng.next_float(), rng.next_float()]));
    let d: Vec<[f64; 3]> = odd.into_iter().chain(random).collect();
    let d32: Vec<[f32; 3]> = d.iter().map(|x| x.map(|v| v as f32)).collect();
    for (w, h) in [(1, 1), (1, 2), (2, 1), (3, 3), (32, 17)] {
        let options = Options {
            mapping: Mapping::LatLong,
            to_world: IDENTITY,
            scale: 2.0,
            sampling: Sampling::Luminance,
            compensate: false,
        };
        let m = EnvMap::new(w, h, &test_image(Mapping::LatLong, w, h), options).unwrap();
        same_bits_as_single_evals(&m, &d);
        same_bits_as_single_evals(&m, &d32);
    }
}

/// The batch `pdf` and `eval` (both read their tables one block behind the
/// block they place) give the one-at-a-time values, in `f64` and `f32`.
#[test]
fn batch_pdfs_and_evals_agree_with_single_queries() {
    // Lengths around the pipelines' blocks of `simd::BLOCK` and the other
    // densities' of `BATCH_BLOCK`, so that the last block (read after the
    // loop) is empty, partial or whole.
    let mut rng = crate::rng::Rng::new(11, 1);
    let block = crate::simd::BLOCK;
    for m in all_maps() {
        // Random directions after those along the seam and the poles of a
        // lat-long map, where the cells wrap and clamp.
        let w = m.image.width() as f64;
        let seam = [0.0, 0.2 / w, 0.5 / w, 1.0 - 0.5 / w, 1.0 - 0.2 / w, 1.0];
        let edges = seam
            .iter()
            .flat_map(|&s| [0.0, 0.3, 1.0].map(|t| m.uv_to_dir([s, t])));
        let random = (0..3 * BATCH_BLOCK + 1)
            .map(|_| warp::square_to_uniform_sphere([rng.next_float(), rng.next_float()]));
        let d: Vec<[f64; 3]> = edges.chain(random).take(3 * BATCH_BLOCK + 1).collect();
        for n in [
            0,
            1,
            block - 1,
            block,
            block + 1,
            BATCH_BLOCK - 1,
            BATCH_BLOCK,
            BATCH_BLOCK + 1,
            3 * BATCH_BLOCK + 1,
        ] {
            let mut out = vec![-1.0; n];
            assert!(m.pdf_into(&d[..n], &mut out, |_| true));
            for (x, o) in d.iter().zip(&out) {
                assert_eq!(*o, m.pdf(*x), "{:?}: n = {n}, d = {x:?}", m.options());
            }
            if let Distribution::Luminance(density) = &m.distribution {
                // In `f32` the batch computes what the one-at-a-time
                // luminance density does in `f32`.
                let d32: Vec<[f32; 3]> = d[..n].iter().map(|x| x.map(|v| v as f32)).collect();
                let mut out32 = vec![-1.0f32; n];
                assert!(m.pdf_into(&d32, &mut out32, |_| true));
                for (x, o) in d32.iter().zip(&out32) {
                    assert_eq!(*o, m.luminance_pdf(density, *x), "n = {n}, d = {x:?}");
                }
            }
            let mut radiance = vec![[-1.0; 3]; n];
            assert!(m.eval_into(&d[..n], &mut radiance, |_| true));
            let d32: Vec<[f32; 3]> = d[..n].iter().map(|x| x.map(|v| v as f32)).collect();
            let mut radiance32 = vec![[-1.0f32; 3]; n];
            assert!(m.eval_into(&d32, &mut radiance32, |_| true));
            for ((x, x32), (o, o32)) in d.iter().zip(&d32).zip(radiance.iter().zip(&radiance32)) {
                assert_eq!(*o, m.eval(*x), "{:?}: n = {n}, d = {x:?}", m.options());
                assert_eq!(
                    *o32,
                    m.eval(*x32),
                    "{:?}: n = {n}, d = {x32:?}",
                    m.options()
                );
            }
        }
        // A direction that fails the check: in the last, partial block, in
        // a whole block, at a row past the first of a partial block.
        for (bad, n) in [
            (3 * BATCH_BLOCK, d.len()),
            (block + 5, d.len()),
            (block + 5, block + 9),
        ] {
            let invalid = |x: &[f64; 3]| x != &d[bad];
            let mut out = vec![0.0; n];
            assert!(!m.pdf_into(&d[..n], &mut out, invalid), "{bad} of {n}");
            let mut radiance = vec![[0.0; 3]; n];
            assert!(
                !m.eval_into(&d[..n], &mut radiance, invalid),
                "{bad} of {n}"
            );
        }
        // Outputs longer than the directions: the rows past them untouched.
        let n = block + 3;
        let mut out = vec![-1.0; n + 70];
        assert!(m.pdf_into(&d[..n], &mut out, |_| true));
        assert!(out[n..].iter().all(|&v| v == -1.0), "{:?}", m.options());
        let mut radiance = vec![[-1.0; 3]; n + 70];
        assert!(m.eval_into(&d[..n], &mut radiance, |_| true));
        assert!(radiance[n..].iter().all(|&v| v == [-1.0; 3]));
    }
}

use super::*;

const ALL: [Sampler; 6] = [
    Sampler::Independent,
    Sampler::Stratified,
    Sampler::MultiJitter,
    Sampler::Sobol,
    Sampler::LowDiscrepancy,
    Sampler::ZSobol,
];

fn stream(sampler: Sampler, key: u64, count: u64) -> Stream {
    Stream::new(
        sampler,
        key,
        Rng::new(key, 1),
        count,
        ZOrder::new((3, 5), (8, 8), count, key),
    )
}

/// The 2D points of dimension `dim` of every sample of a stream.
fn points(s: &mut Stream, count: u32, dim: u32) -> Vec<[f64; 2]> {
    (0..count)
        .map(|i| {
            s.start(i);
            s.get2(dim)
        })
        .collect()
}

#[test]
fn independent_is_the_generator_in_call_order() {
    let mut s = stream(Sampler::Independent, 9, 4);
    let mut rng = Rng::new(9, 1);
    s.start(3);
    assert_eq!(s.get1::<f32>(17), rng.next_float::<f32>());
    assert_eq!(
        s.get2::<f64>(0),
        [rng.next_float::<f64>(), rng.next_float()]
    );
    assert!(s.independent().is_some());
    assert!(stream(Sampler::Sobol, 9, 4).independent().is_none());
}

#[test]
fn one_dimension_has_one_sample_per_stratum() {
    for sampler in &ALL[1..] {
        for dim in [0u32, 5, 11, 2000] {
            let n = 64;
            let mut s = stream(*sampler, 4, n);
            let mut strata: Vec<u64> = (0..n as u32)
                .map(|i| {
                    s.start(i);
                    (s.get1::<f64>(dim) * n as f64) as u64
                })
                .collect();
            strata.sort();
            strata.dedup();
            assert_eq!(strata.len(), n as usize, "{sampler:?} {dim}");
        }
    }
}

/// Whether `p` (of `2^m` points) has one point in every elementary
/// interval `2^-a × 2^-(m-a)`: a (0, m, 2)-net.
fn is_net(p: &[[f64; 2]]) -> bool {
    let m = p.len().trailing_zeros();
    (0..=m).all(|a| {
        let mut cells: Vec<(u64, u64)> = p
            .iter()
            .map(|q| {
                (
                    (q[0] * (1u64 << a) as f64) as u64,
                    (q[1] * (1u64 << (m - a)) as f64) as u64,
                )
            })
            .collect();
        cells.sort();
        cells.dedup();
        cells.len() == p.len()
    })
}

#[test]
fn sobol_pixels_are_nets() {
    // Every 2D request of each Sobol' sampler is a (0, m, 2)-net in each
    // pixel (any power-of-two spp): Owen's scramble and the digital shift
    // both keep the net.
    for m in 0..9 {
        let n = 1u32 << m;
        for key in [1u64, 77] {
            for sampler in [Sampler::Sobol, Sampler::LowDiscrepancy, Sampler::ZSobol] {
                let mut s = stream(sampler, key, u64::from(n));
                for dim in [0, 3, 12, 5000] {
                    assert!(
                        is_net(&points(&mut s, n, dim)),
                        "{sampler:?} m={m} dim={dim}"
                    );
                }
            }
        }
    }
}

#[test]
fn grids_are_stratified() {
    // Stratified: one point per cell of the 8 × 8 grid; multi-jittered:
    // one per cell of 8 × 8 and one per interval of 1/64 on each axis.
    let mut s = stream(Sampler::Stratified, 3, 64);
    let mut cells: Vec<(u32, u32)> = points(&mut s, 64, 4)
        .iter()
        .map(|p| ((p[0] * 8.0) as u32, (p[1] * 8.0) as u32))
        .collect();
    cells.sort();
    cells.dedup();
    assert_eq!(cells.len(), 64);
    let mut s = stream(Sampler::MultiJitter, 3, 64);
    let p = points(&mut s, 64, 4);
    for k in 0..2 {
        let mut strata: Vec<u32> = p.iter().map(|q| (q[k] * 64.0) as u32).collect();
        strata.sort();
        strata.dedup();
        assert_eq!(strata.len(), 64);
    }
}

#[test]
fn each_value_is_uniform_over_keys() {
    // A fixed (sample, dimension) over 20000 keys: chi-square against
    // uniform in 20 bins (critical value at 1e-6 for 19 degrees of freedom:
    // 62.0); the second coordinate of a 2D request and a 1D request too.
    let (keys, bins) = (20_000u64, 20usize);
    for sampler in ALL {
        for (dim, two) in [(0u32, true), (7, false), (40, true)] {
            for coord in 0..if two { 2 } else { 1 } {
                let mut counts = vec![0u32; bins];
                for key in 0..keys {
                    let mut s = stream(sampler, key.wrapping_mul(0x9e37_79b9), 16);
                    s.start(5);
                    let v: f64 = if two { s.get2(dim)[coord] } else { s.get1(dim) };
                    counts[(v * bins as f64) as usize] += 1;
                }
                let e = keys as f64 / bins as f64;
                let chi2: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
                assert!(chi2 < 62.0, "{sampler:?} dim {dim}.{coord}: chi2 {chi2}");
            }
        }
    }
}

#[test]
fn counts_are_checked() {
    assert!(Sampler::Sobol.check_count("n", (1 << 32) - 1).is_ok());
    let e = Sampler::Sobol.check_count("n", 1 << 32).unwrap_err();
    assert!(e.to_string().contains("sampler=\"sobol\""));
    assert!(
        Sampler::Stratified
            .check_count("spp", (1 << 30) + 1)
            .is_err()
    );
    assert!(Sampler::Independent.check_count("n", u64::MAX).is_ok());
}

/// Pearson's correlation of two equally long series.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

#[test]
fn dimensions_are_uncorrelated_within_a_pixel() {
    // Across a pixel's 256 samples, two requests (1D and 2D, near and far
    // apart) are uncorrelated: the mean |r| over 20 pixels is near the
    // 0.05 of independent series (sd 1/16 each), far below the ~0.75 of two
    // scrambles of one index ordering.
    let n = 256u32;
    for sampler in ALL {
        for (a, b) in [(3u32, 9u32), (5, 6), (0, 12)] {
            let mut total = 0.0;
            for key in 0..20u64 {
                let mut s = stream(sampler, key * 7919 + 1, u64::from(n));
                let (mut xa, mut xb) = (Vec::new(), Vec::new());
                for i in 0..n {
                    s.start(i);
                    xa.push(s.get1::<f64>(a));
                    xb.push(s.get2::<f64>(b)[0]);
                }
                total += correlation(&xa, &xb).abs();
            }
            let mean = total / 20.0;
            assert!(mean < 0.12, "{sampler:?} dims {a}, {b}: mean |r| {mean}");
        }
    }
}

#[test]
fn a_batch_of_requests_is_the_requests_one_by_one() {
    // Streams of different keys and pixels, counts a power of two or not
    // (the permutation walks), dimensions cached and not, 1D and 2D.
    for sampler in &ALL[1..] {
        for count in [1u64, 7, 64, 100] {
            let fresh = || -> Vec<Stream> {
                (0..3)
                    .map(|k| {
                        let zorder = ZOrder::new((k, 5 - k), (8, 8), count, 11);
                        Stream::new(*sampler, 40 + k as u64, Rng::new(1, 1), count, zorder)
                    })
                    .collect()
            };
            let samples = || (0..30u32).map(|k| (k % 3, (k * 7 + k / 3) % count as u32));
            let dims: Vec<batch::Dim> = [0, 1, 5, 12, 31, 40, 5]
                .iter()
                .zip([true, false, true, false, true, true, false])
                .map(|(&dim, two)| batch::Dim { dim, two })
                .collect();
            let mut drawn = batch::Drawn::default();
            let mut streams = fresh();
            // No dimensions (a path's last vertex): nothing drawn.
            drawn.draw(&mut streams, samples(), &[]).unwrap();
            assert!(drawn.values.is_empty());
            // Twice: the second time with every key cached.
            for _ in 0..2 {
                drawn.draw(&mut streams, samples(), &dims).unwrap();
                assert_eq!(drawn.values.len(), 30 * dims.len());
                let mut alone = fresh();
                let requests = samples().flat_map(|s| dims.iter().map(move |d| (s, d)));
                for (((stream, index), d), v) in requests.zip(&drawn.values) {
                    let s = &mut alone[stream as usize];
                    s.start(index);
                    let want = if d.two {
                        s.get2(d.dim)
                    } else {
                        [s.get1(d.dim), v[1]]
                    };
                    assert_eq!(
                        v.map(f32::to_bits),
                        want.map(f32::to_bits),
                        "{sampler:?} {count} {stream} {index} {d:?}"
                    );
                }
            }
        }
    }
}

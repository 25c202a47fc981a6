//! Build and sampling times of the discrete tables from 10^6 weights, in
//! the pure-Rust core (no Python conversion): `cargo bench --bench distr_build`.

use mcsample::distr::{AliasTable, Discrete1D};
use std::hint::black_box;
use std::time::Instant;

fn median_ms(f: impl FnMut()) -> f64 {
    times_ms(9, f)[4]
}

/// `runs` timed calls of `f` after one untimed, sorted, in ms.
fn times_ms(runs: usize, mut f: impl FnMut()) -> Vec<f64> {
    f();
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times
}

fn main() {
    let n = 1_000_000;
    // Uniform random weights (a SplitMix64 hash of the index).
    let weights: Vec<f64> = (0..n as u64)
        .map(|i| {
            let mut z = i.wrapping_add(1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            (z >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect();
    // Builds take about a millisecond: 201 of each, min and median.
    let report = |name: &str, t: Vec<f64>| {
        println!(
            "build from 10^6 weights: {name} min {:.2} ms, median {:.2} ms",
            t[0], t[100]
        );
    };
    let discrete = || drop(black_box(Discrete1D::new(black_box(&weights)).ok()));
    report("Discrete1D", times_ms(201, discrete));
    let alias = || drop(black_box(AliasTable::new(black_box(&weights)).ok()));
    report("AliasTable", times_ms(201, alias));
    // Sampling 10^7 indices on one thread.
    let d = Discrete1D::new(&weights).unwrap();
    let t = AliasTable::new(&weights).unwrap();
    let us: Vec<f64> = (0..10_000_000u64)
        .map(|i| ((i * 0x9e37_79b9) % (1 << 32)) as f64 / (1u64 << 32) as f64)
        .collect();
    let mut out = vec![0usize; us.len()];
    let ms = median_ms(|| out.iter_mut().zip(&us).for_each(|(o, &u)| *o = d.sample(u)));
    println!("Discrete1D sample: {:.1} M/s (1 thread)", 1e4 / ms);
    let ms = median_ms(|| out.iter_mut().zip(&us).for_each(|(o, &u)| *o = t.sample(u)));
    println!("AliasTable sample: {:.1} M/s (1 thread)", 1e4 / ms);
    let mut out32 = vec![0u64; us.len()];
    let ms = median_ms(|| t.sample_into(&us, &mut out32));
    println!(
        "AliasTable sample_into: {:.1} M/s (1 thread, prefetching)",
        1e4 / ms
    );
}

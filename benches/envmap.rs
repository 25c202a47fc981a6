//! Environment maps in the core, on one thread: build time of a 1024 × 512
//! and a 2048 × 1024 sky, and nanoseconds per sample, pdf and eval (one
//! at a time, and in batches):
//! `cargo bench --bench envmap`.

use mcsample::envmap::{EnvMap, EnvSamples, Options};
use std::hint::black_box;
use std::time::Instant;

/// A sky with a sun: a smooth gradient and one bright disk, `w × h`.
fn sky(w: usize, h: usize) -> Vec<f32> {
    let sun = [0.5f64, 0.6, 0.6245];
    let mut data = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        for x in 0..w {
            let (theta, phi) = (
                std::f64::consts::PI * y as f64 / (h - 1) as f64,
                std::f64::consts::TAU * (x as f64 + 0.5) / w as f64,
            );
            let d = [
                phi.sin() * theta.sin(),
                theta.cos(),
                -phi.cos() * theta.sin(),
            ];
            let cos_sun = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
            let v = if cos_sun > 0.9995 {
                3000.0
            } else {
                0.1 + d[1].max(0.0)
            };
            data.extend([v as f32, (0.9 * v) as f32, (0.7 * v) as f32]);
        }
    }
    data
}

fn best(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    for (w, h) in [(1024, 512), (2048, 1024)] {
        let data = sky(w, h);
        let t = best(5, || {
            black_box(EnvMap::new(w, h, &data, Options::default()).ok());
        });
        println!("build {w}x{h}: {:.2} ms", t * 1e3);
    }
    let (w, h) = (1024, 512);
    let env = EnvMap::new(w, h, &sky(w, h), Options::default()).expect("a valid sky");
    let n = 2_000_000;
    let u: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let x = (i as f64 * 0.618_033_988_749_894_9).fract();
            [x, (i as f64 + 0.5) / n as f64]
        })
        .collect();
    // Batches on random numbers in f32, as Python's float32 EnvMap.sample
    // and .pdf run them (on each thread).
    let mut state = 0x853c_49e6_748f_ea9b_u64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let random: Vec<[f32; 2]> = (0..n).map(|_| [next(), next()]).collect();
    let (mut d32, mut pdfs, mut weights) =
        (vec![[0.0f32; 3]; n], vec![0.0f32; n], vec![[0.0f32; 3]; n]);
    let t = best(3, || {
        let out = EnvSamples {
            direction: &mut d32,
            pdf: &mut pdfs,
            weight: &mut weights,
        };
        env.sample_into(black_box(&random), out);
    });
    println!("sample_into f32 (random u): {:.1} ns", t / n as f64 * 1e9);
    let mut pdf32 = vec![0.0f32; n];
    let t = best(3, || {
        env.pdf_into(black_box(&d32), &mut pdf32, |_| true);
        black_box(&pdf32);
    });
    println!(
        "pdf_into f32 (sampled directions): {:.1} ns",
        t / n as f64 * 1e9
    );
    let mut dirs = vec![[0.0; 3]; n];
    let t = best(3, || {
        for (d, &x) in dirs.iter_mut().zip(&u) {
            *d = env.sample(black_box(x)).direction;
        }
    });
    println!("sample: {:.1} ns", t / n as f64 * 1e9);
    let t = best(3, || {
        for d in &dirs {
            black_box(env.pdf(black_box(*d)));
        }
    });
    println!("pdf: {:.1} ns", t / n as f64 * 1e9);
    let t = best(3, || {
        for d in &dirs {
            black_box(env.eval(black_box(*d)));
        }
    });
    println!("eval: {:.1} ns", t / n as f64 * 1e9);
    let t = best(3, || {
        for d in &dirs {
            black_box(env.dir_to_uv(black_box(*d)));
        }
    });
    println!("dir_to_uv: {:.1} ns", t / n as f64 * 1e9);
    let t = best(3, || {
        for &x in &u {
            black_box(env.uv_to_dir(black_box(x)));
        }
    });
    println!("uv_to_dir: {:.1} ns", t / n as f64 * 1e9);
}

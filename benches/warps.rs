//! Single-thread throughput of the vectorised warp loops in the core, on
//! reused buffers (no allocation): `cargo bench --bench warps`.

use mcsample::simd::map_rows;
use mcsample::warp;
use std::hint::black_box;
use std::time::Instant;

fn rate<const M: usize>(name: &str, u: &[[f32; 2]], kernel: impl Fn([f32; 2]) -> [f32; M]) {
    // An optional argument picks the warps whose name contains it.
    if let Some(only) = std::env::args().nth(1).filter(|a| !a.starts_with('-'))
        && !name.contains(&only)
    {
        return;
    }
    let mut out = vec![[0.0f32; M]; u.len()];
    let unit = |v: &[f32; 2]| v.iter().fold(true, |ok, &x| ok & (0.0..=1.0).contains(&x));
    let mut best = f64::INFINITY;
    for _ in 0..7 {
        let t = Instant::now();
        black_box(map_rows(&mut out, black_box(u), &kernel, unit));
        best = best.min(t.elapsed().as_secs_f64());
    }
    println!(
        "{name:36} {:8.1} M/s (1 thread, f32)",
        u.len() as f64 / best / 1e6
    );
}

fn main() {
    let n = 1 << 22;
    let u: Vec<[f32; 2]> = (0..n)
        .map(|i| {
            let x = (i as f32 * 0.618_034) % 1.0;
            [x, (i as f32 / n as f32)]
        })
        .collect();
    rate("square_to_uniform_disk", &u, warp::square_to_uniform_disk);
    rate(
        "square_to_uniform_disk_concentric",
        &u,
        warp::square_to_uniform_disk_concentric,
    );
    rate(
        "square_to_uniform_sphere",
        &u,
        warp::square_to_uniform_sphere,
    );
    rate(
        "square_to_uniform_hemisphere",
        &u,
        warp::square_to_uniform_hemisphere,
    );
    rate(
        "square_to_cosine_hemisphere",
        &u,
        warp::square_to_cosine_hemisphere,
    );
    rate("square_to_uniform_cone", &u, |u| {
        warp::square_to_uniform_cone(u, 0.3)
    });
    rate(
        "square_to_uniform_triangle",
        &u,
        warp::square_to_uniform_triangle,
    );
    rate("square_to_cosine_power_hemisphere", &u, |u| {
        warp::square_to_cosine_power_hemisphere(u, 10.0)
    });
}

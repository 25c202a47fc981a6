//! Throughput of the vectorised warp loops in the core on one thread and
//! through the batch engine on all cores, into reused buffers (no
//! allocation): `cargo bench --bench warps [name]`.
//!
//! Two kernels that do no arithmetic come first: they read and write the
//! bytes of a two- and a three-component warp, so they are the memory
//! floor of the loop. At 10^7 points the warps are bound by it: on the
//! 2-core Zen 4 of the issues, the two-component copy ran as fast as a
//! hand-written non-temporal `memcpy` of the same array (2349–3436 against
//! 2409–3388 M/s in three interleaved runs), and the triangle warp within
//! 10% of both.

use mcsample::parallel::for_each_chunk;
use mcsample::simd::map_rows;
use mcsample::warp;
use std::hint::black_box;
use std::time::Instant;

fn rate<const M: usize>(name: &str, u: &[[f32; 2]], kernel: impl Fn([f32; 2]) -> [f32; M] + Sync) {
    // An optional argument picks the warps whose name contains it.
    if let Some(only) = std::env::args().nth(1).filter(|a| !a.starts_with('-'))
        && !name.contains(&only)
    {
        return;
    }
    let mut out = vec![[0.0f32; M]; u.len()];
    let stream = std::env::var_os("NO_STREAM").is_none()
        && size_of_val(&out[..]) >= mcsample::simd::STREAM_MIN_BYTES;
    let unit = |v: &[f32; 2]| v.iter().fold(true, |ok, &x| ok & (0.0..=1.0).contains(&x));
    let mut best = f64::INFINITY;
    for _ in 0..7 {
        let t = Instant::now();
        black_box(map_rows(&mut out, black_box(u), &kernel, unit, stream));
        best = best.min(t.elapsed().as_secs_f64());
    }
    // All cores, through the batch engine.
    let mut best_all = f64::INFINITY;
    for _ in 0..7 {
        let t = Instant::now();
        let ok = for_each_chunk(u.len(), &mut out[..], |range, chunk: &mut [[f32; M]]| {
            map_rows(chunk, &u[range], &kernel, unit, stream)
        });
        black_box(ok.ok());
        best_all = best_all.min(t.elapsed().as_secs_f64());
    }
    println!(
        "{name:36} {:7.1} M/s on 1 thread, {:7.1} M/s on all cores (f32)",
        u.len() as f64 / best / 1e6,
        u.len() as f64 / best_all / 1e6
    );
}

fn main() {
    let n = 10_000_000;
    // Uniform random points (a SplitMix64 hash of the index, 24 bits each).
    let u: Vec<[f32; 2]> = (0..n as u64)
        .map(|i| {
            let mut z = i.wrapping_add(1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            let bits = |s: u32| ((z >> s) & 0xff_ffff) as f32 / (1u32 << 24) as f32;
            [bits(0), bits(32)]
        })
        .collect();
    rate("copy (N, 2) -> (N, 2)", &u, |u| u);
    rate("copy (N, 2) -> (N, 3)", &u, |u| [u[0], u[1], u[0]]);
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
    rate(
        "square_to_cosine_power_hemisphere",
        &u,
        #[inline(always)]
        |u| warp::square_to_cosine_power_hemisphere(u, 10.0),
    );
    rate("square_to_std_normal", &u, warp::square_to_std_normal);
    rate(
        "square_to_beckmann",
        &u,
        #[inline(always)]
        |u| warp::square_to_beckmann(u, 0.3),
    );
    let lobe = warp::VonMisesFisher::new(10.0f32);
    rate(
        "square_to_von_mises_fisher",
        &u,
        #[inline(always)]
        |u| warp::square_to_von_mises_fisher(u, &lobe),
    );
}

//! The renderer in the core, on all cores: camera samples per second on the
//! two scenes of `python -m mcsample bench --only render` (a diffuse sphere
//! under the packaged sky; the same sphere on a plane with a rectangular
//! area light), 256 × 256, 64 spp, MIS, direct and path, with each sampler:
//! `cargo bench --bench render [-- FILTER]`, FILTER a part of a case's name
//! (e.g. `plane`, `Path`, `sobol`).

use std::path::Path;
use std::time::Instant;

use glam::{Affine3A, Vec3A};
use mcsample::envmap::{EnvMap, Options};
use mcsample::phong::{Phong, Selection};
use mcsample::render::camera::{Camera, FovAxis};
use mcsample::render::mesh::Mesh;
use mcsample::render::scene::{Environment, Geometry, Material, Shape};
use mcsample::render::{
    Heuristic, Integrator, Progress, Samples, Scene, Settings, Strategy, render,
};
use mcsample::sampler::Sampler;

const SIZE: usize = 256;
const SPP: u32 = 64;

fn diffuse(rho: [f64; 3]) -> Material {
    Material {
        bsdf: Phong::new(rho, [0.0; 3], 1.0, Selection::Max).expect("valid Phong"),
        two_sided: false,
    }
}

/// Mitsuba's unit rectangle (z = 0, normal +z) placed by `m` (row-major).
fn rectangle(m: [[f64; 4]; 4], material: Material, emission: Option<[f64; 3]>) -> Shape {
    let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let vertices: Vec<[f64; 3]> = corners
        .iter()
        .map(|[x, y]| [0, 1, 2].map(|r| m[r][0] * x + m[r][1] * y + m[r][3]))
        .collect();
    Shape {
        geometry: Mesh::new(&vertices, &[[0, 1, 2], [2, 3, 0]], None, true)
            .map(Geometry::Mesh)
            .expect("valid mesh"),
        material,
        emission,
        motion: None,
    }
}

fn scene(with_plane: bool) -> Scene {
    let sky = mcsample::io::read_exr(Path::new("python/mcsample/data/sky.exr"), None).expect("sky");
    let rgb: Vec<f32> = sky
        .data
        .chunks(sky.channels)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let env = EnvMap::new(sky.width, sky.height, &rgb, Options::default()).expect("envmap");
    // Mitsuba's look_at: camera +z toward the target, +y up, +x = up × dir.
    let (origin, target) = (Vec3A::new(0.0, 1.2, 4.5), Vec3A::new(0.0, 0.6, 0.0));
    let dir = (target - origin).normalize();
    let left = Vec3A::Y.cross(dir).normalize();
    let to_world = Affine3A::from_cols(left, dir.cross(left), dir, origin);
    let camera =
        Camera::new(to_world, 35.0, FovAxis::X, SIZE, SIZE, 1e-2, 1e4, 0.0, 0.0).expect("camera");
    let mut shapes = vec![Shape {
        geometry: Geometry::sphere([0.0, 0.6, 0.0], 0.6, false).expect("sphere"),
        material: diffuse([0.7, 0.6, 0.5]),
        emission: None,
        motion: None,
    }];
    if with_plane {
        let floor = [
            [4.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 4.0, 0.0],
            [0.0, -4.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let light = [
            [0.4, 0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0, 2.0],
            [0.0, -0.4, 0.0, 0.8],
            [0.0, 0.0, 0.0, 1.0],
        ];
        shapes.push(rectangle(floor, diffuse([0.5; 3]), None));
        shapes.push(rectangle(light, diffuse([0.0; 3]), Some([12.0, 11.0, 9.0])));
    }
    Scene::new(
        shapes,
        Some(Environment::Map(std::sync::Arc::new(env))),
        camera,
        SIZE,
        SIZE,
    )
    .expect("scene")
}

fn main() {
    let filter = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let samples = (SIZE * SIZE) as f64 * f64::from(SPP);
    for (name, with_plane) in [("sphere under sky", false), ("sphere on plane", true)] {
        let scene = scene(with_plane);
        let cases = [Integrator::Direct, Integrator::Path]
            .into_iter()
            .flat_map(|i| {
                Sampler::NAMES
                    .iter()
                    .map(move |&(s, sampler)| (i, s, sampler))
            });
        for (integrator, sampler_name, sampler) in cases {
            let case = format!("{name}, {integrator:?}, {sampler_name}");
            if filter.as_ref().is_some_and(|f| !case.contains(f.as_str())) {
                continue;
            }
            let settings = Settings {
                integrator,
                strategy: Strategy::Mis,
                heuristic: Heuristic::Power,
                max_depth: None,
                rr_depth: 5,
                hide_emitters: false,
                sampler,
                strategies: false,
            };
            let mut times: Vec<f64> = (0..5)
                .map(|seed| {
                    let start = Instant::now();
                    render(
                        &scene,
                        Samples::all(SPP),
                        seed,
                        &settings,
                        &Progress::default(),
                    )
                    .expect("render");
                    start.elapsed().as_secs_f64()
                })
                .collect();
            times.sort_by(f64::total_cmp);
            println!(
                "{case:>38}: min {:7.1} ms, median {:7.1} ms, {:5.2} M samples/s",
                times[0] * 1e3,
                times[2] * 1e3,
                samples / times[0] / 1e6
            );
        }
    }
}

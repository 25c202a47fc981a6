use glam::{Affine3A, Quat, Vec3};

use super::*;
use std::sync::Arc;

use crate::envmap::{EnvMap, Options};
use crate::phong::{Phong, Selection};
use crate::render::geometry::Geometry;
use crate::render::integrator::{Integrator, add_escaped};
use crate::render::scene::{Environment, Material, Shape};
use crate::render::tests::{camera, cube, diffuse, light, rectangle, settings};
use crate::sampler::Sampler;
use crate::sampler::zorder::ZOrder;

/// A diffuse floor, a glossy box on it (the BSDF kernels' two groups of
/// rows, [`shade::KernelRows`], mixed in every bounce), a spherical light
/// over it and a sky: a constant one, or a map (whose samples are drawn
/// by the batch), dim enough that emitter sampling draws it and the
/// light about equally often (so that the paths that wait for the map's
/// samples are not all of them).
fn scene(map: bool) -> Scene {
    let still = |geometry, material| Shape {
        geometry,
        material,
        emission: None,
        motion: None,
    };
    let glossy = Material {
        bsdf: Phong::new([0.5; 3], [0.3; 3], 20.0, Selection::Max).unwrap(),
        two_sided: false,
    };
    let turned = Affine3A::from_scale_rotation_translation(
        Vec3::splat(0.5),
        Quat::from_rotation_z(0.4),
        Vec3::new(0.3, 0.0, 0.5),
    );
    let shapes = vec![
        still(
            rectangle(Affine3A::from_scale(Vec3::splat(20.0))),
            diffuse(0.6),
        ),
        still(cube(turned), glossy),
        light(Geometry::sphere([-0.5, 0.4, 1.6], 0.3, false).unwrap(), 6.0),
    ];
    let sky = if map {
        let (w, h) = (16, 8);
        let texels: Vec<f32> = (0..w * h * 3)
            .map(|i| 2e-4 + ((i * 7919) % 13) as f32 / 13e3)
            .collect();
        let env = EnvMap::new(w, h, &texels, Options::default()).unwrap();
        Environment::Map(Arc::new(env))
    } else {
        Environment::Constant([0.4, 0.5, 0.7])
    };
    let sky = Some(sky);
    Scene::new(shapes, sky, camera(), 4, 4).unwrap()
}

/// The light of camera samples `slots` (rays from one point in
/// scattered directions, some to the sky), traced as one batch.
fn trace(scene: &Scene, s: &Settings, slots: std::ops::Range<u32>) -> Vec<[f32; 3]> {
    let count = 1 << 10;
    let zorder = ZOrder::new((0, 0), (1, 1), count, 3);
    let mut streams = [Stream::new(s.sampler, 3, Rng::new(3, 1), count, zorder)];
    let mut paths = Wavefront::default();
    paths.start(slots.len()).unwrap();
    for (slot, index) in slots.clone().enumerate() {
        let mut rng = Rng::new(11, u64::from(index));
        let [a, b] = [rng.next_float::<f32>(), rng.next_float::<f32>()];
        let ray = Ray {
            o: Vec3A::new(0.0, -2.5, 2.0),
            d: Vec3A::new(2.0 * a - 1.0, 1.0, 0.2 - b).normalize(),
            tmax: f32::INFINITY,
        };
        let camera = CameraSample {
            slot: slot as u32,
            pixel: 0,
            index,
            ray,
            hit: scene.intersect(&ray, 0.0),
            time: 0.0,
            rng: (s.sampler == Sampler::Independent).then_some(rng),
        };
        paths.push(scene, s, camera);
    }
    let mut l = vec![[0.0; 3]; slots.len()];
    paths.trace(scene, s, &mut streams, &mut l).unwrap();
    add_escaped(scene, s, &mut paths.escaped, &mut l);
    l
}

/// A path traced in a batch of others gives, bit for bit, what it
/// gives traced alone: its numbers, its light samples and its rays stay
/// its own, for every integrator, strategy and sampler.
#[test]
fn a_path_in_a_batch_is_the_path_alone() {
    let mut lit = 0;
    for (map, integrator, strategy, sampler) in [
        (false, Integrator::Path, Strategy::Mis, Sampler::Independent),
        (false, Integrator::Path, Strategy::Emitter, Sampler::Sobol),
        (
            false,
            Integrator::Path,
            Strategy::Bsdf,
            Sampler::Independent,
        ),
        (
            false,
            Integrator::Direct,
            Strategy::Mis,
            Sampler::Stratified,
        ),
        (true, Integrator::Path, Strategy::Mis, Sampler::Independent),
        (
            true,
            Integrator::Path,
            Strategy::Emitter,
            Sampler::Independent,
        ),
        (true, Integrator::Direct, Strategy::Emitter, Sampler::Sobol),
    ] {
        let scene = scene(map);
        let s = Settings {
            rr_depth: 2,
            sampler,
            ..settings(integrator, strategy)
        };
        let batch = trace(&scene, &s, 0..200);
        for (i, l) in batch.iter().enumerate() {
            let i = i as u32;
            let alone = trace(&scene, &s, i..i + 1);
            assert_eq!(l.map(f32::to_bits), alone[0].map(f32::to_bits), "{s:?} {i}");
        }
        lit += batch.iter().filter(|l| l[0] > 0.0).count();
    }
    // Most samples see light (the sky, the light, lit surfaces).
    assert!(lit > 1000, "{lit}");
}

//! The renderer's estimates against closed forms: a diffuse floor lit by
//! one area light of each shape (near it, far from it and at grazing
//! angles), by each strategy alone and by MIS; closed rooms that glow
//! (`L / (1 − ρ)` for paths of any length); and shadow rays that reach the
//! light samples they aim at.

use glam::{Affine3A, DVec3, Quat, Vec3, Vec3A};
use std::sync::Arc;

use super::camera::{Camera, FovAxis};
use super::integrator;
use super::mesh::Mesh;
use super::scene::{Environment, Geometry, Material, Shape};
use super::shape::Ray;
use super::wavefront::{CameraSample, Wavefront};
use super::{Heuristic, Integrator, Scene, Settings, Strategy};
use crate::envmap::tests::dim_sky_with_block;
use crate::envmap::{EnvMap, Options};
use crate::phong::{Phong, Selection};
use crate::rng::Rng;
use crate::sampler::zorder::ZOrder;
use crate::sampler::{Sampler, Stream};

pub(super) fn diffuse(rho: f64) -> Material {
    Material {
        bsdf: Phong::new([rho; 3], [0.0; 3], 0.0, Selection::Max).unwrap(),
        two_sided: false,
    }
}

fn matrix(m: Affine3A) -> [[f64; 4]; 4] {
    let c = m.to_cols_array();
    std::array::from_fn(|r| {
        std::array::from_fn(|k| match (r, k) {
            (3, 3) => 1.0,
            (3, _) => 0.0,
            _ => f64::from(c[3 * k + r]),
        })
    })
}

fn mesh(m: Affine3A, vertices: &[[f32; 3]], faces: &[[i64; 3]]) -> Geometry {
    let v: Vec<[f64; 3]> = vertices
        .iter()
        .map(|&p| m.transform_point3(Vec3::from(p)).as_dvec3().to_array())
        .collect();
    Geometry::Mesh(Mesh::new(&v, faces, None, true).unwrap())
}

/// Mitsuba's rectangle `[−1, 1]², z = 0`, facing +z, placed by `m`.
pub(super) fn rectangle(m: Affine3A) -> Geometry {
    let v = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    mesh(m, &v, &[[0, 1, 2], [2, 3, 0]])
}

/// Mitsuba's cube `[−1, 1]³`, facing out, placed by `m`.
pub(super) fn cube(m: Affine3A) -> Geometry {
    let mut v = Vec::new();
    let mut f = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let (mut a, mut b) = ((axis + 1) % 3, (axis + 2) % 3);
            if sign < 0.0 {
                std::mem::swap(&mut a, &mut b);
            }
            let base = v.len() as i64;
            for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = [0.0f32; 3];
                (p[axis], p[a], p[b]) = (sign, s, t);
                v.push(p);
            }
            f.extend([[base, base + 1, base + 2], [base + 2, base + 3, base]]);
        }
    }
    mesh(m, &v, &f)
}

pub(super) fn camera() -> Camera {
    Camera::new(
        Affine3A::IDENTITY,
        40.0,
        FovAxis::X,
        4,
        4,
        0.01,
        100.0,
        0.0,
        0.0,
    )
    .unwrap()
}

/// A diffuse floor `z = 0` (albedo `rho`, facing +z) and `lights`.
fn floor_scene(rho: f64, lights: Vec<Shape>) -> Scene {
    let floor = Shape {
        geometry: rectangle(Affine3A::from_scale(Vec3::splat(50.0))),
        material: diffuse(rho),
        emission: None,
        motion: None,
    };
    let mut shapes = vec![floor];
    shapes.extend(lights);
    Scene::new(shapes, None, camera(), 4, 4).unwrap()
}

pub(super) fn light(geometry: Geometry, radiance: f64) -> Shape {
    Shape {
        geometry,
        material: diffuse(0.0),
        emission: Some([radiance; 3]),
        motion: None,
    }
}

pub(super) fn settings(integrator: Integrator, strategy: Strategy) -> Settings {
    Settings {
        integrator,
        strategy,
        heuristic: Heuristic::Power,
        max_depth: None,
        rr_depth: 5,
        hide_emitters: false,
        sampler: Sampler::Independent,
        strategies: false,
    }
}

/// Every strategy with every sampler. (Under a stratified sampler the
/// samples are not independent and the standard error of independent
/// samples usually overstates the error: the tests' bounds stay valid.)
fn strategies_and_samplers() -> impl Iterator<Item = (Strategy, Sampler)> {
    [Strategy::Emitter, Strategy::Bsdf, Strategy::Mis]
        .into_iter()
        .flat_map(|t| Sampler::NAMES.iter().map(move |&(_, s)| (t, s)))
}

/// The mean and standard error of `n` samples of the (first channel of
/// the) radiance leaving `target` toward `from`, as a camera ray sees it.
fn estimate(scene: &Scene, from: Vec3A, target: Vec3A, s: &Settings, n: usize) -> (f64, f64) {
    let ray = Ray {
        o: from,
        d: (target - from).normalize(),
        tmax: f32::INFINITY,
    };
    let hit = scene.accel().intersect(&ray);
    let count = n as u64;
    let zorder = ZOrder::new((0, 0), (1, 1), count, 17);
    let mut streams = [Stream::new(s.sampler, 17, Rng::new(17, 5), count, zorder)];
    let independent = s.sampler == Sampler::Independent;
    let mut paths = Wavefront::default();
    let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
    let mut l = vec![[0.0f32; 3]; 256];
    for block in 0..n / 256 {
        paths.start(256).unwrap();
        for slot in 0..256 {
            let index = (block * 256 + slot) as u32;
            let camera = CameraSample {
                slot: slot as u32,
                pixel: 0,
                index,
                ray,
                hit,
                time: 0.0,
                rng: independent.then(|| Rng::new(17, u64::from(index))),
            };
            paths.push(scene, s, camera);
        }
        l.fill([0.0; 3]);
        paths.trace(scene, s, &mut streams, &mut l).unwrap();
        integrator::add_escaped(scene, s, &mut paths.escaped, &mut l);
        for v in &l {
            sum += f64::from(v[0]);
            sum_sq += f64::from(v[0]).powi(2);
        }
    }
    let m = (n / 256 * 256) as f64;
    let mean = sum / m;
    (mean, ((sum_sq / m - mean * mean).max(0.0) / m).sqrt())
}

/// Irradiance at `x` (normal +z) from a convex polygon of radiance 1 facing
/// it, above the horizon (Lambert): `½ Σ θ_i (n · normalize(a_i × a_{i+1}))`
/// with `a_i` the unit vectors toward the vertices and `θ_i` their angles.
fn polygon_irradiance(x: DVec3, vertices: &[DVec3]) -> f64 {
    let a: Vec<DVec3> = vertices.iter().map(|v| (*v - x).normalize()).collect();
    let mut sum = 0.0;
    for i in 0..a.len() {
        let (p, q) = (a[i], a[(i + 1) % a.len()]);
        sum += p.angle_between(q) * p.cross(q).normalize().z;
    }
    0.5 * sum.abs()
}

/// The placements (affine maps of the unit shapes) of a light near the
/// floor point at the origin (as high as it is wide), far from it (20 sizes
/// up) and at a grazing angle (low and off to the side), each under a
/// non-uniform scale and a rotation; flat lights face down (−z), tilted.
fn placements() -> [(&'static str, Affine3A); 3] {
    let down = Quat::from_rotation_x(std::f32::consts::PI) * Quat::from_rotation_z(0.5);
    let tilt = Quat::from_rotation_y(0.3);
    [
        (
            "near",
            Affine3A::from_scale_rotation_translation(
                Vec3::new(0.3, 0.2, 0.25),
                tilt * down,
                Vec3::new(0.1, 0.0, 0.55),
            ),
        ),
        (
            "far",
            Affine3A::from_scale_rotation_translation(
                Vec3::new(0.3, 0.2, 0.25),
                tilt * down,
                Vec3::new(0.5, -0.3, 6.0),
            ),
        ),
        (
            "grazing",
            Affine3A::from_scale_rotation_translation(
                Vec3::new(0.15, 0.1, 0.12),
                // Facing the origin from 1.5 away, 0.2 above the floor.
                Quat::from_rotation_y(-1.2) * Quat::from_rotation_z(0.4),
                Vec3::new(1.5, 0.0, 0.32),
            ),
        ),
    ]
}

/// The lights of every shape at one placement, each with the irradiance it
/// gives the floor point at the origin (radiance 1).
fn lights_at(m: Affine3A) -> Vec<(&'static str, Geometry, f64)> {
    let corners = |m: Affine3A, face: [[f32; 3]; 4]| -> Vec<DVec3> {
        face.iter()
            .map(|&p| m.transform_point3(Vec3::from(p)).as_dvec3())
            .collect()
    };
    let square = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let x = DVec3::ZERO;
    let rect_e = polygon_irradiance(x, &corners(m, square));
    // The cube's faces that face the point (their irradiances add up).
    let mut cube_e = 0.0;
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut normal = Vec3::ZERO;
            normal[axis] = sign;
            let face: [[f32; 3]; 4] = std::array::from_fn(|k| {
                let (s, t) = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)][k];
                let mut p = [0.0; 3];
                (p[axis], p[(axis + 1) % 3], p[(axis + 2) % 3]) = (sign, s, t);
                p
            });
            let world_n = (m.matrix3.inverse().transpose() * Vec3A::from(normal)).as_dvec3();
            let center = m.transform_point3(normal).as_dvec3();
            if world_n.dot(x - center) > 0.0 {
                cube_e += polygon_irradiance(x, &corners(m, face));
            }
        }
    }
    // A disk by quadrature of cos θ_x cos θ_l / r² over it (smooth: the
    // point is off its plane).
    let disk_e = {
        let (nr, nphi) = (400, 400);
        let normal = (m.matrix3.inverse().transpose() * Vec3A::Z)
            .normalize()
            .as_dvec3();
        let jac = f64::from(m.matrix3.x_axis.cross(m.matrix3.y_axis).length());
        let mut sum = 0.0;
        for i in 0..nr {
            let r = (i as f64 + 0.5) / nr as f64;
            for j in 0..nphi {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / nphi as f64;
                let local = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, 0.0);
                let p = m.transform_point3(local).as_dvec3();
                let to = p - x;
                let d2 = to.length_squared();
                let cos_x = to.z / d2.sqrt();
                let cos_l = -normal.dot(to) / d2.sqrt();
                sum += cos_x * cos_l / d2 * r;
            }
        }
        sum * jac * 2.0 * std::f64::consts::PI / (nr * nphi) as f64
    };
    // A sphere of the placement's mean scale: E = π (r/d)² cos α.
    let radius = f64::from(m.matrix3.x_axis.length());
    let center = m.translation.as_dvec3();
    let d = center - x;
    let sphere_e = std::f64::consts::PI * (radius / d.length()).powi(2) * d.normalize().z;
    vec![
        ("rectangle", rectangle(m), rect_e),
        ("cube", cube(m), cube_e),
        ("disk", Geometry::disk(matrix(m)).unwrap(), disk_e),
        (
            "sphere",
            Geometry::sphere(center.to_array(), radius, false).unwrap(),
            sphere_e,
        ),
    ]
}

/// Every light shape at every placement, rendered by BSDF sampling,
/// emitter sampling and MIS: the radiance of the lit floor point is
/// `ρ/π · E` (E the irradiance in closed form or by quadrature), within 5
/// standard errors and 0.2 %. A small box under the floor, in no ray's
/// way, makes the scene more than one leaf of primitives: the
/// BSDF-sampled rays then find the lights of a few primitives as last
/// vertices do in large scenes ([`Scene::emitters`]), the cube's (twelve
/// triangles) by their nearest hit.
#[test]
fn direct_light_from_every_shape_matches_its_irradiance() {
    let rho = 0.6;
    let from = Vec3A::new(-0.01, 0.004, 0.01);
    let under_the_floor = Affine3A::from_scale_rotation_translation(
        Vec3::splat(0.1),
        Quat::IDENTITY,
        Vec3::new(0.0, 0.0, -5.0),
    );
    for (place, m) in placements() {
        for (shape, geometry, e) in lights_at(m) {
            let clutter = Shape {
                geometry: cube(under_the_floor),
                material: diffuse(0.5),
                emission: None,
                motion: None,
            };
            let scene = floor_scene(rho, vec![light(geometry, 1.0), clutter]);
            assert!(!scene.accel().is_leaf());
            let few = shape != "cube";
            assert_eq!(scene.emitters().is_some(), few, "{shape}");
            let expected = rho / std::f64::consts::PI * e;
            for (strategy, sampler) in strategies_and_samplers() {
                let n = if strategy == Strategy::Bsdf && place != "near" {
                    1 << 21
                } else {
                    1 << 17
                };
                let s = Settings {
                    sampler,
                    ..settings(Integrator::Direct, strategy)
                };
                let (mean, se) = estimate(&scene, from, Vec3A::ZERO, &s, n);
                assert!(
                    (mean - expected).abs() < 5.0 * se + 2e-3 * expected,
                    "{shape} {place} {strategy:?} {sampler:?}: {mean} ± {se}, expected {expected}"
                );
                assert!(
                    se < 0.05 * expected,
                    "{shape} {place} {strategy:?}: se {se}"
                );
            }
        }
    }
}

/// At the last vertex, a BSDF-sampled ray counts the light of the nearest
/// emitter it meets with nothing before it (moving shapes placed where
/// they are at the path's time): with a small light in front of a larger,
/// brighter one and a moving box hiding part of both at time 0, in a scene
/// of more than one leaf ([`Scene::emitters`]), BSDF sampling agrees with
/// emitter sampling (whose shadow rays are tested apart) within 5
/// standard errors of their difference.
#[test]
fn last_vertices_see_the_nearest_light_past_moving_shapes() {
    use crate::render::motion::Motion;
    use glam::DAffine3;
    let shape = |geometry, motion| Shape {
        geometry,
        material: diffuse(0.5),
        emission: None,
        motion,
    };
    let placed = |scale: Vec3, at: Vec3| {
        Affine3A::from_scale_rotation_translation(scale, Quat::IDENTITY, at)
    };
    let away = DAffine3::from_translation(DVec3::new(0.0, 0.0, 50.0));
    let lights = vec![
        light(Geometry::sphere([0.0, 0.0, 2.0], 0.3, false).unwrap(), 1.0),
        light(Geometry::sphere([0.1, 0.0, 3.5], 0.8, false).unwrap(), 4.0),
        // Under the floor, in no ray's way: more than one leaf.
        shape(cube(placed(Vec3::splat(0.1), -5.0 * Vec3::Z)), None),
        shape(
            cube(placed(Vec3::new(0.3, 0.3, 0.05), Vec3::new(0.25, 0.0, 1.0))),
            Some(Motion::new("to_world", DAffine3::IDENTITY, away).unwrap()),
        ),
    ];
    let scene = floor_scene(0.6, lights);
    assert!(scene.emitters().is_some() && scene.moves());
    let from = Vec3A::new(-0.01, 0.004, 0.01);
    let [(b, sb), (e, se)] = [Strategy::Bsdf, Strategy::Emitter].map(|t| {
        estimate(
            &scene,
            from,
            Vec3A::ZERO,
            &settings(Integrator::Direct, t),
            1 << 20,
        )
    });
    assert!(
        (b - e).abs() < 5.0 * sb.hypot(se),
        "BSDF {b} ± {sb}, emitter {e} ± {se}"
    );
    assert!(sb < 0.01 * b, "{b} ± {sb}");
}

/// From a receiver at any distance and angle, the shadow ray toward a
/// light sample is never blocked by the light itself or by the receiver's
/// own surface (nothing else is in the scene).
#[test]
fn shadow_rays_reach_the_light_samples() {
    for (place, m) in placements() {
        for (shape, geometry, _) in lights_at(m) {
            let scene = floor_scene(0.5, vec![light(geometry, 1.0)]);
            let mut rng = Rng::new(3, 1);
            let (mut reached, mut drawn) = (0, 0);
            for i in 0..4000 {
                let k = i as f32;
                let p = Vec3A::new((k * 0.37).sin() * 2.0, (k * 0.91).cos() * 2.0, 0.0);
                let u = [rng.next_float(), rng.next_float(), rng.next_float()];
                let Some(ls) = scene.sample_light(p, u, None::<fn() -> u64>) else {
                    continue;
                };
                if ls.d.z <= 0.0 {
                    continue;
                }
                drawn += 1;
                let ray = integrator::shadow_ray(p, Vec3A::Z, ls.d, ls.end());
                reached += usize::from(!scene.accel().occluded(&ray));
            }
            assert!(drawn > 500, "{shape} {place}: {drawn} samples");
            assert_eq!(reached, drawn, "{shape} {place}");
        }
    }
}

/// The unit sphere around the origin, seen from inside (normals inward):
/// diffuse of albedo `rho`, glowing with radiance `l`.
fn glowing_room(rho: f64, l: f64) -> Scene {
    let room = Shape {
        geometry: Geometry::sphere([0.0, 0.0, 0.0], 1.0, true).unwrap(),
        material: diffuse(rho),
        emission: Some([l; 3]),
        motion: None,
    };
    Scene::new(vec![room], None, camera(), 4, 4).unwrap()
}

/// A closed room that glows: inside a sphere of radiance `L` and albedo
/// `ρ` (normals inward), every point sees `L (1 + ρ + … + ρ^(k−1))` with
/// paths of at most `k` segments, `L / (1 − ρ)` with any length (Russian
/// roulette from depth 2), by every strategy.
#[test]
fn glowing_room_sums_its_bounces() {
    let (rho, l) = (0.6, 0.5);
    let scene = glowing_room(rho, l);
    let from = Vec3A::new(0.1, 0.2, -0.3);
    for (strategy, sampler) in strategies_and_samplers() {
        for (max_depth, expected) in [
            (Some(1), l),
            (Some(2), l * (1.0 + rho)),
            (Some(4), l * (1.0 + rho + rho * rho + rho * rho * rho)),
            (None, l / (1.0 - rho)),
        ] {
            let s = Settings {
                max_depth,
                rr_depth: 2,
                sampler,
                ..settings(Integrator::Path, strategy)
            };
            let (mean, se) = estimate(&scene, from, Vec3A::new(1.0, 0.5, 0.2), &s, 1 << 16);
            assert!(
                (mean - expected).abs() < 5.0 * se + 1e-4 * expected,
                "{strategy:?} {sampler:?} max_depth {max_depth:?}: {mean} ± {se}, expected {expected}"
            );
        }
    }
}

/// Under a constant environment of radiance `L` and nothing else, a
/// diffuse floor reflects `ρ L` by every strategy (BSDF sampling with no
/// variance at all).
#[test]
fn floor_under_a_constant_sky_reflects_its_albedo() {
    let rho = 0.7;
    let floor = Shape {
        geometry: rectangle(Affine3A::from_scale(Vec3::splat(50.0))),
        material: diffuse(rho),
        emission: None,
        motion: None,
    };
    let scene = Scene::new(
        vec![floor],
        Some(Environment::Constant([1.5; 3])),
        camera(),
        4,
        4,
    )
    .unwrap();
    // A plane sees nothing of itself: path tracing adds no bounce to it.
    for (integrator, strategy) in [Integrator::Direct, Integrator::Path]
        .into_iter()
        .flat_map(|i| [Strategy::Emitter, Strategy::Bsdf, Strategy::Mis].map(|s| (i, s)))
    {
        let s = settings(integrator, strategy);
        let (mean, se) = estimate(&scene, Vec3A::new(0.0, 0.3, 1.0), Vec3A::ZERO, &s, 1 << 16);
        assert!(
            (mean - rho * 1.5).abs() < 5.0 * se + 1e-5,
            "{integrator:?} {strategy:?}: {mean} ± {se}"
        );
        if strategy == Strategy::Bsdf {
            assert!(se < 1e-6, "{se}");
        }
    }
}

/// A sky of radiance 1 with a block of 50. MIS draws it by its
/// compensated density, never in the dim part (whose light BSDF sampling
/// brings, with MIS weight 1), emitter sampling alone by the complete one;
/// each draw's density is the one the MIS weights of escaping BSDF
/// samples read; and a floor under it gets the same light by both, with
/// either integrator and (MIS) every sampler, as by BSDF sampling (which
/// reads no density of the map).
#[test]
fn mis_draws_a_compensated_sky_and_stays_unbiased() {
    let data = dim_sky_with_block(2..7, 4..12);
    let map = EnvMap::new(16, 9, &data, Options::default()).unwrap();
    // The centre of texel (row 4, column 1): dim, and so are its neighbours.
    let dim_direction = map.uv_to_dir([1.5 / 16.0, 0.5]).map(|v| v as f32);
    let floor = Shape {
        geometry: rectangle(Affine3A::from_scale(Vec3::splat(50.0))),
        material: diffuse(0.7),
        emission: None,
        motion: None,
    };
    let sky = Environment::Map(Arc::new(map));
    let scene = Scene::new(vec![floor], Some(sky), camera(), 4, 4).unwrap();
    let mut rng = Rng::new(3, 0);
    let mut pdf = [0.0f32];
    for (strategy, dim_least, dim_most) in [(Strategy::Emitter, 20, 4096), (Strategy::Mis, 0, 0)] {
        let density = settings(Integrator::Direct, strategy).env_density();
        let dim = (0..4096)
            .filter(|_| {
                let light = scene.choose_light(0.5, density).unwrap();
                let u = [rng.next_float(), rng.next_float()];
                let bits = light.cells().map(|_| rng.next_u64());
                let ls = scene.sample_chosen(light, Vec3A::ZERO, u, bits).unwrap();
                scene.environment_pdf_into(&[ls.d.to_array()], &mut pdf, density);
                assert!(
                    (pdf[0] - ls.pdf).abs() <= 1e-4 * ls.pdf,
                    "{pdf:?} {}",
                    ls.pdf
                );
                ls.radiance[0] <= 1.0 + 1e-5
            })
            .count();
        assert!(
            (dim_least..=dim_most).contains(&dim),
            "{strategy:?}: {dim} dim draws"
        );
        scene.environment_pdf_into(&[dim_direction], &mut pdf, density);
        assert_eq!(
            pdf[0] == 0.0,
            strategy == Strategy::Mis,
            "{strategy:?}: {pdf:?}"
        );
    }
    // A BSDF sample escaping toward the dim part brings its light with MIS
    // weight 1 (the compensated density is 0 there), one toward the block
    // with less.
    let mis = settings(Integrator::Direct, Strategy::Mis);
    let block_direction = dim_direction.map(|v| -v);
    let mut escaped = integrator::Escaped::default();
    let mut l = [[0.0f32; 3]; 2];
    escaped.push(0, Vec3A::from(dim_direction), [1.0; 3], Some(0.3));
    escaped.push(1, Vec3A::from(block_direction), [1.0; 3], Some(0.3));
    integrator::add_escaped(&scene, &mis, &mut escaped, &mut l);
    assert_eq!(
        l[0][0],
        scene
            .environment()
            .unwrap()
            .eval(Vec3A::from(dim_direction))[0]
    );
    assert!(l[1][0] < 50.0 * 0.99, "{l:?}");
    let (from, to) = (Vec3A::new(0.0, 0.3, 1.0), Vec3A::ZERO);
    let bsdf = settings(Integrator::Direct, Strategy::Bsdf);
    let (reference, se_ref) = estimate(&scene, from, to, &bsdf, 1 << 18);
    let cases = [Integrator::Direct, Integrator::Path]
        .into_iter()
        .flat_map(|i| {
            let emitter = settings(i, Strategy::Emitter);
            let mis = Sampler::NAMES.iter().map(move |&(_, sampler)| Settings {
                sampler,
                ..settings(i, Strategy::Mis)
            });
            std::iter::once(emitter).chain(mis)
        });
    for s in cases {
        let (mean, se) = estimate(&scene, from, to, &s, 1 << 15);
        let bound = 5.0 * se.hypot(se_ref);
        assert!(
            (mean - reference).abs() < bound,
            "{:?} {:?} {:?}: {mean} ± {se}, BSDF sampling {reference} ± {se_ref}",
            s.integrator,
            s.strategy,
            s.sampler
        );
    }
}

/// A wall `z = 5` of four emitting quadrants (radiance 1, 2, 3, 4) facing
/// the camera at the origin, which looks along +z with a 40° field of view:
/// each 2 × 2 block of the 4 × 4 film sees one quadrant only, so each
/// pixel is exactly that quadrant's radiance (the film position of every
/// sample, from its pixel's own x and y, decides it).
#[test]
fn render_puts_each_sample_in_its_own_pixel() {
    let quadrant = |x: f32, y: f32, radiance: f64| {
        let m = Affine3A::from_translation(Vec3::new(x, y, 5.0))
            * Affine3A::from_quat(Quat::from_rotation_y(std::f32::consts::PI));
        light(rectangle(m), radiance)
    };
    let wall = vec![
        quadrant(-1.0, -1.0, 1.0),
        quadrant(1.0, -1.0, 2.0),
        quadrant(-1.0, 1.0, 3.0),
        quadrant(1.0, 1.0, 4.0),
    ];
    let scene = Scene::new(wall, None, camera(), 4, 4).unwrap();
    let s = settings(Integrator::Direct, Strategy::Mis);
    let image = render_all(&scene, 8, 3, &s);
    assert_eq!((image.width, image.height), (4, 4));
    let red = |row: usize, col: usize| image.mean[(row * 4 + col) * 3];
    let mut seen = Vec::new();
    for (block_row, block_col) in [(0, 0), (0, 2), (2, 0), (2, 2)] {
        let value = red(block_row, block_col);
        for (r, c) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            assert_eq!(
                red(block_row + r, block_col + c),
                value,
                "pixel ({}, {})",
                block_row + r,
                block_col + c
            );
        }
        seen.push(value);
    }
    seen.sort_by(f32::total_cmp);
    assert_eq!(seen, [1.0, 2.0, 3.0, 4.0]);
    assert!(image.variance.iter().all(|&v| v == 0.0));
}

/// Inside a glowing room every pixel is an independent estimate of
/// `L / (1 − ρ)`: the image's mean agrees with it, the variance each pixel
/// reports agrees with the spread of its mean over seeds (per channel and
/// in luminance), seeds give different images, and one sample per pixel
/// has no variance estimate (infinite).
#[test]
fn render_reports_the_variance_of_each_pixels_mean() {
    let (rho, l) = (0.5, 0.4);
    let scene = glowing_room(rho, l);
    let s = Settings {
        rr_depth: 2,
        ..settings(Integrator::Path, Strategy::Mis)
    };
    let seeds = 24;
    let images: Vec<_> = (0..seeds)
        .map(|seed| render_all(&scene, 16, seed, &s))
        .collect();
    assert_ne!(
        images[0].mean, images[1].mean,
        "seeds must give different images"
    );
    let pixels = 16;
    let mean_of = |f: &dyn Fn(&super::Image, usize) -> f64, p: usize| {
        images.iter().map(|im| f(im, p)).sum::<f64>() / seeds as f64
    };
    let red = |im: &super::Image, p: usize| f64::from(im.mean[p * 3]);
    let lum = |im: &super::Image, p: usize| {
        let c = &im.mean[p * 3..p * 3 + 3];
        0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2])
    };
    for (name, value, reported) in [
        (
            "red",
            &red as &dyn Fn(&super::Image, usize) -> f64,
            &(|im: &super::Image, p: usize| f64::from(im.variance[p * 3]))
                as &dyn Fn(&super::Image, usize) -> f64,
        ),
        ("luminance", &lum, &|im: &super::Image, p: usize| {
            f64::from(im.luminance_variance[p])
        }),
    ] {
        let (mut spread, mut said, mut total) = (0.0, 0.0, 0.0);
        for p in 0..pixels {
            let m = mean_of(value, p);
            spread += images
                .iter()
                .map(|im| (value(im, p) - m).powi(2))
                .sum::<f64>()
                / (seeds - 1) as f64;
            said += mean_of(reported, p);
            total += m;
        }
        let ratio = spread / said;
        assert!(
            (0.6..1.6).contains(&ratio),
            "{name}: spread {spread} against reported {said}"
        );
        // Each pixel-and-seed mean has variance said / pixels; the grand mean averages them all.
        let se = (said / pixels as f64 / (pixels * seeds as usize) as f64).sqrt();
        let expected = l / (1.0 - rho);
        assert!(
            (total / pixels as f64 - expected).abs() < 5.0 * se,
            "{name}: {total} ± {se}"
        );
    }
    let one = render_all(&scene, 1, 0, &s);
    assert!(
        one.variance
            .iter()
            .chain(&one.luminance_variance)
            .all(|v| v.is_infinite())
    );
}

/// A pixel's moments in closed form: the sample mean, and the unbiased
/// sample variance divided by the count (the variance of the mean), per
/// channel and of the Rec. 709 luminance.
#[test]
fn pixel_moments_are_the_mean_and_the_variance_of_the_mean() {
    let samples: [[f32; 3]; 4] = [
        [1.0, 2.0, 3.0],
        [3.0, 2.0, 1.0],
        [2.0, 5.0, 0.0],
        [6.0, 3.0, 0.0],
    ];
    let sums = samples.iter().map(|l| super::film::sums_of(*l));
    let total = sums.reduce(|a, b| super::film::add(&a, &b)).unwrap();
    let m = super::film::moments(&total, 4);
    assert_eq!(m.mean, [3.0, 3.0, 1.0]);
    // Squared deviations 14, 6 and 6 over n − 1 = 3, over n = 4.
    let expected = [14.0 / 12.0, 0.5, 0.5];
    for (&v, e) in m.variance.iter().zip(expected) {
        assert!((f64::from(v) - e).abs() < 1e-6, "{:?}", m.variance);
    }
    let y: Vec<f64> = samples
        .iter()
        .map(|s| 0.2126 * f64::from(s[0]) + 0.7152 * f64::from(s[1]) + 0.0722 * f64::from(s[2]))
        .collect();
    let mean = y.iter().sum::<f64>() / 4.0;
    let var = y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 3.0 / 4.0;
    assert!((f64::from(m.luminance_variance) - var).abs() < 1e-5 * var);
}

/// A face that names a vertex the mesh does not have (past the end, or
/// negative) is refused by index, before anything reads it.
#[test]
fn mesh_faces_must_index_its_vertices() {
    let v = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert!(Mesh::new(&v, &[[0, 1, 2]], None, true).is_ok());
    for bad in [[0, 1, 3], [0, -1, 2]] {
        let result = Mesh::new(&v, &[bad], None, true);
        assert!(
            matches!(result, Err(crate::error::Error::Index { .. })),
            "{bad:?}"
        );
    }
}

/// All `spp` samples of `scene` (nothing watching).
fn render_all(scene: &Scene, spp: u32, seed: u64, s: &Settings) -> super::Image {
    super::render(
        scene,
        super::Samples::all(spp),
        seed,
        s,
        &super::Progress::default(),
    )
    .unwrap()
}

/// Each camera sample gets its own stream's film, lens and time numbers
/// (drawn for the whole batch beforehand), with a lens and a moving shape
/// so that all three are drawn; under the independent sampler, its path
/// goes on with the generator these draws left.
#[test]
fn camera_samples_draw_their_own_numbers() {
    use super::{Batch, Samples, mix, start_sample};
    use crate::render::integrator::dims;
    use crate::render::motion::Motion;
    use glam::DAffine3;
    let cam = Camera::new(
        Affine3A::IDENTITY,
        40.0,
        FovAxis::X,
        4,
        4,
        0.01,
        100.0,
        0.1,
        3.0,
    )
    .unwrap();
    let moved = DAffine3::from_translation(DVec3::new(0.0, 0.0, -1.0));
    let moving = Shape {
        geometry: cube(Affine3A::from_translation(Vec3::new(0.0, 0.0, -5.0))),
        material: diffuse(0.5),
        emission: None,
        motion: Some(Motion::new("to_world", DAffine3::IDENTITY, moved).unwrap()),
    };
    let scene = Scene::new(vec![moving], None, cam, 4, 4).unwrap();
    // Three pixels of 5 samples; two of more than half a batch each, in
    // more than one group.
    let many = super::BATCH as u32 / 2 + 88;
    let cases = [(5, 11, 3, 1..4), (many, 2 * u64::from(many), 7, 2..4)];
    for &(_, sampler) in Sampler::NAMES {
        for (count, total, first, pixels) in cases.clone() {
            let settings = Settings {
                sampler,
                ..settings(Integrator::Direct, Strategy::Mis)
            };
            let samples = Samples {
                first,
                count,
                total,
                keep_sums: false,
            };
            let (seed, y) = (7, 2);
            let mut batch = Batch::default();
            (batch.run(&scene, &settings, seed, samples, y, pixels.clone())).unwrap();
            let each = batch.camera_u.iter().zip(&batch.times).enumerate();
            for (j, (u, &time)) in each {
                let x = pixels.start + j / count as usize;
                let pixel = (y * 4 + x) as u64;
                let key = mix(seed, pixel);
                let zorder = ZOrder::new((x, y), (4, 4), total, seed);
                let mut s = Stream::new(sampler, key, Rng::new(key, pixel), total, zorder);
                start_sample(&mut s, key, pixel, first + (j % count as usize) as u64);
                let film = s.get2::<f32>(dims::FILM);
                assert_eq!(u[2..], s.get2::<f32>(dims::LENS), "{sampler:?} {j}");
                assert_eq!(time, s.get1::<f32>(dims::TIME), "{sampler:?} {j}");
                assert_eq!(
                    batch.resume.get(j),
                    s.independent().as_deref(),
                    "{sampler:?} {j}"
                );
                let on_film = [u[0] * 4.0 - x as f32, u[1] * 4.0 - y as f32];
                assert!((on_film[0] - film[0]).abs() < 1e-5, "{sampler:?} {j}");
                assert!((on_film[1] - film[1]).abs() < 1e-5, "{sampler:?} {j}");
            }
            assert_eq!(batch.times.len(), pixels.len() * count as usize);
        }
    }
}

/// Spheres shade in their azimuthal frame under the stratified samplers,
/// in the frame of the normal alone under the independent one; other
/// shapes always in the latter ([`integrator::shading`]).
#[test]
fn spheres_shade_in_their_azimuthal_frame_under_stratified_samplers() {
    use crate::frame::Frame;
    use crate::render::shape::Sphere;
    let ball = Shape {
        geometry: Geometry::Sphere(Sphere {
            center: DVec3::new(0.0, 0.0, 3.0),
            radius: 1.0,
            flip: false,
        }),
        material: diffuse(0.5),
        emission: None,
        motion: None,
    };
    let scene = floor_scene(0.5, vec![ball]);
    let ns = Vec3A::new(0.6, 0.0, 0.8);
    let from = Vec3A::new(0.0, 0.6, 0.8);
    for (shape, sampler, want) in [
        (1, Sampler::Sobol, Frame::azimuthal(ns.to_array())),
        (1, Sampler::MultiJitter, Frame::azimuthal(ns.to_array())),
        (1, Sampler::Independent, Frame::from_normal(ns.to_array())),
        (0, Sampler::Sobol, Frame::from_normal(ns.to_array())),
    ] {
        let (frame, _) = integrator::shading(&scene, shape, ns, from, sampler);
        assert_eq!(frame, want, "shape {shape}, {sampler:?}");
    }
}

/// [`Scene::hits_emitter`] (how a path's last vertex skips its surface
/// point) tells an area light as the hit's surface does, on still and
/// moving shapes alike.
#[test]
fn hits_emitter_agrees_with_the_surface_shape() {
    use crate::render::motion::Motion;
    use glam::DAffine3;
    let at = |x: f32| Affine3A::from_translation(Vec3::new(x, 0.0, -6.0));
    let moved = DAffine3::from_translation(DVec3::new(0.0, 1.0, 0.0));
    let shape = |x: f32, emission: Option<[f64; 3]>, moves: bool| Shape {
        geometry: cube(at(x)),
        material: diffuse(0.5),
        emission,
        motion: moves.then(|| Motion::new("to_world", DAffine3::IDENTITY, moved).unwrap()),
    };
    let shapes = vec![
        shape(-3.0, None, false),
        shape(0.0, None, true),
        shape(3.0, Some([2.0; 3]), false),
        shape(6.0, Some([1.0; 3]), false),
    ];
    let scene = Scene::new(shapes, None, camera(), 4, 4).unwrap();
    let mut seen = [false; 4];
    for i in 0..400 {
        let x = -0.7 + 1.4 * (i % 20) as f32 / 19.0;
        let y = -0.25 + 0.5 * (i / 20) as f32 / 19.0;
        let ray = Ray {
            o: Vec3A::ZERO,
            d: Vec3A::new(x, y, -0.6).normalize(),
            tmax: f32::INFINITY,
        };
        let tau = (i % 7) as f32 / 6.0;
        let Some(hit) = scene.intersect(&ray, tau) else {
            continue;
        };
        let (shape, _) = scene.surface(&ray, &hit, tau);
        assert_eq!(scene.hits_emitter(&hit), scene.is_emitter(shape), "ray {i}");
        seen[shape as usize] = true;
    }
    assert_eq!(seen, [true; 4], "every shape hit");
}

#[test]
fn a_row_s_samples_counted_along_are_its_quotients_and_remainders() {
    for spp in [1, 3, 16] {
        let mut sample = (0, 0);
        for j in 0..100 {
            assert_eq!(sample, (j / spp, j % spp), "spp {spp}, sample {j}");
            sample = super::next_sample(sample, spp);
        }
    }
}

/// The seeds of a batch's samples, pixel run by pixel run, are those of
/// each sample alone: batches that start inside a pixel, end inside
/// another, or hold one sample per pixel.
#[test]
fn sample_seeds_are_each_samples_seed() {
    let keys: Vec<(u64, u64)> = (0..6).map(|p| (100 + p, super::mix(7, p))).collect();
    for (start, count, spp) in [
        ((0, 0), 24, 4),
        ((1, 3), 9, 5),
        ((2, 0), 3, 1),
        ((0, 7), 1, 8),
    ] {
        let mut seeds = Vec::new();
        super::sample_seeds(&keys, start, (count, spp), 40, &mut seeds);
        let mut want = Vec::new();
        let mut at = start;
        for _ in 0..count {
            let (pixel, key) = keys[at.0];
            want.push(super::sample_seed(key, pixel, 40 + at.1 as u64));
            at = super::next_sample(at, spp);
        }
        assert_eq!(seeds, want, "start {start:?}, {count} samples, spp {spp}");
    }
}

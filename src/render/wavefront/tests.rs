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
use shade::{Begun, KernelRows};

/// A diffuse floor, a glossy box on it (so that a bounce's rows go to
/// both of the BSDF kernels' groups, [`shade::KernelRows`]), a spherical light
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

/// The BSDF kernels' rows come back to their own paths, in order, from
/// the two groups mixed, and the kernel without the lobe gives the
/// general kernel's bits for every BRDF without a glossy part (exponents
/// 0 and the largest, both selections, `ρs = −0`, a black one; directions
/// above and below the surface; the largest `part` below 1; frames of the
/// normal and of the azimuth, about normals at and near the poles; rows
/// without a light sample), in each of the three forms a bounce runs.
#[test]
fn kernel_rows_give_each_path_the_general_kernel_s_bits() {
    use crate::phong::MAX_EXPONENT;
    use crate::warp::square_to_uniform_sphere;
    use shade::{BSDF_IN, bsdf_row};
    let phong = |d, s, n, selection| Phong::new(d, s, n, selection).unwrap();
    let brdfs = [
        phong([0.6; 3], [0.0; 3], 0.0, Selection::Max),
        phong([0.5, 0.4, 0.3], [0.3, 0.2, 0.1], 20.0, Selection::Max),
        phong(
            [0.2, 0.7, 0.1],
            [0.0; 3],
            MAX_EXPONENT,
            Selection::Luminance,
        ),
        phong([0.5; 3], [-0.0; 3], 5.0, Selection::Max),
        phong([0.1; 3], [0.8; 3], 1000.0, Selection::Luminance),
        phong([0.0; 3], [0.0; 3], 1.0, Selection::Max),
        phong([0.3; 3], [0.0; 3], 1.0, Selection::Max),
    ];
    let mut rng = Rng::new(5, 9);
    let mut direction = || square_to_uniform_sphere::<f32>([rng.next_float(), rng.next_float()]);
    let poles = [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1e-7, 0.0, 1.0]];
    // Rows for 300 paths, of the BRDFs in turn (diffuse and glossy
    // interleaved), every 7th with the largest part below 1, every 11th
    // without a light sample, every 13th about a pole.
    let paths: Vec<(Begun, [f32; BSDF_IN])> = (0..300)
        .map(|k| {
            let bsdf = &brdfs[k % brdfs.len()];
            let n = if k % 13 == 5 {
                poles[k % 3]
            } else {
                direction()
            };
            let (wi, wl) = (direction(), direction());
            let [u0, u1, part] = direction().map(|v| 0.5 * (v + 1.0));
            let part = if k % 7 == 3 {
                1.0 - f32::EPSILON / 2.0
            } else {
                part.min(0.99)
            };
            let light = (k % 11 != 4).then_some((wl, 0.1 + u0, [u1, 2.0 * u0, 0.5]));
            let row = bsdf_row(
                ((n, k % 2 == 0), wi),
                light,
                ([u0, u1], part),
                &bsdf.view_terms(),
            );
            let begun = Begun {
                k: k as u32,
                row: 0,
                ends: false,
                diffuse: !bsdf.is_glossy(),
                to_point: false,
            };
            (begun, row)
        })
        .collect();
    let (begun, rows): (Vec<Begun>, Vec<_>) = paths.iter().copied().unzip();
    assert!(begun.iter().any(|b| b.diffuse) && begun.iter().any(|b| !b.diffuse));
    // (light, sample): MIS with a next bounce, emitter sampling at the
    // last (no BSDF sample), BSDF sampling (no light sample).
    let power = Some(crate::mis::Heuristic::Power);
    let forms = [
        (Strategy::Mis, general_kernel::<true, true>(&rows, power)),
        (
            Strategy::Emitter,
            general_kernel::<true, false>(&rows, None),
        ),
        (Strategy::Bsdf, general_kernel::<false, true>(&rows, None)),
    ];
    for (strategy, expected) in forms {
        let s = settings(Integrator::Direct, strategy);
        let mut kernel_rows = KernelRows::default();
        kernel_rows.reserve(rows.len(), "rows").unwrap();
        for (b, row) in &paths {
            kernel_rows.push(b.diffuse, *row);
        }
        kernel_rows.run(&s, 0);
        let out: Vec<_> = kernel_rows.out(&begun).collect();
        assert_eq!(out.len(), rows.len(), "{strategy:?}");
        for (k, ((b, (row_in, row)), want)) in out.iter().zip(&expected).enumerate() {
            assert_eq!(b.k, k as u32, "{strategy:?}");
            assert_eq!(row_in.map(f32::to_bits), rows[k].map(f32::to_bits));
            // A row without a light sample is never connected.
            if rows[k][10] == 0.0 {
                assert_eq!(row[4], 0.0, "{strategy:?} {k}");
            }
            assert_eq!(
                row.map(f32::to_bits),
                want.map(f32::to_bits),
                "{strategy:?} {k}"
            );
        }
        // Not all zeros: the light's part and the sample's are there.
        assert!(expected.iter().filter(|o| o[3] > 0.0 || o[8] > 0.0).count() > 100);
    }
}

/// [`shade::bsdf_kernel`] of every row (the general kernel), in order,
/// with the MIS heuristic `mis`.
fn general_kernel<const LIGHT: bool, const SAMPLE: bool>(
    rows: &[[f32; shade::BSDF_IN]],
    mis: Option<crate::mis::Heuristic>,
) -> Vec<[f32; shade::BSDF_OUT]> {
    let kernel = {
        #[inline(always)]
        |row| shade::bsdf_kernel::<LIGHT, SAMPLE, true>(row, mis)
    };
    let mut out = vec![[0.0; shade::BSDF_OUT]; rows.len()];
    crate::simd::map_rows(&mut out, rows, &kernel, |_| true, false);
    out
}

/// The kernel, at SIMD width, gives the bits one path at a time gets from
/// its shading frame (of the normal, or of the azimuth, also at and near
/// the poles), the BRDF's view, evaluation and sample in that frame, the
/// power heuristic's weight and the direction taken back to world space
/// and normalised, `v / √((x² + y²) + z²)`.
#[test]
fn the_kernel_gives_each_path_s_frame_light_and_direction() {
    use crate::frame::Frame;
    use crate::mis::Heuristic;
    use crate::warp::square_to_uniform_sphere;
    use shade::bsdf_row;
    let bsdf = Phong::new([0.5, 0.4, 0.3], [0.3, 0.2, 0.1], 20.0, Selection::Max).unwrap();
    let mut rng = Rng::new(8, 3);
    let mut next = || rng.next_float();
    let poles = [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 1e-7, -1.0]];
    let mut checked = [0; 2];
    for k in 0..200 {
        let mut direction = || square_to_uniform_sphere::<f32>([next(), next()]);
        let n = if k % 10 == 0 {
            poles[k % 3]
        } else {
            direction()
        };
        let (wi, wl) = (direction(), direction());
        let azimuthal = k % 2 == 1;
        let u = [next(), next(), next()];
        let (pdf_l, radiance) = (0.2 + u[0], [1.0, u[1], 3.0]);
        let row = bsdf_row(
            ((n, azimuthal), wi),
            Some((wl, pdf_l, radiance)),
            ([u[0], u[1]], u[2]),
            &bsdf.view_terms(),
        );
        let out = general_kernel::<true, true>(&[row], Some(Heuristic::Power))[0];
        let frame = if azimuthal {
            Frame::azimuthal(n)
        } else {
            Frame::from_normal(n)
        };
        let view = bsdf.view(frame.to_local(wi));
        let local = frame.to_local(wl);
        let (f, pdf) = view.eval_pdf(local);
        let w = Heuristic::Power.weight(pdf_l, pdf);
        let s = view.sample(u);
        // (`Vec3A::normalize`'s bits on x86-64.)
        let [x, y, z] = frame.to_world(s.wo);
        let length = (x * x + y * y + z * z).sqrt();
        let d = Vec3A::new(x / length, y / length, z / length);
        let lit = if f.iter().any(|&v| v > 0.0) { 1.0 } else { 0.0 };
        let want = [
            f[0] * radiance[0],
            f[1] * radiance[1],
            f[2] * radiance[2],
            w * local[2].abs() / pdf_l,
            lit,
            d.x,
            d.y,
            d.z,
            s.pdf,
            s.weight[0],
            s.weight[1],
            s.weight[2],
        ];
        assert_eq!(out.map(f32::to_bits), want.map(f32::to_bits), "{k}");
        checked[usize::from(lit > 0.0)] += 1;
    }
    assert!(checked.iter().all(|&c| c > 30), "{checked:?}");
    // A light direction of density 0 (no light sample) is never connected,
    // though the BRDF toward it is not zero.
    let up = [0.0, 0.0, 1.0];
    for pdf_l in [0.0, 1.0] {
        let row = bsdf_row(
            ((up, false), up),
            Some((up, pdf_l, [1.0; 3])),
            ([0.5, 0.5], 0.5),
            &bsdf.view_terms(),
        );
        let out = general_kernel::<true, true>(&[row], Some(Heuristic::Power))[0];
        assert_eq!(out[4], pdf_l, "{out:?}");
    }
}

/// A light sample written into a row after the row was pushed (as the
/// environment map's samples, drawn after the pass that builds the rows)
/// gives the kernel the numbers of a row built with it, in either group.
#[test]
fn a_light_sample_written_later_is_the_row_s_own() {
    use crate::render::scene::LightSample;
    use shade::bsdf_row;
    let ls = LightSample {
        d: Vec3A::new(0.6, 0.0, 0.8),
        dist: f32::INFINITY,
        pdf: 0.7,
        radiance: [1.0, 2.0, 3.0],
        point: None,
    };
    let brdfs = [
        Phong::new([0.6; 3], [0.0; 3], 0.0, Selection::Max).unwrap(),
        Phong::new([0.3; 3], [0.5; 3], 30.0, Selection::Max).unwrap(),
    ];
    let settings = settings(Integrator::Direct, Strategy::Mis);
    for bsdf in &brdfs {
        let row = |light| {
            let normal = ([0.0, 0.6, 0.8], false);
            bsdf_row(
                (normal, [0.0, 0.0, 1.0]),
                light,
                ([0.3, 0.6], 0.4),
                &bsdf.view_terms(),
            )
        };
        let diffuse = !bsdf.is_glossy();
        let (mut later, mut first) = (KernelRows::default(), KernelRows::default());
        later.reserve(1, "rows").unwrap();
        first.reserve(1, "rows").unwrap();
        let begun = Begun {
            k: 0,
            row: later.push(diffuse, row(None)),
            ends: false,
            diffuse,
            to_point: false,
        };
        later.set_light(&begun, &ls);
        first.push(diffuse, row(Some((ls.d.to_array(), ls.pdf, ls.radiance))));
        later.run(&settings, 0);
        first.run(&settings, 0);
        let begun = [begun];
        let (Some((_, (_, a))), Some((_, (_, b)))) =
            (later.out(&begun).next(), first.out(&begun).next())
        else {
            panic!("no row out");
        };
        assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits));
        assert!(a[3] > 0.0, "{a:?}");
    }
}

//! The BVH against the leaf test and Embree against obvhs: the same hits,
//! one ray at a time and in streams.

use super::*;
use crate::render::geometry::Geometry;
use crate::render::mesh::Mesh;
use glam::DVec3;

/// A row of spheres along −z, fewer than [`LEAF_MAX`] (tested directly)
/// and many more (through the BVH).
#[test]
fn nearest_sphere_and_occlusion_with_and_without_a_bvh() {
    for count in [3, LEAF_MAX, 100] {
        // Listed far to near, so that the nearest is not the first tested.
        let prims: Vec<Primitive> = (0..count as u32)
            .rev()
            .map(|i| {
                Primitive::Sphere(Box::new(Sphere {
                    center: DVec3::new(0.0, 0.0, -3.0 * (f64::from(i) + 1.0)),
                    radius: 1.0,
                    flip: false,
                }))
            })
            .collect();
        let accel = Accel::new(prims, (0..count as u32).rev().collect(), Vec::new()).unwrap();
        assert_eq!(accel.bvh.is_some(), count > LEAF_MAX);
        let ray = Ray {
            o: Vec3A::ZERO,
            d: Vec3A::NEG_Z,
            tmax: f32::INFINITY,
        };
        let hit = accel.intersect(&ray).unwrap();
        assert_eq!(accel.shape_of(hit.primitive), 0);
        assert!((hit.t - 2.0).abs() < 1e-5);
        assert!(accel.occluded(&ray));
        assert!(!accel.occluded(&Ray { tmax: 1.5, ..ray }));
        assert!(accel.intersect(&Ray { tmax: 1.5, ..ray }).is_none());
        let up = Ray { d: Vec3A::Y, ..ray };
        assert!(accel.intersect(&up).is_none());
        let (lo, hi) = accel.bounds().unwrap();
        assert!((lo.z + 3.0 * count as f32 + 1.0).abs() < 1e-4 && (hi.z + 2.0).abs() < 1e-4);
    }
}

/// Embree and obvhs find the same hits on a cloud of 2,000 random
/// triangles in two meshes (with a sphere and a mesh of no faces between
/// them), 5,000 rays from random points, and the same occlusion. Where
/// Embree cannot be loaded only obvhs runs, except under CI, which
/// installs it.
#[test]
fn embree_and_obvhs_agree() {
    let mut rng = crate::rng::Rng::new(7, 11);
    let mut u = || rng.next_float::<f32>();
    let mut point = |scale: f32| Vec3A::new(u() - 0.5, u() - 0.5, u() - 0.5) * scale;
    let mut cloud = |n: usize| {
        let v: Vec<[f64; 3]> = (0..n)
            .flat_map(|_| {
                let (p0, e1, e2) = (point(4.0), point(0.6), point(0.6));
                [p0, p0 + e1, p0 + e2].map(|p| p.as_dvec3().to_array())
            })
            .collect();
        let f: Vec<[i64; 3]> = (0..n as i64)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        Geometry::Mesh(Mesh::new(&v, &f, None, true).unwrap())
    };
    let sphere = Geometry::sphere([0.3, -0.2, 0.1], 0.5, false).unwrap();
    let empty = Geometry::Mesh(Mesh::new(&[], &[], None, true).unwrap());
    let (mut prims, mut shapes, mut meshes) = (Vec::new(), Vec::new(), Vec::new());
    for (id, g) in [cloud(1200), sphere, empty, cloud(800)]
        .into_iter()
        .enumerate()
    {
        prims.extend(g.into_primitives(&mut meshes));
        shapes.resize(prims.len(), id as u32);
    }
    assert_eq!((prims.len(), meshes.len()), (2001, 3));
    let rays: Vec<Ray> = (0..5000)
        .map(|i| Ray {
            o: point(6.0),
            d: point(1.0),
            tmax: if i % 2 == 0 { f32::INFINITY } else { 3.0 },
        })
        .collect();
    let embree = Accel::new(prims.clone(), shapes.clone(), meshes.clone()).unwrap();
    let obvhs = Accel::build(prims, shapes, meshes, false).unwrap();
    assert_eq!(obvhs.ray_tracer(), "obvhs");
    if std::env::var_os("CI").is_some() || embree::wanted().unwrap().is_some() {
        assert!(embree.ray_tracer().starts_with("embree"));
    }
    let (mut hits, mut occluded, mut on_each) = (0, 0, [0; 3]);
    for ray in &rays {
        let (a, b) = (embree.intersect(ray), obvhs.intersect(ray));
        assert_eq!(a.is_some(), b.is_some(), "{ray:?}");
        if let (Some(a), Some(b)) = (a, b) {
            assert_eq!(a.primitive, b.primitive, "{ray:?}");
            on_each[obvhs.shape_of(b.primitive).min(2) as usize] += 1;
            assert!((a.t - b.t).abs() <= 1e-5 * (1.0 + a.t), "{} {}", a.t, b.t);
            for k in 0..2 {
                assert!(
                    (a.bary[k] - b.bary[k]).abs() < 1e-4,
                    "{:?} {:?}",
                    a.bary,
                    b.bary
                );
            }
            hits += 1;
        }
        // The shadow rays' test finds a hit where the nearest-hit test
        // does (the renderer asks it whether a ray leaves the scene).
        assert_eq!(embree.occluded(ray), a.is_some(), "{ray:?}");
        assert_eq!(obvhs.occluded(ray), b.is_some(), "{ray:?}");
        occluded += usize::from(obvhs.occluded(ray));
    }
    assert!(hits > 1000 && occluded == hits, "{hits} {occluded}");
    // Each mesh and the sphere were hit (the second mesh's faces numbered
    // after the sphere).
    assert!(on_each.iter().all(|&n| n > 20), "{on_each:?}");
    // The streams find what one ray at a time finds, bit for bit.
    let bits = |h: &Option<Hit>| h.map(|h| (h.primitive, h.t.to_bits(), h.bary.map(f32::to_bits)));
    for (accel, coherent) in [&embree, &obvhs].into_iter().zip([true, false]) {
        let mut stream = Default::default();
        let (mut many, mut blocked) = (vec![None], vec![true]);
        accel
            .intersect_many(&rays, coherent, &mut stream, &mut many)
            .unwrap();
        accel
            .occluded_many(&rays, &mut stream, &mut blocked)
            .unwrap();
        let one: Vec<_> = rays.iter().map(|r| accel.intersect(r)).collect();
        assert!(many[0].is_none() && many.len() == rays.len() + 1);
        assert!(many[1..].iter().map(bits).eq(one.iter().map(bits)));
        assert!(blocked[0] && blocked.len() == rays.len() + 1);
        assert!(
            blocked[1..]
                .iter()
                .copied()
                .eq(rays.iter().map(|r| accel.occluded(r)))
        );
    }
    // Embree's incoherent stream too.
    let (mut stream, mut many) = (Default::default(), Vec::new());
    embree
        .intersect_many(&rays, false, &mut stream, &mut many)
        .unwrap();
    assert!(
        many.iter()
            .map(bits)
            .eq(rays.iter().map(|r| embree.intersect(r)).map(|h| bits(&h)))
    );
}

/// Scenes small enough for one leaf (triangles in numbers that fill a
/// pack or not, with spheres and disks, among them a sphere around the
/// rays' origins, primitives that cross, and ties: a face listed twice, in
/// one pack or across two, and a sphere listed twice): the batch tests, a
/// block of rays at SIMD width, find what one ray at a time finds, bit for
/// bit, for batches of every length around the block's, with degenerate
/// rays among them, without a hit so far and after another tracer's (kept
/// when nearer or as near, replaced when farther).
#[test]
fn leaf_batches_are_single_rays_bit_for_bit() {
    let mut rng = crate::rng::Rng::new(3, 5);
    let mut u = || rng.next_float::<f32>();
    let mut point = |scale: f32| Vec3A::new(u() - 0.5, u() - 0.5, u() - 0.5) * scale;
    // (faces, spheres, disks); one more face repeats the first.
    for (faces, spheres, disks) in [(1, 1, 0), (3, 3, 1), (4, 1, 2), (7, 0, 0), (0, 2, 1)] {
        let (mut prims, mut shapes, mut meshes) = (Vec::new(), Vec::new(), Vec::new());
        let mut add = |g: Geometry, meshes: &mut Vec<Mesh>| {
            prims.extend(g.into_primitives(meshes));
            shapes.resize(prims.len(), shapes.len() as u32);
        };
        if faces > 0 {
            let v: Vec<[f64; 3]> = (0..3 * faces)
                .map(|_| point(6.0).as_dvec3().to_array())
                .collect();
            let f: Vec<[i64; 3]> = (0..faces as i64)
                .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                .chain([[0, 1, 2]])
                .collect();
            add(
                Geometry::Mesh(Mesh::new(&v, &f, None, true).unwrap()),
                &mut meshes,
            );
        }
        let around = point(2.0).as_dvec3().to_array();
        for k in 0..spheres {
            // The first around the origins, the second the same again.
            let (c, radius) = if k < 2 {
                (around, 2.5)
            } else {
                (point(2.0).as_dvec3().to_array(), 0.4)
            };
            add(Geometry::sphere(c, radius, false).unwrap(), &mut meshes);
        }
        for _ in 0..disks {
            let (a, b, c) = (point(2.0), point(2.0), point(2.0));
            let m = [
                [a.x, b.x, 0.3, c.x],
                [a.y, b.y, 0.1, c.y],
                [a.z, b.z, -0.2, c.z],
                [0.0, 0.0, 0.0, 1.0],
            ]
            .map(|r| r.map(f64::from));
            add(Geometry::disk(m).unwrap(), &mut meshes);
        }
        let accel = Accel::build(prims, shapes, meshes, false).unwrap();
        assert!(accel.bvh.is_none());
        let mut rays: Vec<Ray> = (0..296)
            .map(|i| Ray {
                o: point(4.0),
                d: point(1.0),
                tmax: [f32::INFINITY, 2.0, 0.5][i % 3],
            })
            .collect();
        let ray = rays[0];
        rays.splice(
            100..100,
            [
                Ray {
                    o: Vec3A::splat(f32::NAN),
                    ..ray
                },
                Ray {
                    d: Vec3A::ZERO,
                    ..ray
                },
                Ray { tmax: 0.0, ..ray },
                Ray { tmax: -1.0, ..ray },
            ],
        );
        let bits =
            |h: &Option<Hit>| h.map(|h| (h.primitive, h.t.to_bits(), h.bary.map(f32::to_bits)));
        let (mut on_kind, mut replaced) = ([0; 3], 0);
        for n in [0, 1, 63, 64, 65, 129, 300] {
            let rays = &rays[..n];
            let (many, blocked) = streamed(&accel, rays);
            let one: Vec<_> = rays.iter().map(|r| accel.intersect(r)).collect();
            assert!(many.iter().map(bits).eq(one.iter().map(bits)));
            assert!(
                blocked
                    .iter()
                    .copied()
                    .eq(rays.iter().map(|r| accel.occluded(r)))
            );
            assert!(blocked.iter().copied().eq(one.iter().map(Option::is_some)));
            for h in one.iter().flatten() {
                on_kind[match accel.primitives()[h.primitive as usize] {
                    Primitive::Triangle { .. } => 0,
                    Primitive::Sphere(_) => 1,
                    Primitive::Disk(_) => 2,
                }] += 1;
            }
            // After another tracer's hits (a made-up primitive 99), on every
            // other ray: nearer than the leaf's, as near, or farther (at 1
            // where the leaf has none).
            let theirs: Vec<Option<Hit>> = one
                .iter()
                .enumerate()
                .map(|(i, h)| {
                    (i % 2 == 0).then_some(Hit {
                        t: h.map_or(1.0, |h| [0.5, 1.0, 2.0][(i / 2) % 3] * h.t),
                        primitive: 99,
                        bary: [0.25, 0.5],
                    })
                })
                .collect();
            let mut hits = theirs.clone();
            accel.leaf.intersect_many(rays, &mut hits);
            for ((ray, theirs), hits) in rays.iter().zip(&theirs).zip(&hits) {
                let shrunk = Ray {
                    tmax: theirs.map_or(ray.tmax, |h| h.t),
                    ..*ray
                };
                assert_eq!(bits(hits), bits(&accel.leaf.intersect(&shrunk).or(*theirs)));
                replaced += usize::from(theirs.is_some() && hits.unwrap().primitive != 99);
            }
            // Without hits so far, over whatever the slots held.
            let mut fresh = theirs.clone();
            accel.leaf.intersect_fresh(rays, &mut fresh);
            assert!(fresh.iter().map(bits).eq(one.iter().map(bits)));
            let mut blocked: Vec<bool> = (0..n).map(|i| i % 5 == 0).collect();
            accel.leaf.occluded_many(rays, &mut blocked);
            for (i, (ray, b)) in rays.iter().zip(&blocked).enumerate() {
                assert_eq!(*b, i % 5 == 0 || accel.occluded(ray));
            }
        }
        // Every kind of primitive there was hit, and some of the other
        // tracer's hits were replaced.
        let present = [faces > 0, spheres > 0, disks > 0];
        for (count, present) in on_kind.iter().zip(present) {
            assert_eq!(*count > 0, present, "{on_kind:?}");
        }
        assert!(replaced > 10, "{replaced}");
    }
}

/// The nearest hits of `rays` and whether each is blocked, as streams
/// (incoherent).
fn streamed(accel: &Accel, rays: &[Ray]) -> (Vec<Option<Hit>>, Vec<bool>) {
    let (mut hits, mut blocked) = (Vec::new(), Vec::new());
    let mut stream = Default::default();
    accel
        .intersect_many(rays, false, &mut stream, &mut hits)
        .unwrap();
    accel
        .occluded_many(rays, &mut stream, &mut blocked)
        .unwrap();
    (hits, blocked)
}

/// The batch tests skip a sphere for a block of rays none of whose lines
/// meet it: a small sphere that one ray of a block meets (its last, one in
/// its second half, one that only grazes it, or one of a short block's) is
/// still found, by `intersect_many` and `occluded_many` alike, and the
/// other rays of those blocks pass it.
#[test]
fn a_sphere_met_by_one_ray_of_a_block_is_still_tested() {
    let small = Sphere {
        center: DVec3::new(0.0, 10.0, 0.0),
        radius: 0.5,
        flip: false,
    };
    let far = Sphere {
        center: DVec3::new(0.0, 0.0, -50.0),
        ..small
    };
    let prims = [small, far].map(|s| Primitive::Sphere(Box::new(s)));
    let accel = Accel::new(prims.into(), vec![0, 1], Vec::new()).unwrap();
    assert!(accel.bvh.is_none());
    // The grazing ray's discriminant is 0 exactly: it touches the sphere.
    let (toward, grazing) = ([63, 64 + 40, 192 + 7], 128 + 20);
    let rays: Vec<Ray> = (0..200)
        .map(|i| Ray {
            o: if i == grazing {
                Vec3A::new(0.5, 0.0, 0.0)
            } else {
                Vec3A::new(0.0, 0.0, i as f32 * 1e-3)
            },
            d: if toward.contains(&i) || i == grazing {
                Vec3A::Y
            } else {
                Vec3A::X
            },
            tmax: f32::INFINITY,
        })
        .collect();
    let (hits, blocked) = streamed(&accel, &rays);
    for (i, (hit, blocked)) in hits.iter().zip(&blocked).enumerate() {
        let meets = toward.contains(&i) || i == grazing;
        assert_eq!(hit.map(|h| h.primitive), meets.then_some(0), "ray {i}");
        assert_eq!(*blocked, meets, "ray {i}");
    }
    assert_eq!(hits[grazing].map(|h| h.t), Some(10.0));
}

/// A scene's list of primitives holds a triangle as its mesh and face:
/// spheres and disks stay out of line.
#[test]
fn a_primitive_is_16_bytes() {
    assert_eq!(std::mem::size_of::<Primitive>(), 16);
}

#[test]
fn empty_scene_hits_nothing() {
    let accel = Accel::new(Vec::new(), Vec::new(), Vec::new()).unwrap();
    let ray = Ray {
        o: Vec3A::ZERO,
        d: Vec3A::X,
        tmax: f32::INFINITY,
    };
    assert!(accel.intersect(&ray).is_none());
    assert!(!accel.occluded(&ray));
    assert!(accel.bounds().is_none());
}

/// A strip of `quads` unit squares in the plane z = 0 from x = `x0`,
/// facing +z, whose vertex normals tilt with x: `normal(x)` at a vertex.
fn strip(x0: f64, quads: usize, normal: impl Fn(f64) -> [f64; 3]) -> Mesh {
    let v: Vec<[f64; 3]> = (0..=quads)
        .flat_map(|k| [[x0 + k as f64, 0.0, 0.0], [x0 + k as f64, 1.0, 0.0]])
        .collect();
    let f: Vec<[i64; 3]> = (0..quads as i64)
        .flat_map(|k| {
            [
                [2 * k, 2 * k + 2, 2 * k + 1],
                [2 * k + 1, 2 * k + 2, 2 * k + 3],
            ]
        })
        .collect();
    let n: Vec<[f64; 3]> = v.iter().map(|p| normal(p[0])).collect();
    Mesh::new(&v, &f, Some(&n), false).unwrap()
}

/// Each hit shades with its own face's vertex normals, two smooth meshes
/// of 12 faces in one scene, traced by Embree (where it loads) and by
/// obvhs: the normals vary along x (so that a wrong face's blend differs),
/// and from one mesh to the other.
#[test]
fn hits_shade_with_their_own_faces_normals() {
    let normals: [fn(f64) -> [f64; 3]; 2] = [|x| [x, 0.0, 10.0], |x| [0.0, x, 10.0]];
    let (mut prims, mut meshes) = (Vec::new(), Vec::new());
    for (x0, normal) in [0.0, 10.0].into_iter().zip(normals) {
        let mesh = Geometry::Mesh(strip(x0, 6, normal));
        prims.extend(mesh.into_primitives(&mut meshes));
    }
    let shapes: Vec<u32> = (0..prims.len() as u32).map(|i| i / 12).collect();
    let embree = Accel::new(prims.clone(), shapes.clone(), meshes.clone()).unwrap();
    let obvhs = Accel::build(prims, shapes, meshes, false).unwrap();
    for accel in [&embree, &obvhs] {
        for k in 0..40_u32 {
            let (m, x) = ((k % 2) as usize, 0.1 + 0.29 * f64::from(k / 2));
            let ray = Ray {
                o: Vec3A::new((x + 10.0 * m as f64) as f32, 0.3, 5.0),
                d: Vec3A::NEG_Z,
                tmax: f32::INFINITY,
            };
            let hit = accel.intersect(&ray).unwrap();
            assert!((hit.t - 5.0).abs() < 1e-5);
            assert_eq!(accel.shape_of(hit.primitive), m as u32);
            let p = ray.o + ray.d * hit.t;
            let sp = accel.primitives()[hit.primitive as usize].point(p, hit.bary, accel.meshes());
            // The blend of the unit normals at the two ends of its quad.
            let x = f64::from(p.x);
            let unit = |x: f64| DVec3::from(normals[m](x)).normalize();
            let t = x.fract();
            let expected = ((1.0 - t) * unit(x.floor()) + t * unit(x.floor() + 1.0)).normalize();
            assert!(
                (sp.ns.as_dvec3() - expected).length() < 1e-5,
                "{}: {} {expected}",
                accel.ray_tracer(),
                sp.ns
            );
        }
    }
}

/// Faces listed out of their order, missing, repeated, split by another
/// primitive or of a mesh that is not there are refused.
#[test]
fn faces_out_of_their_order_are_refused() {
    let (mut prims, mut meshes) = (Vec::new(), Vec::new());
    for x0 in [0.0, 10.0] {
        prims
            .extend(Geometry::Mesh(strip(x0, 1, |_| [0.0, 0.0, 1.0])).into_primitives(&mut meshes));
    }
    let sphere = Primitive::Sphere(Box::new(Sphere {
        center: DVec3::ZERO,
        radius: 1.0,
        flip: false,
    }));
    let listed = |order: &[usize]| order.iter().map(|&i| prims[i].clone()).collect::<Vec<_>>();
    let mut split = listed(&[0, 1, 2, 3]);
    split.insert(3, sphere);
    let stray = vec![Primitive::Triangle { mesh: 2, face: 0 }];
    for bad in [
        listed(&[1, 0, 2, 3]),
        listed(&[0, 1, 2]),
        listed(&[0, 0, 2, 3]),
        split,
        stray,
    ] {
        let shapes = vec![0; bad.len()];
        let e = Accel::new(bad, shapes, meshes.clone()).err().unwrap();
        assert!(
            matches!(
                e,
                Error::Argument {
                    arg: "primitives",
                    ..
                }
            ),
            "{e}"
        );
    }
    assert!(Accel::new(listed(&[0, 1, 2, 3]), vec![0, 0, 1, 1], meshes).is_ok());
}

/// The reads a hit's surface point asks for ahead stay hints: each step
/// for a primitive past the table (a moving shape's) or past any index
/// loads nothing from the tables and does not panic.
#[test]
fn surface_prefetches_stay_within_the_tables() {
    let mut meshes = Vec::new();
    let prims: Vec<Primitive> = Geometry::Mesh(strip(0.0, 3, |_| [0.0, 0.0, 1.0]))
        .into_primitives(&mut meshes)
        .collect();
    let n = prims.len() as u32;
    let accel = Accel::new(prims, vec![0; n as usize], meshes).unwrap();
    for primitive in [0, n - 1, n, u32::MAX] {
        for step in [Ahead::Entry, Ahead::Face, Ahead::Vertices] {
            accel.prefetch_point(primitive, step);
        }
    }
}

//! Tests of the shapes.

use super::*;
use glam::{Affine3A, DVec3, Vec3A};

fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
    Ray {
        o: Vec3A::from(o),
        d: Vec3A::from(d).normalize(),
        tmax: f32::INFINITY,
    }
}

#[test]
fn triangle_hit_and_normals() {
    let tri = Triangle {
        p0: Vec3A::new(0.0, 0.0, 0.0),
        e1: Vec3A::new(1.0, 0.0, 0.0),
        e2: Vec3A::new(0.0, 1.0, 0.0),
        normals: None,
    };
    let hit = tri
        .intersect(&ray([0.25, 0.25, 2.0], [0.0, 0.0, -1.0]))
        .unwrap();
    assert!((hit.t - 2.0).abs() < 1e-6);
    let sp = tri.point(hit.bary, &[]);
    assert!((sp.p - Vec3A::new(0.25, 0.25, 0.0)).length() < 1e-6);
    assert_eq!(sp.ng, Vec3A::Z);
    assert!(
        tri.intersect(&ray([0.75, 0.75, 2.0], [0.0, 0.0, -1.0]))
            .is_none()
    );
    assert!((tri.area() - 0.5).abs() < 1e-7);
    // With vertex normals (indices into a table), the shading normal is
    // their barycentric blend, normalised: (1 − b1 − b2) n0 + b1 n1 + b2 n2.
    let (n0, n1, n2) = (
        Vec3A::Z,
        Vec3A::new(1.0, 0.0, 1.0).normalize(),
        Vec3A::new(0.0, 1.0, 1.0).normalize(),
    );
    let table = [Vec3A::X, n2, n0, n1];
    let smooth = Triangle {
        normals: Some([2, 3, 1]),
        ..tri
    };
    let sp = smooth.point([0.2, 0.5], &table);
    let expected = (0.3 * n0 + 0.2 * n1 + 0.5 * n2).normalize();
    assert!((sp.ns - expected).length() < 1e-6, "{}", sp.ns);
    assert_eq!(sp.ng, Vec3A::Z);
}

/// Four triangles tested at once give the nearest of the hits each
/// gives alone (and its barycentrics), on rays that hit none, one or
/// several of them; three triangles leave a padding lane that nothing
/// hits.
#[test]
fn four_triangles_at_once_agree_with_one_at_a_time() {
    let tri = |p0: [f32; 3], e1: [f32; 3], e2: [f32; 3]| Triangle {
        p0: Vec3A::from(p0),
        e1: Vec3A::from(e1),
        e2: Vec3A::from(e2),
        normals: None,
    };
    let tris = [
        tri([-1.0, -1.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
        tri([-1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [2.0, 0.0, 0.0]),
        tri([0.0, -2.0, -3.0], [0.0, 4.0, 0.0], [0.0, 0.0, 4.0]),
        tri([0.3, -0.5, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.2]),
    ];
    for count in [3, 4] {
        let pack = Triangles4::new(&tris[..count]);
        let mut nearest_lanes = [0; 4];
        for i in 0..400 {
            let (a, b) = ((i % 20) as f32 / 10.0 - 1.0, (i / 20) as f32 / 10.0 - 1.0);
            let r = ray([a, b, 2.0], [0.3 * b, -0.2, -1.0]);
            let nearest = tris[..count]
                .iter()
                .enumerate()
                .filter_map(|(l, t)| t.intersect(&r).map(|c| (l, c)))
                .min_by(|x, y| x.1.t.total_cmp(&y.1.t));
            let packed = pack.intersect(&r);
            assert_eq!(packed.map(|p| p.0), nearest.map(|n| n.0), "ray {i}");
            if let (Some((_, p)), Some((_, n))) = (packed, nearest) {
                assert_eq!((p.t, p.bary), (n.t, n.bary), "ray {i}");
            }
            assert_eq!(pack.occludes(&r), nearest.is_some());
            if let Some((l, _)) = nearest {
                nearest_lanes[l] += 1;
            }
        }
        assert!(
            nearest_lanes[..count].iter().all(|&n| n > 0),
            "{nearest_lanes:?}"
        );
    }
}

#[test]
fn sphere_hit_from_outside_and_inside() {
    let s = Sphere {
        center: DVec3::new(0.0, 0.0, -5.0),
        radius: 1.0,
        flip: false,
    };
    let outside = s
        .intersect(&ray([0.0, 0.0, 0.0], [0.0, 0.0, -1.0]))
        .unwrap();
    assert!((outside.t - 4.0).abs() < 1e-6);
    let inside = s
        .intersect(&ray([0.0, 0.0, -5.0], [1.0, 0.0, 0.0]))
        .unwrap();
    assert!((inside.t - 1.0).abs() < 1e-6);
    assert!(
        s.intersect(&ray([0.0, 2.0, 0.0], [0.0, 0.0, -1.0]))
            .is_none()
    );
    let sp = s.point(Vec3A::new(0.0, 0.0, -4.0));
    assert!((sp.ng - Vec3A::Z).length() < 1e-6);
}

#[test]
fn sphere_occlusion_agrees_with_the_nearest_hit() {
    let s = Sphere {
        center: DVec3::new(0.2, -0.1, -3.0),
        radius: 0.8,
        flip: false,
    };
    let (mut hits, mut misses) = (0, 0);
    for i in 0..2000 {
        let k = i as f32;
        // Origins outside, inside and just off the surface (as a shadow
        // ray leaves it); directions all around; finite and infinite
        // tmax.
        let start = match i % 3 {
            0 => [0.0, 0.0, 0.0],
            1 => [0.3, -0.2, -3.1],
            _ => {
                let n =
                    Vec3A::new((k * 0.37).sin(), (k * 0.71).cos(), (k * 0.13).sin()).normalize();
                (s.center.as_vec3a() + n * (0.8 + 1e-4)).to_array()
            }
        };
        let mut r = ray(start, [(k * 1.3).sin(), (k * 0.9).cos(), -(k * 0.5).cos()]);
        r.tmax = [f32::INFINITY, 0.5, 2.0, 4.0][i % 4];
        let hit = s.intersect(&r).is_some();
        assert_eq!(s.occludes(&r), hit, "ray {i}: {r:?}");
        (hits, misses) = (hits + usize::from(hit), misses + usize::from(!hit));
    }
    assert!(hits > 300 && misses > 300, "{hits} hits, {misses} misses");
}

#[test]
fn disk_hit_area_and_normal() {
    let m = Affine3A::from_scale_rotation_translation(
        glam::Vec3::new(2.0, 2.0, 1.0),
        glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
        glam::Vec3::new(0.0, 1.0, 0.0),
    );
    let disk = Disk::new(m).unwrap();
    assert!((disk.area - 4.0 * std::f32::consts::PI).abs() < 1e-4);
    assert!((disk.normal - Vec3A::new(0.0, -1.0, 0.0)).length() < 1e-6);
    let hit = disk
        .intersect(&ray([1.5, 5.0, 0.0], [0.0, -1.0, 0.0]))
        .unwrap();
    assert!((hit.t - 4.0).abs() < 1e-5);
    assert!(
        disk.intersect(&ray([2.5, 5.0, 0.0], [0.0, -1.0, 0.0]))
            .is_none()
    );
}

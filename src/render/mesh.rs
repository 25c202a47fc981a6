//! Triangle meshes as indexed vertices, checked, with shading normals. A
//! scene keeps them so (16 bytes a vertex, 12 a face, 16 a vertex normal)
//! and makes a face's [`Triangle`] when a ray meets it or a light sample
//! lands on it; Embree traces the same vertex and index buffers
//! ([`super::embree`]).

use glam::{DVec3, Vec3A};

use super::geometry::{check_primitives, finite_rows};
use super::shape::{SurfacePoint, Triangle};
use crate::alloc;
use crate::error::{Error, Result};

/// A triangle mesh (world space), made by [`Mesh::new`] only: its faces
/// index its vertices (Embree reads them so, unchecked).
#[derive(Clone, Debug)]
pub struct Mesh {
    points: Vec<Vec3A>,
    faces: Vec<[u32; 3]>,
    normals: Vec<Vec3A>,
}

/// Angle-weighted vertex normals (Thürmer and Wüthrich): each face adds its
/// unit normal times its corner angle at the vertex.
fn vertex_normals(vertices: &[Vec3A], faces: &[[u32; 3]]) -> Result<Vec<Vec3A>> {
    let mut normals = alloc::filled(vertices.len(), Vec3A::ZERO, "the vertex normals")?;
    for f in faces {
        let f = f.map(|i| i as usize);
        let p = f.map(|i| vertices[i]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        for k in 0..3 {
            let a = (p[(k + 1) % 3] - p[k]).normalize_or_zero();
            let b = (p[(k + 2) % 3] - p[k]).normalize_or_zero();
            let angle = a.dot(b).clamp(-1.0, 1.0).acos();
            normals[f[k]] += n * angle;
        }
    }
    normals.iter_mut().for_each(|n| *n = n.normalize_or_zero());
    Ok(normals)
}

/// `v/|v|` in single precision (zero for a zero `v`), `v` divided by its
/// largest component first: a normal of any finite length, beyond the
/// range of `f32` or of `|v|²` in `f64`, keeps its direction.
fn unit(v: [f64; 3]) -> Vec3A {
    let v = DVec3::from(v);
    let largest = v.abs().max_element();
    if largest > 0.0 {
        Vec3A::from((v / largest).normalize().as_vec3())
    } else {
        Vec3A::ZERO
    }
}

/// The triangle of face `f` of `points`, with the vertex normals at `f`
/// if `smooth`.
#[inline]
fn triangle(points: &[Vec3A], f: [u32; 3], smooth: bool) -> Triangle {
    let p = f.map(|i| points[i as usize]);
    Triangle {
        p0: p[0],
        e1: p[1] - p[0],
        e2: p[2] - p[0],
        normals: smooth.then_some(f),
    }
}

impl Mesh {
    /// A triangle mesh of `vertices` (world space) and `faces` (vertex
    /// indices, counter-clockwise seen from the front). Shading normals:
    /// `normals` when given (one per vertex), else angle-weighted vertex
    /// normals unless `face_normals`, as Mitsuba's meshes. Faces without
    /// an area are dropped (they are never hit and have no area to sample).
    ///
    /// # Errors
    /// [`Error::Element`] for a coordinate or normal that is not finite (a
    /// coordinate: in single precision),
    /// [`Error::Index`] for a face index out of range, [`Error::Shape`] for
    /// normals not one per vertex, [`Error::TooLarge`] for more than
    /// [`super::geometry::MAX_PRIMITIVES`] faces or vertices, [`Error::Memory`].
    pub fn new(
        vertices: &[[f64; 3]],
        faces: &[[i64; 3]],
        normals: Option<&[[f64; 3]]>,
        face_normals: bool,
    ) -> Result<Self> {
        check_primitives("vertices", vertices.len())?;
        check_primitives("faces", faces.len())?;
        finite_rows("vertices", vertices)?;
        // Kept in single precision: every coordinate must stay finite there.
        let too_large = |(i, v): (usize, &[f64; 3])| {
            let k = v.iter().position(|&x| (x as f32).is_infinite())?;
            Some(Error::Element {
                arg: "vertices",
                index: format!("[{i}, {k}]"),
                value: v[k],
                requirement: "must be finite in single precision (about 3.4e38 in magnitude at \
                              most)"
                    .into(),
            })
        };
        if let Some(e) = vertices.iter().enumerate().find_map(too_large) {
            return Err(e);
        }
        let nv = vertices.len();
        let mut idx: Vec<[u32; 3]> = alloc::with_capacity(faces.len(), "the faces")?;
        for (i, f) in faces.iter().enumerate() {
            if let Some(k) = f.iter().position(|&v| v < 0 || v as usize >= nv) {
                return Err(Error::Index {
                    arg: "faces",
                    index: format!("[{i}, {k}]"),
                    value: f[k],
                    len: nv,
                });
            }
            // At most MAX_PRIMITIVES vertices: an index fits in 31 bits.
            idx.push(f.map(|v| v as u32));
        }
        let points = alloc::collect(
            vertices
                .iter()
                .map(|v| Vec3A::from(DVec3::from(*v).as_vec3())),
            "the vertices",
        )?;
        let shading: Option<Vec<Vec3A>> = match (normals, face_normals) {
            (_, true) => None,
            (Some(n), false) => {
                finite_rows("normals", n)?;
                if n.len() != nv {
                    return Err(Error::Shape {
                        arg: "normals",
                        expected: format!("({nv}, 3), one per vertex"),
                        got: format!("({}, 3)", n.len()),
                    });
                }
                Some(alloc::collect(n.iter().map(|&v| unit(v)), "the normals")?)
            }
            (None, false) => Some(vertex_normals(&points, &idx)?),
        };
        idx.retain(|&f| triangle(&points, f, false).area() > 0.0);
        Ok(Mesh {
            points,
            faces: idx,
            normals: shading.unwrap_or_default(),
        })
    }

    /// The vertices.
    pub fn points(&self) -> &[Vec3A] {
        &self.points
    }

    /// The faces that have an area, as indices of [`Mesh::points`]
    /// (counter-clockwise seen from the front).
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// The vertex normals, one per vertex (none: face normals).
    pub fn normals(&self) -> &[Vec3A] {
        &self.normals
    }

    /// The triangle of face `face` (whose normals index
    /// [`Mesh::normals`]).
    #[inline]
    pub fn triangle(&self, face: u32) -> Triangle {
        triangle(
            &self.points,
            self.faces[face as usize],
            !self.normals.is_empty(),
        )
    }

    /// The surface point of face `face` at barycentrics `bary`
    /// ([`Triangle::point`]).
    #[inline]
    pub fn point(&self, face: u32, bary: [f32; 2]) -> SurfacePoint {
        self.triangle(face).point(bary, &self.normals)
    }

    /// Asks the caches for what [`Mesh::point`] of face `face` reads, in
    /// two steps some hits apart ([`crate::simd::prefetch`], a hint): the
    /// face's indices, then (`vertices`) its vertices and vertex normals,
    /// which reads the face the first step brought.
    #[inline(always)]
    pub fn prefetch_point(&self, face: u32, vertices: bool) {
        if !vertices {
            crate::simd::prefetch(&self.faces, face as usize);
            return;
        }
        for &i in self.faces.get(face as usize).into_iter().flatten() {
            crate::simd::prefetch(&self.points, i as usize);
            if !self.normals.is_empty() {
                crate::simd::prefetch(&self.normals, i as usize);
            }
        }
    }

    /// A point of face `face` drawn uniformly by area (density `1 / area`;
    /// [`Triangle::sample`]).
    #[inline]
    pub fn sample(&self, face: u32, u: [f32; 2]) -> SurfacePoint {
        self.triangle(face).sample(u, &self.normals)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth face blends its own vertex normals by its barycentrics; a
    /// face-normal mesh shades with the face normal; a face without an
    /// area is dropped.
    #[test]
    fn a_face_blends_its_vertex_normals() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let faces = [[0, 1, 2], [0, 1, 1]];
        let flat = Mesh::new(&v, &faces, None, true).unwrap();
        assert_eq!(flat.faces(), [[0, 1, 2]]);
        assert!(flat.normals().is_empty());
        assert_eq!(flat.point(0, [0.2, 0.3]).ns, Vec3A::Z);
        let n = [[1.0, 0.0, 1.0], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]];
        let smooth = Mesh::new(&v, &faces, Some(&n), false).unwrap();
        let sp = smooth.point(0, [0.2, 0.3]);
        let unit = |n: [f64; 3]| DVec3::from(n).normalize();
        let expected = (0.5 * unit(n[0]) + 0.2 * unit(n[1]) + 0.3 * unit(n[2])).normalize();
        assert!((sp.ns.as_dvec3() - expected).length() < 1e-6, "{}", sp.ns);
        assert!((sp.p - Vec3A::new(0.2, 0.3, 0.0)).length() < 1e-7);
    }

    /// A given normal too long or too short for single precision keeps
    /// its direction (made unit before it is rounded); a zero normal
    /// shades with the face's.
    #[test]
    fn a_normal_of_any_finite_length_keeps_its_direction() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        for scale in [1e39, 1e-30, 1e300, 1e-300, 1e-310] {
            let n = [[0.0, scale, scale]; 3];
            let mesh = Mesh::new(&v, &[[0, 1, 2]], Some(&n), false).unwrap();
            let ns = mesh.point(0, [0.2, 0.3]).ns;
            let expected = Vec3A::new(0.0, 1.0, 1.0).normalize();
            assert!((ns - expected).length() < 1e-6, "{scale}: {ns}");
        }
        let zero = [[0.0; 3]; 3];
        let mesh = Mesh::new(&v, &[[0, 1, 2]], Some(&zero), false).unwrap();
        assert_eq!(mesh.point(0, [0.2, 0.3]).ns, Vec3A::Z);
    }

    /// A coordinate beyond single precision's range is refused by name.
    #[test]
    fn a_vertex_beyond_f32_is_refused() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1e39, 0.0]];
        let e = Mesh::new(&v, &[[0, 1, 2]], None, true).unwrap_err();
        assert!(
            matches!(&e, Error::Element { arg: "vertices", index, .. } if index == "[2, 1]"),
            "{e}"
        );
    }
}

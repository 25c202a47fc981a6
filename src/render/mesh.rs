//! Triangle meshes as indexed vertices, checked, with shading normals. A
//! scene keeps them so (16 bytes a vertex, 12 a face, 16 a vertex normal)
//! and makes a face's [`Triangle`] when a ray meets it or a light sample
//! lands on it; Embree traces the same vertex and index buffers
//! ([`super::embree`]).

use glam::{DVec3, Vec3A};

use super::geometry::{check_primitives, finite_rows};
use super::shape::Triangle;
use crate::alloc;
use crate::error::{Error, Result};

/// A triangle mesh (world space).
#[derive(Clone, Debug)]
pub struct Mesh {
    /// The vertices.
    pub points: Vec<Vec3A>,
    /// The faces that have an area, as vertex indices (counter-clockwise
    /// seen from the front).
    pub faces: Vec<[u32; 3]>,
    /// The vertex normals, one per vertex (none: face normals).
    pub normals: Vec<Vec3A>,
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
    /// [`Error::Element`] for a coordinate or normal that is not finite,
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
                Some(alloc::collect(
                    n.iter()
                        .map(|v| Vec3A::from(DVec3::from(*v).as_vec3()).normalize_or_zero()),
                    "the normals",
                )?)
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth mesh's triangles blend its own vertex normals; a
    /// face-normal mesh's shade with the face normal; a face without an
    /// area is dropped.
    #[test]
    fn a_face_shades_with_its_own_meshs_normals() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let faces = [[0, 1, 2], [0, 1, 1]];
        let flat = Mesh::new(&v, &faces, None, true).unwrap();
        assert_eq!(flat.faces, [[0, 1, 2]]);
        assert!(flat.normals.is_empty());
        assert_eq!(
            flat.triangle(0).point([0.2, 0.3], &flat.normals).ns,
            Vec3A::Z
        );
        for n in [[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]] {
            let smooth = Mesh::new(&v, &faces, Some(&[n; 3]), false).unwrap();
            let sp = smooth.triangle(0).point([0.2, 0.3], &smooth.normals);
            let expected = Vec3A::from(DVec3::from(n).as_vec3()).normalize();
            assert!((sp.ns - expected).length() < 1e-6, "{} {expected}", sp.ns);
        }
    }
}

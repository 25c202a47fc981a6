//! The geometry of a shape: triangle meshes (checked, with shading
//! normals), spheres and disks, and the affine maps that place them.

use glam::{DVec3, Vec3A};

use super::accel::Primitive;
use super::shape::{Disk, Sphere, Triangle};
use crate::alloc;
use crate::error::{Error, Result};

/// The geometry of one shape.
#[derive(Clone, Debug)]
pub enum Geometry {
    /// A triangle mesh (world space), kept as indexed vertices (28 bytes
    /// a face with normals, where its [`Triangle`]s would take 64) until a
    /// scene makes its primitives.
    Mesh {
        /// The vertices.
        points: Vec<Vec3A>,
        /// The faces that have an area, as vertex indices.
        faces: Vec<[u32; 3]>,
        /// The vertex normals (none: face normals).
        normals: Vec<Vec3A>,
    },
    /// A sphere.
    Sphere(Sphere),
    /// A disk.
    Disk(Disk),
}

fn finite_rows<const K: usize>(arg: &'static str, rows: &[[f64; K]]) -> Result<()> {
    for (i, row) in rows.iter().enumerate() {
        if let Some(k) = row.iter().position(|v| !v.is_finite()) {
            return Err(Error::Element {
                arg,
                index: format!("[{i}, {k}]"),
                value: row[k],
                requirement: "must be finite".into(),
            });
        }
    }
    Ok(())
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

/// The triangle of face `f` of `points`, its vertex normals at `f` plus
/// `normals` in the scene's table (`None`: face normals).
fn triangle(points: &[Vec3A], f: [u32; 3], normals: Option<u32>) -> Triangle {
    let p = f.map(|i| points[i as usize]);
    Triangle {
        p0: p[0],
        e1: p[1] - p[0],
        e2: p[2] - p[0],
        normals: normals.map(|offset| f.map(|i| i + offset)),
    }
}

/// Primitives a scene may hold (and faces or vertices a mesh may have):
/// they are numbered in 31 bits (the BVH's leaves keep a flag in the 32nd).
pub const MAX_PRIMITIVES: usize = (1 << 31) - 1;

/// Checks a count of `arg` against [`MAX_PRIMITIVES`].
pub(crate) fn check_primitives(arg: &'static str, len: usize) -> Result<()> {
    crate::error::check_at_most(arg, len, MAX_PRIMITIVES)
}

impl Geometry {
    /// How many primitives it adds to a scene.
    pub(crate) fn primitive_count(&self) -> usize {
        match self {
            Geometry::Mesh { faces, .. } => faces.len(),
            Geometry::Sphere(_) | Geometry::Disk(_) => 1,
        }
    }

    /// Its primitives. A mesh's vertex normals join the table `normals`,
    /// and its triangles index them there.
    ///
    /// # Errors
    /// [`Error::TooLarge`] when the table would pass [`MAX_PRIMITIVES`]
    /// entries, [`Error::Memory`] when it cannot grow.
    pub(crate) fn into_primitives(
        self,
        normals: &mut Vec<Vec3A>,
    ) -> Result<Box<dyn ExactSizeIterator<Item = Primitive>>> {
        Ok(match self {
            Geometry::Mesh {
                points,
                faces,
                normals: own,
            } => {
                let offset = normals.len();
                check_primitives("vertex normals", offset.saturating_add(own.len()))?;
                let smooth = (!own.is_empty()).then_some(offset as u32);
                alloc::reserve(normals, own.len(), "the vertex normals")?;
                normals.extend(own);
                Box::new(
                    faces
                        .into_iter()
                        .map(move |f| Primitive::Triangle(triangle(&points, f, smooth))),
                )
            }
            Geometry::Sphere(s) => Box::new(std::iter::once(Primitive::Sphere(s))),
            Geometry::Disk(d) => Box::new(std::iter::once(Primitive::Disk(Box::new(d)))),
        })
    }

    /// A triangle mesh of `vertices` (world space) and `faces` (vertex
    /// indices, counter-clockwise seen from the front). Shading normals:
    /// `normals` when given (one per vertex), else angle-weighted vertex
    /// normals unless `face_normals`, as Mitsuba's meshes.
    ///
    /// # Errors
    /// [`Error::Element`] for a coordinate or normal that is not finite,
    /// [`Error::Index`] for a face index out of range, [`Error::Shape`] for
    /// normals not one per vertex, [`Error::TooLarge`] for more than
    /// [`MAX_PRIMITIVES`] faces or vertices, [`Error::Memory`].
    pub fn mesh(
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
        // Degenerate triangles are never hit and have no area to sample.
        idx.retain(|&f| triangle(&points, f, None).area() > 0.0);
        Ok(Geometry::Mesh {
            points,
            faces: idx,
            normals: shading.unwrap_or_default(),
        })
    }

    /// A sphere of `radius > 0` around `center`; normals inward if `flip`.
    ///
    /// # Errors
    /// [`Error::Parameter`] for a radius that is not finite and > 0,
    /// [`Error::Element`] for a centre that is not finite.
    pub fn sphere(center: [f64; 3], radius: f64, flip: bool) -> Result<Self> {
        finite_rows("center", &[center])?;
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(Error::Parameter {
                arg: "radius",
                value: radius,
                requirement: "must be finite and > 0",
            });
        }
        Ok(Geometry::Sphere(Sphere {
            center: DVec3::from(center),
            radius,
            flip,
        }))
    }

    /// Mitsuba's `disk`: the unit disk in the plane z = 0 (normal +z) placed
    /// by the affine `to_world` (row-major 4×4; the last row is ignored).
    ///
    /// # Errors
    /// [`Error::Element`] for a matrix entry that is not finite,
    /// [`Error::Parameter`] for a matrix that flattens the disk.
    pub fn disk(to_world: [[f64; 4]; 4]) -> Result<Self> {
        let m = affine("to_world", to_world)?;
        Disk::new(m).map(Geometry::Disk).ok_or(Error::Parameter {
            arg: "to_world",
            value: 0.0,
            requirement: "must not flatten the disk (its determinant is 0)",
        })
    }
}

/// The affine map of a row-major 4×4 matrix (its last row ignored), in
/// `f64`.
///
/// # Errors
/// [`Error::Element`] for an entry that is not finite.
pub fn daffine(arg: &'static str, m: [[f64; 4]; 4]) -> Result<glam::DAffine3> {
    finite_rows(arg, &m)?;
    Ok(glam::DAffine3::from_cols_array(&std::array::from_fn(|i| {
        m[i % 3][i / 3]
    })))
}

/// The affine map of a row-major 4×4 matrix (its last row ignored).
///
/// # Errors
/// [`Error::Element`] for an entry that is not finite.
pub fn affine(arg: &'static str, m: [[f64; 4]; 4]) -> Result<glam::Affine3A> {
    daffine(arg, m).map(affine_f32)
}

/// An `f64` affine map in `f32`.
pub fn affine_f32(m: glam::DAffine3) -> glam::Affine3A {
    glam::Affine3A::from_cols_array(&m.to_cols_array().map(|v| v as f32))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two smooth meshes in one table: each triangle's shading normals are
    /// its own mesh's, wherever in the table they landed; a face-normal
    /// mesh adds none.
    #[test]
    fn meshes_share_one_table_of_normals() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let smooth = |n: [f64; 3]| Geometry::mesh(&v, &[[0, 1, 2]], Some(&[n; 3]), false).unwrap();
        let mut table = Vec::new();
        let flat = Geometry::mesh(&v, &[[0, 1, 2]], None, true).unwrap();
        assert_eq!(flat.into_primitives(&mut table).unwrap().count(), 1);
        assert!(table.is_empty());
        let mut prims = Vec::new();
        for n in [[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]] {
            prims.extend(smooth(n).into_primitives(&mut table).unwrap());
        }
        assert_eq!(table.len(), 6);
        for (p, n) in prims.iter().zip([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]) {
            let sp = p.point(Vec3A::ZERO, [0.2, 0.3], &table);
            let expected = Vec3A::from(DVec3::from(n).as_vec3()).normalize();
            assert!((sp.ns - expected).length() < 1e-6, "{} {expected}", sp.ns);
        }
    }
}

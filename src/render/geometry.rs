//! The geometry of a shape: triangle meshes (checked, with shading
//! normals), spheres and disks, and the affine maps that place them.

use glam::{DVec3, Vec3A};

use super::shape::{Disk, Sphere, Triangle};
use crate::alloc;
use crate::error::{Error, Result};

/// The geometry of one shape.
#[derive(Clone, Debug)]
pub enum Geometry {
    /// A triangle mesh (world space).
    Mesh(Vec<Triangle>),
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
fn vertex_normals(vertices: &[Vec3A], faces: &[[usize; 3]]) -> Result<Vec<Vec3A>> {
    let mut normals = alloc::filled(vertices.len(), Vec3A::ZERO, "the vertex normals")?;
    for f in faces {
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
            Geometry::Mesh(tris) => tris.len(),
            Geometry::Sphere(_) | Geometry::Disk(_) => 1,
        }
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
        let mut idx = alloc::with_capacity(faces.len(), "the faces")?;
        for (i, f) in faces.iter().enumerate() {
            if let Some(k) = f.iter().position(|&v| v < 0 || v as usize >= nv) {
                return Err(Error::Index {
                    arg: "faces",
                    index: format!("[{i}, {k}]"),
                    value: f[k],
                    len: nv,
                });
            }
            idx.push(f.map(|v| v as usize));
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
        let mut tris = alloc::with_capacity(idx.len(), "the triangles")?;
        tris.extend(
            idx.iter()
                .map(|f| {
                    let p = f.map(|i| points[i]);
                    Triangle {
                        p0: p[0],
                        e1: p[1] - p[0],
                        e2: p[2] - p[0],
                        normals: shading.as_ref().map(|n| f.map(|i| n[i])),
                    }
                })
                // Degenerate triangles are never hit and have no area to sample.
                .filter(|t| t.area() > 0.0),
        );
        Ok(Geometry::Mesh(tris))
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

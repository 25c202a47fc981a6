//! The geometry of a shape (a triangle mesh, [`super::mesh`], a sphere or
//! a disk), its primitives in a scene, and the affine maps that place
//! shapes.

use glam::DVec3;

use super::accel::Primitive;
use super::mesh::Mesh;
use super::shape::{Disk, Sphere};
use crate::error::{Error, Result};

/// The geometry of one shape.
#[derive(Clone, Debug)]
pub enum Geometry {
    /// A triangle mesh (world space), as indexed vertices.
    Mesh(Mesh),
    /// A sphere.
    Sphere(Sphere),
    /// A disk.
    Disk(Disk),
}

/// Checks that every entry of `rows` (the rows of argument `arg`) is finite.
///
/// # Errors
/// [`Error::Element`] naming the first that is not.
pub(crate) fn finite_rows<const K: usize>(arg: &'static str, rows: &[[f64; K]]) -> Result<()> {
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
            Geometry::Mesh(mesh) => mesh.faces().len(),
            Geometry::Sphere(_) | Geometry::Disk(_) => 1,
        }
    }

    /// Its primitives. A mesh joins `meshes`, and its triangles are its
    /// faces there (in their order, one after the other).
    pub(crate) fn into_primitives(
        self,
        meshes: &mut Vec<Mesh>,
    ) -> Box<dyn ExactSizeIterator<Item = Primitive>> {
        match self {
            Geometry::Mesh(mesh) => {
                // At most MAX_PRIMITIVES faces and meshes (one per shape).
                let index = meshes.len() as u32;
                let faces = mesh.faces().len() as u32;
                meshes.push(mesh);
                Box::new((0..faces).map(move |face| Primitive::Triangle { mesh: index, face }))
            }
            Geometry::Sphere(s) => Box::new(std::iter::once(Primitive::Sphere(Box::new(s)))),
            Geometry::Disk(d) => Box::new(std::iter::once(Primitive::Disk(Box::new(d)))),
        }
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

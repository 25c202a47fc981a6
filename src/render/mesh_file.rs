//! Triangle meshes from PLY (ASCII or binary, via `serde-ply`) and Wavefront
//! OBJ files (via `tobj`): positions, faces (polygons split into fans) and,
//! when the file has them, vertex normals.

use std::path::Path;

use serde::Deserialize;
use serde::de::{DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde_ply::{PlyReader, PropertyType};

use crate::alloc;
use crate::error::{Error, Result};
use crate::render::geometry::check_primitives;

/// The contents of a mesh file.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as vertex indices.
    pub faces: Vec<[i64; 3]>,
    /// One normal per vertex, if the file has them.
    pub normals: Option<Vec<[f64; 3]>>,
}

fn io_error(path: &Path, message: impl Into<String>) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Reads a `.ply` or `.obj` file (chosen by extension).
///
/// # Errors
/// [`Error::Io`] for a file that cannot be read, is not a mesh of that
/// format, or lacks positions or faces.
pub fn read_mesh(path: &Path) -> Result<MeshData> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let mesh = match ext.as_deref() {
        Some("ply") => read_ply(path)?,
        Some("obj") => read_obj(path)?,
        _ => return Err(io_error(path, "unknown mesh format: expected .ply or .obj")),
    };
    if mesh.vertices.is_empty() || mesh.faces.is_empty() {
        return Err(io_error(path, "the mesh has no vertices or no faces"));
    }
    Ok(mesh)
}

/// A PLY vertex's position (other properties skipped).
#[derive(Deserialize)]
struct Position {
    x: f64,
    y: f64,
    z: f64,
}

/// A PLY vertex's position and normal.
#[derive(Deserialize)]
struct Oriented {
    x: f64,
    y: f64,
    z: f64,
    nx: f64,
    ny: f64,
    nz: f64,
}

/// An element of another kind, read and dropped.
#[derive(Deserialize)]
struct Skipped {}

/// The rows of an element of no properties, not visited.
struct IgnoredRows;

impl<'de> DeserializeSeed<'de> for IgnoredRows {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, rows: D) -> std::result::Result<(), D::Error> {
        rows.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for IgnoredRows {
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("the rows of a PLY element")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, _: A) -> std::result::Result<(), A::Error> {
        Ok(())
    }
}

/// The faces of a PLY `face` element, each polygon's list `name` split
/// into the fan `(p0, p_k, p_k+1)` straight into `faces` (no list kept per
/// face).
struct Faces<'a> {
    faces: &'a mut Vec<[i64; 3]>,
    name: &'a str,
}

impl<'de> DeserializeSeed<'de> for Faces<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, rows: D) -> std::result::Result<(), D::Error> {
        rows.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for Faces<'_> {
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("the rows of a PLY face element")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut rows: A) -> std::result::Result<(), A::Error> {
        while rows
            .next_element_seed(Face(&mut *self.faces, self.name))?
            .is_some()
        {}
        Ok(())
    }
}

/// One row of the face element: its list `.1` fanned into `.0`, the other
/// properties skipped.
struct Face<'a>(&'a mut Vec<[i64; 3]>, &'a str);

impl<'de> DeserializeSeed<'de> for Face<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, row: D) -> std::result::Result<(), D::Error> {
        row.deserialize_map(self)
    }
}

impl<'de> Visitor<'de> for Face<'_> {
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a PLY face")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut row: A) -> std::result::Result<(), A::Error> {
        let Face(faces, name) = self;
        while let Some(ours) = row.next_key_seed(IsName(name))? {
            if ours {
                row.next_value_seed(Fan(&mut *faces))?;
            } else {
                row.next_value::<IgnoredAny>()?;
            }
        }
        Ok(())
    }
}

/// A polygon's list of vertex indices, pushed as its fan of triangles.
struct Fan<'a>(&'a mut Vec<[i64; 3]>);

impl<'de> DeserializeSeed<'de> for Fan<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, list: D) -> std::result::Result<(), D::Error> {
        list.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for Fan<'_> {
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a list of vertex indices")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut list: A) -> std::result::Result<(), A::Error> {
        let (Some(first), Some(mut last)) = (list.next_element::<i64>()?, list.next_element()?)
        else {
            return Ok(());
        };
        while let Some(next) = list.next_element()? {
            self.0.push([first, last, next]);
            last = next;
        }
        Ok(())
    }
}

/// Whether a property's name (as the reader gives it, in bytes) is `.0`.
struct IsName<'a>(&'a str);

impl<'de> DeserializeSeed<'de> for IsName<'_> {
    type Value = bool;

    fn deserialize<D: Deserializer<'de>>(self, name: D) -> std::result::Result<bool, D::Error> {
        name.deserialize_bytes(self)
    }
}

impl Visitor<'_> for IsName<'_> {
    type Value = bool;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a property name")
    }

    fn visit_bytes<E>(self, name: &[u8]) -> std::result::Result<bool, E> {
        Ok(name == self.0.as_bytes())
    }

    fn visit_str<E>(self, name: &str) -> std::result::Result<bool, E> {
        Ok(name == self.0)
    }
}

/// Memory the PLY reader takes per vertex or face it reads, checked before
/// it starts: a vertex as read (48 bytes, twice while its list grows) and
/// as kept (24, and 24 for its normal), a face as kept (24, twice for a
/// quad's fan).
const PLY_BYTES_PER_ELEMENT: usize = 192;

fn read_ply(path: &Path) -> Result<MeshData> {
    let file = std::fs::File::open(path).map_err(|e| io_error(path, e.to_string()))?;
    let unreadable =
        |e: serde_ply::DeserializeError| io_error(path, format!("not a readable PLY file: {e}"));
    let mut reader = PlyReader::from_reader(std::io::BufReader::new(file)).map_err(unreadable)?;
    // The header's counts, checked before the payload is read (other
    // elements are skipped, kept nowhere).
    let mut elements = 0usize;
    for element in &reader.header().elem_defs {
        let what = match element.name.as_str() {
            "vertex" => "vertices",
            "face" => "faces",
            _ => continue,
        };
        check_primitives(what, element.count)?;
        elements = elements.saturating_add(element.count);
    }
    alloc::probe::<u8>(
        elements.saturating_mul(PLY_BYTES_PER_ELEMENT),
        "the PLY file's elements",
    )?;
    // The elements in the header's order.
    let (mut vertices, mut normals, mut faces) = (Vec::new(), None, Vec::new());
    let mut has_vertices = false;
    while let Some(element) = reader.current_element() {
        let scalar = |name: &str| {
            element
                .get_property(name)
                .is_some_and(|p| matches!(p.property_type, PropertyType::Scalar(_)))
        };
        match element.name.as_str() {
            "vertex" if ["x", "y", "z"].iter().all(|&k| scalar(k)) => {
                has_vertices = true;
                // Normals when all three are numbers (not lists).
                (vertices, normals) = if ["nx", "ny", "nz"].iter().all(|&k| scalar(k)) {
                    let read: Vec<Oriented> = reader.next_element().map_err(unreadable)?;
                    let normals = read.iter().map(|v| [v.nx, v.ny, v.nz]).collect();
                    (
                        read.into_iter().map(|v| [v.x, v.y, v.z]).collect(),
                        Some(normals),
                    )
                } else {
                    let read: Vec<Position> = reader.next_element().map_err(unreadable)?;
                    (read.into_iter().map(|v| [v.x, v.y, v.z]).collect(), None)
                };
            }
            "vertex" => return Err(io_error(path, "PLY vertices need x, y and z")),
            "face" => {
                let name = ["vertex_indices", "vertex_index"]
                    .into_iter()
                    .find(|&k| element.get_property(k).is_some())
                    .ok_or_else(|| io_error(path, "PLY faces need a 'vertex_indices' list"))?;
                faces = alloc::with_capacity(element.count, "the faces")?;
                let seed = Faces {
                    faces: &mut faces,
                    name,
                };
                // The element read through the reader's map of elements
                // (its `next_element` takes no seed).
                (&mut reader).next_value_seed(seed).map_err(unreadable)?;
            }
            // An element of no properties has no bytes to read: passed
            // over at once (row by row, a huge count would take forever).
            _ if element.properties.is_empty() => (&mut reader)
                .next_value_seed(IgnoredRows)
                .map_err(unreadable)?,
            _ => {
                let _: Vec<Skipped> = reader.next_element().map_err(unreadable)?;
            }
        }
    }
    if !has_vertices {
        return Err(io_error(path, "PLY file without a 'vertex' element"));
    }
    Ok(MeshData {
        vertices,
        faces,
        normals,
    })
}

/// Memory an OBJ file takes to read, per byte of the file (its text holds
/// about 30 bytes a vertex, which become 12 bytes in the reader and 24 in
/// [`MeshData`]), checked before the reader starts.
const OBJ_BYTES_PER_FILE_BYTE: u64 = 4;

fn read_obj(path: &Path) -> Result<MeshData> {
    let size = std::fs::metadata(path)
        .map_err(|e| io_error(path, e.to_string()))?
        .len();
    let bytes = usize::try_from(size.saturating_mul(OBJ_BYTES_PER_FILE_BYTE)).unwrap_or(usize::MAX);
    alloc::probe::<u8>(bytes, "the OBJ file's mesh")?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(path, &options)
        .map_err(|e| io_error(path, format!("not a readable OBJ file: {e}")))?;
    let mut mesh = MeshData::default();
    let mut normals = Vec::new();
    let mut all_have_normals = true;
    for model in models {
        let m = model.mesh;
        let base = mesh.vertices.len() as i64;
        mesh.vertices.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]].map(f64::from)),
        );
        all_have_normals &= m.normals.len() == m.positions.len();
        normals.extend(
            m.normals
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]].map(f64::from)),
        );
        mesh.faces.extend(
            m.indices
                .chunks_exact(3)
                .map(|f| [f[0], f[1], f[2]].map(|i| base + i64::from(i))),
        );
    }
    mesh.normals = all_have_normals.then_some(normals);
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_ply_with_a_quad_and_normals() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("quad.ply");
        std::fs::write(
            &path,
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n\
             0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3\n",
        )
        .unwrap();
        let m = read_mesh(&path).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.normals.unwrap()[2], [0.0, 0.0, 1.0]);
    }

    /// A binary PLY (either byte order) with an element between the
    /// vertices and the faces and `vertex_index` as the list's name; a list
    /// named `nx` leaves the normals out; a file without `z` is refused.
    #[test]
    fn binary_ply_in_either_byte_order_with_another_element() {
        let dir = tempfile::tempdir().unwrap();
        for big in [false, true] {
            let order = if big { "big" } else { "little" };
            let mut bytes = format!(
                "ply\nformat binary_{order}_endian 1.0\nelement vertex 3\nproperty float x\n\
                 property float y\nproperty float z\nelement edge 1\nproperty int a\n\
                 property int b\nelement face 1\nproperty list uchar uint vertex_index\n\
                 end_header\n"
            )
            .into_bytes();
            let f32s = |v: f32| {
                if big {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            };
            let u32s = |v: u32| {
                if big {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            };
            for v in [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.0, 0.5] {
                bytes.extend(f32s(v));
            }
            bytes.extend(u32s(0).into_iter().chain(u32s(1)));
            bytes.push(3);
            for i in [2, 1, 0] {
                bytes.extend(u32s(i));
            }
            let path = dir.path().join(format!("{order}.ply"));
            std::fs::write(&path, &bytes).unwrap();
            let m = read_mesh(&path).unwrap();
            assert_eq!(m.vertices[2], [0.0, 2.0, 0.5], "{order}");
            assert_eq!(m.faces, vec![[2, 1, 0]], "{order}");
            assert!(m.normals.is_none());
        }
        // A list where a normal's coordinate should be: no normals.
        let path = dir.path().join("list_nx.ply");
        std::fs::write(
            &path,
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nproperty list uchar float nx\nelement face 1\n\
             property list uchar int vertex_indices\nend_header\n0 0 0 1 1\n1 0 0 1 1\n\
             0 1 0 1 1\n3 0 1 2\n",
        )
        .unwrap();
        assert!(read_mesh(&path).unwrap().normals.is_none());
        let path = dir.path().join("no_z.ply");
        std::fs::write(
            &path,
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n\
             0 0\n1 0\n0 1\n3 0 1 2\n",
        )
        .unwrap();
        let refused = read_mesh(&path).unwrap_err().to_string();
        assert!(
            refused.contains("PLY vertices need x, y and z"),
            "{refused}"
        );
    }

    /// Doubles, a colour among the vertex's properties, a pentagon, and a
    /// property after the face's list: all skipped or read in place.
    #[test]
    fn binary_ply_with_other_properties_around_the_ones_read() {
        let mut bytes = "ply\nformat binary_little_endian 1.0\nelement vertex 5\n\
                         property uchar red\nproperty double x\nproperty double y\n\
                         property double z\nproperty int nx\nelement face 2\n\
                         property list uchar int vertex_indices\nproperty float quality\n\
                         end_header\n"
            .as_bytes()
            .to_vec();
        for k in 0..5u8 {
            bytes.push(200 + k);
            for c in [f64::from(k), 0.5 * f64::from(k), -1.0] {
                bytes.extend(c.to_le_bytes());
            }
            bytes.extend(7i32.to_le_bytes());
        }
        for poly in [&[4i32, 3, 2, 1, 0][..], &[0, 2, 4]] {
            bytes.push(poly.len() as u8);
            for &i in poly {
                bytes.extend(i.to_le_bytes());
            }
            bytes.extend(0.25f32.to_le_bytes());
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pentagon.ply");
        std::fs::write(&path, &bytes).unwrap();
        let m = read_mesh(&path).unwrap();
        assert_eq!(m.vertices[3], [3.0, 1.5, -1.0]);
        assert_eq!(m.faces, vec![[4, 3, 2], [4, 2, 1], [4, 1, 0], [0, 2, 4]]);
        // Only `nx` of a normal: none.
        assert!(m.normals.is_none());
    }

    /// Binary normals (read by the typed rows' offsets), and an element of
    /// no properties with a count no file could hold, passed over at once.
    #[test]
    fn binary_normals_and_an_element_of_nothing() {
        let mut bytes = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
                         property float x\nproperty float y\nproperty float z\n\
                         property float nx\nproperty float ny\nproperty float nz\n\
                         element nothing 18446744073709551615\nelement face 1\n\
                         property list uchar int vertex_indices\nend_header\n"
            .as_bytes()
            .to_vec();
        for k in 0..3 {
            let p = [k == 1, k == 2, false].map(|b| f32::from(u8::from(b)));
            for c in p.into_iter().chain([0.0, 0.6, 0.8]) {
                bytes.extend(c.to_le_bytes());
            }
        }
        bytes.push(3);
        for i in [0i32, 1, 2] {
            bytes.extend(i.to_le_bytes());
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("normals.ply");
        std::fs::write(&path, &bytes).unwrap();
        let m = read_mesh(&path).unwrap();
        assert_eq!(m.vertices, vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        assert_eq!(m.normals.unwrap()[2], [0.0, 0.6f32 as f64, 0.8f32 as f64]);
        assert_eq!(m.faces, vec![[0, 1, 2]]);
    }

    #[test]
    fn obj_triangle_and_bad_files() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.obj");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let m = read_mesh(&path).unwrap();
        assert_eq!(m.faces, vec![[0, 1, 2]]);
        assert!(m.normals.is_none());
        let bad = dir.path().join("bad.ply");
        std::fs::write(&bad, "not a ply").unwrap();
        assert!(matches!(read_mesh(&bad), Err(Error::Io { .. })));
        assert!(read_mesh(&dir.path().join("missing.obj")).is_err());
        assert!(read_mesh(&dir.path().join("x.stl")).is_err());
    }
}

//! Triangle meshes from PLY (ASCII or binary, via `ply-rs-bw`) and Wavefront
//! OBJ files (via `tobj`): positions, faces (polygons split into fans) and,
//! when the file has them, vertex normals.

use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};

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

/// A PLY vertex as read: its position and normal, and which of the six
/// (`x y z nx ny nz`) the file gave.
#[derive(Default)]
struct PlyVertex {
    values: [f64; 6],
    given: u8,
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let Some(slot) = ["x", "y", "z", "nx", "ny", "nz"]
            .iter()
            .position(|&k| k == name)
        else {
            return PropertyAccessResult::Ignored;
        };
        let value = match property {
            Property::Double(v) => v,
            p => match p.to_f32_lossy() {
                Some(v) => f64::from(v),
                // A list: no coordinate (the normals are then left out).
                None if slot >= 3 => return PropertyAccessResult::Ignored,
                None => return PropertyAccessResult::UnsupportedType,
            },
        };
        self.values[slot] = value;
        self.given |= 1 << slot;
        PropertyAccessResult::Set
    }
}

/// A PLY face as read: its polygon's vertex indices, from
/// `vertex_indices`, or `vertex_index` when it has no `vertex_indices`.
#[derive(Default)]
struct PlyFace {
    indices: Option<Vec<i64>>,
    index: Option<Vec<i64>>,
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let slot = match name {
            "vertex_indices" => &mut self.indices,
            "vertex_index" => &mut self.index,
            _ => return PropertyAccessResult::Ignored,
        };
        *slot = Some(match property {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => return PropertyAccessResult::UnsupportedType,
        });
        PropertyAccessResult::Set
    }
}

/// An element of another kind, skipped.
struct Skipped;

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Skipped
    }
}

/// Splits the polygon `poly` into the fan `(p0, p_k, p_k+1)`.
fn fan(poly: &[i64], faces: &mut Vec<[i64; 3]>) {
    for k in 1..poly.len().saturating_sub(1) {
        faces.push([poly[0], poly[k], poly[k + 1]]);
    }
}

/// Memory the PLY reader takes per vertex or face it reads, checked before
/// it starts: a vertex as read (56 bytes, twice while its list grows) and
/// as kept (48), a face as read (56, twice, and its list of indices) and
/// as kept (24).
const PLY_BYTES_PER_ELEMENT: usize = 192;

fn read_ply(path: &Path) -> Result<MeshData> {
    let file = std::fs::File::open(path).map_err(|e| io_error(path, e.to_string()))?;
    let mut reader = Reader::new(std::io::BufReader::new(file));
    let unreadable =
        |e: ply_rs_bw::parser::ParseError| io_error(path, format!("not a readable PLY file: {e}"));
    let header = Parser::<Skipped>::new()
        .read_header(&mut reader)
        .map_err(unreadable)?;
    // The header's counts, checked before the payload is read (other
    // elements are skipped, kept nowhere).
    let mut elements = 0usize;
    for (name, element) in &header.elements {
        if name == "vertex" || name == "face" {
            check_primitives(
                if name == "vertex" {
                    "vertices"
                } else {
                    "faces"
                },
                element.count,
            )?;
            elements = elements.saturating_add(element.count);
        }
    }
    alloc::probe::<u8>(
        elements.saturating_mul(PLY_BYTES_PER_ELEMENT),
        "the PLY file's elements",
    )?;
    // The elements in the header's order, each read by its own type.
    let (mut verts, mut polys) = (None, Vec::new());
    for (name, element) in &header.elements {
        match name.as_str() {
            "vertex" => {
                verts = Some(
                    Parser::<PlyVertex>::new()
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(unreadable)?,
                );
            }
            "face" => {
                polys = Parser::<PlyFace>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(unreadable)?;
            }
            _ => {
                Parser::<Skipped>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(unreadable)?;
            }
        }
    }
    let verts = verts.ok_or_else(|| io_error(path, "PLY file without a 'vertex' element"))?;
    let mut vertices = alloc::with_capacity(verts.len(), "the vertices")?;
    let mut normals = alloc::with_capacity(verts.len(), "the normals")?;
    for v in &verts {
        if v.given & 0b111 != 0b111 {
            return Err(io_error(path, "PLY vertices need x, y and z"));
        }
        let [x, y, z, a, b, c] = v.values;
        vertices.push([x, y, z]);
        if v.given == 0b11_1111 {
            normals.push([a, b, c]);
        }
    }
    let mut faces = alloc::with_capacity(polys.len(), "the faces")?;
    for f in &polys {
        let poly = f
            .indices
            .as_deref()
            .or(f.index.as_deref())
            .ok_or_else(|| io_error(path, "PLY faces need a 'vertex_indices' list"))?;
        fan(poly, &mut faces);
    }
    let normals = (normals.len() == vertices.len()).then_some(normals);
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
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
             end_header\n0 0\n",
        )
        .unwrap();
        assert!(matches!(read_mesh(&path), Err(Error::Io { .. })));
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

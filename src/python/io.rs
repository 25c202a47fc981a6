//! `mcsample.io`: image files (see [`crate::io`]). Reads return float32
//! arrays `(H, W, 3)` (or `(H, W, 4)` for an EXR with alpha); failures raise
//! `OSError` naming the path, wrong arrays `ValueError`.

use super::c_order;
use super::parallel::detached;
use crate::error::{Error, shape_str};
use crate::io::{self, Raster};
use crate::python::Obj;
use numpy::{AllowTypeChange, PyArray1, PyArrayLikeDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::path::{Path, PathBuf};

fn to_numpy<'py>(py: Python<'py>, raster: Raster) -> PyResult<Obj<'py>> {
    let shape = [raster.height, raster.width, raster.channels];
    Ok(PyArray1::from_vec(py, raster.data)
        .reshape(shape)?
        .into_any())
}

fn from_numpy(image: &Obj<'_>) -> PyResult<Raster> {
    let array: PyArrayLikeDyn<'_, f32, AllowTypeChange> = image.extract()?;
    match *array.shape() {
        [height, width, channels @ (3 | 4)] if height > 0 && width > 0 => Ok(Raster {
            width,
            height,
            channels,
            data: c_order::copy(array.as_array(), "a copy of image")?,
        }),
        _ => Err(Error::Shape {
            arg: "image",
            expected: "(H, W, 3) or (H, W, 4) with H, W > 0".into(),
            got: shape_str(array.shape()),
        }
        .into()),
    }
}

/// Reads an OpenEXR file: scanline or tiled, one part or several, half,
/// float or uint channels, compressed by NONE, RLE, ZIPS, ZIP, PIZ, PXR24,
/// B44, B44A, DWAA or DWAB (ZSTD and HTJ2K raise OSError); the largest
/// mip level. At most 2**28 pixels.
///
/// Parameters
/// ----------
/// path : str or os.PathLike
/// layer : str, optional
///     The layer to read: the channels ``layer.R``, ``layer.G``, ... (a
///     part's name counts as a layer name; ``""`` is the channels without
///     one). Default: the channels without a layer name if they hold
///     colour, else the only layer that does (ValueError, listing them,
///     when several do).
///
/// Returns
/// -------
/// ndarray, shape (H, W, 3), or (H, W, 4) if the layer has alpha; float32
/// linear RGB(A), row 0 at the top. Colour is R, G, B (or lowercase r, g,
/// b), else luminance Y repeated in all three.
#[pyfunction]
#[pyo3(signature = (path, layer = None))]
pub fn read_exr<'py>(py: Python<'py>, path: PathBuf, layer: Option<String>) -> PyResult<Obj<'py>> {
    let raster = detached(py, || io::read_exr(&path, layer.as_deref()))?;
    to_numpy(py, raster)
}

/// Reads an 8- or 16-bit PNG as linear RGB(A): sRGB values decoded, alpha
/// kept as stored. At most 2**28 pixels.
///
/// Parameters
/// ----------
/// path : str or os.PathLike
///
/// Returns
/// -------
/// ndarray, shape (H, W, 3), or (H, W, 4) with alpha; float32.
#[pyfunction]
pub fn read_png<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Obj<'py>> {
    let raster = detached(py, || io::read_png(&path))?;
    to_numpy(py, raster)
}

/// Reads an OpenEXR, Radiance HDR or PNG file, told by its first bytes
/// (``read_exr``, ``read_hdr``, ``read_png``).
///
/// Parameters
/// ----------
/// path : str or os.PathLike
/// layer : str, optional
///     For OpenEXR files, as ``read_exr`` (ValueError for other files).
///
/// Returns
/// -------
/// ndarray, shape (H, W, 3) or (H, W, 4), float32 linear RGB(A).
#[pyfunction]
#[pyo3(signature = (path, layer = None))]
pub fn read_image<'py>(
    py: Python<'py>,
    path: PathBuf,
    layer: Option<String>,
) -> PyResult<Obj<'py>> {
    let raster = detached(py, || io::read_image(&path, layer.as_deref()))?;
    to_numpy(py, raster)
}

/// Writes an OpenEXR file, ZIP-compressed (lossless, blocks of 16
/// scanlines), one part, scanlines.
///
/// Parameters
/// ----------
/// path : str or os.PathLike
/// image : array_like, shape (H, W, 3) or (H, W, 4), linear RGB(A)
/// half : bool
///     Write 16-bit half floats instead of 32-bit floats.
#[pyfunction]
#[pyo3(signature = (path, image, half = false))]
pub fn write_exr(py: Python<'_>, path: PathBuf, image: &Obj<'_>, half: bool) -> PyResult<()> {
    let raster = from_numpy(image)?;
    detached(py, || io::write_exr(&path, &raster, half))
}

/// Reads a Radiance RGBE (.hdr) file, with the signature ``#?RADIANCE``
/// or ``#?RGBE`` (as Mitsuba writes it). At most 2**28 pixels.
///
/// Parameters
/// ----------
/// path : str or os.PathLike
///
/// Returns
/// -------
/// ndarray, shape (H, W, 3), float32 linear RGB, row 0 at the top.
#[pyfunction]
pub fn read_hdr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Obj<'py>> {
    let raster = detached(py, || io::read_hdr(&path))?;
    to_numpy(py, raster)
}

/// Writes an 8-bit PNG of a linear image: scaled by 2**exposure, clamped to
/// [0, 1] and sRGB-encoded (alpha is written as is).
///
/// Parameters
/// ----------
/// path : str or os.PathLike
/// image : array_like, shape (H, W, 3) or (H, W, 4), linear RGB(A); NaN is
///     rejected, infinities clamp to white
/// exposure : float
///     In stops (default 0).
/// srgb : bool
///     Apply the sRGB transfer curve (default True); False writes the
///     clamped linear values.
#[pyfunction]
#[pyo3(signature = (path, image, exposure = 0.0, srgb = true))]
pub fn write_png(
    py: Python<'_>,
    path: PathBuf,
    image: &Obj<'_>,
    exposure: f64,
    srgb: bool,
) -> PyResult<()> {
    let (raster, exposure) = png_input(image, exposure)?;
    detached(py, || io::write_png(&path, &raster, exposure, srgb))
}

/// The raster and exposure of a PNG to write, checked.
fn png_input(image: &Obj<'_>, exposure: f64) -> PyResult<(Raster, f32)> {
    if !exposure.is_finite() {
        return Err(Error::Parameter {
            arg: "exposure",
            value: exposure,
            requirement: "must be finite",
        }
        .into());
    }
    Ok((from_numpy(image)?, exposure as f32))
}

/// The PNG file :func:`write_png` writes, as bytes (for notebooks'
/// ``_repr_png_``).
///
/// Parameters
/// ----------
/// image : array_like, shape (H, W, 3) or (H, W, 4), linear RGB(A)
/// exposure : float
///     In stops (default 0).
/// srgb : bool
///     Apply the sRGB transfer curve (default True).
#[pyfunction]
#[pyo3(signature = (image, exposure = 0.0, srgb = true))]
pub fn encode_png<'py>(
    py: Python<'py>,
    image: &Obj<'py>,
    exposure: f64,
    srgb: bool,
) -> PyResult<Bound<'py, PyBytes>> {
    let (raster, exposure) = png_input(image, exposure)?;
    let bytes = detached(py, || {
        io::encode_png(Path::new("image"), &raster, exposure, srgb)
    })?;
    Ok(PyBytes::new(py, &bytes))
}

/// Reads a triangle mesh from a PLY (ASCII or binary) or OBJ file.
///
/// Parameters
/// ----------
/// path : str or os.PathLike
///     A ``.ply`` or ``.obj`` file; polygons are split into triangle fans.
///
/// Returns
/// -------
/// (vertices, faces, normals)
///     float64 ``(N, 3)``, int64 ``(M, 3)`` and float64 ``(N, 3)`` vertex
///     normals, or None when the file has none.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn read_mesh<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<(Obj<'py>, Obj<'py>, Option<Obj<'py>>)> {
    let mesh = detached(py, || crate::render::mesh_file::read_mesh(&path))?;
    // The rows as they are (no copy): numpy takes over the Vec.
    let rows3 = |v: Vec<[f64; 3]>| -> PyResult<Obj<'py>> {
        let n = v.len();
        Ok(PyArray1::from_vec(py, v.into_flattened())
            .reshape([n, 3])?
            .into_any())
    };
    let m = mesh.faces.len();
    let faces = PyArray1::from_vec(py, mesh.faces.into_flattened())
        .reshape([m, 3])?
        .into_any();
    Ok((
        rows3(mesh.vertices)?,
        faces,
        mesh.normals.map(rows3).transpose()?,
    ))
}

/// Registers the io functions in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(encode_png, m)?)?;
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(read_hdr, m)?)?;
    m.add_function(wrap_pyfunction!(read_png, m)?)?;
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(write_png, m)?)?;
    Ok(())
}

//! The inputs of ``EnvMap``: its options (mapping, sampling, `to_world`),
//! its image as an array, and image files.

use crate::alloc;
use crate::envmap::{MAX_TEXELS, Mapping, Matrix3, Options, Sampling};
use crate::error::{Error, check_at_most, shape_str};
use crate::io;
use crate::python::Obj;
use crate::python::args::choice;
use crate::python::arrays::not_numbers;
use numpy::{AllowTypeChange, PyArrayLikeDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use std::path::Path;

/// `mapping`, by the names of [`Mapping::name`].
pub fn mapping_arg(name: &str) -> PyResult<Mapping> {
    let options = [Mapping::LatLong, Mapping::Angular, Mapping::Cube].map(|m| (m.name(), m));
    choice("mapping", name, &options)
}

/// `sampling`, by the names of [`Sampling::name`]; `None` is
/// [`Sampling::default_for`] `mapping`.
pub fn sampling_arg(name: Option<&str>, mapping: Mapping) -> PyResult<Sampling> {
    let Some(name) = name else {
        return Ok(Sampling::default_for(mapping));
    };
    let options =
        [Sampling::Luminance, Sampling::Piecewise, Sampling::Mitsuba].map(|m| (m.name(), m));
    choice("sampling", name, &options)
}

/// `to_world` as a 3×3 rotation: None (identity), a 3×3 or 4×4 array-like
/// (translation ignored) or an object with a ``matrix`` (a Mitsuba
/// transform).
pub fn to_world_arg(ob: Option<&Obj<'_>>) -> PyResult<Matrix3> {
    let Some(ob) = ob.filter(|o| !o.is_none()) else {
        return Ok(Options::default().to_world);
    };
    let py = ob.py();
    let source = match ob.getattr(pyo3::intern!(py, "matrix")) {
        Ok(m) if !ob.hasattr("shape")? => m,
        _ => ob.clone(),
    };
    let array = py
        .import(pyo3::intern!(py, "numpy"))?
        .call_method1(pyo3::intern!(py, "asarray"), (source,))
        .and_then(|a| a.call_method1("astype", ("float64",)))
        .map_err(|e| {
            PyTypeError::new_err(format!(
                "to_world must be a 3x3 or 4x4 matrix or a Mitsuba transform: {e}"
            ))
        })?;
    let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = array.extract()?;
    let shape = array.shape().to_vec();
    // A Mitsuba JIT transform's matrix has a trailing axis of width 1.
    // (The shape is checked before its values are read: a huge array is a
    // shape error, not an allocation.)
    let n = match shape.as_slice() {
        [3, 3] | [3, 3, 1] => 3,
        [4, 4] | [4, 4, 1] => 4,
        _ => {
            return Err(Error::Shape {
                arg: "to_world",
                expected: "(3, 3) or (4, 4)".into(),
                got: shape_str(&shape),
            }
            .into());
        }
    };
    let flat: Vec<f64> = array.as_array().iter().copied().collect();
    if let Some(i) = flat.iter().position(|v| !v.is_finite()) {
        return Err(Error::Element {
            arg: "to_world",
            index: format!("[{}, {}]", i / n, i % n),
            value: flat[i],
            requirement: "must be finite".into(),
        }
        .into());
    }
    Ok(std::array::from_fn(|r| {
        std::array::from_fn(|c| flat[r * n + c])
    }))
}

/// The texels of `image` for `mapping` as `(width, height, array)`: shape
/// `(H, W, 3)`, or `(6, R, R, 3)` for cube maps (faces stacked).
pub fn image_arg<'py>(
    image: &Obj<'py>,
    mapping: Mapping,
) -> PyResult<(usize, usize, PyArrayLikeDyn<'py, f32, AllowTypeChange>)> {
    let array: PyArrayLikeDyn<'py, f32, AllowTypeChange> = image
        .extract()
        .map_err(|e| not_numbers(image.py(), "image", e))?;
    let shape = array.shape().to_vec();
    let (width, height) = match (mapping, shape.as_slice()) {
        (Mapping::Cube, [6, r, r2, 3]) if r == r2 => (*r, 6 * r),
        (Mapping::LatLong | Mapping::Angular, [h, w, 3]) => (*w, *h),
        _ => {
            return Err(Error::Shape {
                arg: "image",
                expected: match mapping {
                    Mapping::Cube => "(6, R, R, 3)".into(),
                    _ => "(H, W, 3)".into(),
                },
                got: shape_str(&shape),
            }
            .into());
        }
    };
    // Checked before the array is copied (a non-contiguous one is).
    check_at_most("image", width * height, MAX_TEXELS)?;
    Ok((width, height, array))
}

/// A file's image for `mapping` ([`io::read_image`]: OpenEXR, of `layer`,
/// Radiance HDR or PNG): RGB (alpha dropped); cube maps as a vertical strip
/// of six faces (6R × R) or a horizontal one (R × 6R), in the order +x,
/// -x, +y, -y, +z, -z.
pub fn read_image(
    path: &Path,
    mapping: Mapping,
    layer: Option<&str>,
) -> crate::Result<(usize, usize, Vec<f32>)> {
    let raster = io::read_image(path, layer)?;
    let rgb: Vec<f32> = if raster.channels == 3 {
        raster.data
    } else {
        let mut rgb = alloc::with_capacity(raster.width * raster.height * 3, "the image")?;
        rgb.extend(
            raster
                .data
                .chunks(raster.channels)
                .flat_map(|px| [px[0], px[1], px[2]]),
        );
        rgb
    };
    let (w, h) = (raster.width, raster.height);
    if mapping != Mapping::Cube || h == 6 * w {
        return Ok((w, h, rgb));
    }
    if w != 6 * h {
        return Err(Error::Io {
            path: path.to_path_buf(),
            message: format!(
                "a cube map file must be a strip of six square faces, 6R x R or R x 6R; got {w} x {h}"
            ),
        });
    }
    // Horizontal strip: face f is columns [f·R, (f + 1)·R).
    let mut stacked = alloc::with_capacity(rgb.len(), "the cube map's faces")?;
    for face in 0..6 {
        for y in 0..h {
            let start = (y * w + face * h) * 3;
            stacked.extend_from_slice(&rgb[start..start + 3 * h]);
        }
    }
    Ok((h, 6 * h, stacked))
}

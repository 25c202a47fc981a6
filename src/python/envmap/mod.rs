//! `mcsample.EnvMap`: environment maps (see [`crate::envmap`]), batched
//! over directions and uniform samples.

mod input;

use super::args::index_arg;
use super::arrays::{Check, Points, PyFloat, output, tuple_outputs, with_precision};
use super::arrays::{writable, zeros};
use super::batch::{map_each, map_into};
use super::c_order;
use super::parallel::{detached, run_batch};
use super::pickle::reduce;
use super::records::record;
use crate::alloc;
use crate::envmap::{EnvMap, EnvSamples, Mapping, Options, TableFloat};
use crate::error::Error;
use crate::io::Raster;
use crate::python::{Obj, Out};
use input::{image_arg, mapping_arg, read_image, sampling_arg, to_world_arg};
use numpy::{PyArray1, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyUserWarning};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple, PyType};
use std::ffi::CString;
use std::path::PathBuf;
use std::sync::Arc;

/// A float type the envmap bindings compute in: a [`PyFloat`] whose
/// sampling-table densities the map keeps ([`TableFloat`]).
trait EnvFloat: PyFloat + TableFloat {}
impl<F: PyFloat + TableFloat> EnvFloat for F {}

record! {
    /// Samples of ``EnvMap.sample``.
    PyEnvSample, "EnvSample", "mcsample._core", {
        /// World directions toward the environment, (N, 3) or (3,), unit.
        direction,
        /// Their densities per steradian, (N,).
        pdf,
        /// Radiance / pdf per RGB channel, (N, 3); 0 where pdf = 0.
        weight,
    }
}

/// An environment map: radiance arriving from every direction (an
/// infinitely distant light), and importance sampling of directions in
/// proportion to its luminance. Every method takes and returns world
/// directions.
///
/// Parameters
/// ----------
/// image : array_like or None
///     Linear RGB radiance, float32 after conversion: (H, W, 3) for
///     "latlong" and "angular" (square), (6, R, R, 3) for "cube"; finite
///     and >= 0. None: the packaged sky (``mcsample.data.sky_path()``).
/// mapping : "latlong" (default), "angular" or "cube"
///     "latlong" is Mitsuba 3's envmap convention (Y up, u = 0 at -Z, u =
///     1/4 at +X, v = theta / pi; texel columns centred at (x + 1/2) / W,
///     rows at v = y / (H - 1)); "angular" is Debevec's light probe (centre
///     +Z, rim -Z, +Y up); "cube" holds the faces +x, -x, +y, -y, +z, -z
///     oriented as OpenGL's.
/// to_world : None, (3, 3) or (4, 4) array_like, or a Mitsuba transform
///     Rotation from the map's frame to the world (translation ignored).
/// scale : float
///     Radiance scale, finite and >= 0.
/// sampling : None (default), "luminance", "piecewise" or "mitsuba"
///     "luminance" (lat-long only; the default for lat-long maps): pdf(d)
///     = Y(eval(d)) / integral of Y over the sphere exactly, Y the
///     luminance, so that env-only sampling of a grey map has one weight
///     for every direction. "piecewise" (the default for angular and cube
///     maps): piecewise-constant over the cells of the bilinear radiance.
///     Both have pdf > 0 wherever eval > 0. "mitsuba" (lat-long only):
///     Mitsuba's bilinear density, equal to its envmap emitter's
///     ``pdf_direction``, sampled by Mitsuba's hierarchical warping: the
///     same ``u`` gives the emitter's direction to float32 precision, but
///     for the rare ``u`` that Mitsuba's float32 arithmetic sends across
///     a boundary of its choices.
/// compensate : bool
///     MIS compensation: the mean luminance is subtracted before the
///     sampling density is built (Karlik et al. 2019), as Mitsuba's
///     ``mis_compensation``. Only for use in MIS. ``render`` needs no
///     compensated map: under MIS it draws every map by its compensated
///     density by itself, and by its own under emitter sampling alone,
///     light tracing and BDPT (where a map given with ``compensate=True``
///     would be biased).
///
/// Everything after ``image`` is keyword-only.
#[pyclass(module = "mcsample._core", name = "EnvMap", frozen)]
pub struct PyEnvMap(Arc<EnvMap>);

/// Whether every coordinate of the direction `x` is finite (the check of
/// the batch methods, inlined into their loops).
#[inline(always)]
fn finite<F: EnvFloat>(x: &[F; 3]) -> bool {
    Check::Finite.holds_all(x)
}

impl PyEnvMap {
    fn build(py: Python<'_>, w: usize, h: usize, data: &[f32], options: Options) -> PyResult<Self> {
        Ok(Self(Arc::new(detached(py, || {
            EnvMap::new(w, h, data, options)
        })?)))
    }

    fn directions<'py, F: EnvFloat, const M: usize>(
        &self,
        py: Python<'py>,
        d: &Obj<'py>,
        kernel: impl Fn(&EnvMap, [f64; 3]) -> [f64; M] + Sync + Send,
    ) -> PyResult<Obj<'py>> {
        let d = Points::<F, 3>::extract(d, "d")?;
        let env = &self.0;
        map_each(py, &d, Check::Finite, |x: [F; 3]| {
            kernel(env, x.map(F::f64)).map(F::c)
        })
    }

    /// `M` values per world direction of `d`, computed in `F` by a batch
    /// method of [`EnvMap`] (`eval_into`, `pdf_into`) that checks with
    /// [`finite`] that every direction is finite, in the same pass; into
    /// `out` when given (see [`output`]).
    fn batch_as<'py, F: EnvFloat, const M: usize>(
        &self,
        py: Python<'py>,
        d: &Obj<'py>,
        out: Out<'_, 'py>,
        kernel: impl Fn(&EnvMap, &[[F; 3]], &mut [[F; M]]) -> bool + Sync + Send,
    ) -> PyResult<Obj<'py>> {
        let d = Points::<F, 3>::extract(d, "d")?;
        let out = output::<F>(py, &d.out_shape(M), out, "out")?;
        {
            let mut guard = writable(&out)?;
            let rows = d.rows();
            let env = &self.0;
            let flat = guard.as_slice_mut()?.as_chunks_mut::<M>().0;
            let valid = run_batch(py, d.n, flat, |range, chunk: &mut [[F; M]]| {
                kernel(env, &rows[range], chunk)
            })?;
            if !valid {
                return Err(d.invalid(Check::Finite));
            }
        }
        out.finish()
    }

    /// Samples for `u`, into the arrays of `out` (direction, pdf, weight)
    /// when given (see [`output`]).
    fn sample_as<'py, F: EnvFloat>(
        &self,
        py: Python<'py>,
        u: &Obj<'py>,
        out: Out<'_, 'py>,
    ) -> PyResult<PyEnvSample> {
        let u = Points::<F, 2>::extract(u, "u")?;
        let (vec_shape, scalar_shape) = (u.out_shape(3), u.out_shape(1));
        let [o_d, o_p, o_w] = tuple_outputs::<3>(out, "direction, pdf, weight")?;
        let direction = output::<F>(py, &vec_shape, o_d.as_ref(), "out[0]")?;
        let pdf = output::<F>(py, &scalar_shape, o_p.as_ref(), "out[1]")?;
        let weight = output::<F>(py, &vec_shape, o_w.as_ref(), "out[2]")?;
        {
            let (mut g_d, mut g_p, mut g_w) =
                (writable(&direction)?, writable(&pdf)?, writable(&weight)?);
            let outputs = (
                g_d.as_slice_mut()?.as_chunks_mut::<3>().0,
                g_p.as_slice_mut()?,
                g_w.as_slice_mut()?.as_chunks_mut::<3>().0,
            );
            let rows = u.rows();
            let env = &self.0;
            let valid = run_batch(py, u.n, outputs, |range, (o_d, o_p, o_w)| {
                let mut ok = true;
                let (zero, one) = (F::zero(), F::one());
                let out = EnvSamples {
                    direction: o_d,
                    pdf: o_p,
                    weight: o_w,
                };
                let check = |x: &[F; 2]| {
                    ok &= Check::Unit.holds_all(x);
                    x.map(|v| v.max(zero).min(one))
                };
                env.sample_rows(&rows[range], check, out);
                ok
            })?;
            if !valid {
                return Err(u.invalid(Check::Unit));
            }
        }
        Ok(PyEnvSample::new(
            direction.finish()?,
            pdf.finish()?,
            weight.finish()?,
        ))
    }

    fn uv_to_dir_as<'py, F: EnvFloat>(&self, py: Python<'py>, uv: &Obj<'py>) -> PyResult<Obj<'py>> {
        let uv = Points::<F, 2>::extract(uv, "uv")?;
        let env = &self.0;
        let bounds = [[0.0, 1.0], [0.0, env.options().mapping.t_max()]];
        map_into(
            py,
            &uv,
            Check::Within(bounds),
            None,
            #[inline(always)]
            |p: [F; 2]| env.uv_to_dir(p.map(F::f64)).map(F::c),
        )
    }
}

#[pymethods]
impl PyEnvMap {
    #[new]
    #[pyo3(signature = (image = None, *, mapping = "latlong", to_world = None, scale = 1.0, sampling = None, compensate = false))]
    fn new(
        py: Python<'_>,
        image: Option<&Obj<'_>>,
        mapping: &str,
        to_world: Option<&Obj<'_>>,
        scale: f64,
        sampling: Option<&str>,
        compensate: bool,
    ) -> PyResult<Self> {
        let mapping = mapping_arg(mapping)?;
        let options = Options {
            mapping,
            to_world: to_world_arg(to_world)?,
            scale,
            sampling: sampling_arg(sampling, mapping)?,
            compensate,
        };
        let Some(image) = image.filter(|i| !i.is_none()) else {
            if options.mapping != Mapping::LatLong {
                return Err(Error::Choice {
                    arg: "mapping",
                    value: options.mapping.name().into(),
                    requirement: "the packaged sky (image=None) is lat-long; convert() it".into(),
                }
                .into());
            }
            let path: PathBuf = py
                .import("mcsample.data")?
                .call_method0("sky_path")?
                .extract()?;
            let (w, h, data) = detached(py, || read_image(&path, Mapping::LatLong, None))?;
            return Self::build(py, w, h, &data, options);
        };
        let (w, h, array) = image_arg(image, options.mapping)?;
        // Read a C-ordered array in place; copy anything else once.
        match array.as_slice().ok().filter(|_| array.is_c_contiguous()) {
            Some(data) => Self::build(py, w, h, data, options),
            None => {
                let data = c_order::copy_to_buffer(array.as_array(), "a copy of image")?;
                Self::build(py, w, h, &data, options)
            }
        }
    }

    /// Reads an environment map from an OpenEXR, Radiance .hdr or PNG file
    /// (told by its first bytes; alpha is dropped; PNG's sRGB values are
    /// decoded to linear). ``layer`` picks an EXR layer (as
    /// ``mcsample.io.read_exr``). Cube maps are a strip of six square
    /// faces, vertical (6R x R) or horizontal (R x 6R), in the order +x,
    /// -x, +y, -y, +z, -z. The other parameters are as for ``EnvMap``, and
    /// keyword-only (and checked as ``EnvMap`` checks them).
    ///
    /// Negative values (which compression and resampling leave in many
    /// files) are clamped to 0, as renderers do, with a ``UserWarning``
    /// giving their count and the most negative; NaN or infinite values
    /// are refused (ValueError). Raises OSError naming the path for a file
    /// that cannot be read.
    #[classmethod]
    #[pyo3(
        signature = (path, **options),
        text_signature = "(path, *, layer=None, mapping='latlong', to_world=None, scale=1.0, sampling=None, compensate=False)"
    )]
    fn load<'py>(
        cls: &Bound<'py, PyType>,
        path: PathBuf,
        options: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Obj<'py>> {
        let py = cls.py();
        let mapping = match options
            .map(|o| o.get_item("mapping"))
            .transpose()?
            .flatten()
        {
            Some(name) => mapping_arg(&name.extract::<String>()?)?,
            None => Mapping::LatLong,
        };
        let layer: Option<String> = match options {
            Some(o) => match o.get_item("layer")? {
                Some(l) => {
                    o.del_item("layer")?;
                    l.extract()?
                }
                None => None,
            },
            None => None,
        };
        let (w, h, mut data) = detached(py, || read_image(&path, mapping, layer.as_deref()))?;
        let (negative, lowest) =
            data.iter_mut()
                .filter(|v| **v < 0.0)
                .fold((0usize, 0.0f32), |(n, low), v| {
                    let low = low.min(*v);
                    *v = 0.0;
                    (n + 1, low)
                });
        if negative > 0 {
            let message = format!(
                "{}: {negative} negative values (the lowest {lowest}) clamped to 0",
                path.display()
            );
            PyErr::warn(
                py,
                &py.get_type::<PyUserWarning>(),
                &CString::new(message)?,
                1,
            )?;
        }
        // The constructor's layout: (6, R, R, 3) for a cube map's stacked
        // faces, (H, W, 3) otherwise.
        let shape = if mapping == Mapping::Cube {
            vec![6, w, w, 3]
        } else {
            vec![h, w, 3]
        };
        let image = PyArray1::from_vec(py, data).reshape(shape)?;
        cls.call((image,), options)
    }

    /// Radiance arriving from world directions d, per RGB channel.
    ///
    /// Parameters
    /// ----------
    /// d : array_like, shape (N, 3) or (3,), directions of any length (only
    ///     the direction counts; float32 lengths below about 1e-19 lose
    ///     precision in their squares)
    /// out : ndarray, optional, keyword only
    ///     Array to write into (the result's shape and dtype, C-ordered), as
    ///     numpy's ufuncs take; saves allocating a fresh result per call.
    ///
    /// Returns
    /// -------
    /// ndarray, shape (N, 3) or (3,), in d's precision (and computed in
    /// it: for float32 directions the place on the map is good to a few
    /// float32 ulps, as in Mitsuba's float32 variants).
    #[pyo3(signature = (d, *, out = None))]
    fn eval<'py>(&self, py: Python<'py>, d: &Obj<'py>, out: Out<'_, 'py>) -> PyResult<Obj<'py>> {
        with_precision!(d, F => self.batch_as::<F, 3>(py, d, out, |env, d, out| {
            env.eval_into(d, out, finite::<F>)
        }))
    }

    /// The density of ``sample`` at world directions d, per steradian.
    ///
    /// Parameters
    /// ----------
    /// d : array_like, shape (N, 3) or (3,), directions of any length (only
    ///     the direction counts; float32 lengths below about 1e-19 lose
    ///     precision in their squares)
    /// out : ndarray, optional, keyword only
    ///     Array to write into, shape (N,), of d's dtype (as for ``eval``).
    ///
    /// Returns
    /// -------
    /// ndarray, shape (N,) (a scalar for one direction), in d's precision.
    #[pyo3(signature = (d, *, out = None))]
    fn pdf<'py>(&self, py: Python<'py>, d: &Obj<'py>, out: Out<'_, 'py>) -> PyResult<Obj<'py>> {
        with_precision!(d, F => self.batch_as::<F, 1>(py, d, out, |env, d, out| {
            env.pdf_into(d, out.as_flattened_mut(), finite::<F>)
        }))
    }

    /// Directions drawn with density ``pdf``.
    ///
    /// Parameters
    /// ----------
    /// u : array_like, shape (N, 2) or (2,), values in [0, 1]
    /// out : tuple of three ndarrays, optional, keyword only
    ///     ``(direction, pdf, weight)`` to write into, of shapes (N, 3),
    ///     (N,) and (N, 3) and u's dtype, as numpy's ufuncs with several
    ///     results take; the EnvSample then holds these arrays.
    ///
    /// Returns
    /// -------
    /// EnvSample
    ///     ``.direction`` (N, 3), ``.pdf`` (N,) per steradian, ``.weight``
    ///     (N, 3) = eval / pdf (0 where pdf = 0), in u's precision.
    #[pyo3(signature = (u, *, out = None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        u: &Obj<'py>,
        out: Out<'_, 'py>,
    ) -> PyResult<PyEnvSample> {
        with_precision!(u, F => self.sample_as::<F>(py, u, out))
    }

    /// The map coordinates (u, v) that look along world directions d:
    /// lat-long as Mitsuba (u in [0, 1), v = theta / pi); angular, the
    /// image position (u to the right, v down, both in [0, 1]); cube, u
    /// across the face and v = face + position down the face, in [0, 6).
    ///
    /// Parameters
    /// ----------
    /// d : array_like, shape (N, 3) or (3,)
    ///
    /// Returns
    /// -------
    /// ndarray, shape (N, 2) or (2,).
    fn dir_to_uv<'py>(&self, py: Python<'py>, d: &Obj<'py>) -> PyResult<Obj<'py>> {
        with_precision!(d, F => self.directions::<F, 2>(py, d, |e, x| e.dir_to_uv(x)))
    }

    /// The world directions at map coordinates uv (see ``dir_to_uv``).
    ///
    /// Parameters
    /// ----------
    /// uv : array_like, shape (N, 2) or (2,); u in [0, 1], v in [0, 1]
    ///     ([0, 6] for cube maps)
    ///
    /// Returns
    /// -------
    /// ndarray, shape (N, 3) or (3,), unit vectors.
    fn uv_to_dir<'py>(&self, py: Python<'py>, uv: &Obj<'py>) -> PyResult<Obj<'py>> {
        with_precision!(uv, F => self.uv_to_dir_as::<F>(py, uv))
    }

    /// The same light in another parameterisation: every new texel takes
    /// this map's bilinear value in its direction.
    ///
    /// Parameters
    /// ----------
    /// mapping : "latlong", "angular" or "cube"
    /// resolution : int or (height, width)
    ///     Lat-long: width W (height W // 2, at least 3) or (H, W);
    ///     angular: R (R x R); cube: the face size R.
    ///
    /// Returns
    /// -------
    /// EnvMap with the same to_world, scale and compensate (and sampling,
    /// where the new mapping has it).
    fn convert(&self, py: Python<'_>, mapping: &str, resolution: &Obj<'_>) -> PyResult<Self> {
        let mapping = mapping_arg(mapping)?;
        let side = |ob: &Obj<'_>| index_arg(ob, "resolution", 1, 1 << 15);
        let (w, h) = match resolution.extract::<(Obj<'_>, Obj<'_>)>() {
            Ok((h, w)) if mapping == Mapping::LatLong => (side(&w)? as usize, side(&h)? as usize),
            Ok(_) => {
                return Err(PyTypeError::new_err(
                    "resolution is a single int R for angular and cube maps",
                ));
            }
            Err(_) => {
                let r = side(resolution)? as usize;
                match mapping {
                    Mapping::LatLong => (r, (r / 2).max(3)),
                    Mapping::Angular => (r, r),
                    Mapping::Cube => (r, 6 * r),
                }
            }
        };
        if w == 0 || h == 0 || w.saturating_mul(h) > 1 << 28 {
            return Err(Error::Integer {
                arg: "resolution",
                value: format!("({h}, {w})"),
                requirement: "must give between 1 and 2**28 texels".into(),
            }
            .into());
        }
        let env = &self.0;
        Ok(Self(Arc::new(detached(py, || env.convert(mapping, w, h))?)))
    }

    /// The texels, float32: (H, W, 3), or (6, R, R, 3) for cube maps (tiny
    /// lat-long maps as padded).
    #[getter]
    fn image<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let img = self.0.image();
        let (w, h) = (img.width(), img.height());
        let array = match self.0.options().mapping {
            Mapping::Cube => zeros::<f32>(py, &[6, w, w, 3])?,
            _ => zeros::<f32>(py, &[h, w, 3])?,
        };
        array
            .readwrite()
            .as_slice_mut()?
            .copy_from_slice(img.texels().as_flattened());
        Ok(array.into_any())
    }

    /// "latlong", "angular" or "cube".
    #[getter]
    fn mapping(&self) -> &'static str {
        self.0.options().mapping.name()
    }

    /// "piecewise" or "mitsuba".
    #[getter]
    fn sampling(&self) -> &'static str {
        self.0.options().sampling.name()
    }

    /// The radiance scale.
    #[getter]
    fn scale(&self) -> f64 {
        self.0.options().scale
    }

    /// Whether MIS compensation was asked for.
    #[getter]
    fn compensate(&self) -> bool {
        self.0.options().compensate
    }

    /// The local-to-world rotation, (3, 3) float64.
    #[getter]
    fn to_world<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let m = self.0.options().to_world;
        Ok(PyArray1::from_vec(py, m.concat())
            .reshape([3, 3])?
            .into_any())
    }

    /// The map as a PNG (tone-mapped as ``io.write_png``: clamped, sRGB),
    /// for notebooks: lat-long and angular maps as they are stored, the six
    /// faces of a cube map side by side (+x, -x, +y, -y, +z, -z).
    fn _repr_png_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let img = self.0.image();
        let (w, h) = (img.width(), img.height());
        let scale = self.0.options().scale as f32;
        let texels = img.texels();
        let raster = if self.0.options().mapping == Mapping::Cube {
            // Face f's row y, texel x sits at column f w + x of row y.
            let mut data = alloc::filled(6 * w * w * 3, 0.0f32, "the PNG's pixels")?;
            for (k, t) in texels.iter().enumerate() {
                let (f, y, x) = (k / (w * w), (k / w) % w, k % w);
                let at = 3 * (y * 6 * w + f * w + x);
                data[at..at + 3].copy_from_slice(&t.map(|v| v * scale));
            }
            Raster {
                width: 6 * w,
                height: w,
                channels: 3,
                data,
            }
        } else {
            let mut data = alloc::with_capacity(texels.len() * 3, "the PNG's pixels")?;
            data.extend(texels.iter().flat_map(|t| t.map(|v| v * scale)));
            Raster {
                width: w,
                height: h,
                channels: 3,
                data,
            }
        };
        let png = detached(py, || {
            crate::io::encode_png(std::path::Path::new("EnvMap"), &raster, 0.0, true)
        })?;
        Ok(PyBytes::new(py, &png))
    }

    /// Pickles as its image and options (the tables are built again, to
    /// the same bits).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let py = slf.py();
        let kwargs = PyDict::new(py);
        for key in ["mapping", "sampling", "scale", "compensate", "to_world"] {
            kwargs.set_item(key, slf.getattr(key)?)?;
        }
        let image = slf.getattr("image")?;
        reduce(slf.as_any(), None, PyTuple::new(py, [image])?, Some(kwargs))
    }

    fn __repr__(&self) -> String {
        let (img, o) = (self.0.image(), self.0.options());
        format!(
            "EnvMap(mapping={:?}, resolution={}x{}, scale={}, sampling={:?}, compensate={})",
            o.mapping.name(),
            img.width(),
            img.height(),
            o.scale,
            o.sampling.name(),
            if o.compensate { "True" } else { "False" }
        )
    }
}

impl PyEnvMap {
    /// The core map (for the estimators' and the scene's bindings), shared.
    pub fn inner(&self) -> &Arc<EnvMap> {
        &self.0
    }
}

//! `mcsample.Phong`: the energy-normalised Phong BRDF of [`crate::phong`],
//! batched over directions.

use super::args::{choice, three_floats};
use super::arrays::{Check, Points, PyFloat, result_shape, with_precision, zeros};
use super::batch::{map_pair, pair_shape, run_batch_pair};
use super::pickle::reduce;
use crate::phong::{Phong, PhongSamples, Selection};
use crate::python::Obj;
use numpy::PyArrayMethods;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::records::record;

record! {
    /// Samples of ``Phong.sample``.
    PyPhongSample, "PhongSample", "mcsample._core", {
        /// Sampled directions, (N, 3) or (3,), local frame (normal +z).
        wo,
        /// Their densities per steradian (the mixture of both parts), (N,).
        pdf,
        /// f_r(wi, wo) cos(theta_o) / pdf per RGB channel, (N, 3); 0 below
        /// the surface.
        weight,
        /// 0 where the diffuse part drew the sample, 1 for the glossy part,
        /// (N,) int64.
        component,
    }
}

/// The energy-normalised modified Phong BRDF (Lafortune and Willems):
/// f_r(wi, wo) = rho_d / pi + rho_s (n + 2) / (2 pi) max(0, cos alpha)^n,
/// alpha the angle between wo and the mirror direction of wi; 0 when wi or
/// wo is below the surface. Directions are in the local frame (normal +z),
/// ``wi`` toward the viewer, unit length.
///
/// Sampling picks the diffuse part (a cosine-weighted direction) with
/// probability ``diffuse_probability`` and otherwise the glossy part (a
/// cos^n lobe around the mirror direction); the pdf of every sample is the
/// mixture of both densities.
///
/// Parameters
/// ----------
/// diffuse, specular : float or (3,) RGB
///     rho_d and rho_s, >= 0, with rho_d + rho_s <= 1 in every channel.
/// exponent : float in [0, 1e30]
/// selection : "max" (default) or "luminance", keyword only
///     How the diffuse probability is chosen: max(rho_d) / (max(rho_d) +
///     max(rho_s)) over channels, or the same with Rec. 709 luminance
///     (Mitsuba 0.6's rule).
#[pyclass(module = "mcsample._core", name = "Phong", frozen)]
pub struct PyPhong(Phong, &'static str);

impl PyPhong {
    fn pair<'py, F: PyFloat, const M: usize>(
        &self,
        py: Python<'py>,
        wi: &Obj<'py>,
        wo: &Obj<'py>,
        kernel: impl Fn(&Phong, [F; 3], [F; 3]) -> [F; M] + Sync + Send,
    ) -> PyResult<Obj<'py>> {
        let wi = Points::<F, 3>::extract(wi, "wi")?;
        let wo = Points::<F, 3>::extract(wo, "wo")?;
        let phong = &self.0;
        map_pair(
            py,
            (&wi, Check::Finite),
            (&wo, Check::Finite),
            #[inline(always)]
            |a, b| kernel(phong, a, b),
        )
    }
}

#[pymethods]
impl PyPhong {
    #[new]
    #[pyo3(signature = (diffuse, specular, exponent, *, selection = "max"))]
    fn new(
        diffuse: &Obj<'_>,
        specular: &Obj<'_>,
        exponent: f64,
        selection: &str,
    ) -> PyResult<Self> {
        let (selection, name) = choice(
            "selection",
            selection,
            &[
                ("max", (Selection::Max, "max")),
                ("luminance", (Selection::Luminance, "luminance")),
            ],
        )?;
        let (d, s) = (
            three_floats(diffuse, "diffuse", true)?,
            three_floats(specular, "specular", true)?,
        );
        Ok(Self(Phong::new(d, s, exponent, selection)?, name))
    }

    /// BRDF values f_r(wi, wo) per RGB channel, without the cosine.
    ///
    /// Parameters
    /// ----------
    /// wi, wo : array_like, shape (N, 3) or (3,), unit vectors (a single
    ///     direction broadcasts)
    ///
    /// Returns
    /// -------
    /// ndarray, shape (N, 3) or (3,), per steradian.
    fn eval<'py>(&self, py: Python<'py>, wi: &Obj<'py>, wo: &Obj<'py>) -> PyResult<Obj<'py>> {
        with_precision!(wo, F => self.pair::<F, 3>(py, wi, wo, #[inline(always)] |p, a, b| p.eval(a, b)))
    }

    /// The density of ``sample`` at wo for wi, per steradian.
    ///
    /// Parameters
    /// ----------
    /// wi, wo : array_like, shape (N, 3) or (3,), unit vectors
    ///
    /// Returns
    /// -------
    /// ndarray, shape (N,) (a scalar for single directions).
    fn pdf<'py>(&self, py: Python<'py>, wi: &Obj<'py>, wo: &Obj<'py>) -> PyResult<Obj<'py>> {
        with_precision!(wo, F => self.pair::<F, 1>(py, wi, wo, #[inline(always)] |p, a, b| [p.pdf(a, b)]))
    }

    /// Directions drawn for wi.
    ///
    /// Parameters
    /// ----------
    /// wi : array_like, shape (N, 3) or (3,), unit vectors (one broadcasts)
    /// u : array_like, shape (N, 3) or (3,), values in [0, 1]: u[:, 2] picks
    ///     the part, u[:, :2] place the direction
    ///
    /// Returns
    /// -------
    /// PhongSample
    ///     ``.wo`` (N, 3), ``.pdf`` (N,), ``.weight`` (N, 3), ``.component``
    ///     (N,) int64, in u's precision.
    fn sample<'py>(&self, py: Python<'py>, wi: &Obj<'py>, u: &Obj<'py>) -> PyResult<PyPhongSample> {
        with_precision!(u, F => self.sample_as::<F>(py, wi, u))
    }

    /// The probability of sampling the diffuse part.
    #[getter]
    fn diffuse_probability(&self) -> f64 {
        self.0.diffuse_probability()
    }

    /// rho_d (RGB).
    #[getter]
    fn diffuse(&self) -> [f64; 3] {
        self.0.diffuse()
    }

    /// rho_s (RGB).
    #[getter]
    fn specular(&self) -> [f64; 3] {
        self.0.specular()
    }

    /// The lobe exponent n.
    #[getter]
    fn exponent(&self) -> f64 {
        self.0.exponent()
    }

    fn __repr__(&self) -> String {
        format!(
            "Phong(diffuse={:?}, specular={:?}, exponent={})",
            self.0.diffuse(),
            self.0.specular(),
            self.0.exponent()
        )
    }

    /// Pickles as the parameters it was built from.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let py = slf.py();
        let this = slf.get();
        let args = (this.0.diffuse(), this.0.specular(), this.0.exponent());
        let kwargs = PyDict::new(py);
        kwargs.set_item("selection", this.1)?;
        reduce(slf.as_any(), None, args.into_pyobject(py)?, Some(kwargs))
    }
}

impl PyPhong {
    /// The core BRDF (for the estimators' bindings).
    pub fn inner(&self) -> &Phong {
        &self.0
    }

    fn sample_as<'py, F: PyFloat>(
        &self,
        py: Python<'py>,
        wi: &Obj<'py>,
        u: &Obj<'py>,
    ) -> PyResult<PyPhongSample> {
        let wi = Points::<F, 3>::extract(wi, "wi")?;
        let u = Points::<F, 3>::extract(u, "u")?;
        let batch = pair_shape(&wi, &u)?;
        let n = batch.iter().product();
        let (vec_shape, scalar_shape) = (result_shape(&batch, 3), result_shape(&batch, 1));
        let wo = zeros::<F>(py, &vec_shape)?;
        let pdf = zeros::<F>(py, &scalar_shape)?;
        let weight = zeros::<F>(py, &vec_shape)?;
        let component = zeros::<i64>(py, &scalar_shape)?;
        {
            let (mut g_wo, mut g_pdf) = (wo.readwrite(), pdf.readwrite());
            let (mut g_w, mut g_c) = (weight.readwrite(), component.readwrite());
            let outputs = (
                g_wo.as_slice_mut()?.as_chunks_mut::<3>().0,
                g_pdf.as_slice_mut()?,
                g_w.as_slice_mut()?.as_chunks_mut::<3>().0,
                g_c.as_slice_mut()?,
            );
            let (rows_wi, rows_u) = (wi.rows(), u.rows());
            let (step_wi, step_u) = (usize::from(wi.n != 1), usize::from(u.n != 1));
            let phong = &self.0;
            let (ok_wi, ok_u) =
                run_batch_pair(py, n, outputs, |range, (o_wo, o_pdf, o_w, o_c)| {
                    if step_wi == 0 {
                        // One wi for all rows: the core's vectorised batch.
                        let w = rows_wi[0];
                        // A single u (then n = 1) or one per row.
                        let inputs = if step_u == 0 {
                            &rows_u[..1]
                        } else {
                            &rows_u[range]
                        };
                        let mut ok_u = true;
                        let check = |x: &[F; 3]| {
                            ok_u &= Check::Unit.holds_all(x);
                            *x
                        };
                        let out = PhongSamples {
                            wo: o_wo,
                            pdf: o_pdf,
                            weight: o_w,
                            component: o_c,
                        };
                        phong.view(w).sample_rows(inputs, check, out);
                        return (Check::Finite.holds_all(&w), ok_u);
                    }
                    let (mut ok_wi, mut ok_u) = (true, true);
                    for (k, i) in range.enumerate() {
                        let (w, x) = (rows_wi[i], rows_u[i * step_u]);
                        ok_wi &= Check::Finite.holds_all(&w);
                        ok_u &= Check::Unit.holds_all(&x);
                        let s = phong.sample(w, x);
                        (o_wo[k], o_pdf[k], o_w[k], o_c[k]) =
                            (s.wo, s.pdf, s.weight, i64::from(s.component));
                    }
                    (ok_wi, ok_u)
                })?;
            if !ok_wi {
                return Err(wi.invalid(Check::Finite));
            }
            if !ok_u {
                return Err(u.invalid(Check::Unit));
            }
        }
        PyPhongSample::finished(wo, pdf, weight, component)
    }
}

//! `mcsample.Frame`: orthonormal frames around one normal or a batch of
//! normals (see [`crate::frame`]).

use super::arrays::{Check, Points, PyFloat, broadcast, finish, position, result_shape};
use super::arrays::{with_precision, zeros};
use super::batch::map_into;
use super::parallel::run_batch;
use super::pickle::reduce;
use crate::alloc;
use crate::error::{Error, shape_str};
use crate::frame::Frame;
use crate::math::Real;
use crate::python::Obj;
use numpy::PyArrayMethods;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// An orthonormal frame (s, t, n) around a normal, built without a branch
/// that breaks near +-z (Duff et al. 2017); right-handed, s x t = n. The
/// local shading frame of mcsample has the normal along +z: ``to_local``
/// gives a vector's coordinates (v.s, v.t, v.n), ``to_world`` maps them
/// back.
///
/// Parameters
/// ----------
/// normal : array_like, shape (3,) or (N, 3)
///     One normal, or one per row of the vectors to transform. Normalised
///     here; must be finite and non-zero.
#[pyclass(module = "mcsample._core", name = "Frame", frozen)]
pub struct PyFrame {
    frames: Vec<Frame<f64>>,
    /// The normals' batch shape; empty for one normal given as `(3,)`.
    batch: Vec<usize>,
}

fn cast<F: Real>(f: &Frame<f64>) -> Frame<F> {
    let c = |v: [f64; 3]| v.map(F::c);
    Frame {
        s: c(f.s),
        t: c(f.t),
        n: c(f.n),
    }
}

impl PyFrame {
    /// `op(frame, v)` for every row: one frame for all rows, or frame i for
    /// row i (one row of `v` serves every frame).
    fn apply<'py, F: PyFloat>(
        &self,
        py: Python<'py>,
        v: &Obj<'py>,
        op: fn(&Frame<F>, [F; 3]) -> [F; 3],
    ) -> PyResult<Obj<'py>> {
        let v = Points::<F, 3>::extract(v, "v")?;
        let frames = alloc::collect(self.frames.iter().map(cast), "the frames")?;
        if self.batch.is_empty() {
            let f = frames[0];
            return map_into(
                py,
                &v,
                Check::Finite,
                None,
                #[inline(always)]
                move |x| op(&f, x),
            );
        }
        let batch =
            broadcast(("normal", &self.batch), ("v", &v.batch)).map_err(|_| Error::Shape {
                arg: "v",
                expected: format!("{} or (3,), one row per normal", shape_str(&self.shape())),
                got: shape_str(&v.out_shape(3)),
            })?;
        let n = batch.iter().product();
        let (step_f, step_v) = (usize::from(frames.len() != 1), usize::from(v.n != 1));
        let out = zeros::<F>(py, &result_shape(&batch, 3))?;
        {
            let mut guard = out.readwrite();
            let rows = guard.as_slice_mut()?.as_chunks_mut::<3>().0;
            let inputs = v.rows();
            let valid = run_batch(py, n, rows, |range, chunk: &mut [[F; 3]]| {
                let mut ok = true;
                for (k, i) in range.enumerate() {
                    let x = inputs[i * step_v];
                    ok &= x.iter().all(|c| c.is_finite());
                    chunk[k] = op(&frames[i * step_f], x);
                }
                ok
            })?;
            if !valid {
                return Err(v.invalid(Check::Finite));
            }
        }
        finish(out)
    }

    /// The shape of one axis for every frame: the normals' shape.
    fn shape(&self) -> Vec<usize> {
        result_shape(&self.batch, 3)
    }

    fn axis<'py>(&self, py: Python<'py>, pick: fn(&Frame<f64>) -> [f64; 3]) -> PyResult<Obj<'py>> {
        let out = zeros::<f64>(py, &self.shape())?;
        {
            let mut guard = out.readwrite();
            let flat = guard.as_slice_mut()?;
            for (row, f) in flat.as_chunks_mut::<3>().0.iter_mut().zip(&self.frames) {
                *row = pick(f);
            }
        }
        finish(out)
    }
}

#[pymethods]
impl PyFrame {
    #[new]
    fn new(normal: &Obj<'_>) -> PyResult<Self> {
        let normals = Points::<f64, 3>::extract(normal, "normal")?;
        let mut frames = alloc::with_capacity(normals.n, "the frames")?;
        for (i, n) in normals.rows().iter().enumerate() {
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if !(len.is_finite() && len > 0.0) {
                return Err(Error::Element {
                    arg: "normal",
                    index: position(&normals.batch, i, None),
                    value: len,
                    requirement: "the normal must be finite and non-zero (this is its length)"
                        .into(),
                }
                .into());
            }
            frames.push(Frame::from_normal(n.map(|c| c / len)));
        }
        Ok(PyFrame {
            frames,
            batch: normals.batch,
        })
    }

    /// Local coordinates (v.s, v.t, v.n) of world vectors ``v``.
    ///
    /// Parameters
    /// ----------
    /// v : array_like, shape (N, 3) or (3,)
    ///     With a batch of N normals, one row per normal (or one (3,) vector
    ///     for all).
    ///
    /// Returns
    /// -------
    /// ndarray, shape of the batch (N, 3) or (3,), in v's precision.
    fn to_local<'py>(&self, py: Python<'py>, v: &Obj<'py>) -> PyResult<Obj<'py>> {
        with_precision!(v, F => self.apply::<F>(py, v, |f, x| f.to_local(x)))
    }

    /// World vectors v.x s + v.y t + v.z n from local coordinates ``v``.
    ///
    /// Parameters
    /// ----------
    /// v : array_like, shape (N, 3) or (3,)
    ///
    /// Returns
    /// -------
    /// ndarray, shape of the batch (N, 3) or (3,), in v's precision.
    fn to_world<'py>(&self, py: Python<'py>, v: &Obj<'py>) -> PyResult<Obj<'py>> {
        with_precision!(v, F => self.apply::<F>(py, v, |f, x| f.to_world(x)))
    }

    /// First tangent(s), shape (3,) or (N, 3).
    #[getter]
    fn s<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        self.axis(py, |f| f.s)
    }

    /// Second tangent(s), shape (3,) or (N, 3).
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        self.axis(py, |f| f.t)
    }

    /// The unit normal(s), shape (3,) or (N, 3).
    #[getter]
    fn n<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        self.axis(py, |f| f.n)
    }

    fn __len__(&self) -> usize {
        self.frames.len()
    }

    /// The frames of `frames` (`(..., 9)`: s, t and n of each), the
    /// unpickling constructor (frames made once, copied bit for bit).
    #[doc(hidden)]
    #[staticmethod]
    fn _from_frames(frames: &Obj<'_>) -> PyResult<Self> {
        let rows = Points::<f64, 9>::extract(frames, "frames")?;
        let frames = alloc::collect(
            rows.rows().iter().map(|r| Frame {
                s: [r[0], r[1], r[2]],
                t: [r[3], r[4], r[5]],
                n: [r[6], r[7], r[8]],
            }),
            "the frames",
        )?;
        Ok(PyFrame {
            frames,
            batch: rows.batch,
        })
    }

    /// Pickles as its frames.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Obj<'py>> {
        let py = slf.py();
        let this = slf.get();
        let mut flat = alloc::with_capacity(9 * this.frames.len(), "the frames")?;
        flat.extend(this.frames.iter().flat_map(|f| [f.s, f.t, f.n]).flatten());
        let mut shape = this.batch.clone();
        shape.push(9);
        let frames = numpy::PyArray1::from_vec(py, flat).reshape(shape)?;
        reduce(
            slf.as_any(),
            Some("_from_frames"),
            PyTuple::new(py, [frames])?,
            None,
        )
    }

    fn __repr__(&self) -> String {
        match (self.batch.is_empty(), self.frames.first()) {
            (true, Some(f)) => format!("Frame(n={:?})", f.n),
            _ => format!("Frame({} normals)", self.frames.len()),
        }
    }
}

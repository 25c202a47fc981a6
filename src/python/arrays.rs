//! Array conventions of every binding, written once:
//!
//! - any array-like is accepted (lists, ints, float16, non-contiguous views);
//! - float32 input is computed and returned in float32, anything else in
//!   float64 ([`with_precision!`]);
//! - batches are sample-major `(N, K)`; a single `(K,)` point (or a scalar
//!   for `K = 1`) gives an unbatched result;
//! - shape and value errors name the argument and the first offending index;
//! - outputs are fresh numpy arrays, filled with the GIL released.

use super::parallel::run_batch;
use crate::error::{Error, shape_str};
use crate::math::Real;
use crate::simd::{STREAM_MIN_BYTES, map_rows};
use numpy::PyReadwriteArrayDyn;
use numpy::{AllowTypeChange, Element, PyArray, PyArrayDescrMethods, PyArrayDyn, PyArrayLikeDyn};
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// A float type the bindings compute in: `f32` or `f64`, readable from
/// Python and storable in numpy arrays.
pub trait PyFloat:
    Element + Real + crate::envmap::TableFloat + for<'a, 'py> FromPyObject<'a, 'py>
{
}
impl PyFloat for f32 {}
impl PyFloat for f64 {}

/// Whether `ob` is a float32 array or numpy float32 scalar.
pub fn is_float32(ob: &Bound<'_, PyAny>) -> bool {
    ob.getattr(pyo3::intern!(ob.py(), "dtype"))
        .ok()
        .and_then(|d| d.cast_into::<numpy::PyArrayDescr>().ok())
        .is_some_and(|d| d.is_equiv_to(&numpy::dtype::<f32>(ob.py())))
}

/// Evaluates `$body` with the type alias `$F` set to `f32` if `$ob` is
/// float32 data, else to `f64`: one generic kernel, two precisions.
macro_rules! with_precision {
    ($ob:expr, $F:ident => $body:expr) => {
        if $crate::python::arrays::is_float32($ob) {
            type $F = f32;
            $body
        } else {
            type $F = f64;
            $body
        }
    };
}
pub(crate) use with_precision;

/// An integer argument in `[min, max]`; values outside (however large)
/// raise ValueError (never OverflowError), non-integers TypeError.
pub fn index_arg(ob: &Bound<'_, PyAny>, arg: &'static str, min: u64, max: u64) -> PyResult<u64> {
    let py = ob.py();
    let int = py
        .import(pyo3::intern!(py, "operator"))?
        .call_method1(pyo3::intern!(py, "index"), (ob,))
        .map_err(|_| {
            PyTypeError::new_err(format!(
                "{arg} must be an integer, got {}",
                ob.get_type()
                    .name()
                    .map_or_else(|_| "?".into(), |n| n.to_string())
            ))
        })?;
    if int.lt(min)? || int.gt(max)? {
        return Err(Error::Integer {
            arg,
            value: int.to_string(),
            requirement: format!("must be an integer from {min} to {max}"),
        }
        .into());
    }
    int.extract()
}

/// What every input value must satisfy.
#[derive(Clone, Copy, Debug)]
pub enum Check {
    /// In the closed unit interval (uniform samples `u`).
    Unit,
    /// Finite (points, directions).
    Finite,
    /// Component `k` in the closed interval `bounds[k]` (points of a
    /// rectangle or, for one component, an interval).
    Within([[f64; 2]; 2]),
    /// A density: `>= 0`, possibly infinite (a delta), not NaN.
    Density,
}

impl Check {
    /// Whether component `k` of a point may be `x`.
    #[inline(always)]
    fn holds<F: Real>(self, k: usize, x: F) -> bool {
        match self {
            Check::Unit => x >= F::zero() && x <= F::one(),
            Check::Finite => x.is_finite(),
            Check::Within(bounds) => {
                let [lo, hi] = bounds[k.min(1)];
                x.f64() >= lo && x.f64() <= hi
            }
            Check::Density => x >= F::zero(),
        }
    }

    /// Whether every component of `point` passes.
    #[inline(always)]
    pub fn holds_all<F: Real, const K: usize>(self, point: &[F; K]) -> bool {
        point
            .iter()
            .enumerate()
            .fold(true, |acc, (k, &v)| acc & self.holds(k, v))
    }

    fn requirement(self, k: usize) -> String {
        match self {
            Check::Unit => "must lie in [0, 1]".into(),
            Check::Finite => "must be finite".into(),
            Check::Within(bounds) => {
                let [lo, hi] = bounds[k.min(1)];
                format!("must lie in [{lo}, {hi}]")
            }
            Check::Density => "a density must be >= 0 (inf allowed, NaN not)".into(),
        }
    }
}

/// `(N, batched)` of a batch of `K`-vectors of `shape`: `(N, K)` or `(K,)`,
/// or for `K = 1`, `(N,)` or `()`; else the error naming `arg`.
fn batch_shape<const K: usize>(arg: &'static str, shape: &[usize]) -> PyResult<(usize, bool)> {
    match (K, shape) {
        (1, []) => Ok((1, false)),
        (1, [n]) => Ok((*n, true)),
        (_, [k]) if *k == K => Ok((1, false)),
        (_, [n, k]) if *k == K => Ok((*n, true)),
        _ => {
            let expected = if K == 1 {
                "(N,) or ()".to_string()
            } else {
                format!("(N, {K}) or ({K},)")
            };
            Err(Error::Shape {
                arg,
                expected,
                got: shape_str(shape),
            }
            .into())
        }
    }
}

/// A batch of `K`-vectors read from an array-like: `(N, K)` or `(K,)`, or
/// for `K = 1`, `(N,)` or a scalar.
pub struct Points<'py, F: Element, const K: usize> {
    array: PyArrayLikeDyn<'py, F, AllowTypeChange>,
    /// A C-ordered copy when the input is not contiguous.
    owned: Option<Vec<F>>,
    /// Number of points.
    pub n: usize,
    /// False for a single point given without the batch axis.
    pub batched: bool,
    /// Argument name, for messages.
    pub arg: &'static str,
}

impl<'py, F: PyFloat, const K: usize> Points<'py, F, K> {
    /// Reads `ob` as points of dimension `K`.
    pub fn extract(ob: &Bound<'py, PyAny>, arg: &'static str) -> PyResult<Self> {
        let array: PyArrayLikeDyn<'py, F, AllowTypeChange> = ob
            .extract()
            .map_err(|e| PyTypeError::new_err(format!("{arg} must be an array of numbers: {e}")))?;
        let shape = array.shape().to_vec();
        let (n, batched) = batch_shape::<K>(arg, &shape)?;
        // Only C order can be read in place (a Fortran-ordered array is
        // contiguous too, in the wrong order): copy anything else once.
        let owned = if array.is_c_contiguous() {
            None
        } else {
            Some(array.as_array().iter().copied().collect())
        };
        Ok(Points {
            array,
            owned,
            n,
            batched,
            arg,
        })
    }

    /// The points, one `[F; K]` each.
    pub fn rows(&self) -> &[[F; K]] {
        let flat = match &self.owned {
            Some(v) => v.as_slice(),
            None => self.array.as_slice().unwrap_or_default(),
        };
        flat.as_chunks::<K>().0
    }

    /// Shape of a result with `m` values per point (`m = 1`: a scalar each).
    pub fn out_shape(&self, m: usize) -> Vec<usize> {
        match (self.batched, m) {
            (true, 1) => vec![self.n],
            (true, _) => vec![self.n, m],
            (false, 1) => vec![],
            (false, _) => vec![m],
        }
    }

    /// The error for the first value that fails `check`.
    pub fn invalid(&self, check: Check) -> PyErr {
        for (i, row) in self.rows().iter().enumerate() {
            if let Some(j) = (0..K).find(|&k| !check.holds(k, row[k])) {
                let index = match (self.batched, K) {
                    (true, 1) => format!("[{i}]"),
                    (true, _) => format!("[{i}, {j}]"),
                    (false, 1) => String::new(),
                    (false, _) => format!("[{j}]"),
                };
                return Error::Element {
                    arg: self.arg,
                    index,
                    value: row[j].f64(),
                    requirement: check.requirement(j),
                }
                .into();
            }
        }
        Error::Element {
            arg: self.arg,
            index: String::new(),
            value: f64::NAN,
            requirement: check.requirement(0),
        }
        .into()
    }
}

/// A fresh zeroed numpy array of `shape` (allocated by numpy, so a failed
/// allocation is a `MemoryError`, and untouched pages cost nothing).
pub fn zeros<'py, F: Element>(py: Python<'py>, shape: &[usize]) -> Bound<'py, PyArrayDyn<F>> {
    PyArray::zeros(py, shape, false)
}

/// `array` as returned to Python: a numpy scalar when it is 0-d.
pub fn finish<'py, F: Element>(array: Bound<'py, PyArrayDyn<F>>) -> PyResult<Bound<'py, PyAny>> {
    if array.ndim() == 0 {
        array.get_item(PyTuple::empty(array.py()))
    } else {
        Ok(array.into_any())
    }
}

/// Maps every point through `kernel` (`K` values in, `M` out, of any
/// element type), checking each input value in the same pass; the GIL is
/// released and the batch runs on all cores.
pub fn map<'py, F, T, const K: usize, const M: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    kernel: impl Fn([F; K]) -> [T; M] + Sync + Send,
) -> PyResult<Bound<'py, PyAny>>
where
    F: PyFloat,
    T: Element + Copy + Default + Send,
{
    map_into(py, x, check, None, kernel)
}

/// [`map`] for kernels that cannot vectorise (table lookups, library
/// calls): a plain loop per chunk, without the SIMD dispatch and the
/// transposes of [`map_rows`], which would only add work to them.
pub fn map_each<'py, F, T, const K: usize, const M: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    kernel: impl Fn([F; K]) -> [T; M] + Sync + Send,
) -> PyResult<Bound<'py, PyAny>>
where
    F: PyFloat,
    T: Element + Copy + Default + Send,
{
    let out = zeros::<T>(py, &x.out_shape(M));
    {
        let mut guard = out.readwrite();
        let out_rows = guard.as_slice_mut()?.as_chunks_mut::<M>().0;
        let in_rows = x.rows();
        let valid = run_batch(py, x.n, out_rows, |range, chunk: &mut [[T; M]]| {
            let mut ok = true;
            for (o, p) in chunk.iter_mut().zip(&in_rows[range]) {
                ok &= check.holds_all(p);
                *o = kernel(*p);
            }
            ok
        })?;
        if !valid {
            return Err(x.invalid(check));
        }
    }
    finish(out)
}

/// [`map`] for kernels that take a whole chunk of points at once and
/// write one value per point (for work shared across points, such as
/// prefetching table cells): every input value is checked first, and the
/// kernel runs only on chunks that pass.
pub fn map_chunks<'py, F, T, const K: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    kernel: impl Fn(&[[F; K]], &mut [T]) + Sync + Send,
) -> PyResult<Bound<'py, PyAny>>
where
    F: PyFloat,
    T: Element + Copy + Default + Send,
{
    let out = zeros::<T>(py, &x.out_shape(1));
    {
        let mut guard = out.readwrite();
        let in_rows = x.rows();
        let valid = run_batch(py, x.n, guard.as_slice_mut()?, |range, chunk: &mut [T]| {
            let inputs = &in_rows[range];
            let ok = inputs.iter().fold(true, |ok, p| ok & check.holds_all(p));
            if ok {
                kernel(inputs, chunk);
            }
            ok
        })?;
        if !valid {
            return Err(x.invalid(check));
        }
    }
    finish(out)
}

/// The array results go to: `out` when given (checked to be a writeable,
/// C-ordered array of `shape` and of dtype `T`, as numpy's ufuncs check
/// theirs), else a fresh one.
pub fn output<'py, T: Element>(
    py: Python<'py>,
    shape: &[usize],
    out: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    let Some(out) = out.filter(|o| !o.is_none()) else {
        return Ok(zeros::<T>(py, shape));
    };
    let array = out.cast::<PyArrayDyn<T>>().map_err(|_| {
        PyTypeError::new_err(format!(
            "out must be a numpy array of dtype {}, got {}",
            numpy::dtype::<T>(py),
            out.get_type()
                .name()
                .map_or_else(|_| "?".into(), |n| n.to_string())
        ))
    })?;
    let writeable: bool = array.getattr("flags")?.getattr("writeable")?.extract()?;
    let fits = array.shape() == shape && array.is_c_contiguous() && writeable;
    if !fits {
        return Err(Error::Shape {
            arg: "out",
            expected: format!("{} (a writeable C-ordered array)", shape_str(shape)),
            got: shape_str(array.shape()),
        }
        .into());
    }
    Ok(array.clone())
}

/// Write access to an output array, which fails (rather than panics) when
/// an `out` array shares memory with an input or another output.
pub fn writable<'py, T: Element>(
    out: &Bound<'py, PyArrayDyn<T>>,
) -> PyResult<PyReadwriteArrayDyn<'py, T>> {
    out.try_readwrite().map_err(|_| {
        pyo3::exceptions::PyValueError::new_err(
            "out must not share memory with an input array or another output",
        )
    })
}

/// As [`map`], writing into `out` when it is given (see [`output`]).
pub fn map_into<'py, F, T, const K: usize, const M: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    out: Option<&Bound<'py, PyAny>>,
    kernel: impl Fn([F; K]) -> [T; M] + Sync + Send,
) -> PyResult<Bound<'py, PyAny>>
where
    F: PyFloat,
    T: Element + Copy + Default + Send,
{
    let out = output::<T>(py, &x.out_shape(M), out)?;
    {
        let mut guard = writable(&out)?;
        let out_rows = guard.as_slice_mut()?.as_chunks_mut::<M>().0;
        let in_rows = x.rows();
        // One batch per check, each with a loop that has no dispatch left.
        // (One batch holding the three loops behind a `match` ran the
        // kernels a third slower: LLVM compiled that closure worse.)
        let valid = match check {
            Check::Unit => map_batch(py, out_rows, in_rows, &kernel, |u| {
                u.iter()
                    .fold(true, |ok, &v| ok & (v >= F::zero()) & (v <= F::one()))
            }),
            Check::Finite => map_batch(py, out_rows, in_rows, &kernel, |u| {
                u.iter().fold(true, |ok, &v| ok & v.is_finite())
            }),
            Check::Within(_) | Check::Density => {
                map_batch(py, out_rows, in_rows, &kernel, |u| check.holds_all(u))
            }
        }?;
        if !valid {
            return Err(x.invalid(check));
        }
    }
    finish(out)
}

/// `out[i] = kernel(inputs[i])` on all cores with the GIL released (see
/// [`map_rows`]; streamed for outputs of [`STREAM_MIN_BYTES`] or more);
/// whether `valid` held for every input.
fn map_batch<F, T, const K: usize, const M: usize>(
    py: Python<'_>,
    out: &mut [[T; M]],
    inputs: &[[F; K]],
    kernel: &(impl Fn([F; K]) -> [T; M] + Sync),
    valid: impl Fn(&[F; K]) -> bool + Sync,
) -> PyResult<bool>
where
    F: Copy + Default + Sync,
    T: Copy + Default + Send,
{
    let stream = size_of_val(out) >= STREAM_MIN_BYTES;
    run_batch(py, inputs.len(), out, |range, chunk: &mut [[T; M]]| {
        map_rows(chunk, &inputs[range], kernel, &valid, stream)
    })
}

/// Maps pairs `(a[i], b[i])` through `kernel`; either input may be a single
/// point, used for every row (the result is unbatched only when both are).
/// Each input value is checked in the same pass; the GIL is released.
pub fn map_pair<'py, F, T, const KA: usize, const KB: usize, const M: usize>(
    py: Python<'py>,
    a: (&Points<'py, F, KA>, Check),
    b: (&Points<'py, F, KB>, Check),
    kernel: impl Fn([F; KA], [F; KB]) -> [T; M] + Sync + Send,
) -> PyResult<Bound<'py, PyAny>>
where
    F: PyFloat,
    T: Element + Copy + Default + Send,
{
    let ((a, check_a), (b, check_b)) = (a, b);
    let n = pair_len(a, b)?;
    let shape = match (a.batched || b.batched, M) {
        (true, 1) => vec![n],
        (true, _) => vec![n, M],
        (false, 1) => vec![],
        (false, _) => vec![M],
    };
    let out = zeros::<T>(py, &shape);
    {
        let mut guard = out.readwrite();
        let out_rows = guard.as_slice_mut()?.as_chunks_mut::<M>().0;
        let (rows_a, rows_b) = (a.rows(), b.rows());
        let (step_a, step_b) = (usize::from(a.batched), usize::from(b.batched));
        let (valid_a, valid_b) = run_batch_pair(py, n, out_rows, |range, chunk: &mut [[T; M]]| {
            let (mut ok_a, mut ok_b) = (true, true);
            for (o, i) in chunk.iter_mut().zip(range) {
                let (x, y) = (rows_a[i * step_a], rows_b[i * step_b]);
                ok_a &= check_a.holds_all(&x);
                ok_b &= check_b.holds_all(&y);
                *o = kernel(x, y);
            }
            (ok_a, ok_b)
        })?;
        if !valid_a {
            return Err(a.invalid(check_a));
        }
        if !valid_b {
            return Err(b.invalid(check_b));
        }
    }
    finish(out)
}

/// The row count of a pair of inputs that broadcast against each other.
pub fn pair_len<F: Element, const KA: usize, const KB: usize>(
    a: &Points<'_, F, KA>,
    b: &Points<'_, F, KB>,
) -> PyResult<usize> {
    match (a.batched, b.batched) {
        (true, true) if a.n != b.n => Err(Error::Shape {
            arg: b.arg,
            expected: format!("{} rows, as {} has (or a single point)", a.n, a.arg),
            got: format!("{} rows", b.n),
        }
        .into()),
        (_, true) => Ok(b.n),
        _ => Ok(a.n),
    }
}

/// [`run_batch`] for kernels that check two inputs: returns whether each
/// was valid throughout.
pub fn run_batch_pair<O, K>(
    py: Python<'_>,
    n: usize,
    outputs: O,
    kernel: K,
) -> PyResult<(bool, bool)>
where
    O: crate::parallel::Outputs,
    K: Fn(std::ops::Range<usize>, O) -> (bool, bool) + Sync + Send,
{
    use std::sync::atomic::{AtomicBool, Ordering};
    let (bad_a, bad_b) = (AtomicBool::new(false), AtomicBool::new(false));
    run_batch(py, n, outputs, |range, out| {
        let (ok_a, ok_b) = kernel(range, out);
        if !ok_a {
            bad_a.store(true, Ordering::Relaxed);
        }
        if !ok_b {
            bad_b.store(true, Ordering::Relaxed);
        }
        ok_a && ok_b
    })?;
    Ok((!bad_a.into_inner(), !bad_b.into_inner()))
}

/// As [`map`] for kernels with two results (`M` and `L` values per point),
/// returned as two arrays.
pub fn map2<'py, F, T, S, const K: usize, const M: usize, const L: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    kernel: impl Fn([F; K]) -> ([T; M], [S; L]) + Sync + Send,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)>
where
    F: PyFloat,
    T: Element + Copy + Default + Send,
    S: Element + Copy + Default + Send,
{
    let first = zeros::<T>(py, &x.out_shape(M));
    let second = zeros::<S>(py, &x.out_shape(L));
    {
        let (mut g1, mut g2) = (first.readwrite(), second.readwrite());
        let rows1 = g1.as_slice_mut()?.as_chunks_mut::<M>().0;
        let rows2 = g2.as_slice_mut()?.as_chunks_mut::<L>().0;
        let in_rows = x.rows();
        let valid = run_batch(py, x.n, (rows1, rows2), |range, (c1, c2)| {
            let mut ok = true;
            for ((o1, o2), u) in c1.iter_mut().zip(c2.iter_mut()).zip(&in_rows[range]) {
                ok &= check.holds_all(u);
                (*o1, *o2) = kernel(*u);
            }
            ok
        })?;
        if !valid {
            return Err(x.invalid(check));
        }
    }
    Ok((finish(first)?, finish(second)?))
}

/// Integer indices read from an array-like: `(N, K)` or `(K,)` (for
/// `K = 1`, `(N,)` or a scalar), each column `k` checked to lie in
/// `[0, bounds[k])`.
pub struct Indices<const K: usize> {
    /// The indices, one `[usize; K]` per point.
    pub rows: Vec<[usize; K]>,
    /// False for a single point given without the batch axis.
    pub batched: bool,
}

impl<const K: usize> Indices<K> {
    /// Reads and checks `ob` (argument `arg`); floats raise TypeError, an
    /// index out of range ValueError naming its position.
    pub fn extract(ob: &Bound<'_, PyAny>, arg: &'static str, bounds: [usize; K]) -> PyResult<Self> {
        let py = ob.py();
        let array = py
            .import(pyo3::intern!(py, "numpy"))?
            .call_method1(pyo3::intern!(py, "asarray"), (ob,))?;
        let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
        if kind != "i" && kind != "u" {
            return Err(PyTypeError::new_err(format!(
                "{arg} must be integers, got an array of dtype {}",
                array.getattr("dtype")?
            )));
        }
        let array: PyArrayLikeDyn<'_, i64, AllowTypeChange> = array.extract()?;
        let shape = array.shape().to_vec();
        let (_, batched) = batch_shape::<K>(arg, &shape)?;
        let flat: Vec<i64> = array.as_array().iter().copied().collect();
        let mut rows = Vec::with_capacity(flat.len() / K);
        for (i, chunk) in flat.as_chunks::<K>().0.iter().enumerate() {
            let mut row = [0usize; K];
            for (k, (&v, &bound)) in chunk.iter().zip(&bounds).enumerate() {
                if v < 0 || v as u64 >= bound as u64 {
                    let index = match (batched, K) {
                        (true, 1) => format!("[{i}]"),
                        (true, _) => format!("[{i}, {k}]"),
                        (false, 1) => String::new(),
                        (false, _) => format!("[{k}]"),
                    };
                    return Err(Error::Index {
                        arg,
                        index,
                        value: v,
                        len: bound,
                    }
                    .into());
                }
                row[k] = v as usize;
            }
            rows.push(row);
        }
        Ok(Indices { rows, batched })
    }

    /// Maps every index row to one float64 value; shape `(N,)`, or a
    /// scalar for an unbatched row.
    pub fn map_f64<'py>(
        &self,
        py: Python<'py>,
        f: impl Fn([usize; K]) -> f64 + Sync + Send,
    ) -> PyResult<Bound<'py, PyAny>> {
        let shape: Vec<usize> = if self.batched {
            vec![self.rows.len()]
        } else {
            vec![]
        };
        let out = zeros::<f64>(py, &shape);
        {
            let mut guard = out.readwrite();
            let values = guard.as_slice_mut()?;
            let rows = &self.rows;
            run_batch(py, rows.len(), values, |range, chunk: &mut [f64]| {
                for (o, &r) in chunk.iter_mut().zip(&rows[range]) {
                    *o = f(r);
                }
                true
            })?;
        }
        finish(out)
    }
}

/// A table of weights read as float64 (converted only if it is not already
/// a C-ordered float64 array); `ndim` must be 1 or 2 as asked. The values
/// are checked by the core constructors.
pub struct Table<'py> {
    array: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    owned: Option<Vec<f64>>,
    /// The table's shape.
    pub shape: Vec<usize>,
}

impl<'py> Table<'py> {
    /// Reads `ob` (argument `arg`).
    pub fn extract(ob: &Bound<'py, PyAny>, arg: &'static str, ndim: usize) -> PyResult<Self> {
        let array: PyArrayLikeDyn<'py, f64, AllowTypeChange> = ob
            .extract()
            .map_err(|e| PyTypeError::new_err(format!("{arg} must be an array of numbers: {e}")))?;
        let shape = array.shape().to_vec();
        if shape.len() != ndim {
            return Err(Error::Shape {
                arg,
                expected: if ndim == 1 {
                    "(N,)".into()
                } else {
                    "(rows, cols)".into()
                },
                got: shape_str(&shape),
            }
            .into());
        }
        let owned = (!array.is_c_contiguous()).then(|| array.as_array().iter().copied().collect());
        Ok(Table {
            array,
            owned,
            shape,
        })
    }

    /// The values in row-major order.
    pub fn values(&self) -> &[f64] {
        match &self.owned {
            Some(v) => v,
            None => self.array.as_slice().unwrap_or_default(),
        }
    }
}

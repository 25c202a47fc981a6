//! The batch drivers: each maps the points of its inputs ([`Points`],
//! [`Indices`]) through a kernel into fresh arrays (or the caller's `out`),
//! checking every input value in the kernel's own pass, with the GIL
//! released and on all cores ([`run_batch`]). An invalid value is reported
//! after the pass, naming the first offending index.

use super::arrays::{Check, Indices, Points, PyFloat, broadcast, finish, output, result_shape};
use super::arrays::{fresh, tuple_outputs, writable};
use super::parallel::run_batch;
use crate::python::{Obj, Out};
use crate::simd::{STREAM_MIN_BYTES, dispatch, map_rows};
use numpy::{Element, PyArrayMethods};
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// [`map_into`] for kernels that cannot vectorise (table lookups, library
/// calls): a plain loop per chunk, without the SIMD dispatch and the
/// transposes of [`map_rows`], which would only add work to them.
pub fn map_each<'py, F, T, const K: usize, const M: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    kernel: impl Fn([F; K]) -> [T; M] + Sync + Send,
) -> PyResult<Obj<'py>>
where
    F: PyFloat,
    T: Element + bytemuck::Pod + Default + Send,
{
    let out = fresh::<T>(py, &x.out_shape(M))?;
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

/// [`map_into`] for kernels that take a whole chunk of points at once and
/// write `M` values per point (for work shared across points, such as
/// prefetching table cells), into `out` when it is given: every input
/// value is checked first, and the kernel runs only on chunks that pass.
pub fn map_chunks<'py, F, T, const K: usize, const M: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    out: Out<'_, 'py>,
    kernel: impl Fn(&[[F; K]], &mut [[T; M]]) + Sync + Send,
) -> PyResult<Obj<'py>>
where
    F: PyFloat,
    T: Element + bytemuck::Pod + Default + Send,
{
    let out = output::<T>(py, &x.out_shape(M), out, "out")?;
    {
        let mut guard = writable(&out)?;
        let out_rows = guard.as_slice_mut()?.as_chunks_mut::<M>().0;
        let in_rows = x.rows();
        let valid = run_batch(py, x.n, out_rows, |range, chunk: &mut [[T; M]]| {
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
    out.finish()
}

/// [`map_chunks`] for kernels of two results per point (`M` and `L`
/// values), returned as two arrays, or written into the two arrays of
/// `out` when it is given (a tuple, see [`tuple_outputs`]; `names` names
/// the results in its message).
pub fn map_chunks2<'py, F, T, S, const K: usize, const M: usize, const L: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    (out, names): (Out<'_, 'py>, &str),
    kernel: impl Fn(&[[F; K]], &mut [[T; M]], &mut [[S; L]]) + Sync + Send,
) -> PyResult<(Obj<'py>, Obj<'py>)>
where
    F: PyFloat,
    T: Element + bytemuck::Pod + Default + Send,
    S: Element + bytemuck::Pod + Default + Send,
{
    let [o1, o2] = tuple_outputs::<2>(out, names)?;
    let first = output::<T>(py, &x.out_shape(M), o1.as_ref(), "out[0]")?;
    let second = output::<S>(py, &x.out_shape(L), o2.as_ref(), "out[1]")?;
    {
        let (mut g1, mut g2) = (writable(&first)?, writable(&second)?);
        let rows1 = g1.as_slice_mut()?.as_chunks_mut::<M>().0;
        let rows2 = g2.as_slice_mut()?.as_chunks_mut::<L>().0;
        let in_rows = x.rows();
        let valid = run_batch(py, x.n, (rows1, rows2), |range, (c1, c2)| {
            let inputs = &in_rows[range];
            let ok = inputs.iter().fold(true, |ok, p| ok & check.holds_all(p));
            if ok {
                kernel(inputs, c1, c2);
            }
            ok
        })?;
        if !valid {
            return Err(x.invalid(check));
        }
    }
    Ok((first.finish()?, second.finish()?))
}

/// Maps every point through `kernel` (`K` values in, `M` out, of any
/// element type), checking each input value in the same pass, into `out`
/// when it is given (see [`output`]); the GIL is released and the batch
/// runs on all cores.
pub fn map_into<'py, F, T, const K: usize, const M: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    out: Out<'_, 'py>,
    kernel: impl Fn([F; K]) -> [T; M] + Sync + Send,
) -> PyResult<Obj<'py>>
where
    F: PyFloat,
    T: Element + bytemuck::Pod + Default + Send,
{
    let out = output::<T>(py, &x.out_shape(M), out, "out")?;
    {
        let mut guard = writable(&out)?;
        let out_rows = guard.as_slice_mut()?.as_chunks_mut::<M>().0;
        let in_rows = x.rows();
        // One batch per check, each with a loop that has no dispatch left
        // (one batch holding the loops behind a `match` compiles worse).
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
    out.finish()
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

/// The batch shape of a pair of inputs (see [`broadcast`]).
pub fn pair_shape<F: Element + bytemuck::Pod, const KA: usize, const KB: usize>(
    a: &Points<'_, F, KA>,
    b: &Points<'_, F, KB>,
) -> PyResult<Vec<usize>> {
    broadcast((a.arg, &a.batch), (b.arg, &b.batch))
}

/// Maps pairs `(a[i], b[i])` through `kernel`; either input may be a single
/// point (or a batch of one), used for every row of the other. Each input
/// value is checked in the same pass; the GIL is released.
pub fn map_pair<'py, F, T, const KA: usize, const KB: usize, const M: usize>(
    py: Python<'py>,
    a: (&Points<'py, F, KA>, Check),
    b: (&Points<'py, F, KB>, Check),
    kernel: impl Fn([F; KA], [F; KB]) -> [T; M] + Sync + Send,
) -> PyResult<Obj<'py>>
where
    F: PyFloat,
    T: Element + bytemuck::Pod + Default + Send,
{
    let ((a, check_a), (b, check_b)) = (a, b);
    let batch = pair_shape(a, b)?;
    let n = batch.iter().product();
    let out = fresh::<T>(py, &result_shape(&batch, M))?;
    {
        let mut guard = out.readwrite();
        let out_rows = guard.as_slice_mut()?.as_chunks_mut::<M>().0;
        let (rows_a, rows_b) = (a.rows(), b.rows());
        let (step_a, step_b) = (usize::from(a.n != 1), usize::from(b.n != 1));
        let (valid_a, valid_b) = run_batch_pair(py, n, out_rows, |range, chunk: &mut [[T; M]]| {
            // Inside the dispatch, so that the kernel (inlined) is built
            // for the CPU's vector unit, not the baseline instruction set.
            dispatch(
                #[inline(always)]
                |_| {
                    let (mut ok_a, mut ok_b) = (true, true);
                    for (o, i) in chunk.iter_mut().zip(range) {
                        let (x, y) = (rows_a[i * step_a], rows_b[i * step_b]);
                        ok_a &= check_a.holds_all(&x);
                        ok_b &= check_b.holds_all(&y);
                        *o = kernel(x, y);
                    }
                    (ok_a, ok_b)
                },
            )
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

/// As [`map_into`] for kernels with two results (`M` and `L` values per point),
/// returned as two arrays, or written into the two arrays of `out` when it
/// is given (a tuple, see [`tuple_outputs`]; `names` names the results in
/// its message). The loop runs inside the SIMD dispatch, as
/// [`map_pair`]'s.
pub fn map2<'py, F, T, S, const K: usize, const M: usize, const L: usize>(
    py: Python<'py>,
    x: &Points<'py, F, K>,
    check: Check,
    out: (Out<'_, 'py>, &str),
    kernel: impl Fn([F; K]) -> ([T; M], [S; L]) + Sync + Send,
) -> PyResult<(Obj<'py>, Obj<'py>)>
where
    F: PyFloat,
    T: Element + bytemuck::Pod + Default + Send,
    S: Element + bytemuck::Pod + Default + Send,
{
    map_chunks2(py, x, check, out, |inputs, c1, c2| {
        dispatch(
            #[inline(always)]
            |_| {
                for ((o1, o2), u) in c1.iter_mut().zip(c2.iter_mut()).zip(inputs) {
                    (*o1, *o2) = kernel(*u);
                }
            },
        )
    })
}

/// Maps every index row to one float64 value: the batch's shape, or a
/// scalar for an unbatched row; into `out` when it is given.
pub fn map_indices<'py, const K: usize>(
    py: Python<'py>,
    indices: &Indices<K>,
    out: Out<'_, 'py>,
    f: impl Fn([usize; K]) -> f64 + Sync + Send,
) -> PyResult<Obj<'py>> {
    let out = output::<f64>(py, &indices.batch, out, "out")?;
    {
        let mut guard = writable(&out)?;
        let values = guard.as_slice_mut()?;
        let rows = &indices.rows;
        run_batch(py, rows.len(), values, |range, chunk: &mut [f64]| {
            for (o, &r) in chunk.iter_mut().zip(&rows[range]) {
                *o = f(r);
            }
            true
        })?;
    }
    out.finish()
}

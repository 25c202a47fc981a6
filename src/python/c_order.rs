//! Copies of numpy arrays in C order, for the bindings that read a
//! non-contiguous input (a transposed, strided or broadcast view) as one
//! flat slice.
//!
//! An element-by-element walk over an arbitrary view (`ndarray`'s `iter()`
//! on a dynamic shape) steps an index through every axis for each value:
//! a transposed `(10⁷, 2)` float32 batch took about 680 ms to copy that
//! way, 67 times the warp it fed. Here the view is given its static number
//! of axes (up to 4) and copied by `assign`, its axes (and the output's)
//! put in an order whose innermost loop runs along the input's smallest
//! stride; a view of [`PARALLEL_MIN`] values or more is cut along its
//! first axis into blocks that mcsample's threads copy at once.

use crate::alloc;
use crate::buffer::Buffer;
use crate::error::Result;
use crate::parallel;
use bytemuck::Pod;
use numpy::ndarray::{ArrayViewD, ArrayViewMut, Axis, Dimension, Ix1, Ix2, Ix3, Ix4, IxDyn};
use rayon::prelude::*;

/// Copies of fewer values than this run on the calling thread.
const PARALLEL_MIN: usize = 1 << 16;

/// The values of `a` in C (row-major) order, in a `Vec` reserved first
/// (`what` names it in a [`crate::Error::Memory`]).
///
/// # Errors
/// [`crate::Error::Memory`] when the copy's memory cannot be had; for a
/// copy on several threads, [`crate::Error::Integer`] if
/// `MCSAMPLE_NUM_THREADS` is malformed (see [`parallel::num_threads`]) and
/// [`crate::Error::ThreadPool`] if the pool cannot be made.
pub fn copy<T: Pod + Send + Sync>(a: ArrayViewD<'_, T>, what: &'static str) -> Result<Vec<T>> {
    let mut out = alloc::filled(a.len(), T::zeroed(), what)?;
    fill(&mut out, a)?;
    Ok(out)
}

/// [`copy`] into a [`Buffer`] made by [`Buffer::for_overwrite`]: a copy
/// of 1 MiB or more reuses a recycled memory map of about its size as it
/// is (no page faults, no zeroing) when there is one, as the batch outputs
/// do.
///
/// # Errors
/// As [`copy`].
pub fn copy_to_buffer<T: Pod + Send + Sync>(
    a: ArrayViewD<'_, T>,
    what: &'static str,
) -> Result<Buffer<T>> {
    let mut out = Buffer::for_overwrite(a.len(), what)?;
    fill(&mut out, a)?;
    Ok(out)
}

/// Writes `a` into `out` (of its length) in C order: as one slice if it is
/// contiguous in that order; else by [`assign_any`], in blocks of its
/// first axis on mcsample's threads when it holds [`PARALLEL_MIN`] values
/// or more and its first axis 2 or more.
fn fill<T: Pod + Send + Sync>(out: &mut [T], a: ArrayViewD<'_, T>) -> Result<()> {
    if let Some(flat) = a.as_slice() {
        out.copy_from_slice(flat);
        return Ok(());
    }
    let rows = a.shape().first().copied().unwrap_or(1);
    if out.len() < PARALLEL_MIN || rows < 2 {
        assign_any(out, a);
        return Ok(());
    }
    let threads = parallel::num_threads()?;
    // A few blocks per thread, so that a slow one does not hold the rest up.
    let block = rows.div_ceil(4 * threads);
    let row_len = out.len() / rows;
    let blocks: Vec<_> = a.axis_chunks_iter(Axis(0), block).collect();
    parallel::install(|| {
        out.par_chunks_mut(block * row_len)
            .zip(blocks.into_par_iter())
            .for_each(|(out, a)| assign_any(out, a));
    })
}

/// Writes `a` into `out` (of its length) in C order, as a view of its
/// static number of axes (up to 4, else dynamic).
fn assign_any<T: Copy>(out: &mut [T], a: ArrayViewD<'_, T>) {
    match a.ndim() {
        1 => assign::<T, Ix1>(out, a),
        2 => assign::<T, Ix2>(out, a),
        3 => assign::<T, Ix3>(out, a),
        4 => assign::<T, Ix4>(out, a),
        _ => assign::<T, IxDyn>(out, a),
    }
}

/// Writes `a` into `out` (of its length) in C order, as a view of `D`
/// axes (the caller's match makes it one); element by element should
/// that fail.
///
/// Both views get their axes in the same new order, `a`'s largest stride
/// first: the pairs of elements are the same, but the innermost loop of
/// `assign` then runs along `a`'s smallest stride. (For `u.T` of a `(2, N)`
/// array it reads each of the two rows in order, instead of stepping
/// between them for every point.)
fn assign<T: Copy, D: Dimension>(out: &mut [T], a: ArrayViewD<'_, T>) {
    let views = a.view().into_dimensionality::<D>().ok().and_then(|a| {
        let out = ArrayViewMut::from_shape(a.raw_dim(), &mut *out).ok()?;
        let mut axes: Vec<usize> = (0..a.ndim()).collect();
        // (An axis of length 1 has no loop: it goes first.)
        let step = |i: usize| match a.shape()[i] {
            0 | 1 => usize::MAX,
            _ => a.strides()[i].unsigned_abs(),
        };
        axes.sort_by_key(|&i| std::cmp::Reverse(step(i)));
        let mut order = D::zeros(a.ndim());
        for (k, &i) in axes.iter().enumerate() {
            order[k] = i;
        }
        Some((out.permuted_axes(order.clone()), a.permuted_axes(order)))
    });
    match views {
        Some((mut out, a)) => out.assign(&a),
        None => out.iter_mut().zip(a.iter()).for_each(|(o, &v)| *o = v),
    }
}

//! Copies of numpy arrays in C order, for the bindings that read a
//! non-contiguous input (a transposed, strided or broadcast view) as one
//! flat slice.
//!
//! An element-by-element walk over an arbitrary view (`ndarray`'s `iter()`
//! on a dynamic shape) steps an index through every axis for each value:
//! a transposed `(10⁷, 2)` float32 batch took about 680 ms to copy that
//! way, 67 times the warp it fed. Here the view is given its static number
//! of axes (up to 4) and copied by `assign`, whose loops run along the
//! last axis at its stride.

use crate::alloc;
use crate::error::Result;
use numpy::ndarray::{ArrayViewD, ArrayViewMut, Dimension, Ix1, Ix2, Ix3, Ix4, IxDyn};

/// The values of `a` in C (row-major) order, in memory reserved first
/// (`what` names it in a [`crate::Error::Memory`]).
///
/// # Errors
/// [`crate::Error::Memory`] when the copy's memory cannot be had.
pub fn copy<T: Copy + Default>(a: ArrayViewD<'_, T>, what: &'static str) -> Result<Vec<T>> {
    if let Some(flat) = a.as_slice() {
        return alloc::collect(flat.iter().copied(), what);
    }
    let mut out = alloc::filled(a.len(), T::default(), what)?;
    match a.ndim() {
        1 => assign::<T, Ix1>(&mut out, a),
        2 => assign::<T, Ix2>(&mut out, a),
        3 => assign::<T, Ix3>(&mut out, a),
        4 => assign::<T, Ix4>(&mut out, a),
        _ => assign::<T, IxDyn>(&mut out, a),
    }
    Ok(out)
}

/// Writes `a` into `out` (of its length) in C order, as a view of `D`
/// axes (the caller's match makes it one); element by element should
/// that fail.
fn assign<T: Copy, D: Dimension>(out: &mut [T], a: ArrayViewD<'_, T>) {
    let views = a.view().into_dimensionality::<D>().ok().and_then(|a| {
        let out = ArrayViewMut::from_shape(a.raw_dim(), &mut *out).ok()?;
        Some((out, a))
    });
    match views {
        Some((mut out, a)) => out.assign(&a),
        None => out.iter_mut().zip(a.iter()).for_each(|(o, &v)| *o = v),
    }
}

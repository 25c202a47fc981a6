//! Recycled memory for large fresh outputs, as Dr.Jit's memory cache
//! serves Mitsuba. A fresh numpy array of 10^7 rows costs its pages' first
//! touch (a page fault and the kernel's zeroing of every page), which at
//! these sizes is a good part of a warp's or an envmap lookup's time; an
//! output written into memory already touched runs at the `out=` speed.
//!
//! Outputs of at least [`MIN_BYTES`] are arrays over a block of this
//! cache, owned by a [`RecycledBlock`] object (the array's `base`); when Python
//! frees the array, the block goes back to the cache, which keeps at most
//! [`MAX_BLOCKS`] blocks and [`MAX_BYTES`] in all (the oldest leave
//! first). A request the cache cannot serve is allocated fresh, after the
//! cache is emptied if memory is short: a request too big for memory is
//! still a `MemoryError`, and every `MemoryError` mcsample raises empties
//! the cache too. Only kernels that write every element of their
//! output take these arrays ([`super::arrays::fresh`]): a recycled block
//! holds an earlier array's values.

use std::sync::{Mutex, PoisonError};

use bytemuck::Pod;
use numpy::ndarray::{ArrayViewMut, IxDyn};
use numpy::{Element, PyArrayDyn};
use pyo3::prelude::*;

use crate::error::{Error, Result};

/// Outputs smaller than this are plain `numpy.zeros` arrays (which malloc
/// recycles by itself).
pub const MIN_BYTES: usize = 1 << 20;
/// The most blocks the cache keeps.
const MAX_BLOCKS: usize = 8;
/// The most bytes the cache keeps.
const MAX_BYTES: usize = 1 << 30;

/// 64 bytes aligned to 64, the unit blocks are counted in (any element
/// type lies aligned in it).
#[derive(Clone, Copy)]
#[repr(C, align(64))]
struct Line([u8; 64]);

/// The cache: blocks freed by Python, oldest first.
static CACHE: Mutex<Vec<Vec<Line>>> = Mutex::new(Vec::new());

/// The cached block that fits `lines` best (at least `lines`, at most
/// twice), or a new one.
fn take(lines: usize) -> Result<Vec<Line>> {
    let mut cache = CACHE.lock().unwrap_or_else(PoisonError::into_inner);
    let best = (0..cache.len())
        .filter(|&i| (lines..=2 * lines).contains(&cache[i].len()))
        .min_by_key(|&i| cache[i].len());
    if let Some(i) = best {
        return Ok(cache.remove(i));
    }
    let mut block = Vec::new();
    if block.try_reserve_exact(lines).is_err() {
        cache.clear();
        block.try_reserve_exact(lines).map_err(|_| Error::Memory {
            what: "an output array",
            bytes: lines as u128 * 64,
        })?;
    }
    drop(cache);
    block.resize(lines, Line([0; 64]));
    Ok(block)
}

/// Empties the cache (when memory is short: see [`super::error`]).
pub fn clear() {
    CACHE.lock().unwrap_or_else(PoisonError::into_inner).clear();
}

/// Returns `block` to the cache, making room for it.
fn give_back(block: Vec<Line>) {
    let bytes = block.len() * 64;
    if bytes > MAX_BYTES {
        return;
    }
    let mut cache = CACHE.lock().unwrap_or_else(PoisonError::into_inner);
    while cache.len() >= MAX_BLOCKS
        || cache.iter().map(|b| b.len() * 64).sum::<usize>() + bytes > MAX_BYTES
    {
        cache.remove(0);
    }
    cache.push(block);
}

/// The memory under a recycled numpy array (its `base`): the block goes
/// back to the cache when the array is freed.
#[pyclass(module = "mcsample._core", frozen)]
pub struct RecycledBlock(Vec<Line>);

impl Drop for RecycledBlock {
    fn drop(&mut self) {
        give_back(std::mem::take(&mut self.0));
    }
}

/// A numpy array of `shape` over a recycled block, holding whatever the
/// block held: for kernels that write every element.
///
/// # Errors
/// `MemoryError` when the memory cannot be had.
pub fn array<'py, T: Element + Pod>(
    py: Python<'py>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    let len: usize = shape.iter().product();
    let lines = len.saturating_mul(size_of::<T>()).div_ceil(64);
    let mut block = take(lines)?;
    let ptr = block.as_mut_ptr().cast::<T>();
    let owner = Bound::new(py, RecycledBlock(block))?;
    // SAFETY: the block holds `len` values of `T` (64 · lines bytes, aligned
    // to 64, initialised, and any bytes are a valid `T`: `Pod`), and no
    // other array or reference uses it; `owner` becomes the array's base,
    // so the block lives, never reallocated, as long as the array.
    #[allow(unsafe_code)]
    unsafe {
        let view = ArrayViewMut::from_shape_ptr(IxDyn(shape), ptr);
        Ok(PyArrayDyn::borrow_from_array(&view, owner.into_any()))
    }
}

//! Recycled memory for large fresh outputs, as Dr.Jit's memory cache
//! serves Mitsuba. A fresh numpy array of 10^7 rows costs its pages' first
//! touch (a page fault and the kernel's zeroing of every page), which at
//! these sizes is a good part of a warp's or an envmap lookup's time; an
//! output written into memory already touched runs at the `out=` speed.
//!
//! Outputs of at least [`MIN_BYTES`] are arrays over a block of this
//! cache, owned by a [`RecycledBlock`] object (the array's `base`); when
//! Python frees the array, the block goes back to the cache, which keeps
//! at most 8 blocks and 1 GiB in all (the oldest leave first: [`CACHE`]).
//! A request the cache cannot serve is allocated fresh, after the cache is
//! emptied if memory is short: a request too big for memory is
//! still a `MemoryError`, and every `MemoryError` mcsample raises empties
//! the cache too. Only kernels that write every element of their
//! output take these arrays ([`super::arrays::fresh`]): a recycled block
//! holds an earlier array's values.

use bytemuck::Pod;
use memmap2::MmapMut;
use numpy::ndarray::{ArrayViewMut, IxDyn};
use numpy::{Element, PyArrayDyn};
use pyo3::prelude::*;

use crate::buffer::{MapCache, fresh_map};
use crate::error::{Error, Result};

/// Outputs smaller than this are plain `numpy.zeros` arrays (which malloc
/// recycles by itself).
pub const MIN_BYTES: usize = 1 << 20;

/// The cache: blocks freed by Python, at most 8 blocks and 1 GiB. Each
/// block is an anonymous map advised to use huge pages, as numpy's own
/// large arrays are: an output of 4 KiB pages, beside inputs and `out=`
/// arrays of 2 MiB ones, made the plain call of a warp 5-50 % slower than
/// `out=`.
static CACHE: MapCache = MapCache::new(1 << 30, 8);

/// The cached block that fits `bytes` best (at least `bytes`, at most
/// twice), or a new one (zeros).
fn take(bytes: usize) -> Result<MmapMut> {
    if let Some(block) = CACHE.take(bytes).or_else(|| fresh_map(bytes)) {
        return Ok(block);
    }
    CACHE.clear();
    fresh_map(bytes).ok_or(Error::Memory {
        what: "an output array",
        bytes: bytes as u128,
    })
}

/// Empties the cache (when memory is short: see [`super::error`]).
pub fn clear() {
    CACHE.clear();
}

/// The memory under a recycled numpy array (its `base`): the block goes
/// back to the cache when the array is freed.
#[pyclass(module = "mcsample._core", frozen)]
pub struct RecycledBlock(Option<MmapMut>);

impl Drop for RecycledBlock {
    fn drop(&mut self) {
        if let Some(block) = self.0.take() {
            CACHE.give_back(block);
        }
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
    let mut block = take(len.saturating_mul(size_of::<T>()))?;
    let ptr = block.as_mut_ptr().cast::<T>();
    let owner = Bound::new(py, RecycledBlock(Some(block)))?;
    // SAFETY: the block holds `len` values of `T` (at least that many bytes,
    // aligned to a page, initialised (zeros, or an earlier array's values),
    // and any bytes are a valid `T`: `Pod`), and no other array or
    // reference uses it; `owner` becomes the array's base, so the map lives,
    // never moved, as long as the array.
    #[allow(unsafe_code)]
    unsafe {
        let view = ArrayViewMut::from_shape_ptr(IxDyn(shape), ptr);
        Ok(PyArrayDyn::borrow_from_array(&view, owner.into_any()))
    }
}

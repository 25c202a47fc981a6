//! [`Buffer`]: a flat array of plain numbers, backed by transparent huge
//! pages when it is large.
//!
//! A fresh heap allocation of a few megabytes costs more in page faults
//! (one per 4 KiB page, each zeroing its page) than the work that fills it.
//! Large buffers are therefore anonymous memory maps advised to use huge
//! pages (2 MiB, where the OS offers them, as numpy does for its arrays),
//! which cut the faults by a factor of 512. Small ones stay on the heap.

use bytemuck::Pod;
use memmap2::MmapMut;
use std::ops::{Deref, DerefMut};

/// Buffers of at least this many bytes are memory maps.
const MAP_MIN_BYTES: usize = 1 << 20;

enum Storage<T> {
    Heap(Vec<T>),
    Mapped(MmapMut),
}

/// A zero-initialised array of `len` values of `T`.
pub struct Buffer<T: Pod> {
    storage: Storage<T>,
    len: usize,
}

impl<T: Pod> Buffer<T> {
    /// `len` zeros.
    pub fn zeroed(len: usize) -> Self {
        let bytes = len.saturating_mul(size_of::<T>());
        let storage = if bytes >= MAP_MIN_BYTES {
            match MmapMut::map_anon(bytes) {
                Ok(map) => {
                    // Advice only: without huge pages the map still works.
                    #[cfg(target_os = "linux")]
                    let _ = map.advise(memmap2::Advice::HugePage);
                    Storage::Mapped(map)
                }
                Err(_) => Storage::Heap(vec![T::zeroed(); len]),
            }
        } else {
            Storage::Heap(vec![T::zeroed(); len])
        };
        Buffer { storage, len }
    }

    /// A copy of `values`.
    pub fn from_slice(values: &[T]) -> Self {
        let mut buffer = Self::zeroed(values.len());
        buffer.copy_from_slice(values);
        buffer
    }
}

impl<T: Pod> Deref for Buffer<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        match &self.storage {
            Storage::Heap(v) => v,
            Storage::Mapped(map) => bytemuck::cast_slice(&map[..self.len * size_of::<T>()]),
        }
    }
}

impl<T: Pod> DerefMut for Buffer<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        match &mut self.storage {
            Storage::Heap(v) => v,
            Storage::Mapped(map) => bytemuck::cast_slice_mut(&mut map[..self.len * size_of::<T>()]),
        }
    }
}

impl<T: Pod> Clone for Buffer<T> {
    fn clone(&self) -> Self {
        Self::from_slice(self)
    }
}

impl<T: Pod + std::fmt::Debug> std::fmt::Debug for Buffer<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mapped = matches!(self.storage, Storage::Mapped(_));
        write!(f, "Buffer(len={}, mapped={mapped})", self.len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_and_large_buffers_hold_their_values() {
        for len in [0, 3, 1 << 18] {
            let mut b = Buffer::<f64>::zeroed(len);
            assert_eq!(b.len(), len);
            assert!(b.iter().all(|&x| x == 0.0));
            for (i, x) in b.iter_mut().enumerate() {
                *x = i as f64;
            }
            let c = b.clone();
            assert!(c.iter().enumerate().all(|(i, &x)| x == i as f64));
        }
        let u = Buffer::from_slice(&[1u32, 2, 3]);
        assert_eq!(&u[..], &[1, 2, 3]);
    }
}

//! [`Buffer`]: a flat array of plain numbers, backed by transparent huge
//! pages when it is large.
//!
//! A fresh heap allocation of a few megabytes costs more in page faults
//! (one per 4 KiB page, each zeroing its page) than the work that fills it.
//! Large buffers are therefore anonymous memory maps advised to use huge
//! pages (2 MiB, where the OS offers them, as numpy does for its arrays),
//! which cut the faults by a factor of 512. Small ones stay on the heap.
//!
//! Even so, touching fresh memory costs more than writing it again (the
//! kernel zeroes each page on its first fault): a dropped map is therefore
//! kept for the next large buffer of about its size, as Dr.Jit's allocator
//! keeps its arrays, up to `RECYCLE_MAX_BYTES` in all. A buffer that its
//! maker overwrites whole ([`Buffer::for_overwrite`]) reuses one as it is.

use crate::alloc;
use crate::error::Result;
use bytemuck::Pod;
use memmap2::MmapMut;
use std::ops::{Deref, DerefMut};
use std::sync::{Mutex, PoisonError};

/// Buffers of at least this many bytes are memory maps.
const MAP_MIN_BYTES: usize = 1 << 20;

/// Dropped maps kept for reuse, up to 256 MiB.
static RECYCLED: MapCache = MapCache::new(256 << 20, usize::MAX);

/// Dropped memory maps kept for the next request of about their size,
/// oldest first, at most `max_maps` of them and `max_bytes` in all.
pub(crate) struct MapCache {
    kept: Mutex<Vec<MmapMut>>,
    max_bytes: usize,
    max_maps: usize,
}

impl MapCache {
    /// An empty cache with these caps.
    pub(crate) const fn new(max_bytes: usize, max_maps: usize) -> Self {
        MapCache {
            kept: Mutex::new(Vec::new()),
            max_bytes,
            max_maps,
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<MmapMut>> {
        self.kept.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The kept map of at least `bytes` and at most twice that, the
    /// smallest, taken out of the cache.
    pub(crate) fn take(&self, bytes: usize) -> Option<MmapMut> {
        let mut kept = self.lock();
        let fits = |m: &MmapMut| (bytes..=bytes.saturating_mul(2)).contains(&m.len());
        let best = (0..kept.len())
            .filter(|&i| fits(&kept[i]))
            .min_by_key(|&i| kept[i].len())?;
        Some(kept.remove(best))
    }

    /// Keeps `map` for reuse, dropping the oldest maps beyond the caps (or
    /// `map` itself, when it alone is over the byte cap).
    pub(crate) fn give_back(&self, map: MmapMut) {
        if map.len() > self.max_bytes {
            return;
        }
        let mut kept = self.lock();
        kept.push(map);
        while kept.len() > self.max_maps
            || kept.iter().map(|m| m.len()).sum::<usize>() > self.max_bytes
        {
            kept.remove(0);
        }
    }

    /// Drops every kept map.
    #[cfg(feature = "python")]
    pub(crate) fn clear(&self) {
        self.lock().clear();
    }
}

/// A fresh anonymous map of `bytes` (zeros), advised to use huge pages.
pub(crate) fn fresh_map(bytes: usize) -> Option<MmapMut> {
    let map = MmapMut::map_anon(bytes).ok()?;
    // Advice only: without huge pages the map still works.
    #[cfg(target_os = "linux")]
    let _ = map.advise(memmap2::Advice::HugePage);
    Some(map)
}

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
    /// `len` zeros, for `what` (named if the memory cannot be had).
    ///
    /// # Errors
    /// [`Error::Memory`](crate::error::Error::Memory).
    pub fn zeroed(len: usize, what: &'static str) -> Result<Self> {
        let (storage, recycled) = allocate::<T>(len, what)?;
        let mut buffer = Buffer { storage, len };
        if recycled {
            buffer.fill(T::zeroed());
        }
        Ok(buffer)
    }

    /// `len` values that the caller overwrites before reading them: a
    /// recycled map keeps what its last buffer held (any bit pattern is a
    /// valid `T`), which saves zeroing it.
    ///
    /// # Errors
    /// [`Error::Memory`](crate::error::Error::Memory).
    pub fn for_overwrite(len: usize, what: &'static str) -> Result<Self> {
        Ok(Buffer {
            storage: allocate::<T>(len, what)?.0,
            len,
        })
    }

    /// A copy of `values`.
    ///
    /// # Errors
    /// [`Error::Memory`](crate::error::Error::Memory).
    pub fn from_slice(values: &[T], what: &'static str) -> Result<Self> {
        let mut buffer = Self::for_overwrite(values.len(), what)?;
        buffer.copy_from_slice(values);
        Ok(buffer)
    }
}

/// Storage for `len` values of `T`, and whether it is a recycled map (which
/// holds old values; fresh storage holds zeros).
fn allocate<T: Pod>(len: usize, what: &'static str) -> Result<(Storage<T>, bool)> {
    let bytes = len.saturating_mul(size_of::<T>());
    if bytes >= MAP_MIN_BYTES {
        if let Some(map) = RECYCLED.take(bytes) {
            return Ok((Storage::Mapped(map), true));
        }
        if let Some(map) = fresh_map(bytes) {
            return Ok((Storage::Mapped(map), false));
        }
    }
    Ok((Storage::Heap(alloc::filled(len, T::zeroed(), what)?), false))
}

impl<T: Pod> Drop for Buffer<T> {
    fn drop(&mut self) {
        if let Storage::Mapped(map) =
            std::mem::replace(&mut self.storage, Storage::Heap(Vec::new()))
        {
            RECYCLED.give_back(map);
        }
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

/// Infallible, as `Vec`'s clone: mcsample's own code does not clone buffers
/// whose size follows the input.
impl<T: Pod> Clone for Buffer<T> {
    fn clone(&self) -> Self {
        let mut buffer = Buffer {
            storage: Storage::Heap(vec![T::zeroed(); self.len]),
            len: self.len,
        };
        buffer.copy_from_slice(self);
        buffer
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
            let mut b = Buffer::<f64>::zeroed(len, "b").unwrap();
            assert_eq!(b.len(), len);
            assert!(b.iter().all(|&x| x == 0.0));
            for (i, x) in b.iter_mut().enumerate() {
                *x = i as f64;
            }
            let c = b.clone();
            assert!(c.iter().enumerate().all(|(i, &x)| x == i as f64));
        }
        // A recycled map comes back as zeros.
        drop(Buffer::<f64>::from_slice(&[7.0; 1 << 18], "b").unwrap());
        assert!(
            Buffer::<f64>::zeroed(1 << 18, "b")
                .unwrap()
                .iter()
                .all(|&x| x == 0.0)
        );
        let u = Buffer::from_slice(&[1u32, 2, 3], "u").unwrap();
        assert_eq!(&u[..], &[1, 2, 3]);
    }

    #[test]
    fn a_buffer_beyond_memory_is_an_error() {
        let e = Buffer::<f64>::zeroed(usize::MAX / 16, "the table").unwrap_err();
        assert!(e.to_string().contains("the table"), "{e}");
    }
}

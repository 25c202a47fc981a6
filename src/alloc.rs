//! Fallible allocation. Every buffer whose size follows the input (tables,
//! images, films, meshes, BVHs, copies of arrays) is reserved here, so that
//! a request too big for memory is [`Error::Memory`] (Python's
//! `MemoryError`) rather than the process abort that Rust's infallible
//! `Vec` allocation ends in.

use crate::error::{Error, Result};
use rayon::prelude::*;

/// The error of a failed request for `len` values of `T`, for `what`.
fn memory<T>(len: usize, what: &'static str) -> Error {
    Error::Memory {
        what,
        bytes: len as u128 * size_of::<T>() as u128,
    }
}

/// An empty `Vec` with room for `len` values, for `what` (named in the
/// error).
///
/// # Errors
/// [`Error::Memory`] when the memory cannot be had.
pub fn with_capacity<T>(len: usize, what: &'static str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    reserve(&mut v, len, what)?;
    Ok(v)
}

/// Room for `additional` more values in `v`.
///
/// # Errors
/// [`Error::Memory`] when the memory cannot be had.
pub fn reserve<T>(v: &mut Vec<T>, additional: usize, what: &'static str) -> Result<()> {
    v.try_reserve_exact(additional)
        .map_err(|_| memory::<T>(v.len().saturating_add(additional), what))
}

/// Room for `additional` more values in each of the vectors named, for
/// `what`: [`reserve`] of each in turn, stopping at the first error.
macro_rules! reserve_each {
    ($additional:expr, $what:expr; $($v:expr),+ $(,)?) => {{
        let done: $crate::error::Result<()> = Ok(());
        $(let done = done.and_then(|()| $crate::alloc::reserve(&mut $v, $additional, $what));)+
        done
    }};
}
pub(crate) use reserve_each;

/// `len` copies of `value`.
///
/// # Errors
/// [`Error::Memory`] when the memory cannot be had.
pub fn filled<T: Clone>(len: usize, value: T, what: &'static str) -> Result<Vec<T>> {
    let mut v = with_capacity(len, what)?;
    v.resize(len, value);
    Ok(v)
}

/// The values of `iter`, which knows its length, in a `Vec` reserved first.
///
/// # Errors
/// [`Error::Memory`] when the memory cannot be had.
pub fn collect<T>(
    iter: impl IntoIterator<Item = T, IntoIter: ExactSizeIterator>,
    what: &'static str,
) -> Result<Vec<T>> {
    let iter = iter.into_iter();
    let mut v = with_capacity(iter.len(), what)?;
    v.extend(iter);
    Ok(v)
}

/// The values of the indexed parallel iterator `iter` in order, in a `Vec`
/// reserved first.
///
/// # Errors
/// [`Error::Memory`] when the memory cannot be had.
pub fn par_collect<T: Send>(
    iter: impl IndexedParallelIterator<Item = T>,
    what: &'static str,
) -> Result<Vec<T>> {
    let mut v = with_capacity(iter.len(), what)?;
    iter.collect_into_vec(&mut v);
    Ok(v)
}

/// Checks that `len` values of `T` could be had now, before a library that
/// allocates infallibly (a file decoder, the BVH builder) asks for about
/// that much: the memory is reserved and given back at once.
///
/// # Errors
/// [`Error::Memory`] when the memory cannot be had.
pub fn probe<T>(len: usize, what: &'static str) -> Result<()> {
    with_capacity::<T>(len, what).map(drop)
}

/// A copy of `values`.
///
/// # Errors
/// [`Error::Memory`] when the memory cannot be had.
pub fn copy<T: Clone>(values: &[T], what: &'static str) -> Result<Vec<T>> {
    let mut v = with_capacity(values.len(), what)?;
    v.extend_from_slice(values);
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_beyond_memory_is_an_error_naming_its_size() {
        let e = with_capacity::<[f32; 3]>(usize::MAX / 4, "the image").unwrap_err();
        let text = e.to_string();
        assert!(
            matches!(
                e,
                Error::Memory {
                    what: "the image",
                    ..
                }
            ),
            "{text}"
        );
        assert!(
            text.contains("the image") && text.contains("bytes"),
            "{text}"
        );
        assert!(filled(usize::MAX / 2, 0u16, "x").is_err());
        assert!(probe::<u64>(usize::MAX / 8, "x").is_err());
    }

    #[test]
    fn helpers_keep_the_values() {
        assert_eq!(filled(3, 7u8, "x").unwrap(), [7, 7, 7]);
        assert_eq!(collect((0..4).map(|i| i * 2), "x").unwrap(), [0, 2, 4, 6]);
        assert_eq!(
            par_collect((0..5).into_par_iter().map(|i| i + 1), "x").unwrap(),
            [1, 2, 3, 4, 5]
        );
        assert_eq!(copy(&[1.5, 2.5], "x").unwrap(), [1.5, 2.5]);
        probe::<f64>(10, "x").unwrap();
    }
}

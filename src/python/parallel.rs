//! The one place where work leaves the GIL: [`detached`] releases it and
//! runs the work under a panic guard, [`run_batch`] runs the core batch
//! engine so. Also the Python thread-count controls.

use super::args::index_arg;
use super::error::guarded;
use crate::parallel::{self, MAX_THREADS, Outputs};
use crate::python::Obj;
use pyo3::prelude::*;
use std::ops::Range;

/// Runs `f` with the GIL released and panics turned into `RuntimeError`.
pub fn detached<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> crate::Result<T> + Send,
) -> PyResult<T> {
    py.detach(|| guarded(|| Ok(f()?)))
}

/// Runs `kernel` over `n` items with the GIL released (see
/// [`parallel::for_each_chunk`]); returns whether every input was valid.
pub fn run_batch<O, K>(py: Python<'_>, n: usize, outputs: O, kernel: K) -> PyResult<bool>
where
    O: Outputs,
    K: Fn(Range<usize>, O) -> bool + Sync + Send,
{
    detached(py, || parallel::for_each_chunk(n, outputs, kernel))
}

/// Sets the number of threads batch calls use.
///
/// Parameters
/// ----------
/// n : int
///     From 1 to 1024. Overrides the ``MCSAMPLE_NUM_THREADS`` variable.
///     Results do not depend on it, only speed does.
#[pyfunction]
pub fn set_num_threads(n: &Obj<'_>) -> PyResult<()> {
    let n = index_arg(n, "n", 1, MAX_THREADS as u64)? as usize;
    Ok(parallel::set_num_threads(n)?)
}

/// The number of threads batch calls use: the value given to
/// ``set_num_threads``, else ``MCSAMPLE_NUM_THREADS``, else the core count.
#[pyfunction]
pub fn get_num_threads() -> PyResult<usize> {
    Ok(parallel::num_threads()?)
}

/// Panics inside a batch kernel on a pool thread: lets the test suite check
/// that a Rust panic reaches Python as ``RuntimeError``.
#[pyfunction]
pub fn _trigger_panic(py: Python<'_>) -> PyResult<()> {
    let n = 4 * parallel::CHUNK;
    run_batch(py, n, (), |range, ()| {
        assert!(
            !range.contains(&(n - 1)),
            "deliberate panic for the test suite"
        );
        true
    })?;
    Ok(())
}

//! Error mapping: core [`Error`]s become `ValueError` / `OSError` /
//! `MemoryError` (and
//! `RuntimeError` when the worker threads cannot start) with the core's
//! message unchanged; a Rust panic becomes `RuntimeError` (never PyO3's
//! `PanicException`, which `except Exception` does not catch).

use crate::error::Error;
use pyo3::exceptions::{PyMemoryError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{AssertUnwindSafe, catch_unwind};

impl From<Error> for PyErr {
    fn from(e: Error) -> PyErr {
        match e {
            Error::Io { .. } => PyOSError::new_err(e.to_string()),
            Error::Memory { .. } => {
                // Memory is short: the recycled outputs' cache gives its
                // blocks back, so that the next request may succeed.
                super::recycle::clear();
                PyMemoryError::new_err(e.to_string())
            }
            Error::ThreadPool { .. } => PyRuntimeError::new_err(e.to_string()),
            Error::InvalidWeight { .. }
            | Error::AllZero { .. }
            | Error::Shape { .. }
            | Error::Parameter { .. }
            | Error::Element { .. }
            | Error::Choice { .. }
            | Error::Integer { .. }
            | Error::TooLarge { .. }
            | Error::Index { .. }
            | Error::Argument { .. }
            | Error::Rows { .. }
            | Error::NotEnergyConserving { .. } => PyValueError::new_err(e.to_string()),
        }
    }
}

/// Runs `f`, turning a panic into `RuntimeError`: the last line of defence
/// between a bug in mcsample and the Python process. It needs no GIL, so it
/// can wrap work done with the GIL released.
pub fn guarded<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|payload| {
        let detail = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        Err(PyRuntimeError::new_err(format!(
            "internal error in mcsample (please report it): {detail}"
        )))
    })
}

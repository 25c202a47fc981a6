//! Pickling of the compiled classes: each `__reduce__` names how to make
//! the object again — its class (or one of the class's private `_from_*`
//! constructors), the arguments and the keyword arguments — and
//! `mcsample._pickling.rebuild` makes it on unpickling. The arguments are
//! the values the object was built from, so the rebuilt object gives the
//! same bits.

use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// `__reduce__`'s value for `obj`: `(rebuild, (type(obj), method, args,
/// kwargs))`; `method` None calls the class itself.
pub fn reduce<'py>(
    obj: &Obj<'py>,
    method: Option<&str>,
    args: Bound<'py, PyTuple>,
    kwargs: Option<Bound<'py, PyDict>>,
) -> PyResult<Obj<'py>> {
    let py = obj.py();
    let rebuild = py
        .import(pyo3::intern!(py, "mcsample._pickling"))?
        .getattr(pyo3::intern!(py, "rebuild"))?;
    let kwargs = match kwargs {
        Some(k) => k,
        None => PyDict::new(py),
    };
    let call = (obj.get_type(), method, args, kwargs);
    Ok((rebuild, call).into_pyobject(py)?.into_any())
}

//! Result records of the bindings, one family with the Python ones
//! (`mcsample.results`): attributes by name, a short repr (arrays by shape
//! and dtype, through `mcsample.results.describe`), and unpacking,
//! indexing and a length in field order (where a record took the place of
//! a tuple, that tuple's order).

use pyo3::prelude::*;
use pyo3::types::{PyString, PyTuple};

/// `Name(field=..., ...)`, each field described as `mcsample.results`
/// describes it.
pub fn repr(py: Python<'_>, name: &str, fields: &[(&str, &Py<PyAny>)]) -> PyResult<String> {
    let describe = py
        .import(pyo3::intern!(py, "mcsample.results"))?
        .getattr(pyo3::intern!(py, "describe"))?;
    let parts = fields
        .iter()
        .map(|(field, value)| {
            let text = describe.call1((value.bind(py),))?;
            Ok(format!("{field}={}", text.cast::<PyString>()?.to_cow()?))
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok(format!("{name}({})", parts.join(", ")))
}

/// The tuple a record stands for.
pub fn tuple<'py>(py: Python<'py>, fields: &[&Py<PyAny>]) -> PyResult<Bound<'py, PyTuple>> {
    PyTuple::new(py, fields.iter().map(|f| f.bind(py)))
}

/// A frozen pyclass of array fields with getters and the family's repr,
/// which also unpacks, indexes and has a length in field order (as the
/// tuple a record took the place of; every record is true).
macro_rules! record {
    (
        $(#[$meta:meta])*
        $rust:ident, $name:literal, $module:literal,
        { $( $(#[$fmeta:meta])* $field:ident ),+ $(,)? }
    ) => {
        $(#[$meta])*
        #[pyclass(module = $module, name = $name, frozen, sequence)]
        pub struct $rust {
            $( $(#[$fmeta])* #[pyo3(get)] pub $field: Py<PyAny>, )+
        }

        #[pymethods]
        impl $rust {
            fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
                $crate::python::records::repr(py, $name, &[$((stringify!($field), &self.$field)),+])
            }

            fn __bool__(&self) -> bool {
                true
            }

            /// The record of these fields (the unpickling constructor).
            #[staticmethod]
            #[doc(hidden)]
            fn _from_fields($($field: $crate::python::Obj<'_>),+) -> Self {
                Self::new($($field),+)
            }

            /// Pickles as its fields.
            fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<$crate::python::Obj<'py>> {
                let this = slf.get();
                let fields = $crate::python::records::tuple(slf.py(), &[$(&this.$field),+])?;
                $crate::python::pickle::reduce(slf.as_any(), Some("_from_fields"), fields, None)
            }

            fn __len__(&self) -> usize {
                [$(stringify!($field)),+].len()
            }

            fn __getitem__<'py>(&self, py: Python<'py>, index: isize) -> PyResult<$crate::python::Obj<'py>> {
                $crate::python::records::tuple(py, &[$(&self.$field),+])?
                    .as_any()
                    .get_item(index)
            }

            fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<$crate::python::Obj<'py>> {
                Ok($crate::python::records::tuple(py, &[$(&self.$field),+])?
                    .as_any()
                    .try_iter()?
                    .into_any())
            }
        }

        impl $rust {
            /// The record of these values, in field order.
            pub fn new($($field: $crate::python::Obj<'_>),+) -> Self {
                Self { $($field: $field.unbind()),+ }
            }

            /// The record of freshly computed arrays, each through
            /// [`finish`]($crate::python::arrays::finish).
            pub fn finished<'py>(
                $($field: Bound<'py, numpy::PyArrayDyn<impl numpy::Element>>),+
            ) -> PyResult<Self> {
                Ok(Self { $($field: $crate::python::arrays::finish($field)?.unbind()),+ })
            }
        }
    };
}
pub(crate) use record;

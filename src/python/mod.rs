//! The binding layer (`mcsample._core`): argument checks, numpy in and out,
//! GIL release and error mapping, one file per Python submodule. No
//! sampling logic lives here.

mod args;
mod arrays;
mod batch;
mod c_order;
mod distr;
mod envmap;
mod error;
mod estimators;
mod frame;
mod io;
mod mis;
mod parallel;
mod phong;
mod pickle;
mod piecewise;
mod qmc;
mod records;
mod recycle;
mod render;
mod rng;
mod warp;

use pyo3::prelude::*;

/// Any Python object an argument or result may be (most arguments are
/// array-likes converted in the function).
pub type Obj<'py> = Bound<'py, PyAny>;

/// The keyword `out` of the batch methods: an array to write into, or none.
pub type Out<'a, 'py> = Option<&'a Obj<'py>>;

fn submodule<'py>(
    parent: &Bound<'py, PyModule>,
    name: &str,
    register: fn(&Bound<'py, PyModule>) -> PyResult<()>,
) -> PyResult<()> {
    let py = parent.py();
    let m = PyModule::new(py, name)?;
    register(&m)?;
    parent.add_submodule(&m)?;
    // Make `import mcsample._core.<name>` and `from mcsample._core.<name>
    // import f` work: extension submodules are not packages.
    let qualified = format!("mcsample._core.{name}");
    m.setattr("__name__", &qualified)?;
    py.import("sys")?
        .getattr("modules")?
        .set_item(qualified, &m)
}

/// mcsample's compiled core. Use the ``mcsample`` package, which re-exports it.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<rng::PyRng>()?;
    m.add_function(wrap_pyfunction!(rng::uniform, m)?)?;
    m.add_function(wrap_pyfunction!(parallel::set_num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(parallel::get_num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(parallel::_trigger_panic, m)?)?;
    distr::register(m)?;
    piecewise::register(m)?;
    m.add_class::<frame::PyFrame>()?;
    m.add_class::<phong::PyPhong>()?;
    m.add_class::<phong::PyPhongSample>()?;
    m.add_class::<envmap::PyEnvMap>()?;
    m.add_class::<envmap::PyEnvSample>()?;
    submodule(m, "warp", warp::register)?;
    submodule(m, "io", io::register)?;
    submodule(m, "mis", mis::register)?;
    submodule(m, "estimators", estimators::register)?;
    submodule(m, "render", render::register)?;
    submodule(m, "qmc", qmc::register)?;
    Ok(())
}

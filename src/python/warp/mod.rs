//! `mcsample.warp`: batched bindings of [`crate::warp`]. Every function
//! takes an array-like of points (`(..., K)`, or any shape for the interval
//! warps), keeps float32 input in float32, checks `u ∈ [0, 1]` (or
//! finiteness of points) in the kernel's own pass, and runs on all cores
//! with the GIL released.
//!
//! The functions live in [`shapes`] (disks, spheres, hemispheres, cones,
//! triangles, intervals, tents, linear ramps) and [`lobes`] (the standard
//! normal, Beckmann, von Mises–Fisher, rough fibre, lunes, tangent
//! directions, the bilinear density); [`params`] checks their parameters.

/// Defines one `#[pyfunction]` per entry, mapping `$x` (points of `$k`
/// values, checked with `Check::$check`) to `$m` values through the kernel
/// `$kernel` (built with the precision alias `$F` in scope; `?` may be used
/// to validate parameters). The docstring is the entry's summary followed
/// by Parameters and Returns sections made from the shapes and the
/// phrases given (`$k` and `$m` are checked against the kernel's).
/// Parameters in braces before the points come first in the signature (as
/// Mitsuba orders `interval_to_linear(v0, v1, sample)`). Every function
/// also takes a keyword `out`: an array to write into, as numpy's ufuncs
/// do. Kernels given as closures are marked `#[inline(always)]`: one left
/// out of line is compiled for the baseline instruction set, outside the
/// vector loop of [`crate::simd::map_rows`] (the cosine-power warp's took
/// 122 ms for 10^7 float32 points, calling the C library's `floor` per
/// point; inlined, 11.5 ms).
macro_rules! warps {
    ($(
        $(#[doc = $summary:literal])*
        fn $name:ident(
            $({ $($q:ident: $qty:ty = $q_doc:literal),* })?
            $x:ident: [$k:tt; $check:ident] $x_doc:literal
            $(, $p:ident: $pty:ty = $p_doc:literal)*
        ) -> [$m:tt] $result_doc:literal
        = |$F:ident| $(let $bound:pat_param = $check_param:expr;)* $kernel:expr;
    )*) => {$(
        #[pyfunction]
        #[pyo3(signature = ($($($q,)*)? $x $(, $p)*, *, out = None))]
        $(#[doc = $summary])*
        #[doc = ""]
        #[doc = "Parameters"]
        #[doc = "----------"]
        $($(#[doc = concat!(stringify!($q), " : ", $q_doc)])*)?
        #[doc = concat!(stringify!($x), " : ", points_doc!($k), ", ", $x_doc)]
        $(#[doc = concat!(stringify!($p), " : ", $p_doc)])*
        #[doc = "out : ndarray, optional, keyword only"]
        #[doc = "     Written with the result and returned (its shape and dtype)."]
        #[doc = ""]
        #[doc = "Returns"]
        #[doc = "-------"]
        #[doc = concat!(result_doc!($m), ", ", $result_doc, ".")]
        pub fn $name<'py>(
            py: Python<'py>,
            $($($q: $qty,)*)?
            $x: &Obj<'py>
            $(, $p: $pty)*,
            out: Out<'_, 'py>,
        ) -> PyResult<Obj<'py>> {
            with_precision!($x, $F => {
                let points = Points::<$F, $k>::extract($x, stringify!($x))?;
                $(let $bound = $check_param;)*
                let kernel = shaped::<$F, $k, $m, _>($kernel);
                map_into(py, &points, Check::$check, out, kernel)
            })
        }
    )*};
}

/// The input line of a warp's docstring for points of `$k` values.
macro_rules! points_doc {
    (1) => {
        "float or array_like, any shape (one value a point)"
    };
    ($k:tt) => {
        concat!("array_like, shape (..., ", $k, ")")
    };
}

/// The result line of a warp's docstring for `$m` values per point.
macro_rules! result_doc {
    (1) => {
        "ndarray, the points' batch shape (a scalar for one point)"
    };
    ($m:tt) => {
        concat!("ndarray, shape (..., ", $m, ")")
    };
}

/// `kernel`, with the point and result sizes a [`warps!`] entry states.
fn shaped<F, const K: usize, const M: usize, G: Fn([F; K]) -> [F; M]>(kernel: G) -> G {
    kernel
}

/// Adds the `#[pyfunction]`s named to module `m`.
macro_rules! add_functions {
    ($m:expr, $($f:ident),* $(,)?) => { $($m.add_function(wrap_pyfunction!($f, $m)?)?;)* };
}

mod lobes;
mod params;
mod shapes;

use pyo3::prelude::*;

/// Registers the warp functions in module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    shapes::register(m)?;
    lobes::register(m)
}

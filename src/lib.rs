//! # mcsample
//!
//! The Monte Carlo sampling toolkit of a physically based renderer: random
//! numbers, warps, distributions and the statistics that prove them right,
//! with a Python front (the `python` feature) built by maturin.
//!
//! ## Modules
//! - [`rng`]: PCG32 with jump-ahead, uniform batches.
//! - [`parallel`]: the batch engine (chunks on a rayon pool, thread count).
//! - [`warp`]: `square_to_*` warps, their densities and inverses.
//! - [`alloc`]: fallible allocation (a request too big for memory is an
//!   error, never an abort).
//! - [`buffer`]: large flat arrays on huge pages.
//! - [`distr`]: discrete tables (CDF inversion, alias), 2D tables and
//!   piecewise-constant densities.
//! - [`envmap`]: environment maps (lat-long, angular, cube) and their
//!   importance sampling.
//! - [`estimators`]: irradiance and reflected radiance under an envmap,
//!   by several strategies and MIS.
//! - [`phong`]: the energy-normalised Phong BRDF and its sampling.
//! - [`qmc`]: quasi-Monte Carlo point sets (Sobol', Halton).
//! - [`mis`]: multiple importance sampling heuristics.
//! - [`render`]: a compact renderer (BVH, camera, direct and path
//!   integrators) for comparing sampling strategies with Mitsuba 3.
//! - [`frame`]: orthonormal frames around a normal.
//! - [`io`]: EXR, Radiance HDR and PNG files.
//! - [`simd`]: runtime dispatch of batch loops to AVX-512 or AVX2 + FMA.
//! - [`math`]: the [`math::Real`] scalar trait (`f32` / `f64`) and helpers.
//! - [`error`]: the one error type.
//!
//! ## Conventions
//! - Densities on directions are per steradian; on planar domains per unit
//!   area; on intervals per unit length.
//! - Local shading frame: the normal is +z.
//! - Uniform input `u` lies in `[0, 1]`; `u = 1` maps inside the domain.
//! - Kernels are infallible and total; inputs are validated at the batch
//!   boundary. Results are independent of the thread count.
#![deny(unsafe_code)]
#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod alloc;
pub mod buffer;
pub mod distr;
pub mod envmap;
pub mod error;
pub mod estimators;
pub mod frame;
pub mod io;
pub mod math;
pub mod mis;
pub mod parallel;
pub mod phong;
pub mod qmc;
#[cfg(test)]
mod quadrature;
pub mod render;
pub mod rng;
pub mod sampler;
pub mod simd;
pub mod warp;

#[cfg(feature = "python")]
mod python;

pub use error::{Error, Result};

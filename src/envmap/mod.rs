//! Environment maps (image-based lighting): radiance from every direction,
//! and importance sampling of directions in proportion to it.
//!
//! An [`EnvMap`] is an [`Image`] on the sphere through a [`Mapping`]
//! (lat-long exactly as Mitsuba 3's `envmap` emitter, Debevec's angular
//! probes, OpenGL cube maps), turned by `to_world` and scaled by `scale`.
//! Every method takes and returns world directions.
//!
//! # Sampling
//! [`Sampling::Luminance`] (the default for lat-long maps) follows `Y`, the
//! luminance of the bilinear radiance (in `luminance.rs`):
//! the patches between texel centres are drawn in proportion to their
//! `∫ Y dω` exactly, and points within them in proportion to `Y`, so the
//! density per steradian is `Y(ω)/∫Y dω` times `s̄/sin θ` (`s̄` the patch's
//! mean `sin θ`: a ratio within about `Δθ·cot θ/2` of 1). Wherever
//! `eval(d) > 0`, `pdf(d) > 0`, also at the poles.
//!
//! [`Sampling::Piecewise`] (the default for angular and cube maps) samples
//! a [`PiecewiseConstant2D`]
//! over the cells of the map's domain in which the bilinear radiance is one
//! polynomial (lat-long: the patches between texel centres, `W × (H − 1)`;
//! angular and cube: half-texel cells), each weighted by the luminance of
//! its mean radiance times the Jacobian `dω/dp` at its centre. A cell where
//! the radiance is not 0 has weight > 0, so wherever `eval(d) > 0`,
//! `pdf(d) > 0`: environment-only sampling is unbiased (also for one bright
//! texel, also at the poles). Within a cell the density per steradian is
//! `p_cell / (dω/dp)`.
//!
//! [`Sampling::Mitsuba`] (lat-long only) reproduces Mitsuba's density: the
//! bilinear interpolant of luminance × sin θ on the `(W + 1) × H` vertex
//! grid (the periodic column repeated), shifted by half a texel,
//! `pdf = bilerp / (2π² sin θ)`. It is 0 near a pole whose neighbouring row
//! is black, even where the map is not, as Mitsuba's is.
//!
//! `compensate` subtracts the mean texel luminance before the distribution
//! is built and clamps at 0 (MIS compensation, Karlík et al. 2019, as
//! Mitsuba's `mis_compensation`); it is switched off for maps whose minimum
//! is within 1% of the mean. A compensated map is only unbiased in an MIS
//! combination with a strategy that covers its dark parts.
//!
//! An all-black map (or `scale = 0`) is valid: it samples nothing (pdf 0,
//! weight 0, a valid unit direction) and its pdf is 0 everywhere.
//!
//! # Files
//! This file holds the types, the constructor and the one-at-a-time `eval`
//! and `pdf`. [`EnvMap::sample`] and the one way every draw becomes an
//! [`EnvSample`] are in `sample.rs`; the batch pipelines in `batch.rs`; the
//! build of the sampling distribution in `distribution.rs`; the polar lookup
//! table of `pdf` in `polar.rs`; resampling in `convert.rs`; [`CellSampler`]
//! (one O(1) draw at a time) in `cell_sampler.rs`; the parameterisations,
//! the texels, the luminance density and Mitsuba's bilinear density in
//! `mapping.rs`, `image.rs`, `luminance.rs` and `bilinear.rs`; the
//! hierarchical warping that samples the latter in `pyramid.rs`.

mod batch;
mod bilinear;
mod cell;
mod cell_sampler;
mod convert;
mod distribution;
mod image;
mod luminance;
mod mapping;
mod polar;
mod pyramid;
mod sample;

pub use batch::EnvSamples;

/// Texels an environment map may have, by any way in (an array, a file,
/// `convert`): `2^28`, a 16384 × 16384 map (3 GiB of float32 RGB).
pub const MAX_TEXELS: usize = crate::io::MAX_PIXELS;
pub use bilinear::BilinearGrid;
pub use cell_sampler::CellSampler;
pub use convert::texel_centre;
pub use image::{Corners, Image};
pub use mapping::{Mapping, normalized, polar_angle};
pub use polar::{PolarQuery, PolarTable, TableFloat};
pub use sample::{EnvSample, PdfQuery};

use crate::error::{Error, Result};
use crate::math::Real;
use crate::warp::V3;
use distribution::Distribution;
use std::sync::Arc;

#[cfg(doc)]
use crate::distr::PiecewiseConstant2D;

/// A 3×3 matrix, row-major.
pub type Matrix3 = [[f64; 3]; 3];

const IDENTITY: Matrix3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// How an [`EnvMap`] samples directions (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// In proportion to the luminance of the bilinear radiance within
    /// cells, and to its integral over the sphere across them (lat-long
    /// only; their default).
    Luminance,
    /// Piecewise-constant over the cells of the bilinear radiance (the
    /// default of angular and cube maps).
    Piecewise,
    /// Mitsuba 3's bilinear density on the vertex grid (lat-long only).
    Mitsuba,
}

impl Sampling {
    /// The name used in the Python API: `"luminance"`, `"piecewise"` or
    /// `"mitsuba"`.
    pub fn name(self) -> &'static str {
        match self {
            Sampling::Luminance => "luminance",
            Sampling::Piecewise => "piecewise",
            Sampling::Mitsuba => "mitsuba",
        }
    }

    /// The mode called `name` (see [`Sampling::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "luminance" => Some(Sampling::Luminance),
            "piecewise" => Some(Sampling::Piecewise),
            "mitsuba" => Some(Sampling::Mitsuba),
            _ => None,
        }
    }

    /// The default of maps of `mapping`: [`Sampling::Luminance`] for
    /// lat-long maps, [`Sampling::Piecewise`] for the others.
    pub fn default_for(mapping: Mapping) -> Self {
        match mapping {
            Mapping::LatLong => Sampling::Luminance,
            Mapping::Angular | Mapping::Cube => Sampling::Piecewise,
        }
    }

    /// Whether maps of `mapping` can be sampled this way (the lat-long
    /// densities need a lat-long map).
    pub fn supports(self, mapping: Mapping) -> bool {
        self == Sampling::Piecewise || mapping == Mapping::LatLong
    }
}

/// The options of an [`EnvMap`] beyond its image. The default is a
/// lat-long map's ([`Options::for_mapping`] gives another mapping's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// How the image covers the sphere.
    pub mapping: Mapping,
    /// Local-to-world rotation (row-major).
    pub to_world: Matrix3,
    /// Radiance scale, finite and `>= 0`.
    pub scale: f64,
    /// The sampling density.
    pub sampling: Sampling,
    /// MIS compensation.
    pub compensate: bool,
}

impl Options {
    /// The default options of a map of `mapping`, with its default sampling
    /// ([`Sampling::default_for`]).
    pub fn for_mapping(mapping: Mapping) -> Self {
        Options {
            mapping,
            sampling: Sampling::default_for(mapping),
            ..Options::default()
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            mapping: Mapping::LatLong,
            to_world: IDENTITY,
            scale: 1.0,
            sampling: Sampling::Luminance,
            compensate: false,
        }
    }
}

/// An environment map: radiance `L(d)` for every world direction and a
/// sampler of directions with a density close to `L`.
#[derive(Clone, Debug)]
pub struct EnvMap {
    /// Shared with the compensated twin ([`EnvMap::compensated`]).
    image: Arc<Image>,
    options: Options,
    distribution: Distribution,
    polar: Option<PolarTable>,
}

impl EnvMap {
    /// An environment map of the row-major RGB `image` (`width × height`
    /// texels; cube maps: the six faces one below the other).
    ///
    /// # Errors
    /// As [`Image::new`]; [`Error::Parameter`] for a `scale` that is
    /// negative or not finite, or a `to_world` that is not a rotation (an
    /// orthonormal matrix, to 1e-4); [`Error::Choice`] for
    /// [`Sampling::Luminance`] or [`Sampling::Mitsuba`] on a map that is
    /// not lat-long.
    pub fn new(width: usize, height: usize, data: &[f32], options: Options) -> Result<Self> {
        let image = Image::new(options.mapping, width, height, data)?;
        Self::from_image(image, options)
    }

    fn from_image(image: Image, options: Options) -> Result<Self> {
        if !(options.scale >= 0.0 && options.scale.is_finite()) {
            return Err(Error::Parameter {
                arg: "scale",
                value: options.scale,
                requirement: "must be finite and >= 0",
            });
        }
        check_rotation(&options.to_world)?;
        if !options.sampling.supports(options.mapping) {
            return Err(Error::Choice {
                arg: "sampling",
                value: options.sampling.name().into(),
                requirement: format!(
                    "{:?} sampling is for lat-long maps; mapping is {:?} (use \"piecewise\")",
                    options.sampling.name(),
                    options.mapping.name()
                ),
            });
        }
        let (distribution, polar) = distribution::build(&image, &options)?;
        Ok(EnvMap {
            image: Arc::new(image),
            options,
            distribution,
            polar,
        })
    }

    /// The texels (after the padding of tiny lat-long maps).
    pub fn image(&self) -> &Image {
        &self.image
    }

    /// The options it was built with.
    pub fn options(&self) -> &Options {
        &self.options
    }

    /// The same map with `compensate` set (its texels shared, its mapping
    /// and sampling; the density of MIS compensation), or `None` when that
    /// changes nothing: a map already compensated, or one whose
    /// compensation is switched off (black, or nearly constant).
    ///
    /// # Errors
    /// [`Error::Memory`] when its tables cannot be had.
    pub fn compensated(&self) -> Result<Option<EnvMap>> {
        if self.options.compensate || !distribution::compensates(&self.image, &self.options)? {
            return Ok(None);
        }
        let options = Options {
            compensate: true,
            ..self.options
        };
        let (distribution, polar) = distribution::build(&self.image, &options)?;
        Ok(Some(EnvMap {
            image: Arc::clone(&self.image),
            options,
            distribution,
            polar,
        }))
    }

    /// The local direction of the world direction `d`: `to_worldᵀ·d`.
    #[inline(always)]
    fn to_local<F: Real>(&self, d: V3<F>) -> V3<F> {
        let m = &self.options.to_world;
        std::array::from_fn(|k| F::c(m[0][k]) * d[0] + F::c(m[1][k]) * d[1] + F::c(m[2][k]) * d[2])
    }

    /// The world direction of the local direction `d`: `to_world·d`.
    #[inline(always)]
    fn to_world<F: Real>(&self, d: V3<F>) -> V3<F> {
        let m = &self.options.to_world;
        std::array::from_fn(|k| F::c(m[k][0]) * d[0] + F::c(m[k][1]) * d[1] + F::c(m[k][2]) * d[2])
    }

    /// The domain point of `mapping` (this map's) that looks along the
    /// world direction `d`, computed in `F`.
    #[inline(always)]
    fn uv_of<F: Real>(&self, mapping: Mapping, d: V3<F>) -> [F; 2] {
        mapping.from_dir(self.to_local(d))
    }

    /// The domain point `(s, t)` that looks along the world direction `d`.
    #[inline]
    pub fn dir_to_uv(&self, d: V3<f64>) -> [f64; 2] {
        self.uv_of(self.options.mapping, d)
    }

    /// The world direction of the domain point `p`.
    #[inline]
    pub fn uv_to_dir(&self, p: [f64; 2]) -> V3<f64> {
        self.to_world(self.options.mapping.to_dir(p))
    }

    /// Radiance at domain point `p`: the bilinear image value times scale.
    #[inline(always)]
    fn radiance_at<F: Real>(&self, p: [F; 2]) -> V3<F> {
        self.radiance_of(&self.image.corners(self.options.mapping, p))
    }

    /// The blend of the texels `corners` times scale.
    #[inline(always)]
    fn radiance_of<F: Real>(&self, corners: &Corners<F>) -> V3<F> {
        let scale = F::c(self.options.scale);
        self.image.blend(corners).map(|v| v * scale)
    }

    /// Radiance arriving from the world direction `d`, per RGB channel,
    /// computed in `F` (in `f32`, the place on the map is good to a few
    /// `f32` ulps, a ten-thousandth of a texel on a 1024-wide map).
    #[inline]
    pub fn eval<F: Real>(&self, d: V3<F>) -> V3<F> {
        self.radiance_at(self.uv_of(self.options.mapping, d))
    }

    /// The density of [`EnvMap::sample`] at the world direction `d`, per
    /// steradian.
    #[inline]
    pub fn pdf(&self, d: V3<f64>) -> f64 {
        match (&self.polar, &self.distribution) {
            (Some(table), _) => table.pdf(table.query(d)),
            (None, Distribution::Luminance(density)) => self.luminance_pdf(density, d),
            (None, _) => self.pdf_at(self.pdf_query(d)),
        }
    }
}

/// Checks that `m` is orthonormal (to 1e-4) and finite.
fn check_rotation(m: &Matrix3) -> Result<()> {
    let mut worst = 0.0f64;
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|k| m[k][i] * m[k][j]).sum();
            let expected = if i == j { 1.0 } else { 0.0 };
            let err = (dot - expected).abs();
            worst = if err.is_nan() {
                f64::NAN
            } else {
                worst.max(err)
            };
        }
    }
    if worst <= 1e-4 {
        Ok(())
    } else {
        Err(Error::Parameter {
            arg: "to_world",
            value: worst,
            requirement: "must be a rotation: the deviation of to_world^T to_world from the identity (shown) must be <= 1e-4",
        })
    }
}

#[cfg(test)]
pub(crate) mod tests;

//! The polar lookup table behind [`EnvMap::pdf`] for piecewise lat-long
//! and angular maps: where a world direction falls in the sampling table,
//! without branches or library calls, and the density of each cell.

use super::distribution::Distribution;
use super::image::Image;
use super::luminance::LuminanceFloat;
use super::mapping::Mapping;
use super::{EnvMap, Matrix3, Options};
use crate::buffer::Buffer;
use crate::error::Result;
use crate::math::{Real, atan2};
use crate::parallel;
use crate::warp::V3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Mitsuba's `Epsilon<float>` (2⁻²⁴): the floor of sin θ in the density of
/// the polar tables, as in Mitsuba's envmap pdf.
pub(super) const SIN_FLOOR: f64 = 1.0 / 16_777_216.0;

/// `dω/dq` of a polar sampling table at a direction `θ` from its axis:
/// `2π² max(|sin θ|, 2⁻²⁴)` (see [`SIN_FLOOR`]).
#[inline(always)]
pub(super) fn polar_jacobian<F: Real>(sin_theta: F) -> F {
    F::c(2.0 * PI * PI) * sin_theta.abs().max(F::c(SIN_FLOOR))
}

/// The piecewise table of a lat-long or angular map seen from a world
/// direction, for [`EnvMap::pdf`] without branches or library calls (so
/// that batches vectorise): the table's axes `(a, b, c)` = `axes · d`,
/// azimuth `ψ = atan2(a, b)/2π − shift` wrapped into `[0, 1)`, polar angle
/// `ρ = atan2(√(a² + b²), c)/π`, and the density of each cell per unit
/// table area, row-major.
#[derive(Clone, Debug)]
pub struct PolarTable {
    axes: Matrix3,
    shift: f64,
    rows: usize,
    cols: usize,
    density: Buffer<f64>,
    /// `density` rounded to `f32`, for batches in `f32`: half the bytes, so
    /// more of the table stays in the caches.
    density_f32: Buffer<f32>,
}

/// The float types in which [`EnvMap::pdf_into`] reads a [`PolarTable`]'s
/// densities and the luminance density's tables: each from its own copy
/// of the table. Sealed: its supertrait holds the luminance density's
/// reads and is the crate's own.
pub trait TableFloat: LuminanceFloat {
    /// The densities of `table` in this type.
    fn densities(table: &PolarTable) -> &[Self];
}

impl TableFloat for f32 {
    fn densities(table: &PolarTable) -> &[f32] {
        &table.density_f32
    }
}

impl TableFloat for f64 {
    fn densities(table: &PolarTable) -> &[f64] {
        &table.density
    }
}

/// Where a direction falls in a [`PolarTable`]: the cell's row and column
/// (whole numbers, as floats so that batches of queries vectorise) and
/// `dq/dω` there, computed in `F`.
pub type PolarQuery<F> = [F; 3];

impl PolarTable {
    /// The table of `distribution` when it is a piecewise polar table, from
    /// the `weights` it was built from (reused for the densities).
    ///
    /// # Errors
    /// As [`parallel::install`].
    pub(super) fn new(
        distribution: &Distribution,
        mut weights: Buffer<f64>,
        image: &Image,
        options: &Options,
    ) -> Result<Option<Self>> {
        let Distribution::Piecewise(table) = distribution else {
            return Ok(None);
        };
        // Rows of the local frame that give (a, b, c): lat-long (x, −z, y)
        // with the azimuth shifted to the first texel centre, angular (y, x, z).
        let (pick, shift): ([[f64; 3]; 3], f64) = match options.mapping {
            Mapping::LatLong => (
                [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
                0.5 / image.width() as f64,
            ),
            Mapping::Angular => ([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], 0.0),
            Mapping::Cube => return Ok(None),
        };
        // axes = pick · to_worldᵀ, so that (a, b, c) = axes · d for world d.
        let m = &options.to_world;
        let axes = pick.map(|p| std::array::from_fn(|j| (0..3).map(|k| p[k] * m[j][k]).sum()));
        let (rows, cols) = table.table().shape();
        // The same division as PiecewiseConstant2D::cell_pdf, so the same bits.
        let integral = table.integral();
        parallel::install(|| weights.par_iter_mut().for_each(|w| *w /= integral))?;
        let density = weights;
        let mut density_f32 = Buffer::for_overwrite(density.len(), "the polar table")?;
        parallel::install(|| {
            (density_f32.par_iter_mut(), density.par_iter())
                .into_par_iter()
                .for_each(|(single, &double)| *single = double as f32);
        })?;
        Ok(Some(PolarTable {
            axes,
            shift,
            rows,
            cols,
            density,
            density_f32,
        }))
    }

    /// The cell and Jacobian of the world direction `d` (see [`PolarQuery`]).
    #[inline(always)]
    pub fn query<F: Real>(&self, d: V3<F>) -> PolarQuery<F> {
        let [a, b, c] = self
            .axes
            .map(|m| F::c(m[0]) * d[0] + F::c(m[1]) * d[1] + F::c(m[2]) * d[2]);
        // The angles need no normalisation of `d`; sin θ = r/|d| does.
        let r = (a * a + b * b).sqrt();
        let length = (r * r + c * c).sqrt();
        let psi = atan2(a, b) * F::c(0.5 / PI) - F::c(self.shift);
        let psi = psi - psi.floor();
        let rho = atan2(r, c) * F::c(1.0 / PI);
        let (rows, cols) = (F::c(self.rows as f64), F::c(self.cols as f64));
        let col = (psi * cols).floor().min(cols - F::one());
        let row = (rho * rows).floor().min(rows - F::one());
        // 1/(2π² max(sin θ, floor)), one division; 0 for d = 0.
        let scaled_sin = (r.max(F::c(SIN_FLOOR) * length)).max(F::min_positive_value());
        [row, col, length / (F::c(2.0 * PI * PI) * scaled_sin)]
    }

    /// The index in [`PolarTable::density`] of a query's cell.
    #[inline(always)]
    pub fn cell<F: Real>(&self, [row, col, _]: PolarQuery<F>) -> usize {
        row.f64() as usize * self.cols + col.f64() as usize
    }

    /// The density of every cell per unit table area, row-major.
    pub fn density(&self) -> &[f64] {
        &self.density
    }

    /// The density per steradian of a query.
    #[inline(always)]
    pub(super) fn pdf<F: Real>(&self, query: PolarQuery<F>) -> f64 {
        self.density.get(self.cell(query)).copied().unwrap_or(0.0) * query[2].f64()
    }
}

impl EnvMap {
    /// The polar table behind [`EnvMap::pdf`] (piecewise lat-long and
    /// angular maps; else None), for batches: [`PolarTable::query`] is
    /// branch-free and vectorises; then the cells' densities are read, all
    /// of a block together so that the reads overlap, and multiplied by the
    /// query's `dq/dω`. Computed in `f64` this is [`EnvMap::pdf`]; in `f32`
    /// a direction within a few `f32` ulps of a cell edge may be placed in
    /// the neighbouring cell.
    pub fn polar_table(&self) -> Option<&PolarTable> {
        self.polar.as_ref()
    }
}

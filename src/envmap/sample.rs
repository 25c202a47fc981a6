//! The one sampling path of an [`EnvMap`]: a point drawn in the sampling
//! table becomes a direction, its density per steradian and the radiance
//! along it, an [`EnvSample`]. [`EnvMap::sample`], the batch pipeline
//! ([`EnvMap::sample_into`]) and [`CellSampler::sample`] differ only in how
//! they draw the table point; all three then go through
//! [`EnvMap::sample_at`] (the batch as its two halves, with a SIMD loop
//! between them). Also the way back, for `pdf`: where a direction falls in
//! the table ([`EnvMap::pdf_query`]).

use super::EnvMap;
use super::distribution::Distribution;
use super::image::Corners;
use super::luminance::{LuminanceDensity, LuminanceFloat};
use super::mapping::{Mapping, normalized, polar_angle};
use super::polar::{SIN_FLOOR, polar_jacobian};
use crate::distr::PiecewiseConstant2D;
use crate::math::{Real, atan2, sin_cos_turn};
use crate::warp::{self, V3};
use std::f64::consts::PI;

#[cfg(doc)]
use super::{CellSampler, PolarTable, image::Image, image::LatLongPlace};

/// A direction drawn from an environment map: the record of every way of
/// drawing one ([`EnvMap::sample`], [`EnvMap::sample_into`],
/// [`CellSampler::sample`]), computed in `F`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnvSample<F = f64> {
    /// World direction toward the environment (unit length).
    pub direction: V3<F>,
    /// Its density per steradian.
    pub pdf: F,
    /// `L(direction)/pdf` per RGB channel; 0 when `pdf = 0`.
    pub weight: V3<F>,
    /// The radiance `L(direction)` arriving along it, per RGB channel (not
    /// divided by the density, as a renderer's light sample wants it).
    pub radiance: V3<F>,
}

impl<F: Real> EnvSample<F> {
    /// The sample rounded to `G`, field by field.
    pub fn cast<G: Real>(&self) -> EnvSample<G> {
        let round = |v: V3<F>| v.map(|x| G::c(x.f64()));
        EnvSample {
            direction: round(self.direction),
            pdf: G::c(self.pdf.f64()),
            weight: round(self.weight),
            radiance: round(self.radiance),
        }
    }
}

/// A point drawn in the sampling table, placed on the map: its domain point,
/// the density it was drawn with per unit table area and the texels under
/// it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Placed<F> {
    /// The domain point (`dir_to_uv`'s coordinates).
    pub(super) point: [F; 2],
    /// The density per unit area of the sampling table.
    pub(super) pdf_q: F,
    /// The texels under `point` and their weights.
    pub(super) corners: Corners<F>,
}

impl EnvMap {
    /// A direction drawn with density [`EnvMap::pdf`], for `u` in `[0, 1]²`.
    #[inline]
    pub fn sample(&self, u: [f64; 2]) -> EnvSample {
        let placed = match &self.distribution {
            Distribution::Luminance(density) => {
                let (cell, r) = density.cells().sample_reuse(u);
                self.place_luminance(density, cell, r)
            }
            Distribution::Piecewise(table) => {
                let (cell, r) = table.table().sample_reuse(u);
                self.place_in_cell(table, cell, r)
            }
            Distribution::Bilinear(grid) => {
                let (q, pdf_q) = grid.sample(u);
                self.place_at(q, pdf_q)
            }
            Distribution::Black => return self.sample_black(u),
        };
        self.sample_at(&placed)
    }

    /// The point at fractions `r` of cell `cell` of the piecewise `table`
    /// (this map's), placed on the map. A lat-long map's cells are the
    /// patches between texel centres, so its texels are the cell's corners
    /// weighted by `r`, found without locating the point again.
    #[inline(always)]
    pub(super) fn place_in_cell<F: Real>(
        &self,
        table: &PiecewiseConstant2D,
        cell: (usize, usize),
        r: [F; 2],
    ) -> Placed<F> {
        let (q, pdf_q) = table.sample_in_cell(cell, r);
        match self.options.mapping {
            Mapping::LatLong => Placed {
                point: self.table_to_uv(q),
                pdf_q,
                corners: self.image.cell_corners(cell, r),
            },
            _ => self.place_at(q, pdf_q),
        }
    }

    /// The point that the fractions `r` place in cell `cell` of the
    /// luminance `density` (this map's), with its density per unit table
    /// area, placed in `F` ([`LuminanceFloat::place`]: in `f32` from the
    /// `f32` tables that [`EnvMap::pdf_into`] reads in `f32`); the texels are the cell's
    /// corners weighted by the point's fractions.
    #[inline(always)]
    pub(super) fn place_luminance<F: LuminanceFloat>(
        &self,
        density: &LuminanceDensity,
        cell: (usize, usize),
        r: [F; 2],
    ) -> Placed<F> {
        let ([x, y], pdf_q) = F::place(density.tables(), cell, r);
        let (w, h) = (self.image.width() as f64, (self.image.height() - 1) as f64);
        let q = [
            (F::c(cell.1 as f64) + x) / F::c(w),
            (F::c(cell.0 as f64) + y) / F::c(h),
        ];
        Placed {
            point: self.table_to_uv(q),
            pdf_q,
            corners: self.image.cell_corners(cell, [x, y]),
        }
    }

    /// The table point `q`, drawn with density `pdf_q` per unit table area,
    /// placed on the map.
    #[inline(always)]
    pub(super) fn place_at<F: Real>(&self, q: [F; 2], pdf_q: F) -> Placed<F> {
        let point = self.table_to_uv(q);
        Placed {
            point,
            pdf_q,
            corners: self.image.corners(self.options.mapping, point),
        }
    }

    /// The sample at a placed table point: its world direction, density per
    /// steradian and radiance. Every sampler ends here; the batch pipeline
    /// runs its two halves ([`EnvMap::frame_at`] for a whole group, then
    /// [`EnvMap::sample_from`]) so that the first vectorises.
    #[inline(always)]
    pub(super) fn sample_at<F: Real>(&self, placed: &Placed<F>) -> EnvSample<F> {
        let frame = self.frame_at(self.options.mapping, placed.point, placed.pdf_q);
        self.sample_from(&frame, &placed.corners)
    }

    /// The world direction at domain point `p` of `mapping` (this map's),
    /// its density per steradian and the inverse of that density (0 where
    /// it is 0), for a point drawn with density `pdf_q` per unit area of
    /// the sampling table: `[x, y, z, pdf, 1/pdf]`. Branch-free for the
    /// polar mappings, so that a group's frames are computed at SIMD width.
    /// The Jacobian takes sin θ from the direction's own formula (a unit
    /// vector by construction): no normalisation, as
    /// [`EnvMap::table_jacobian`] needs for a query.
    #[inline(always)]
    pub(super) fn frame_at<F: Real>(&self, mapping: Mapping, p: [F; 2], pdf_q: F) -> [F; 5] {
        let (local, sin_theta) = mapping.to_dir_and_sin(p);
        let jacobian = match mapping {
            Mapping::Cube => mapping.jacobian(p),
            _ => polar_jacobian(sin_theta),
        };
        let pdf = pdf_q / jacobian;
        let inv_pdf = if pdf > F::zero() {
            pdf.recip()
        } else {
            F::zero()
        };
        let [x, y, z] = self.to_world(local);
        [x, y, z, pdf, inv_pdf]
    }

    /// The sample of a frame ([`EnvMap::frame_at`]) whose radiance is the
    /// blend of `corners` times scale.
    #[inline(always)]
    pub(super) fn sample_from<F: Real>(
        &self,
        frame: &[F; 5],
        corners: &Corners<F>,
    ) -> EnvSample<F> {
        let [x, y, z, pdf, inv_pdf] = *frame;
        let radiance = self.radiance_of(corners);
        EnvSample {
            direction: [x, y, z],
            pdf,
            weight: radiance.map(|l| l * inv_pdf),
            radiance,
        }
    }

    /// The sample of an all-black map: a uniform direction that carries no
    /// light (pdf 0, weight 0, radiance 0).
    pub(super) fn sample_black(&self, u: [f64; 2]) -> EnvSample {
        EnvSample {
            direction: self.to_world(warp::square_to_uniform_sphere(u)),
            ..EnvSample::default()
        }
    }

    /// The domain point (`dir_to_uv`'s coordinates) of the table point `q`.
    #[inline(always)]
    fn table_to_uv<F: Real>(&self, q: [F; 2]) -> [F; 2] {
        match self.options.mapping {
            Mapping::LatLong => self.lat_long_uv(q),
            Mapping::Angular => angular_uv(q[0], q[1]),
            Mapping::Cube => q,
        }
    }

    /// [`EnvMap::table_to_uv`] of a lat-long map: the table's columns
    /// start half a texel right of `s = 0`, wrapped.
    #[inline(always)]
    pub(super) fn lat_long_uv<F: Real>(&self, q: [F; 2]) -> [F; 2] {
        let s = q[0] + F::c(0.5 / self.image.width() as f64);
        [if s >= F::one() { s - F::one() } else { s }, q[1]]
    }
}

/// The domain point of polar coordinates `(ψ, ρ)` around +Z of an angular
/// map.
pub(super) fn angular_uv<F: Real>(psi: F, rho: F) -> [F; 2] {
    let (sin_psi, cos_psi) = sin_cos_turn(psi);
    let (one, half) = (F::one(), F::c(0.5));
    [(rho * cos_psi + one) * half, (one - rho * sin_psi) * half]
}

/// A direction located in the sampling table ([`EnvMap::pdf_query`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PdfQuery {
    q: [f64; 2],
    jacobian: f64,
}

impl EnvMap {
    /// The first half of [`EnvMap::pdf`], which reads no table: where `d`
    /// falls in the sampling table, and the Jacobian there. Batches run it
    /// over a block of directions before [`EnvMap::pdf_at`] reads the table
    /// for all of them, so that those reads (cache misses for a large map)
    /// overlap instead of waiting one after the other.
    #[inline]
    pub fn pdf_query(&self, d: V3<f64>) -> PdfQuery {
        let local = self.to_local(d);
        PdfQuery {
            q: self.table_point(local),
            jacobian: self.table_jacobian(local),
        }
    }

    /// The second half of [`EnvMap::pdf`]: the table's density at the
    /// query's point, per steradian.
    #[inline]
    pub fn pdf_at(&self, query: PdfQuery) -> f64 {
        let pdf_q = match &self.distribution {
            Distribution::Luminance(density) => self.luminance_table_pdf(density, query.q),
            Distribution::Piecewise(table) => table.pdf(query.q),
            Distribution::Bilinear(grid) => grid.pdf(query.q),
            Distribution::Black => return 0.0,
        };
        pdf_q / query.jacobian
    }

    /// The luminance `density`'s value (this map's) at table point `q`.
    #[inline(always)]
    fn luminance_table_pdf(&self, density: &LuminanceDensity, q: [f64; 2]) -> f64 {
        let (w, h) = (self.image.width(), self.image.height() - 1);
        let (x, y) = (q[0] * w as f64, q[1] * h as f64);
        let (col, row) = (x.floor_index(w - 1), y.floor_index(h - 1));
        let fractions = [x - col as f64, y - row as f64].map(|f| f.clamp(0.0, 1.0));
        density.table_pdf((row, col), fractions)
    }

    /// The density of the luminance `density` (this map's) along the world
    /// direction `d`, per steradian, computed in `F` from the texels
    /// [`EnvMap::eval`] reads there (in `f32`, from their `f32` table and
    /// the row's moments: `density_f32`) and `1/(dω/dq)`, as
    /// [`PolarTable::query`] finds it without normalising `d` (0 for
    /// `d = 0`). Batches run its three steps apart: the query
    /// ([`EnvMap::luminance_query`]) over a block at SIMD width, the
    /// cells under them ([`Image::place_texels`], at SIMD width) and their
    /// table lines prefetched,
    /// and one block later the densities of the block
    /// ([`LuminanceFloat::luminance_block`]).
    #[inline(always)]
    pub(super) fn luminance_pdf<F: LuminanceFloat>(
        &self,
        density: &LuminanceDensity,
        d: V3<F>,
    ) -> F {
        let q = self.luminance_query(d);
        let k = self.image.place_texel(q[0], q[1]);
        F::luminance_pdf(density.tables(), k, [q[0], q[1]], [q[2], q[3], q[4], q[5]]) * q[6]
    }

    /// The place on a lat-long map of the world direction `d` and
    /// `1/(dω/dq)` there: `[x₀, y₀, w₀, w₁, w₂, w₃, 1/(dω/dq)]`, the
    /// [`LatLongPlace`] of its domain point `(s, t)` and the Jacobian.
    #[inline(always)]
    pub(super) fn luminance_query<F: Real>(&self, d: V3<F>) -> [F; 7] {
        let local = self.to_local(d);
        let place = self.image.lat_long_place(Mapping::LatLong.from_dir(local));
        let r = (local[0] * local[0] + local[2] * local[2]).sqrt();
        let length = (r * r + local[1] * local[1]).sqrt();
        let scaled_sin = r.max(F::c(SIN_FLOOR) * length).max(F::min_positive_value());
        let [x0, y0, w00, w10, w01, w11] = place;
        let jacobian_inv = length / (F::c(2.0 * PI * PI) * scaled_sin);
        [x0, y0, w00, w10, w01, w11, jacobian_inv]
    }

    /// The point of the sampling table that looks along the local
    /// direction `d`: lat-long `(s − ½/W, t)` wrapped into the table (which
    /// starts half a texel into the turn, at the first texel centre);
    /// angular, polar coordinates around +Z `(ψ, ρ) = (atan2(d.y, d.x)/2π,
    /// acos(d.z)/π)`; cube maps, the domain point itself.
    #[inline(always)]
    pub(super) fn table_point(&self, d: V3<f64>) -> [f64; 2] {
        let mapping = self.options.mapping;
        match mapping {
            Mapping::LatLong => {
                let p = mapping.from_dir(d);
                let s = p[0] - 0.5 / self.image.width() as f64;
                [s - s.floor(), p[1]]
            }
            Mapping::Angular => {
                let d = normalized(d);
                let psi = atan2(d[1], d[0]) * (0.5 / PI);
                [psi - psi.floor(), polar_angle(d[2], d[0], d[1]) / PI]
            }
            Mapping::Cube => mapping.from_dir(d),
        }
    }

    /// `dω/dq` of the sampling table at the local direction `d`: for the
    /// polar tables (lat-long around Y, angular around Z)
    /// `2π² max(sin θ, 2⁻²⁴)` with sin θ from `d` (Mitsuba's floor, so a
    /// pole has a finite density); for cube maps [`Mapping::jacobian`];
    /// `+∞` (density 0) for `d = 0`, which has no direction.
    #[inline(always)]
    fn table_jacobian(&self, d: V3<f64>) -> f64 {
        if d == [0.0; 3] {
            return f64::INFINITY;
        }
        let d = normalized(d);
        let polar = |x: f64, y: f64| polar_jacobian((x * x + y * y).sqrt());
        match self.options.mapping {
            Mapping::LatLong => polar(d[0], d[2]),
            Mapping::Angular => polar(d[0], d[1]),
            Mapping::Cube => Mapping::Cube.jacobian(Mapping::Cube.from_dir(d)),
        }
    }
}

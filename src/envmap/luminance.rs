//! [`LuminanceDensity`]: the density of [`Sampling::Luminance`], which
//! follows a lat-long map's bilinear luminance within each cell and its
//! integral over the sphere across cells.
//!
//! [`Sampling::Luminance`]: super::Sampling::Luminance

use super::bilinear::{bilerp, warp_bilinear};
use super::cell::{cell_texels, cell_u32, gather_corner_rows, right_of};
use super::image::bilinear_weights;
use crate::buffer::Buffer;
use crate::distr::{Discrete2D, GROUP};
use crate::error::Result;
use crate::math::Real;
use crate::parallel;
use crate::simd::{self, BLOCK, OnLines};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Below this angle (radians) [`angle_terms`] sums Taylor series
/// instead of calling the library's `sin_cos`.
const SERIES_BELOW: f64 = 0.25;

/// The luminance `Y` of a lat-long map, interpolated bilinearly between
/// the texel centres as the radiance is, made a density on its sampling
/// table.
///
/// # Density
/// The table's cells are the `W × (H − 1)` patches between texel centres
/// (columns at `s = (i + ½)/W`, rows at `θ = π j/(H − 1)`), in which `Y` is
/// bilinear in the cell's fractions `(x, y)`: corners `a, b` on row `j`,
/// `c, d` on row `j + 1`. Cell `c` is drawn with probability
/// `P_c = ∫_c Y dω / ∫ Y dω`, exactly: with `dω = 2π² sin θ ds dt` and
/// `θ = θ_j + Δy` (`Δ = π/(H − 1)`), `∫_c Y dω ∝ α I₀ + β I₁`, where
/// `α = (a + b)/2`, `β = (c + d)/2 − α`, `I₀ = ∫₀¹ sin θ dy` and
/// `I₁ = ∫₀¹ y sin θ dy` in closed form. Within the cell the point follows
/// `Y` itself (the bilinear warp, closed form), so the density per unit
/// table area is
///
/// ```text
/// p_q = P_c · WH' · Y(x, y) / Ȳ_c,   Ȳ_c = (a + b + c + d)/4,  H' = H − 1
/// ```
///
/// and per steradian `p_q / (2π² sin θ)`: `Y(ω)/∫Y dω` times
/// `s̄_c / sin θ`, with `s̄_c = ∫_c Y sin θ / ∫_c Y` the cell's mean `sin θ`
/// (a ratio within about `Δ·cot θ / 2` of 1: 1 % at 45° on a 128-row map;
/// it grows toward the poles, where it only lowers `L/p`). Wherever `Y > 0`, `p > 0`,
/// also at the poles (where Mitsuba's `sin θ`-weighted table is 0).
#[derive(Clone, Debug)]
pub(super) struct LuminanceDensity {
    /// Each texel's sampling luminance, row-major.
    lum: Buffer<f64>,
    width: usize,
    /// The cells `(row, col)`, weighted `∫∫ Y sin θ dx dy`.
    cells: Discrete2D,
    /// `P_c · WH' / Ȳ_c` of each cell (0 where `Ȳ_c = 0`): `p_q` is `Y`
    /// times this.
    scale: Buffer<f64>,
    /// Each texel's luminance times `WH'/Σw` (`L = Y·WH'/Σw`), rounded to
    /// `f32`, from which a query in `f32` computes `p_q` (see
    /// [`density_f32`]) and a draw in `f32` is placed in its cell
    /// ([`Tables::place_f32`]): 4 bytes a texel, so that a 1024 × 512 map's
    /// (2 MiB) stays in a core's cache. A texel adds at least
    /// `Y(Δ − sin Δ)/Δ² ≥ 0.88·YΔ/6` to the weights of the two cells of
    /// its row it is a corner of (the least at a pole), so `L` is at most
    /// `7 WH'/Δ` and never overflows; a texel dark beside
    /// the map's brightest may round to a subnormal or 0, as its own `f32`
    /// density would.
    lum_f32: Buffer<f32>,
    /// Each row's `[I₀, I₁]` (the cells' weights are `α·I₀ + β·I₁`), in
    /// `f32`.
    moments_f32: Buffer<[f32; 2]>,
}

impl LuminanceDensity {
    /// The density of the row-major `width × height` texel luminances
    /// `lum` (non-negative; `width >= 1`, `height >= 2`), or `None` when
    /// they are all 0.
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the tables cannot be had.
    pub(super) fn new(lum: Buffer<f64>, width: usize, height: usize) -> Result<Option<Self>> {
        debug_assert!(width >= 1 && height >= 2 && lum.len() == width * height);
        let delta = PI / (height - 1) as f64;
        let cell_count = width * (height - 1);
        let mut weights = Buffer::for_overwrite(cell_count, "the sampling cells")?;
        let mut moments_f32 = Buffer::for_overwrite(height - 1, "the sampling rows")?;
        let rows = (weights.par_chunks_mut(width)).zip(moments_f32.par_iter_mut());
        by_rows(rows, width, |j, (row, m)| {
            let (sin, cos) = (j as f64 * delta).sin_cos();
            let [i0, i1] = moments([sin.max(0.0), cos], delta);
            *m = [i0 as f32, i1 as f32];
            for (i, w) in row.iter_mut().enumerate() {
                let [a, b, c, d] = corners(&lum, width, j * width + i);
                let alpha = 0.5 * (a + b);
                *w = alpha * i0 + (0.5 * (c + d) - alpha) * i1;
            }
        })?;
        if !weights.iter().any(|&w| w > 0.0) {
            return Ok(None);
        }
        let cells = Discrete2D::with_arg("image", &weights, height - 1, width)?;
        let per_cell = cell_count as f64 / cells.sum();
        let mut scale = Buffer::for_overwrite(cell_count, "the sampling cells")?;
        by_rows(scale.par_chunks_mut(width), width, |j, scale| {
            for (i, s) in scale.iter_mut().enumerate() {
                let k = j * width + i;
                let mean = 0.25 * corners(&lum, width, k).iter().sum::<f64>();
                *s = if mean > 0.0 {
                    weights[k] * per_cell / mean
                } else {
                    0.0
                };
            }
        })?;
        let mut lum_f32 = Buffer::for_overwrite(lum.len(), "the sampling texels")?;
        let rows = (lum_f32.par_chunks_mut(width)).zip(lum.par_chunks(width));
        by_rows(rows, width, |_, (l, y)| {
            for (l, &y) in l.iter_mut().zip(y) {
                *l = (y * per_cell) as f32;
            }
        })?;
        Ok(Some(LuminanceDensity {
            lum,
            width,
            cells,
            scale,
            lum_f32,
            moments_f32,
        }))
    }

    /// The cells, by their weights.
    pub(super) fn cells(&self) -> &Discrete2D {
        &self.cells
    }

    /// Asks the CPU for the table lines that [`LuminanceFloat::place`]
    /// reads in `F` for cell `(row, col)`
    /// ([`LuminanceFloat::prefetch_luminance`]).
    #[inline(always)]
    pub(super) fn prefetch_cell<F: LuminanceFloat>(&self, (row, col): (usize, usize)) {
        F::prefetch_luminance(self.tables(), row * self.width + col);
    }

    /// `p_q` at the fractions `(x, y)` of cell `(row, col)`.
    #[inline]
    pub(super) fn table_pdf(&self, (row, col): (usize, usize), [x, y]: [f64; 2]) -> f64 {
        let k = row * self.width + col;
        bilerp(corners(&self.lum, self.width, k), x, y) * self.scale[k]
    }

    /// The tables that [`Tables::pdf_at`] and [`Tables::pdf_at_f32`]
    /// read.
    #[inline(always)]
    pub(super) fn tables(&self) -> Tables<'_> {
        Tables {
            width: self.width,
            lum: &self.lum,
            below: &self.lum[self.width..],
            scale: &self.scale,
            lum_f32: &self.lum_f32,
            moments_f32: &self.moments_f32,
        }
    }
}

/// A group's points placed in their luminance cells
/// ([`LuminanceFloat::place_columns`]), one column per quantity, in `F`:
/// lane `i` is the group's draw `i`.
#[derive(Debug)]
#[repr(align(64))]
pub struct PlacedCells<F> {
    /// Each cell's corner texels `[k, right, k + W, right + W]` (`k` its
    /// top-left texel, `right` the texel right of it, wrapped): the texels
    /// whose luminances are the corners `a, b, c, d`.
    pub texels: [[u32; BLOCK]; 4],
    /// Each cell's column and row.
    pub cell: [[F; BLOCK]; 2],
    /// The point's fractions `x, y` in its cell and `p_q` there.
    pub place: [[F; BLOCK]; 3],
}

impl<F: Real> PlacedCells<F> {
    /// Columns of zeros.
    pub(super) fn new() -> Self {
        let zero = F::zero();
        PlacedCells {
            texels: [[0; BLOCK]; 4],
            cell: [[zero; BLOCK]; 2],
            place: [[zero; BLOCK]; 3],
        }
    }
}

/// Fills tables of `width` values a row, row by row on all cores: `fill(j,
/// row)` writes row `j` of each (`rows` yields them, one item a row), the
/// same values whatever the thread count.
///
/// # Errors
/// As [`parallel::install`].
fn by_rows<R: IndexedParallelIterator>(
    rows: R,
    width: usize,
    fill: impl Fn(usize, R::Item) + Sync + Send,
) -> Result<()> {
    parallel::install(|| {
        (rows.enumerate())
            .with_min_len(parallel::CHUNK.div_ceil(width))
            .for_each(|(j, row)| fill(j, row));
    })
}

/// The tables of a [`LuminanceDensity`] that its density reads, as slices
/// that a batch takes out of its loop.
#[derive(Clone, Copy)]
pub struct Tables<'a> {
    /// The map's width in texels.
    width: usize,
    /// The texels' luminances.
    lum: &'a [f64],
    /// The same from the second row on: texel `k + W` is `below[k]`.
    below: &'a [f64],
    /// The cells' `P_c · WH' / Ȳ_c`.
    scale: &'a [f64],
    /// The texels' `L = Y·WH'/Σw`, in `f32`.
    lum_f32: &'a [f32],
    /// The rows' `[I₀, I₁]`, in `f32`.
    moments_f32: &'a [[f32; 2]],
}

impl Tables<'_> {
    /// The point of cell `(row, col)` that the fractions `r` in `[0, 1]²`
    /// place, as the cell's fractions `(x, y)`, and `p_q` there, in `f64`
    /// from the `f64` tables.
    #[inline]
    fn place(self, (row, col): (usize, usize), r: [f64; 2]) -> ([f64; 2], f64) {
        let k = row * self.width + col;
        let [x, y, bilerp] = warp_corners(corners(self.lum, self.width, k), r);
        ([x, y], bilerp * self.scale[k])
    }

    /// [`Tables::place`] in `f32`, from the texels' `f32` table
    /// (`L = Y·WH'/Σw`) and the row's moments: the point by the bilinear
    /// warp of the cell's `L` ([`warp_corners_f32`]), `p_q` by
    /// [`density_f32`] there, as `pdf` computes it in `f32`.
    #[inline]
    fn place_f32(self, (row, col): (usize, usize), r: [f32; 2]) -> ([f32; 2], f32) {
        let k = row * self.width + col;
        let c = corners(self.lum_f32, self.width, k);
        let [x, y] = warp_corners_f32(c, r);
        (
            [x, y],
            density_f32(c, self.moments_f32[row], bilinear_weights(x, y)),
        )
    }

    /// The columns of `out` for `cells` (at most [`GROUP`]): each cell's
    /// corner texels, row and column, and its fractions `r` as `F`. Lanes
    /// past the group's draws keep what they held (texels of a cell of
    /// the map).
    #[inline(always)]
    fn cell_columns<F: Real>(
        self,
        cells: &[((usize, usize), [F; 2])],
        out: &mut PlacedCells<F>,
        r: &mut [[F; BLOCK]; 2],
    ) {
        debug_assert!(cells.len() <= GROUP);
        let width = self.width;
        for (i, &((row, col), [r0, r1])) in cells.iter().enumerate() {
            let k = row * width + col;
            let right = right_of(k, col, width);
            for (j, t) in [k, right, k + width, right + width].into_iter().enumerate() {
                out.texels[j][i] = t as u32;
            }
            (r[0][i], r[1][i]) = (r0, r1);
            (out.cell[0][i], out.cell[1][i]) = (F::c(col as f64), F::c(row as f64));
        }
    }

    /// [`Tables::place`] of each `(cell, r)` of `cells` (at most
    /// [`GROUP`]) into the columns of `out`: the cells' corners and scales
    /// read by gathers, the warps in `f64` at SIMD width, the same bits as
    /// one by one. Lanes past the group's draws are left holding values of
    /// no draw.
    #[inline(always)]
    fn place_columns_f64(self, cells: &[((usize, usize), [f64; 2])], out: &mut PlacedCells<f64>) {
        let OnLines(r) = &mut OnLines([[0.0; BLOCK]; 2]);
        self.cell_columns(cells, out, r);
        let OnLines(at) = &mut OnLines([[0u64; BLOCK]; 4]);
        for (at, texels) in at.iter_mut().zip(&out.texels) {
            *at = texels.map(u64::from);
        }
        let OnLines(lum) = &mut OnLines([[0.0; BLOCK]; 4]);
        for (lum, at) in lum.iter_mut().zip(&*at) {
            simd::gather(self.lum, at, lum);
        }
        let OnLines(scale) = &mut OnLines([0.0; BLOCK]);
        simd::gather(self.scale, &at[0], scale);
        for i in 0..BLOCK {
            let corners = [lum[0][i], lum[1][i], lum[2][i], lum[3][i]];
            let [x, y, bilerp] = warp_corners(corners, [r[0][i], r[1][i]]);
            (out.place[0][i], out.place[1][i]) = (x, y);
            out.place[2][i] = bilerp * scale[i];
        }
    }

    /// [`Tables::place_f32`] of each `(cell, r)` of `cells` (at
    /// most [`GROUP`]) into the columns of `out`: the cells' `L` and rows'
    /// moments read by gathers, the warps and densities in `f32` at SIMD
    /// width, the same bits as one by one. Lanes past the group's draws
    /// are left holding values of no draw.
    #[inline(always)]
    fn place_columns_f32(self, cells: &[((usize, usize), [f32; 2])], out: &mut PlacedCells<f32>) {
        let OnLines(r) = &mut OnLines([[0.0; BLOCK]; 2]);
        self.cell_columns(cells, out, r);
        let OnLines([[l00, l10], [l01, l11]]) =
            &gather_corner_rows::<1, 2>(self.lum_f32, &out.texels);
        let OnLines(rows) = &mut OnLines([0; BLOCK]);
        for (row, &((j, _), _)) in rows.iter_mut().zip(cells) {
            *row = j as u32;
        }
        let OnLines(moments) = &mut OnLines([[0.0; BLOCK]; 2]);
        simd::gather_columns(self.moments_f32, rows, moments);
        for i in 0..BLOCK {
            let c = [l00[i], l10[i], l01[i], l11[i]];
            let [x, y] = warp_corners_f32(c, [r[0][i], r[1][i]]);
            let pdf_q = density_f32(c, [moments[0][i], moments[1][i]], bilinear_weights(x, y));
            (out.place[0][i], out.place[1][i], out.place[2][i]) = (x, y, pdf_q);
        }
    }

    /// Asks the CPU for the lines that [`Tables::pdf_at`] (and
    /// [`Tables::place`]) read for cell `k` (its top-left texel): its two
    /// rows' luminances and its scale.
    #[inline(always)]
    pub(super) fn prefetch(self, k: usize) {
        simd::prefetch(self.lum, k);
        simd::prefetch(self.below, k);
        simd::prefetch(self.scale, k);
    }

    /// Asks the CPU for the lines that [`Tables::pdf_at_f32`] (and
    /// [`Tables::place_f32`]) read for cell `k`: its two rows' `L`.
    #[inline(always)]
    pub(super) fn prefetch_f32(self, k: usize) {
        simd::prefetch(self.lum_f32, k);
        simd::prefetch(self.lum_f32, k + self.width);
    }

    /// The texels `[a, b, c, d]` of cell `k` (its top-left texel) of the
    /// lat-long place `(x₀, y₀)` ([`cell_u32`] and [`cell_texels`]), and
    /// its row: in `u32` arithmetic that vectorises.
    #[inline(always)]
    fn cell_texels_f32(self, k: u32, x0: f32, y0: f32) -> ([u32; 4], u32) {
        let w = self.width as u32;
        let [col, row] = cell_u32(x0, y0, w, self.moments_f32.len() as u32);
        (cell_texels(k, col, w), row)
    }

    /// `p_q` in `f32` at the blend by `wt` of cell `k` (its top-left
    /// texel) of the lat-long place `(x₀, y₀)` ([`density_f32`] of its
    /// `L` and its row's moments). A texel past the table reads as the
    /// last, as [`simd::gather_columns`] reads it (callers pass none).
    #[inline(always)]
    pub(super) fn pdf_at_f32(self, k: usize, x0: f32, y0: f32, wt: [f32; 4]) -> f32 {
        debug_assert!(k < self.scale.len(), "cell {k} is not one of the map's");
        let (texels, row) = self.cell_texels_f32(k as u32, x0, y0);
        let last = self.lum_f32.len() - 1;
        let corners = texels.map(|t| self.lum_f32[(t as usize).min(last)]);
        density_f32(corners, self.moments_f32[row as usize], wt)
    }

    /// `out[i]` = the density per steradian of the query in row `i` of the
    /// columns `q` (`EnvMap::luminance_query`'s) in the cell `cells[i]`, in
    /// `f64`: [`Tables::pdf_at`] times `1/(dω/dq)`.
    #[inline(always)]
    fn block_pdfs(self, q: &[[f64; BLOCK]; 7], cells: &[u32; BLOCK], out: &mut [f64]) {
        debug_assert!(out.len() <= BLOCK);
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.pdf_at(
                cells[i] as usize,
                q[0][i],
                [q[2][i], q[3][i], q[4][i], q[5][i]],
            ) * q[6][i];
        }
    }

    /// [`Tables::block_pdfs`] in `f32`: [`Tables::pdf_at_f32`] times
    /// `1/(dω/dq)` for each row (the same bits), the texels and rows found
    /// at SIMD width, their `L` and moments read by gathers, the densities
    /// computed at SIMD width.
    #[inline(always)]
    fn block_pdfs_f32(self, q: &[[f32; BLOCK]; 7], cells: &[u32; BLOCK], out: &mut [f32]) {
        debug_assert!(out.len() <= BLOCK);
        let OnLines(texels) = &mut OnLines([[0; BLOCK]; 4]);
        let OnLines(rows) = &mut OnLines([0; BLOCK]);
        for i in 0..BLOCK {
            let (t, row) = self.cell_texels_f32(cells[i], q[0][i], q[1][i]);
            for (column, t) in texels.iter_mut().zip(t) {
                column[i] = t;
            }
            rows[i] = row;
        }
        let OnLines([[l00, l10], [l01, l11]]) = &gather_corner_rows::<1, 2>(self.lum_f32, texels);
        let OnLines(moments) = &mut OnLines([[0.0; BLOCK]; 2]);
        simd::gather_columns(self.moments_f32, rows, moments);
        let OnLines(pdf) = &mut OnLines([0.0; BLOCK]);
        for (i, p) in pdf.iter_mut().enumerate() {
            let wt = [q[2][i], q[3][i], q[4][i], q[5][i]];
            let c = [l00[i], l10[i], l01[i], l11[i]];
            *p = density_f32(c, [moments[0][i], moments[1][i]], wt) * q[6][i];
        }
        out.copy_from_slice(&pdf[..out.len()]);
    }

    /// `p_q` at the blend by `wt` of the texels of cell `k` (its top-left
    /// texel) of column `x₀`: texel `k`, the one right of it
    /// ([`right_of`]) and the two below them, in `F`, the sum from 0 as a
    /// blend of texels starts. A texel outside the tables reads as 0
    /// (never one of a cell of the map).
    #[inline(always)]
    pub(super) fn pdf_at<F: Real>(self, k: usize, x0: F, wt: [F; 4]) -> F {
        debug_assert!(k < self.scale.len(), "cell {k} is not one of the map's");
        let right = right_of(k, x0.floor_index(self.width - 1), self.width);
        let at = |table: &[f64], i: usize| F::c(table.get(i).copied().unwrap_or(0.0));
        let y = F::zero() + wt[0] * at(self.lum, k) + wt[1] * at(self.lum, right);
        let y = y + wt[2] * at(self.below, k) + wt[3] * at(self.below, right);
        y * at(self.scale, k)
    }
}

/// The float types in which a [`LuminanceDensity`] is read: each from
/// its own tables (`f64` from the luminances and scales, `f32` from the
/// texels' `L` and the rows' moments). The crate's own (it seals
/// [`super::TableFloat`]).
pub trait LuminanceFloat: Real {
    /// Asks the CPU for the lines of `tables` that
    /// [`LuminanceFloat::luminance_pdf`] reads for cell `k`.
    fn prefetch_luminance(tables: Tables<'_>, k: usize);

    /// The luminance density `p_q` at the blend by `wt` of cell `k`'s
    /// corners (`k` its top-left texel, at the lat-long place `[x₀, y₀]`).
    fn luminance_pdf(tables: Tables<'_>, k: usize, place: [Self; 2], wt: [Self; 4]) -> Self;

    /// The luminance density per steradian of a block of queries
    /// (`EnvMap::luminance_query`'s, in columns) in their `cells`, into
    /// `out` (at most a block): each what
    /// [`LuminanceFloat::luminance_pdf`] times `1/(dω/dq)` gives.
    fn luminance_block(
        tables: Tables<'_>,
        q: &[[Self; BLOCK]; 7],
        cells: &[u32; BLOCK],
        out: &mut [Self],
    );

    /// The point that the fractions `r` place in cell `(row, col)` of
    /// `tables`' density, as the cell's fractions `(x, y)`, and `p_q`
    /// there: [`Tables::place`] in `f64`, [`Tables::place_f32`] in `f32`.
    fn place(tables: Tables<'_>, cell: (usize, usize), r: [Self; 2]) -> ([Self; 2], Self);

    /// [`LuminanceFloat::place`] of each `(cell, r)` of `cells` (at most
    /// [`GROUP`]) into the columns of `out`, at SIMD width: the same bits
    /// as one by one.
    fn place_columns(
        tables: Tables<'_>,
        cells: &[((usize, usize), [Self; 2])],
        out: &mut PlacedCells<Self>,
    );
}

impl LuminanceFloat for f32 {
    #[inline(always)]
    fn prefetch_luminance(tables: Tables<'_>, k: usize) {
        tables.prefetch_f32(k);
    }
    #[inline(always)]
    fn luminance_pdf(tables: Tables<'_>, k: usize, [x0, y0]: [f32; 2], wt: [f32; 4]) -> f32 {
        tables.pdf_at_f32(k, x0, y0, wt)
    }
    #[inline(always)]
    fn luminance_block(
        tables: Tables<'_>,
        q: &[[f32; BLOCK]; 7],
        cells: &[u32; BLOCK],
        out: &mut [f32],
    ) {
        tables.block_pdfs_f32(q, cells, out);
    }
    #[inline(always)]
    fn place(tables: Tables<'_>, cell: (usize, usize), r: [f32; 2]) -> ([f32; 2], f32) {
        tables.place_f32(cell, r)
    }
    #[inline(always)]
    fn place_columns(
        tables: Tables<'_>,
        cells: &[((usize, usize), [f32; 2])],
        out: &mut PlacedCells<f32>,
    ) {
        tables.place_columns_f32(cells, out);
    }
}

impl LuminanceFloat for f64 {
    #[inline(always)]
    fn prefetch_luminance(tables: Tables<'_>, k: usize) {
        tables.prefetch(k);
    }
    #[inline(always)]
    fn luminance_pdf(tables: Tables<'_>, k: usize, [x0, _]: [f64; 2], wt: [f64; 4]) -> f64 {
        tables.pdf_at(k, x0, wt)
    }
    #[inline(always)]
    fn luminance_block(
        tables: Tables<'_>,
        q: &[[f64; BLOCK]; 7],
        cells: &[u32; BLOCK],
        out: &mut [f64],
    ) {
        tables.block_pdfs(q, cells, out);
    }
    #[inline(always)]
    fn place(tables: Tables<'_>, cell: (usize, usize), r: [f64; 2]) -> ([f64; 2], f64) {
        tables.place(cell, r)
    }
    #[inline(always)]
    fn place_columns(
        tables: Tables<'_>,
        cells: &[((usize, usize), [f64; 2])],
        out: &mut PlacedCells<f64>,
    ) {
        tables.place_columns_f64(cells, out);
    }
}

/// `p_q` in `f32` at the blend by `wt` of a cell's corners `c = [a, b,
/// c, d]` of `L = Y·WH'/Σw`, its row's moments `[I₀, I₁]`:
///
/// ```text
/// p_q = L(x, y) · w_c / L̄_c,   w_c = α I₀ + β I₁,   α = (a + b)/2,   β = (c + d)/2 − α
/// ```
///
/// with `L̄_c = (a + b + c + d)/4` (0 where `L̄_c = 0`): `Y · P_c WH'/Ȳ_c`,
/// as the `f64` tables give it, since `w_c/L̄_c` is the same for any
/// multiple of `Y`. Branch-free, so that a block computes it at SIMD
/// width; the blend is summed from 0 as a blend of texels starts.
#[inline(always)]
fn density_f32(c: [f32; 4], [i0, i1]: [f32; 2], wt: [f32; 4]) -> f32 {
    let alpha = 0.5 * (c[0] + c[1]);
    let weight = alpha * i0 + (0.5 * (c[2] + c[3]) - alpha) * i1;
    let mean = 0.25 * (c[0] + c[1] + c[2] + c[3]);
    let blend = 0.0 + wt[0] * c[0] + wt[1] * c[1] + wt[2] * c[2] + wt[3] * c[3];
    if mean > 0.0 {
        blend * (weight / mean)
    } else {
        0.0
    }
}

/// `[x, y, bilerp(c, x, y)]`: the point of the unit square that `r` places
/// with density `∝ bilerp(c, ·)` ([`warp_bilinear`]), and that blend there.
#[inline(always)]
fn warp_corners(c: [f64; 4], r: [f64; 2]) -> [f64; 3] {
    let [x, y] = warp_bilinear(c, r);
    [x, y, bilerp(c, x, y)]
}

/// The point of the unit square that `r` places with density `∝ bilerp(c,
/// ·)` ([`warp_bilinear`]), in `f32`: the corners first divided by the
/// largest (the warp is the same for any multiple of them), so that their
/// squares neither overflow nor, beside a bright corner, vanish against
/// it; a cell whose largest corner is subnormal is scaled by 2¹²⁶, which
/// leaves its corners' squares normal.
#[inline(always)]
fn warp_corners_f32(c: [f32; 4], r: [f32; 2]) -> [f32; 2] {
    let largest = c[0].max(c[1]).max(c[2]).max(c[3]);
    let scale = if largest > 0.0 {
        largest.recip().min(2f32.powi(126))
    } else {
        0.0
    };
    warp_bilinear(c.map(|v| v * scale), r)
}

/// The corners `[a, b, c, d]` of cell `k` (row-major, `width` a row):
/// texels `col` and the next column (wrapped) on rows `row` and `row + 1`.
#[inline(always)]
fn corners<T: Copy>(lum: &[T], width: usize, k: usize) -> [T; 4] {
    let next = right_of(k, k % width, width);
    [lum[k], lum[next], lum[k + width], lum[next + width]]
}

/// `[∫₀¹ sin(θ_j + Δy) dy, ∫₀¹ y sin(θ_j + Δy) dy]` for a row whose
/// `(sin θ_j, cos θ_j)` is `row`: a cell's weight is `α·I₀ + β·I₁`.
fn moments([s0, c0]: [f64; 2], delta: f64) -> [f64; 2] {
    let [sin, versine, sin_minus_x_cos] = angle_terms(delta);
    [
        (c0 * versine + s0 * sin) / delta,
        (s0 * (delta * sin - versine) + c0 * sin_minus_x_cos) / (delta * delta),
    ]
}

/// `[sin x, 1 − cos x, sin x − x cos x]` for `x` in `[0, π/2]`, each to its
/// relative precision (the last two start at `x²/2` and `x³/3`): below
/// [`SERIES_BELOW`] from the Taylor series of `sin x` and `1 − cos x` to
/// `x¹²`, with `sin x − x cos x = x(1 − cos x) − (x − sin x)` and
/// `x − sin x` from the series without its first term.
fn angle_terms(x: f64) -> [f64; 3] {
    if x >= SERIES_BELOW {
        let (sin, cos) = x.sin_cos();
        return [sin, 1.0 - cos, sin - x * cos];
    }
    let (z, z2) = (x * x, x * x * x * x);
    let z4 = z2 * z2;
    // x − sin x = x z (1/3! − z/5! + z²/7! − …).
    let x_minus_sin =
        x * z * ((1.0 / 6.0 - z / 120.0) + z2 * (1.0 / 5040.0 - z / 362_880.0) + z4 / 39_916_800.0);
    // 1 − cos x = z (1/2! − z/4! + z²/6! − …).
    let versine = z
        * ((0.5 - z / 24.0)
            + z2 * (1.0 / 720.0 - z / 40_320.0)
            + z4 * (1.0 / 3_628_800.0 - z / 479_001_600.0));
    [x - x_minus_sin, versine, x * versine - x_minus_sin]
}

#[cfg(test)]
mod tests;

//! The batch draws of an [`EnvMap`]: `sample_into` and the renderer's
//! cell draws (`CellSampler::sample_many`), group by group, the first half
//! of each draw for a whole group at SIMD width.

use super::EnvSamples;
use crate::distr::{GROUP, PiecewiseConstant2D};
use crate::envmap::cell_sampler::CellSampler;
use crate::envmap::distribution::Distribution;
use crate::envmap::image::{Corners, bilinear_weights};
use crate::envmap::luminance::{LuminanceDensity, PlacedCells};
use crate::envmap::mapping::Mapping;
use crate::envmap::polar::TableFloat;
use crate::envmap::sample::Placed;
use crate::envmap::{EnvMap, EnvSample};
use crate::math::Real;
use crate::simd;

#[cfg(doc)]
use crate::envmap::luminance::LuminanceFloat;

impl EnvMap {
    /// `out[i] = sample(us[i])` for a batch, in groups: the table points by
    /// the tables' batch samplers (whose cache misses overlap), then placed
    /// on the map as [`EnvMap::sample`] places them, the directions and
    /// densities of the group at SIMD width, and last the radiance (for a
    /// luminance density, two groups in flight and the second half in
    /// columns). Computed in `F` past the table draw (whose searches run in
    /// `f64`; Mitsuba's bilinear density is sampled in `f64` and rounded);
    /// in `f64`, the same bits as [`EnvMap::sample`]. In `f32` a direction
    /// and its density are good to a few ulps of `f32` (the density near a
    /// pole of a polar table to about `10⁻⁷/sin θ`); a luminance density's
    /// points are placed in their cells in `f32`, from the `f32` table that
    /// [`EnvMap::pdf_into`] reads in `f32` (`LuminanceFloat::place`): a
    /// texel whose `f32` luminance rounds to 0 beside the map's brightest
    /// has density 0 there, as `pdf_into` gives it in `f32`.
    ///
    /// # Panics
    /// If an array of `out` is shorter than `us`.
    pub fn sample_into<F: TableFloat>(&self, us: &[[F; 2]], out: EnvSamples<'_, F>) {
        self.sample_rows(us, |&u| u, out);
    }

    /// [`EnvMap::sample_into`] of `prepare(row)` for each of `rows`: the
    /// numbers `u` of a group are made (checked, clamped) as the group is
    /// drawn, in the same pass, so that a caller needs no pass of its own
    /// over its input.
    ///
    /// # Panics
    /// If an array of `out` is shorter than `rows`.
    pub fn sample_rows<F: TableFloat, R>(
        &self,
        rows: &[R],
        prepare: impl FnMut(&R) -> [F; 2],
        out: EnvSamples<'_, F>,
    ) {
        simd::dispatch(
            #[inline(always)]
            |_| self.sample_groups(rows, prepare, out),
        )
    }

    /// The pipeline of [`EnvMap::sample_rows`], group by group: the draw
    /// of [`EnvMap::sample_at`] in its two halves, the first for a whole
    /// group at SIMD width. Maps drawn by cells run in
    /// [`EnvMap::sample_cell_groups`].
    #[inline(always)]
    fn sample_groups<F: TableFloat, R>(
        &self,
        rows: &[R],
        mut prepare: impl FnMut(&R) -> [F; 2],
        mut out: EnvSamples<'_, F>,
    ) {
        let grid = match &self.distribution {
            Distribution::Luminance(density) => {
                return self.sample_cell_groups(Cells::Luminance(density), rows, prepare, out);
            }
            Distribution::Piecewise(table) => {
                return self.sample_cell_groups(Cells::Piecewise(table), rows, prepare, out);
            }
            Distribution::Bilinear(grid) => grid,
            Distribution::Black => {
                for (k, row) in rows.iter().enumerate() {
                    out.set(k, self.sample_black(prepare(row).map(F::f64)).cast());
                }
                return;
            }
        };
        let zero = F::zero();
        let simd::OnLines(points) = &mut simd::OnLines([[zero; 3]; GROUP]);
        let simd::OnLines(frames) = &mut simd::OnLines([[zero; 5]; GROUP]);
        let mut corners = [([0; 4], [zero; 4]); GROUP];
        let mut bilinear = [([0.0; 2], 0.0); GROUP];
        let mut us = [[0.0; 2]; GROUP];
        for (g, rows) in rows.chunks(GROUP).enumerate() {
            let n = rows.len();
            let (us, b) = (&mut us[..n], &mut bilinear[..n]);
            for (u, row) in us.iter_mut().zip(rows) {
                *u = prepare(row).map(F::f64);
            }
            grid.sample_into(us, b);
            for (k, &(q, pdf)) in b.iter().enumerate() {
                let placed = self.place_at(q.map(F::c), F::c(pdf));
                self.stage(placed, &mut points[k], &mut corners[k]);
            }
            self.finish_group(&points[..n], &corners, frames, |k, s| {
                out.set(g * GROUP + k, s);
            });
        }
    }

    /// [`EnvMap::sample_groups`] of a map drawn by the cells of `table`,
    /// two groups in flight: a group's cells are drawn and, for a luminance
    /// density, the lines that placing its points and reading their texels
    /// will read are prefetched ([`EnvMap::prefetch_cell`]), then the group
    /// before is placed and finished ([`EnvMap::finish_cells`]), its lines
    /// by now in the caches.
    #[inline(always)]
    fn sample_cell_groups<F: TableFloat, R>(
        &self,
        table: Cells<'_>,
        rows: &[R],
        mut prepare: impl FnMut(&R) -> [F; 2],
        mut out: EnvSamples<'_, F>,
    ) {
        let zero = F::zero();
        let mut cells = [[((0, 0), [zero; 2]); GROUP]; 2];
        let mut staged = Staged::new();
        let mut us = [[zero; 2]; GROUP];
        // The group waiting to be finished: its index and size.
        let mut previous: Option<(usize, usize)> = None;
        for (g, rows) in rows.chunks(GROUP).enumerate() {
            let us = &mut us[..rows.len()];
            for (u, row) in us.iter_mut().zip(rows) {
                *u = prepare(row);
            }
            let drawn = &mut cells[g % 2][..rows.len()];
            table.draw(us, drawn);
            for &(cell, _) in drawn.iter() {
                self.prefetch_cell::<F>(table, cell);
            }
            if let Some((p, n)) = previous.replace((g, rows.len())) {
                self.finish_cells(table, &cells[p % 2][..n], &mut staged, |k, s| {
                    out.set(p * GROUP + k, s);
                });
            }
        }
        if let Some((p, n)) = previous {
            self.finish_cells(table, &cells[p % 2][..n], &mut staged, |k, s| {
                out.set(p * GROUP + k, s);
            });
        }
    }

    /// Asks the CPU for the lines that placing a point in `cell` of
    /// `table` reads: a luminance density's table lines and the cell's
    /// texels (its corners); a piecewise table's cells read none.
    #[inline(always)]
    fn prefetch_cell<F: TableFloat>(&self, table: Cells<'_>, cell: (usize, usize)) {
        if let Cells::Luminance(density) = table {
            density.prefetch_cell::<F>(cell);
            self.image
                .prefetch_cell(cell.0 * self.image.width() + cell.1);
        }
    }

    /// The second half of the draws of `cells` (at most [`GROUP`]), each
    /// sample handed to `emit` with its index in the group: from a
    /// luminance density by [`EnvMap::finish_luminance`]; from a piecewise
    /// table, each point placed in its cell and its texels prefetched, then
    /// [`EnvMap::finish_group`].
    #[inline(always)]
    fn finish_cells<F: TableFloat>(
        &self,
        table: Cells<'_>,
        cells: &[((usize, usize), [F; 2])],
        staged: &mut Staged<F>,
        emit: impl FnMut(usize, EnvSample<F>),
    ) {
        let Staged {
            points: simd::OnLines(points),
            frames: simd::OnLines(frames),
            corners,
            placed,
        } = staged;
        match table {
            Cells::Luminance(density) => self.finish_luminance(density, cells, placed, emit),
            Cells::Piecewise(table) => {
                for (k, &(cell, r)) in cells.iter().enumerate() {
                    let placed = self.place_in_cell(table, cell, r);
                    self.stage(placed, &mut points[k], &mut corners[k]);
                }
                self.finish_group(&points[..cells.len()], corners, frames, emit);
            }
        }
    }

    /// The second half of the draws of `cells` (at most [`GROUP`]) from a
    /// luminance `density` (this map's), in columns: the points placed in
    /// their cells ([`LuminanceFloat::place_columns`]); their directions,
    /// densities and texel weights at SIMD width; their texels read by
    /// gathers and blended ([`Image::blend_texels`](crate::envmap::image::Image::blend_texels)).
    /// Each sample is handed to `emit` with its index in the group: the
    /// same bits as [`EnvMap::place_luminance`] then [`EnvMap::sample_at`].
    #[inline(always)]
    fn finish_luminance<F: TableFloat>(
        &self,
        density: &LuminanceDensity,
        cells: &[((usize, usize), [F; 2])],
        placed: &mut PlacedCells<F>,
        mut emit: impl FnMut(usize, EnvSample<F>),
    ) {
        const B: usize = simd::BLOCK;
        // (Only lat-long maps are sampled by their luminance.)
        debug_assert_eq!(self.options.mapping, Mapping::LatLong);
        F::place_columns(density.tables(), cells, placed);
        let w = F::c(self.image.width() as f64);
        let h = F::c((self.image.height() - 1) as f64);
        let zero = F::zero();
        let simd::OnLines(points) = &mut simd::OnLines([[zero; B]; 3]);
        let simd::OnLines(weights) = &mut simd::OnLines([[zero; B]; 4]);
        for i in 0..B {
            let [x, y, pdf_q] = std::array::from_fn(|m| placed.place[m][i]);
            let q = [(placed.cell[0][i] + x) / w, (placed.cell[1][i] + y) / h];
            let [s, t] = self.lat_long_uv(q);
            (points[0][i], points[1][i], points[2][i]) = (s, t, pdf_q);
            for (column, wt) in weights.iter_mut().zip(bilinear_weights(x, y)) {
                column[i] = wt;
            }
        }
        let frame = {
            #[inline(always)]
            |[s, t, pdf_q]: [F; 3]| self.frame_at(Mapping::LatLong, [s, t], pdf_q)
        };
        let simd::OnLines(frames) = &mut simd::OnLines([[zero; B]; 5]);
        simd::map_columns(frames, points, &frame, &|_| true);
        let [w00, w10, w01, w11] = &*weights;
        let simd::OnLines(rgb) = &self
            .image
            .blend_texels(&placed.texels, [w00, w10, w01, w11]);
        let scale = F::c(self.options.scale);
        for i in 0..cells.len() {
            let radiance: [F; 3] = std::array::from_fn(|c| rgb[c][i] * scale);
            let [x, y, z, pdf, inv_pdf] = std::array::from_fn(|m| frames[m][i]);
            let weight = radiance.map(|l| l * inv_pdf);
            emit(
                i,
                EnvSample {
                    direction: [x, y, z],
                    pdf,
                    weight,
                    radiance,
                },
            );
        }
    }

    /// The second half of a group's draws: the directions and densities of
    /// `points` (domain point and table density) at SIMD width, then each
    /// sample's radiance from its `corners`, handed to `emit` with its index
    /// in the group.
    #[inline(always)]
    fn finish_group<F: Real>(
        &self,
        points: &[[F; 3]],
        corners: &[Corners<F>],
        frames: &mut [[F; 5]; GROUP],
        mut emit: impl FnMut(usize, EnvSample<F>),
    ) {
        let frames = &mut frames[..points.len()];
        per_mapping!(self.options.mapping, |M| {
            let frame = {
                #[inline(always)]
                |[s, t, pdf_q]: [F; 3]| self.frame_at(M, [s, t], pdf_q)
            };
            simd::map_rows(frames, points, &frame, |_| true, false)
        });
        for (k, (f, c)) in frames.iter().zip(corners).enumerate() {
            emit(k, self.sample_from(f, c));
        }
    }

    /// A placed point's texels prefetched, and its domain point and density
    /// (`[s, t, p_q]`) and texels staged for [`EnvMap::finish_group`].
    #[inline(always)]
    fn stage<F: Real>(&self, placed: Placed<F>, point: &mut [F; 3], corners: &mut Corners<F>) {
        self.image.prefetch(&placed.corners.0);
        let [s, t] = placed.point;
        (*point, *corners) = ([s, t, placed.pdf_q], placed.corners);
    }

    /// [`CellSampler::sample`] by `sampler` (built for this map) of each
    /// `(bits, r)` of `draws`, appended to `out`, group by group as
    /// [`EnvMap::sample_rows`] draws: the cells (their alias-table reads
    /// overlap) and the lines that placing points in them read prefetched,
    /// then [`EnvMap::finish_cells`].
    #[inline(always)]
    pub(in crate::envmap) fn sample_cells<F: TableFloat>(
        &self,
        sampler: &CellSampler,
        draws: &[(u64, [F; 2])],
        out: &mut Vec<EnvSample<F>>,
    ) {
        match &self.distribution {
            Distribution::Luminance(density) => {
                self.sample_cells_by(sampler, draws, out, Cells::Luminance(density))
            }
            Distribution::Piecewise(table) => {
                self.sample_cells_by(sampler, draws, out, Cells::Piecewise(table))
            }
            // (Maps without cells have no cell sampler.)
            Distribution::Bilinear(_) | Distribution::Black => {
                out.extend(draws.iter().map(|&(bits, r)| sampler.sample(self, bits, r)));
            }
        }
    }

    /// [`EnvMap::sample_cells`] of a map whose cells are `table`, group by
    /// group: the cells (their alias-table reads overlap) and the lines
    /// that placing points in them read prefetched, then
    /// [`EnvMap::finish_cells`].
    #[inline(always)]
    fn sample_cells_by<F: TableFloat>(
        &self,
        sampler: &CellSampler,
        draws: &[(u64, [F; 2])],
        out: &mut Vec<EnvSample<F>>,
        table: Cells<'_>,
    ) {
        let mut cells = [((0, 0), [F::zero(); 2]); GROUP];
        let mut staged = Staged::new();
        for draws in draws.chunks(GROUP) {
            for (cell, &(bits, r)) in cells.iter_mut().zip(draws) {
                *cell = (sampler.cell(bits), r);
                self.prefetch_cell::<F>(table, cell.0);
            }
            self.finish_cells(table, &cells[..draws.len()], &mut staged, |_, s| {
                out.push(s)
            });
        }
    }
}

/// A group's scratch columns for [`EnvMap::finish_cells`]: a piecewise
/// table's points (`[s, t, p_q]`), their frames and texels, and a
/// luminance density's placed cells.
struct Staged<F> {
    points: simd::OnLines<[[F; 3]; GROUP]>,
    frames: simd::OnLines<[[F; 5]; GROUP]>,
    corners: [Corners<F>; GROUP],
    placed: PlacedCells<F>,
}

impl<F: Real> Staged<F> {
    #[inline(always)]
    fn new() -> Self {
        let zero = F::zero();
        Staged {
            points: simd::OnLines([[zero; 3]; GROUP]),
            frames: simd::OnLines([[zero; 5]; GROUP]),
            corners: [([0; 4], [zero; 4]); GROUP],
            placed: PlacedCells::new(),
        }
    }
}

/// The table of a map whose draws are a cell and the fractions `r` in it.
#[derive(Clone, Copy)]
enum Cells<'a> {
    Luminance(&'a LuminanceDensity),
    Piecewise(&'a PiecewiseConstant2D),
}

impl Cells<'_> {
    /// The cell and the fractions in it of each of `us`, by the table's
    /// batch sampler (whose cache misses overlap).
    #[inline(always)]
    fn draw<F: Real>(self, us: &[[F; 2]], out: &mut [((usize, usize), [F; 2])]) {
        match self {
            Cells::Luminance(density) => density.cells().sample_groups(us, out),
            Cells::Piecewise(table) => table.table().sample_groups(us, out),
        }
    }
}

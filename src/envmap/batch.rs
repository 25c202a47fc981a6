//! The batch pipelines of an [`EnvMap`]: `eval`, `pdf` and `sample` over
//! many directions or numbers at once, in blocks whose steps run at SIMD
//! width and whose table and texel reads are prefetched so that their
//! cache misses overlap. Each computes what its one-at-a-time method does:
//! the same bits.

use super::distribution::Distribution;
use super::image::Corners;
use super::mapping::Mapping;
use super::polar::TableFloat;
use super::sample::PdfQuery;
use super::{EnvMap, EnvSample};
use crate::math::Real;
use crate::simd;
use crate::warp::V3;

#[cfg(doc)]
use super::{PolarTable, image::Image};

/// Directions per block of [`EnvMap::pdf_into`] for the densities that
/// are read one direction at a time ([`EnvMap::pdf_query`]).
pub(super) const BATCH_BLOCK: usize = 256;

/// `$run`, once per mapping with `$m` that mapping as a constant, so that
/// each loop has its own formulas inlined (a match inside a loop would
/// keep it from vectorising).
macro_rules! per_mapping {
    ($mapping:expr, |$m:ident| $run:expr) => {
        match $mapping {
            Mapping::LatLong => {
                const $m: Mapping = Mapping::LatLong;
                $run
            }
            Mapping::Angular => {
                const $m: Mapping = Mapping::Angular;
                $run
            }
            Mapping::Cube => {
                const $m: Mapping = Mapping::Cube;
                $run
            }
        }
    };
}

/// The arrays a batch of [`EnvMap::sample_into`] writes: each sample's
/// parts into their own array, as a caller's separate outputs want them.
#[derive(Debug)]
pub struct EnvSamples<'a, F> {
    /// The directions.
    pub direction: &'a mut [V3<F>],
    /// Their densities per steradian.
    pub pdf: &'a mut [F],
    /// `L/pdf` per RGB channel.
    pub weight: &'a mut [V3<F>],
}

impl<F: Copy> EnvSamples<'_, F> {
    /// Writes sample `k`.
    #[inline(always)]
    fn set(&mut self, k: usize, s: EnvSample<F>) {
        (self.direction[k], self.pdf[k], self.weight[k]) = (s.direction, s.pdf, s.weight);
    }
}

impl EnvMap {
    /// `out[i] = eval(d[i])` for a batch, in `F`: every direction's place on
    /// the map by one loop at SIMD width (for lat-long maps its cell and
    /// weights too), then its texels located and prefetched, and read one
    /// block behind (two blocks in flight); a lat-long map's cells are
    /// found, and their texels read (by gathers) and blended, at SIMD width
    /// (`Image::blend_places`).
    /// Returns whether `valid` held for every direction (it is checked in
    /// the same pass).
    pub fn eval_into<F: Real>(
        &self,
        d: &[[F; 3]],
        out: &mut [[F; 3]],
        valid: impl Fn(&[F; 3]) -> bool,
    ) -> bool {
        match self.options.mapping {
            Mapping::LatLong => {
                let place = {
                    #[inline(always)]
                    |x: [F; 3]| self.image.lat_long_place(self.uv_of(Mapping::LatLong, x))
                };
                let locate = {
                    #[inline(always)]
                    |q: &Columns<F, 6>, cells: &mut [u32; simd::BLOCK], rows: usize| {
                        self.image.place_texels(&q[0], &q[1], cells);
                        for &k in &cells[..rows] {
                            self.image.prefetch_cell(k as usize);
                        }
                    }
                };
                let read = {
                    #[inline(always)]
                    |q: &Columns<F, 6>, cells: &[u32; simd::BLOCK], o: &mut [[F; 3]]| {
                        let simd::OnLines(rgb) = &self.image.blend_places(q, cells);
                        let scale = F::c(self.options.scale);
                        for (i, o) in o.iter_mut().enumerate() {
                            *o = [0, 1, 2].map(|c| rgb[c][i] * scale);
                        }
                    }
                };
                pipelined_blocks(d, out, &place, valid, locate, read)
            }
            Mapping::Angular => self.eval_by_corners(d, out, valid, Mapping::Angular),
            Mapping::Cube => self.eval_by_corners(d, out, valid, Mapping::Cube),
        }
    }

    /// [`EnvMap::eval_into`] of a map whose places are found by
    /// [`Image::corners`] (called with each `mapping` as a constant, so that
    /// its formulas are inlined without a branch).
    #[inline(always)]
    fn eval_by_corners<F: Real>(
        &self,
        d: &[[F; 3]],
        out: &mut [[F; 3]],
        valid: impl Fn(&[F; 3]) -> bool,
        mapping: Mapping,
    ) -> bool {
        let place = {
            #[inline(always)]
            |x: [F; 3]| self.uv_of(mapping, x)
        };
        let locate = {
            #[inline(always)]
            |p: &[F; 2]| self.prefetched(self.image.corners(mapping, *p))
        };
        pipelined(d, out, &place, valid, locate, |_, c| self.radiance_of(c))
    }

    /// `corners`, their texels prefetched.
    #[inline(always)]
    fn prefetched<F: Real>(&self, corners: Corners<F>) -> Corners<F> {
        self.image.prefetch(&corners.0);
        corners
    }

    /// `out[i] = pdf(d[i])` for a batch, in `F`. For the luminance density
    /// and polar tables in blocks of [`simd::BLOCK`], two in flight: for
    /// the luminance density, every
    /// direction's cell, bilinear weights and Jacobian at full SIMD width
    /// (`EnvMap::luminance_query`), then the table lines of the cell
    /// prefetched; for polar tables, every direction's cell by the
    /// branch-free [`PolarTable::query`] at full SIMD width and its density
    /// prefetched; either read one block behind, so that the reads wait on
    /// no cache miss; for the others [`EnvMap::pdf_query`] then
    /// [`EnvMap::pdf_at`]. Returns whether `valid` held for every direction
    /// (it is checked in the same pass).
    pub fn pdf_into<F: TableFloat>(
        &self,
        d: &[[F; 3]],
        out: &mut [F],
        valid: impl Fn(&[F; 3]) -> bool,
    ) -> bool {
        if let Distribution::Luminance(density) = &self.distribution {
            let query = {
                #[inline(always)]
                |x: [F; 3]| self.luminance_query(x)
            };
            let tables = density.tables();
            let locate = {
                #[inline(always)]
                |q: &Columns<F, 7>, cells: &mut [u32; simd::BLOCK], rows: usize| {
                    self.image.place_texels(&q[0], &q[1], cells);
                    for &k in &cells[..rows] {
                        F::prefetch_luminance(tables, k as usize);
                    }
                }
            };
            let read = {
                #[inline(always)]
                move |q: &Columns<F, 7>, cells: &[u32; simd::BLOCK], o: &mut [F]| {
                    F::luminance_block(tables, q, cells, o)
                }
            };
            pipelined_blocks(d, out, &query, valid, locate, read)
        } else if let Some(table) = &self.polar {
            let densities = F::densities(table);
            let query = {
                #[inline(always)]
                |x| table.query(x)
            };
            let locate = {
                #[inline(always)]
                |q: &[F; 3]| {
                    let c = table.cell(*q);
                    simd::prefetch(densities, c);
                    c
                }
            };
            let read = {
                #[inline(always)]
                |q: &[F; 3], &c: &usize| densities.get(c).copied().unwrap_or(F::zero()) * q[2]
            };
            pipelined(d, out, &query, valid, locate, read)
        } else {
            let mut ok = true;
            let mut queries = [PdfQuery::default(); BATCH_BLOCK];
            for (o, x) in out.chunks_mut(BATCH_BLOCK).zip(d.chunks(BATCH_BLOCK)) {
                for (q, x) in queries.iter_mut().zip(x) {
                    ok &= valid(x);
                    *q = self.pdf_query(x.map(F::f64));
                }
                for (o, q) in o.iter_mut().zip(&queries[..x.len()]) {
                    *o = F::c(self.pdf_at(*q));
                }
            }
            ok
        }
    }
}

/// `out[i] = read(q, locate(q))` with `q = query(d[i])`: [`pipelined_blocks`]
/// with `locate` and `read` called for each direction of a block.
#[inline(always)]
fn pipelined<F: Real, T, C: Copy + Default, const K: usize>(
    d: &[[F; 3]],
    out: &mut [T],
    query: &impl Fn([F; 3]) -> [F; K],
    valid: impl Fn(&[F; 3]) -> bool,
    locate: impl Fn(&[F; K]) -> C,
    read: impl Fn(&[F; K], &C) -> T,
) -> bool {
    let read_block = {
        #[inline(always)]
        |q: &Columns<F, K>, c: &[C; simd::BLOCK], o: &mut [T]| {
            for (i, (o, c)) in o.iter_mut().zip(c).enumerate() {
                *o = read(&row(q, i), c);
            }
        }
    };
    pipelined_blocks(d, out, query, valid, each_row(locate), read_block)
}

/// `locate` of each of a block's first `rows` queries, for [`pipelined_blocks`].
#[inline(always)]
fn each_row<F: Copy, C, const K: usize>(
    locate: impl Fn(&[F; K]) -> C,
) -> impl Fn(&Columns<F, K>, &mut [C; simd::BLOCK], usize) {
    #[inline(always)]
    move |q: &Columns<F, K>, c: &mut [C; simd::BLOCK], rows: usize| {
        for (i, c) in c[..rows].iter_mut().enumerate() {
            *c = locate(&row(q, i));
        }
    }
}

/// A block's queries, one column per component.
type Columns<F, const K: usize> = [[F; simd::BLOCK]; K];

/// Row `i` of the columns `q`.
#[inline(always)]
fn row<F: Copy, const K: usize>(q: &Columns<F, K>, i: usize) -> [F; K] {
    std::array::from_fn(|m| q[m][i])
}

/// `out[i] = read(q, locate(q))` with `q = query(d[i])`, in blocks of
/// [`simd::BLOCK`] with two in flight: each block's queries at full SIMD
/// width into columns ([`simd::map_to_columns`], which checks `valid` in
/// the same pass), then their table entries located (`locate` of the
/// columns and the number of rows prefetches them), then the block before
/// read (`read` of its columns and entries into its outputs), its entries
/// by now in the caches: the table reads overlap the next block's
/// arithmetic instead of waiting on it. Returns whether `valid` held for
/// every direction.
#[inline(always)]
fn pipelined_blocks<F: Real, T, C: Copy + Default, const K: usize>(
    d: &[[F; 3]],
    out: &mut [T],
    query: &impl Fn([F; 3]) -> [F; K],
    valid: impl Fn(&[F; 3]) -> bool,
    locate: impl Fn(&Columns<F, K>, &mut [C; simd::BLOCK], usize),
    read: impl Fn(&Columns<F, K>, &[C; simd::BLOCK], &mut [T]),
) -> bool {
    const B: usize = simd::BLOCK;
    let simd::OnLines(queries) = &mut simd::OnLines([[[F::zero(); B]; K]; 2]);
    let simd::OnLines(entries) = &mut simd::OnLines([[C::default(); B]; 2]);
    simd::dispatch(
        #[inline(always)]
        |_| {
            let mut ok = true;
            // The block waiting to be read: its buffers' index and its
            // outputs, as many as its rows.
            let mut previous: Option<(usize, &mut [T])> = None;
            for (b, (o, x)) in out.chunks_mut(B).zip(d.chunks(B)).enumerate() {
                let (q, c) = (&mut queries[b % 2], &mut entries[b % 2]);
                ok &= simd::map_to_columns(q, x, query, &valid);
                locate(q, c, x.len());
                let rows = x.len().min(o.len());
                if let Some((p, o)) = previous.replace((b % 2, &mut o[..rows])) {
                    read(&queries[p], &entries[p], o);
                }
            }
            if let Some((p, o)) = previous {
                read(&queries[p], &entries[p], o);
            }
            ok
        },
    )
}

mod draws;

#[cfg(test)]
mod tests;

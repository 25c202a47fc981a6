//! Environment maps (image-based lighting): radiance from every direction,
//! and importance sampling of directions in proportion to it.
//!
//! An [`EnvMap`] is an [`Image`] on the sphere through a [`Mapping`]
//! (lat-long exactly as Mitsuba 3's `envmap` emitter, Debevec's angular
//! probes, OpenGL cube maps), turned by `to_world` and scaled by `scale`.
//! Every method takes and returns world directions.
//!
//! # Sampling
//! [`Sampling::Piecewise`] (the default) samples a [`PiecewiseConstant2D`]
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

mod bilinear;
mod cell_sampler;
mod image;
mod mapping;

pub use bilinear::BilinearGrid;
pub use cell_sampler::CellSampler;
pub use image::{Corners, Image};
pub use mapping::{Mapping, normalized, polar_angle};

use crate::buffer::Buffer;
use crate::distr::{GROUP, PiecewiseConstant2D};
use crate::error::{Error, Result};
use crate::math::{Real, atan2, sin_cos_turn};
use crate::parallel;
use crate::simd;
use crate::warp::{self, V3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// A 3×3 matrix, row-major.
pub type Matrix3 = [[f64; 3]; 3];

const IDENTITY: Matrix3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Mitsuba's `Epsilon<float>` (2⁻²⁴): the floor of sin θ in the density of
/// the polar tables, as in Mitsuba's envmap pdf.
const SIN_FLOOR: f64 = 1.0 / 16_777_216.0;

/// Directions per block of [`EnvMap::eval_into`] and [`EnvMap::pdf_into`].
const BATCH_BLOCK: usize = 256;

/// `dω/dq` of a polar sampling table at a direction `θ` from its axis:
/// `2π² max(|sin θ|, 2⁻²⁴)` (see [`SIN_FLOOR`]).
#[inline(always)]
fn polar_jacobian<F: Real>(sin_theta: F) -> F {
    F::c(2.0 * PI * PI) * sin_theta.abs().max(F::c(SIN_FLOOR))
}

/// The luminance weights of Mitsuba 3's `luminance()`, used in
/// [`Sampling::Mitsuba`] mode so that its density is Mitsuba's.
const MITSUBA_LUMINANCE: [f64; 3] = [0.212671, 0.715160, 0.072169];

/// How an [`EnvMap`] samples directions (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// Piecewise-constant over the cells of the bilinear radiance (default).
    Piecewise,
    /// Mitsuba 3's bilinear density on the vertex grid (lat-long only).
    Mitsuba,
}

impl Sampling {
    /// The name used in the Python API: `"piecewise"` or `"mitsuba"`.
    pub fn name(self) -> &'static str {
        match self {
            Sampling::Piecewise => "piecewise",
            Sampling::Mitsuba => "mitsuba",
        }
    }

    /// The mode called `name` (see [`Sampling::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "piecewise" => Some(Sampling::Piecewise),
            "mitsuba" => Some(Sampling::Mitsuba),
            _ => None,
        }
    }
}

/// The options of an [`EnvMap`] beyond its image.
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

impl Default for Options {
    fn default() -> Self {
        Options {
            mapping: Mapping::LatLong,
            to_world: IDENTITY,
            scale: 1.0,
            sampling: Sampling::Piecewise,
            compensate: false,
        }
    }
}

#[derive(Clone, Debug)]
enum Distribution {
    Piecewise(PiecewiseConstant2D),
    Bilinear(BilinearGrid),
    Black,
}

/// An environment map: radiance `L(d)` for every world direction and a
/// sampler of directions with a density close to `L`.
#[derive(Clone, Debug)]
pub struct EnvMap {
    image: Image,
    options: Options,
    distribution: Distribution,
    polar: Option<PolarTable>,
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
/// densities: each from its own copy of the table.
pub trait TableFloat: Real {
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
    fn new(
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
        let mut density_f32 = Buffer::for_overwrite(density.len());
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
    fn pdf<F: Real>(&self, query: PolarQuery<F>) -> f64 {
        self.density.get(self.cell(query)).copied().unwrap_or(0.0) * query[2].f64()
    }
}

/// A direction located in the sampling table ([`EnvMap::pdf_query`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PdfQuery {
    q: [f64; 2],
    jacobian: f64,
}

/// One sample of [`EnvMap::sample`] (computed in `F`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnvSample<F = f64> {
    /// World direction toward the environment (unit length).
    pub direction: V3<F>,
    /// Its density per steradian.
    pub pdf: F,
    /// `L(direction)/pdf` per RGB channel; 0 when `pdf = 0`.
    pub weight: V3<F>,
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

impl<F: Real> EnvSample<F> {
    /// The radiance arriving along the direction, `weight · pdf`.
    pub fn radiance(&self) -> V3<F> {
        self.weight.map(|w| w * self.pdf)
    }

    /// The sample rounded to `G`.
    pub fn cast<G: Real>(&self) -> EnvSample<G> {
        EnvSample {
            direction: self.direction.map(|x| G::c(x.f64())),
            pdf: G::c(self.pdf.f64()),
            weight: self.weight.map(|x| G::c(x.f64())),
        }
    }
}

impl EnvMap {
    /// An environment map of the row-major RGB `image` (`width × height`
    /// texels; cube maps: the six faces one below the other).
    ///
    /// # Errors
    /// As [`Image::new`]; [`Error::Parameter`] for a `scale` that is
    /// negative or not finite, or a `to_world` that is not a rotation (an
    /// orthonormal matrix, to 1e-4); [`Error::Choice`] for
    /// [`Sampling::Mitsuba`] on a map that is not lat-long.
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
        if options.sampling == Sampling::Mitsuba && options.mapping != Mapping::LatLong {
            return Err(Error::Choice {
                arg: "sampling",
                value: "mitsuba".into(),
                requirement: format!(
                    "Mitsuba's envmap is lat-long only; mapping is {:?}",
                    options.mapping.name()
                ),
            });
        }
        let (distribution, polar) = if options.scale == 0.0 {
            (Distribution::Black, None)
        } else {
            match options.sampling {
                Sampling::Piecewise => {
                    let (distribution, values) = piecewise_table(&image, &options)?;
                    let polar = PolarTable::new(&distribution, values, &image, &options)?;
                    (distribution, polar)
                }
                Sampling::Mitsuba => (mitsuba_grid(&image, options.compensate)?, None),
            }
        };
        Ok(EnvMap {
            image,
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

    /// The local direction of the world direction `d`: `to_worldᵀ·d`.
    #[inline(always)]
    fn to_local<F: Real>(&self, d: V3<F>) -> V3<F> {
        let m = &self.options.to_world;
        std::array::from_fn(|k| F::c(m[0][k]) * d[0] + F::c(m[1][k]) * d[1] + F::c(m[2][k]) * d[2])
    }

    #[inline(always)]
    fn to_world<F: Real>(&self, d: V3<F>) -> V3<F> {
        let m = &self.options.to_world;
        std::array::from_fn(|k| F::c(m[k][0]) * d[0] + F::c(m[k][1]) * d[1] + F::c(m[k][2]) * d[2])
    }

    /// The domain point `(s, t)` that looks along the world direction `d`.
    #[inline]
    pub fn dir_to_uv(&self, d: V3<f64>) -> [f64; 2] {
        self.options.mapping.from_dir(self.to_local(d))
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
        let mapping = self.options.mapping;
        self.radiance_at(mapping.from_dir(self.to_local(d)))
    }

    /// The density of [`EnvMap::sample`] at the world direction `d`, per
    /// steradian.
    #[inline]
    pub fn pdf(&self, d: V3<f64>) -> f64 {
        match &self.polar {
            Some(table) => table.pdf(table.query(d)),
            None => self.pdf_at(self.pdf_query(d)),
        }
    }

    /// `out[i] = eval(d[i])` for a batch, in `F`: every direction's place on
    /// the map by one loop (which vectorises for lat-long maps), then the
    /// texel reads of the whole block, which overlap. Returns whether
    /// `valid` held for every direction (it is checked in the same pass).
    pub fn eval_into<F: Real>(
        &self,
        d: &[[F; 3]],
        out: &mut [[F; 3]],
        valid: impl Fn(&[F; 3]) -> bool,
    ) -> bool {
        // One loop per mapping, each with its own from_dir inlined: a
        // match inside the loop would keep it from vectorising.
        macro_rules! place {
            ($mapping:expr) => {{
                #[inline(always)]
                |x: [F; 3]| $mapping.from_dir(self.to_local(x))
            }};
        }
        match self.options.mapping {
            Mapping::LatLong => self.eval_blocks(d, out, &place!(Mapping::LatLong), valid),
            Mapping::Angular => self.eval_blocks(d, out, &place!(Mapping::Angular), valid),
            Mapping::Cube => self.eval_blocks(d, out, &place!(Mapping::Cube), valid),
        }
    }

    /// [`EnvMap::eval_into`] with `place` the mapping's `from_dir`.
    #[inline(always)]
    fn eval_blocks<F: Real>(
        &self,
        d: &[[F; 3]],
        out: &mut [[F; 3]],
        place: &impl Fn([F; 3]) -> [F; 2],
        valid: impl Fn(&[F; 3]) -> bool,
    ) -> bool {
        let mut ok = true;
        let mut points = [[F::zero(); 2]; BATCH_BLOCK];
        for (d, out) in d.chunks(BATCH_BLOCK).zip(out.chunks_mut(BATCH_BLOCK)) {
            let points = &mut points[..d.len()];
            ok &= simd::map_rows(points, d, place, &valid, false);
            for (o, &p) in out.iter_mut().zip(points.iter()) {
                *o = self.radiance_at(p);
            }
        }
        ok
    }

    /// `out[i] = pdf(d[i])` for a batch, in `F`, in blocks of
    /// `BATCH_BLOCK`: for polar tables, every direction's cell by the
    /// branch-free [`PolarTable::query`] at full SIMD width and its density
    /// prefetched, then the densities of the block before read (one block
    /// behind, so that the reads wait on no cache miss); for the others
    /// [`EnvMap::pdf_query`] then [`EnvMap::pdf_at`]. Returns whether `valid` held for every
    /// direction (it is checked in the same pass).
    pub fn pdf_into<F: TableFloat>(
        &self,
        d: &[[F; 3]],
        out: &mut [F],
        valid: impl Fn(&[F; 3]) -> bool,
    ) -> bool {
        let mut ok = true;
        let blocks = out.chunks_mut(BATCH_BLOCK).zip(d.chunks(BATCH_BLOCK));
        if let Some(table) = &self.polar {
            // Two blocks in flight: each block's cells are located and their
            // densities prefetched, then the densities of the block before
            // are read (by now in the caches), so that the table reads
            // overlap the next block's arithmetic instead of waiting on it.
            let mut queries = [[[F::zero(); 3]; BATCH_BLOCK]; 2];
            let mut cells = [[0usize; BATCH_BLOCK]; 2];
            let densities = F::densities(table);
            let query = {
                #[inline(always)]
                |x| table.query(x)
            };
            let read = {
                #[inline(always)]
                |o: &mut [F], q: &[[F; 3]; BATCH_BLOCK], c: &[usize; BATCH_BLOCK]| {
                    for ((o, q), &c) in o.iter_mut().zip(q).zip(c) {
                        *o = densities.get(c).copied().unwrap_or(F::zero()) * q[2];
                    }
                }
            };
            ok = simd::dispatch(
                #[inline(always)]
                |_| {
                    let mut ok = true;
                    let mut previous: Option<&mut [F]> = None;
                    for (b, (o, x)) in blocks.enumerate() {
                        let (q, c) = (&mut queries[b % 2], &mut cells[b % 2]);
                        ok &= simd::map_rows(&mut q[..x.len()], x, &query, &valid, false);
                        for (c, q) in c.iter_mut().zip(&q[..x.len()]) {
                            *c = table.cell(*q);
                            simd::prefetch(densities, *c);
                        }
                        if let Some(p) = previous.replace(o) {
                            read(p, &queries[(b + 1) % 2], &cells[(b + 1) % 2]);
                        }
                    }
                    if let Some(p) = previous {
                        let last = d.len().div_ceil(BATCH_BLOCK) - 1;
                        read(p, &queries[last % 2], &cells[last % 2]);
                    }
                    ok
                },
            );
        } else {
            let mut queries = [PdfQuery::default(); BATCH_BLOCK];
            for (o, x) in blocks {
                for (q, x) in queries.iter_mut().zip(x) {
                    ok &= valid(x);
                    *q = self.pdf_query(x.map(F::f64));
                }
                for (o, q) in o.iter_mut().zip(&queries) {
                    *o = F::c(self.pdf_at(*q));
                }
            }
        }
        ok
    }

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
            Distribution::Piecewise(table) => table.pdf(query.q),
            Distribution::Bilinear(grid) => grid.pdf(query.q),
            Distribution::Black => return 0.0,
        };
        pdf_q / query.jacobian
    }

    /// A direction drawn with density [`EnvMap::pdf`], for `u` in `[0, 1]²`.
    #[inline]
    pub fn sample(&self, u: [f64; 2]) -> EnvSample {
        let mapping = self.options.mapping;
        let (p, pdf_q, corners) = match &self.distribution {
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
        self.sample_from(&self.frame_at(mapping, p, pdf_q), &corners)
    }

    /// The point at fractions `r` of cell `cell` of the piecewise `table`
    /// (this map's): its domain point, its density per unit table area and
    /// the texels under it. A lat-long map's cells are the patches between
    /// texel centres, so its texels are the cell's corners weighted by `r`,
    /// found without locating the point again.
    #[inline(always)]
    fn place_in_cell<F: Real>(
        &self,
        table: &PiecewiseConstant2D,
        cell: (usize, usize),
        r: [F; 2],
    ) -> ([F; 2], F, Corners<F>) {
        let (q, pdf_q) = table.sample_in_cell(cell, r);
        match self.options.mapping {
            Mapping::LatLong => (self.table_to_uv(q), pdf_q, self.image.cell_corners(cell, r)),
            _ => self.place_at(q, pdf_q),
        }
    }

    /// The table point `q`, drawn with density `pdf_q` per unit table area:
    /// its domain point, that density and the texels under it.
    #[inline(always)]
    fn place_at<F: Real>(&self, q: [F; 2], pdf_q: F) -> ([F; 2], F, Corners<F>) {
        let p = self.table_to_uv(q);
        (p, pdf_q, self.image.corners(self.options.mapping, p))
    }

    /// `out[i] = sample(us[i])` for a batch, in groups: the table points by
    /// the tables' batch samplers (whose cache misses overlap), then the
    /// texels under them located (a lat-long map's from the drawn cell, see
    /// `place_in_cell`) and prefetched, the directions and
    /// densities of the group in one loop at SIMD width, and last the
    /// radiance. Computed in `F` past the table draw (whose searches run in
    /// `f64`; Mitsuba's bilinear density is sampled in `f64` and rounded);
    /// in `f64`, the same bits as [`EnvMap::sample`]. In `f32` a direction
    /// and its density are good to a few ulps of `f32` (the density near a
    /// pole of a polar table to about `10⁻⁷/sin θ`).
    ///
    /// # Panics
    /// If an array of `out` is shorter than `us`.
    pub fn sample_into<F: Real>(&self, us: &[[F; 2]], out: EnvSamples<'_, F>) {
        self.sample_rows(us, |&u| u, out);
    }

    /// [`EnvMap::sample_into`] of `prepare(row)` for each of `rows`: the
    /// numbers `u` of a group are made (checked, clamped) as the group is
    /// drawn, in the same pass, so that a caller needs no pass of its own
    /// over its input.
    ///
    /// # Panics
    /// If an array of `out` is shorter than `rows`.
    pub fn sample_rows<F: Real, R>(
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

    #[inline(always)]
    fn sample_groups<F: Real, R>(
        &self,
        rows: &[R],
        mut prepare: impl FnMut(&R) -> [F; 2],
        mut out: EnvSamples<'_, F>,
    ) {
        // One loop per mapping, each with its own formulas inlined (see
        // `eval_into`).
        macro_rules! frame {
            ($mapping:expr) => {{
                #[inline(always)]
                |[s, t, pdf_q]: [F; 3]| self.frame_at($mapping, [s, t], pdf_q)
            }};
        }
        let zero = F::zero();
        let mut cells = [((0, 0), [zero; 2]); GROUP];
        let mut points = [[zero; 3]; GROUP];
        let mut frames = [[zero; 5]; GROUP];
        let mut corners = [([0; 4], [zero; 4]); GROUP];
        let mut bilinear = [([0.0; 2], 0.0); GROUP];
        let mut group = [[zero; 2]; GROUP];
        let mapping = self.options.mapping;
        for (g, rows) in rows.chunks(GROUP).enumerate() {
            let n = rows.len();
            let first = g * GROUP;
            let us = &mut group[..n];
            for (u, row) in us.iter_mut().zip(rows) {
                *u = prepare(row);
            }
            let us = &*us;
            // Each point's domain point and density, and its texels
            // (prefetched).
            let mut place = |k: usize, (p, pdf_q, c): ([F; 2], F, Corners<F>)| {
                self.image.prefetch(&c);
                (points[k], corners[k]) = ([p[0], p[1], pdf_q], c);
            };
            match &self.distribution {
                Distribution::Piecewise(table) => {
                    let cells = &mut cells[..n];
                    table.table().sample_groups(us, cells);
                    for (k, &(cell, r)) in cells.iter().enumerate() {
                        place(k, self.place_in_cell(table, cell, r));
                    }
                }
                Distribution::Bilinear(grid) => {
                    let (u64s, b) = (&mut [[0.0; 2]; GROUP][..n], &mut bilinear[..n]);
                    for (u, x) in u64s.iter_mut().zip(us) {
                        *u = x.map(F::f64);
                    }
                    grid.sample_into(u64s, b);
                    for (k, &(q, pdf)) in b.iter().enumerate() {
                        place(k, self.place_at(q.map(F::c), F::c(pdf)));
                    }
                }
                Distribution::Black => {
                    for (k, &u) in (first..).zip(us) {
                        out.set(k, self.sample_black(u.map(F::f64)).cast());
                    }
                    continue;
                }
            }
            let (points, frames) = (&points[..n], &mut frames[..n]);
            match mapping {
                Mapping::LatLong => {
                    simd::map_rows(frames, points, &frame!(Mapping::LatLong), |_| true, false)
                }
                Mapping::Angular => {
                    simd::map_rows(frames, points, &frame!(Mapping::Angular), |_| true, false)
                }
                Mapping::Cube => {
                    simd::map_rows(frames, points, &frame!(Mapping::Cube), |_| true, false)
                }
            };
            for ((k, f), c) in (first..).zip(frames.iter()).zip(&corners) {
                out.set(k, self.sample_from(f, c));
            }
        }
    }

    /// The sample of an all-black map: a uniform direction that carries no
    /// light (pdf 0, weight 0).
    fn sample_black(&self, u: [f64; 2]) -> EnvSample {
        EnvSample {
            direction: self.to_world(warp::square_to_uniform_sphere(u)),
            pdf: 0.0,
            weight: [0.0; 3],
        }
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
    fn frame_at<F: Real>(&self, mapping: Mapping, p: [F; 2], pdf_q: F) -> [F; 5] {
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
    fn sample_from<F: Real>(&self, frame: &[F; 5], corners: &Corners<F>) -> EnvSample<F> {
        let [x, y, z, pdf, inv_pdf] = *frame;
        EnvSample {
            direction: [x, y, z],
            pdf,
            weight: self.radiance_of(corners).map(|l| l * inv_pdf),
        }
    }

    /// The point of the sampling table that looks along the local
    /// direction `d`: lat-long `(s − ½/W, t)` wrapped into the table (which
    /// starts half a texel into the turn, at the first texel centre);
    /// angular, polar coordinates around +Z `(ψ, ρ) = (atan2(d.y, d.x)/2π,
    /// acos(d.z)/π)`; cube maps, the domain point itself.
    #[inline(always)]
    fn table_point(&self, d: V3<f64>) -> [f64; 2] {
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

    /// The domain point (`dir_to_uv`'s coordinates) of the table point `q`.
    #[inline(always)]
    fn table_to_uv<F: Real>(&self, q: [F; 2]) -> [F; 2] {
        match self.options.mapping {
            Mapping::LatLong => {
                let s = q[0] + F::c(0.5 / self.image.width() as f64);
                [if s >= F::one() { s - F::one() } else { s }, q[1]]
            }
            Mapping::Angular => angular_uv(q[0], q[1]),
            Mapping::Cube => q,
        }
    }

    /// `dω/dq` of the sampling table at the local direction `d`: for the
    /// polar tables (lat-long around Y, angular around Z)
    /// `2π² max(sin θ, 2⁻²⁴)` with sin θ from `d` (Mitsuba's floor, so a
    /// pole has a finite density); for cube maps [`Mapping::jacobian`].
    #[inline(always)]
    fn table_jacobian(&self, d: V3<f64>) -> f64 {
        let d = normalized(d);
        let polar = |x: f64, y: f64| polar_jacobian((x * x + y * y).sqrt());
        match self.options.mapping {
            Mapping::LatLong => polar(d[0], d[2]),
            Mapping::Angular => polar(d[0], d[1]),
            Mapping::Cube => Mapping::Cube.jacobian(Mapping::Cube.from_dir(d)),
        }
    }

    /// The same light resampled into `mapping` at `width × height` texels
    /// (cube maps: `height = 6·width`): every new texel takes the bilinear
    /// value of this map in its direction. `to_world`, `scale` and
    /// `compensate` are kept; the sampling mode too where the new mapping
    /// has it (else [`Sampling::Piecewise`]).
    ///
    /// # Errors
    /// As [`EnvMap::new`] for the new shape.
    pub fn convert(&self, mapping: Mapping, width: usize, height: usize) -> Result<EnvMap> {
        let mut data = Vec::with_capacity(width * height * 3);
        for y in 0..height {
            for x in 0..width {
                let p = texel_centre(mapping, width, height, x, y);
                let lit = mapping.jacobian(p) > 0.0 || mapping != Mapping::Angular;
                let rgb = if lit {
                    let d = mapping.to_dir(p);
                    self.image
                        .lookup(self.options.mapping, self.options.mapping.from_dir(d))
                } else {
                    [0.0; 3]
                };
                data.extend(rgb.map(|v| v as f32));
            }
        }
        let sampling = if mapping == Mapping::LatLong {
            self.options.sampling
        } else {
            Sampling::Piecewise
        };
        EnvMap::new(
            width,
            height,
            &data,
            Options {
                mapping,
                sampling,
                ..self.options
            },
        )
    }
}

/// Where texel `(x, y)` of a `width × height` image of `mapping` sits in
/// the domain (lat-long rows on the poles and between; others centred).
pub fn texel_centre(mapping: Mapping, width: usize, height: usize, x: usize, y: usize) -> [f64; 2] {
    let s = (x as f64 + 0.5) / width as f64;
    match mapping {
        Mapping::LatLong => [s, y as f64 / (height.max(2) - 1) as f64],
        Mapping::Angular => [s, (y as f64 + 0.5) / height as f64],
        Mapping::Cube => [s, (y as f64 + 0.5) / width as f64],
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

/// Texel luminances, with the mean subtracted and clamped at 0 when
/// `compensate` is set (and the map is not nearly constant). `weights` are
/// the luminance coefficients; for angular maps only texels inside the
/// circle count toward the mean.
fn sampling_luminance(
    image: &Image,
    mapping: Mapping,
    weights: [f64; 3],
    compensate: bool,
) -> Result<Vec<f64>> {
    let luminance = |t: &[f32; 3]| (0..3).map(|k| weights[k] * f64::from(t[k])).sum::<f64>();
    let lum: Vec<f64> = parallel::install(|| image.texels().par_iter().map(luminance).collect())?;
    if !compensate {
        return Ok(lum);
    }
    let (w, h) = (image.width(), image.height());
    let (mut sum, mut count, mut min) = (0.0, 0usize, f64::INFINITY);
    for (i, &l) in lum.iter().enumerate() {
        let inside = mapping != Mapping::Angular
            || mapping.jacobian(texel_centre(mapping, w, h, i % w, i / w)) > 0.0;
        if inside {
            sum += l;
            count += 1;
            min = min.min(l);
        }
    }
    let mean = sum / count.max(1) as f64;
    if mean - min <= 0.01 * mean {
        return Ok(lum);
    }
    Ok(lum.into_iter().map(|l| (l - mean).max(0.0)).collect())
}

/// The piecewise-constant table of [`Sampling::Piecewise`] (or
/// [`Distribution::Black`] when nothing is lit) and its cells' weights,
/// row-major.
///
/// Cells and weights (luminance `Y` bilinear between texels, `J` the
/// table's Jacobian without the floor):
/// - lat-long: the `W × (H − 1)` patches between texel centres, weight
///   `Y(centre)·J(centre)`, the exact mean of `Y` times `J` at the centre;
/// - cube: half-texel cells of every face, the same weight;
/// - angular: a polar table of `2W` sectors × `W` rings around +Z, weight
///   the mean of `Y·J` over 4 × 4 points; a sector whose points all miss the
///   light but whose footprint touches a lit texel gets that texel's `Y`
///   times `J` at its centre / 16, so that lit sectors are never 0.
fn piecewise_table(image: &Image, options: &Options) -> Result<(Distribution, Buffer<f64>)> {
    let mapping = options.mapping;
    let lum = sampling_luminance(image, mapping, [0.2126, 0.7152, 0.0722], options.compensate)?;
    let (w, h) = (image.width(), image.height());
    let (cols, rows, domain) = match mapping {
        Mapping::LatLong => (w, h - 1, [[0.0, 1.0], [0.0, 1.0]]),
        Mapping::Angular => ((2 * w).max(4), w.max(2), [[0.0, 1.0], [0.0, 1.0]]),
        Mapping::Cube => (2 * w, 2 * h, [[0.0, 1.0], [0.0, 6.0]]),
    };
    let size = [
        (domain[0][1] - domain[0][0]) / cols as f64,
        (domain[1][1] - domain[1][0]) / rows as f64,
    ];
    let bilinear_lum = |p: [f64; 2]| {
        let (idx, wt) = image.corners(mapping, p);
        (0..4).map(|k| wt[k] * lum[idx[k]]).sum::<f64>()
    };
    let polar = |rho: f64| 2.0 * PI * PI * (PI * rho).sin().max(0.0);
    let fill_row = |(j, row): (usize, &mut [f64])| {
        if mapping == Mapping::LatLong {
            // A patch's mean luminance is that of its four corner texels.
            let jacobian = 0.25 * polar((j as f64 + 0.5) * size[1]);
            let (top, bottom) = (&lum[j * w..(j + 1) * w], &lum[(j + 1) * w..(j + 2) * w]);
            for (i, v) in row.iter_mut().enumerate() {
                let next = if i + 1 == w { 0 } else { i + 1 };
                *v = (top[i] + top[next] + bottom[i] + bottom[next]) * jacobian;
            }
            return;
        }
        for (i, v) in row.iter_mut().enumerate() {
            let q = [
                (i as f64 + 0.5) * size[0],
                domain[1][0] + (j as f64 + 0.5) * size[1],
            ];
            *v = match mapping {
                Mapping::Angular => angular_sector(q, size, image, &lum, &bilinear_lum),
                _ => bilinear_lum(q) * mapping.jacobian(q),
            };
        }
    };
    // Rows are independent: fill them on all cores. (A Buffer: it becomes
    // the polar table's densities, read at random, best on huge pages.)
    let mut values = Buffer::zeroed(rows * cols);
    parallel::install(|| values.par_chunks_mut(cols).enumerate().for_each(fill_row))?;
    let distribution = PiecewiseConstant2D::new(&values, rows, cols, domain)
        .map_or(Distribution::Black, Distribution::Piecewise);
    Ok((distribution, values))
}

/// The domain point of polar coordinates `(ψ, ρ)` around +Z of an angular
/// map.
fn angular_uv<F: Real>(psi: F, rho: F) -> [F; 2] {
    let (sin_psi, cos_psi) = sin_cos_turn(psi);
    let (one, half) = (F::one(), F::c(0.5));
    [(rho * cos_psi + one) * half, (one - rho * sin_psi) * half]
}

/// The weight of the angular-map sector centred at `q = (ψ, ρ)` of size
/// `size` (see [`piecewise_table`]).
fn angular_sector(
    q: [f64; 2],
    size: [f64; 2],
    image: &Image,
    lum: &[f64],
    bilinear_lum: &impl Fn([f64; 2]) -> f64,
) -> f64 {
    let k = 4;
    let polar = |rho: f64| 2.0 * PI * PI * (PI * rho).sin().max(0.0);
    let mut total = 0.0;
    for a in 0..k {
        for b in 0..k {
            let psi = q[0] + ((a as f64 + 0.5) / k as f64 - 0.5) * size[0];
            let rho = q[1] + ((b as f64 + 0.5) / k as f64 - 0.5) * size[1];
            total += bilinear_lum(angular_uv(psi, rho)) * polar(rho);
        }
    }
    if total > 0.0 {
        return total / (k * k) as f64;
    }
    // The sector's bounding box in the image: its corners, and its outer
    // arc where it crosses an axis.
    let (psi0, psi1) = (q[0] - 0.5 * size[0], q[0] + 0.5 * size[0]);
    let (rho0, rho1) = (q[1] - 0.5 * size[1], q[1] + 0.5 * size[1]);
    let mut points = vec![
        angular_uv(psi0, rho0),
        angular_uv(psi0, rho1),
        angular_uv(psi1, rho0),
        angular_uv(psi1, rho1),
    ];
    points.extend(
        [0.0, 0.25, 0.5, 0.75, 1.0]
            .into_iter()
            .filter(|&axis| axis > psi0 && axis < psi1)
            .map(|axis| angular_uv(axis, rho1)),
    );
    let n = image.width();
    let texel_range = |c: usize| {
        let lo = points.iter().map(|p| p[c]).fold(f64::INFINITY, f64::min);
        let hi = points
            .iter()
            .map(|p| p[c])
            .fold(f64::NEG_INFINITY, f64::max);
        let first = (lo * n as f64 - 0.5).floor().clamp(0.0, (n - 1) as f64) as usize;
        let last = ((hi * n as f64 - 0.5).floor() + 1.0).clamp(0.0, (n - 1) as f64) as usize;
        first..=last
    };
    let brightest = texel_range(1)
        .flat_map(|y| texel_range(0).map(move |x| y * n + x))
        .map(|i| lum[i])
        .fold(0.0, f64::max);
    brightest * polar(q[1]) / (k * k) as f64
}

/// The vertex grid of [`Sampling::Mitsuba`]: luminance (Mitsuba's weights)
/// × sin θ of the row, the first column repeated after the last.
fn mitsuba_grid(image: &Image, compensate: bool) -> Result<Distribution> {
    let lum = sampling_luminance(image, Mapping::LatLong, MITSUBA_LUMINANCE, compensate)?;
    let (w, h) = (image.width(), image.height());
    let mut values = Vec::with_capacity((w + 1) * h);
    for y in 0..h {
        let sin_theta = (y as f64 * PI / (h - 1) as f64).sin().max(0.0);
        let row = &lum[y * w..(y + 1) * w];
        values.extend(row.iter().chain(&row[..1]).map(|l| l * sin_theta));
    }
    Ok(BilinearGrid::new(values, w + 1, h).map_or(Distribution::Black, Distribution::Bilinear))
}

#[cfg(test)]
mod tests;

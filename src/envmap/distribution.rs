//! The build of an [`EnvMap`]'s sampling distribution from its image: the
//! luminance density of [`Sampling::Luminance`], the piecewise-constant
//! table of [`Sampling::Piecewise`] (with the polar lookup table of `pdf`
//! where the mapping has one), or Mitsuba's bilinear vertex grid of
//! [`Sampling::Mitsuba`].

use super::bilinear::BilinearGrid;
use super::convert::texel_centre;
use super::image::Image;
use super::luminance::LuminanceDensity;
use super::mapping::Mapping;
use super::polar::PolarTable;
use super::sample::angular_uv;
use super::{Options, Sampling};
use crate::buffer::Buffer;
use crate::distr::PiecewiseConstant2D;
use crate::error::{Error, Result};
use crate::{alloc, parallel};
use rayon::prelude::*;
use std::f64::consts::PI;

#[cfg(doc)]
use super::EnvMap;

/// The luminance weights of Mitsuba 3's `luminance()`, used in
/// [`Sampling::Mitsuba`] mode so that its density is Mitsuba's.
const MITSUBA_LUMINANCE: [f64; 3] = [0.212671, 0.715160, 0.072169];

/// Rec. 709 luminance weights, as [`crate::math::luminance`].
const REC709: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// The density an [`EnvMap`] draws directions from.
#[derive(Clone, Debug)]
pub(super) enum Distribution {
    /// The luminance of the bilinear radiance on the sphere, exactly.
    Luminance(LuminanceDensity),
    /// Piecewise-constant over the cells of the bilinear radiance.
    Piecewise(PiecewiseConstant2D),
    /// Mitsuba's bilinear density on the lat-long vertex grid.
    Bilinear(BilinearGrid),
    /// Nothing is lit (or `scale = 0`): no direction is drawn with density.
    Black,
}

/// The distribution of `options.sampling` over `image`, and the polar table
/// of a piecewise lat-long or angular map.
///
/// # Errors
/// As [`parallel::install`].
pub(super) fn build(
    image: &Image,
    options: &Options,
) -> Result<(Distribution, Option<PolarTable>)> {
    if options.scale == 0.0 {
        return Ok((Distribution::Black, None));
    }
    match options.sampling {
        Sampling::Luminance => Ok((luminance_density(image, options.compensate)?, None)),
        Sampling::Piecewise => {
            let (distribution, values) = piecewise_table(image, options)?;
            let polar = PolarTable::new(&distribution, values, image, options)?;
            Ok((distribution, polar))
        }
        Sampling::Mitsuba => Ok((mitsuba_grid(image, options.compensate)?, None)),
    }
}

/// Texel luminances, with the mean subtracted and clamped at 0 when
/// `compensate` is set (and the map is not nearly constant,
/// [`compensation_mean`]). `weights` are the luminance coefficients.
fn sampling_luminance(
    image: &Image,
    mapping: Mapping,
    weights: [f64; 3],
    compensate: bool,
) -> Result<Buffer<f64>> {
    let mut lum = luminances(image, weights)?;
    if let Some(mean) = compensate
        .then(|| compensation_mean(&lum, image, mapping))
        .flatten()
    {
        lum.iter_mut().for_each(|l| *l = (*l - mean).max(0.0));
    }
    Ok(lum)
}

/// Each texel's luminance by the coefficients `weights`.
fn luminances(image: &Image, weights: [f64; 3]) -> Result<Buffer<f64>> {
    let luminance = |t: &[f32; 3]| (0..3).map(|k| weights[k] * f64::from(t[k])).sum::<f64>();
    let mut lum = Buffer::for_overwrite(image.texels().len(), "the luminances")?;
    parallel::install(|| {
        (lum.par_iter_mut().zip(image.texels()))
            .with_min_len(parallel::CHUNK)
            .for_each(|(l, t)| *l = luminance(t));
    })?;
    Ok(lum)
}

/// The mean of the texel luminances `lum` that compensation subtracts (for
/// angular maps, of the texels inside the circle), or `None` when the map
/// is nearly constant (its minimum within 1 % of the mean) or black, and
/// compensation is switched off.
fn compensation_mean(lum: &[f64], image: &Image, mapping: Mapping) -> Option<f64> {
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
    (mean - min > 0.01 * mean).then_some(mean)
}

/// Whether `compensate` changes the density of `options` over `image`
/// (not for a black map, `scale = 0` or a nearly constant one).
///
/// # Errors
/// As [`parallel::install`].
pub(super) fn compensates(image: &Image, options: &Options) -> Result<bool> {
    if options.scale == 0.0 {
        return Ok(false);
    }
    let weights = match options.sampling {
        Sampling::Mitsuba => MITSUBA_LUMINANCE,
        Sampling::Luminance | Sampling::Piecewise => REC709,
    };
    let lum = luminances(image, weights)?;
    Ok(compensation_mean(&lum, image, options.mapping).is_some())
}

/// The density of [`Sampling::Luminance`] over a lat-long `image`.
fn luminance_density(image: &Image, compensate: bool) -> Result<Distribution> {
    let lum = sampling_luminance(image, Mapping::LatLong, REC709, compensate)?;
    let density = LuminanceDensity::new(lum, image.width(), image.height())?;
    Ok(density.map_or(Distribution::Black, Distribution::Luminance))
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
    let lum = sampling_luminance(image, mapping, REC709, options.compensate)?;
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
    let mut values = Buffer::zeroed(rows * cols, "the sampling table")?;
    parallel::install(|| values.par_chunks_mut(cols).enumerate().for_each(fill_row))?;
    let distribution = PiecewiseConstant2D::new(&values, rows, cols, domain)
        .map_or(Distribution::Black, Distribution::Piecewise);
    Ok((distribution, values))
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
    let mut values = alloc::with_capacity((w + 1) * h, "the sampling grid")?;
    for y in 0..h {
        let sin_theta = (y as f64 * PI / (h - 1) as f64).sin().max(0.0);
        let row = &lum[y * w..(y + 1) * w];
        values.extend(row.iter().chain(&row[..1]).map(|l| l * sin_theta));
    }
    match BilinearGrid::new(values, w + 1, h) {
        Ok(grid) => Ok(Distribution::Bilinear(grid)),
        Err(Error::AllZero { .. }) => Ok(Distribution::Black),
        Err(e) => Err(e),
    }
}

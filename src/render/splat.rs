//! The film of light tracing (and of bidirectional path tracing): light
//! paths land anywhere on it, so each pixel's estimate is a sum over all
//! paths of what they splat there.
//!
//! A render of `n` samples per pixel traces `N = n·P` light paths (`P`
//! the film's pixels); path `i` splats values `c` at film positions, each
//! spread over the pixels around it by the reconstruction filter as
//! Mitsuba's `ImageBlock::put` spreads it with `normalize`: weights
//! `w_x w_y` with `w_x = f(x − p_x) / Σ_i f(i − p_x)` over the pixel
//! centres `i` within the filter's radius (those off the film included, so
//! light splatted near an edge is partly lost, as in Mitsuba). Pixel `q`'s
//! value is `I_q = (1/n) Σ_i Σ c w_q = (1/N) Σ_i Y_{i,q}` with
//! `Y_{i,q} = P Σ c w_q`, the path's total at `q` scaled by `P`: the
//! paths being independent, the variance of `I_q` is `s²/N` with `s²` the
//! sample variance of the `Y_{i,q}` over all `N` paths (most of them 0).
//! The film keeps the [`Sums`] of the `Y` per pixel (each path's values at
//! a pixel added before squaring), one film per sample index (the `P`
//! paths of that index), added over the sample index in the tree of
//! [`film`] so that chunks of samples merge to the bits of one render.
//! Where paths are not alike (a camera path splats its own pixel), the
//! film keeps instead the sums of each sample index's total at a pixel, an
//! estimate of the pixel on its own ([`SplatFilm::new`]).

use rayon::prelude::*;

use super::film::{self, Block, Sums, Tree};
use super::filter::Filter;
use crate::alloc;
use crate::error::Result;
use crate::parallel;

/// A value splatted onto the film.
#[derive(Clone, Copy, Debug)]
pub struct Splat {
    /// The position on the film, in `[0, 1]²` (x right, y down).
    pub film: [f32; 2],
    /// The value `c` (RGB).
    pub value: [f32; 3],
    /// Which image it goes to (0: the render; others: images of parts of
    /// it, such as bidirectional path tracing's strategies), each of the
    /// film's size, one after the other.
    pub channel: u32,
}

/// A path's value `Y` at one pixel (the pixel's index, row-major, plus
/// `channel · P`).
pub type Entry = (u32, [f32; 3]);

/// Spreads a path's splats over pixels.
#[derive(Clone, Debug)]
pub struct Splatter {
    filter: Filter,
    size: [usize; 2],
    /// Images on the film.
    channels: u32,
    /// `P`, the film's pixels, or 1 (see [`SplatFilm::new`]).
    scale: f32,
    xs: Vec<(u32, f32)>,
    ys: Vec<(u32, f32)>,
    entries: Vec<Entry>,
}

impl Splatter {
    /// For a film of `width × height` pixels and `channels` images, and
    /// `filter`, values scaled by `scale` (`P` for a per-path variance,
    /// else 1).
    pub fn new(filter: Filter, (width, height): (usize, usize), channels: u32, scale: f32) -> Self {
        Splatter {
            filter,
            size: [width, height],
            channels,
            scale,
            xs: Vec::new(),
            ys: Vec::new(),
            entries: Vec::new(),
        }
    }

    /// Appends to `out` one path's values `Y` (see the module's text) at
    /// each pixel its `splats` reach, each pixel once, in pixel order.
    /// Splats that are not finite or name a channel the film does not have
    /// are left out.
    pub fn path(&mut self, splats: &[Splat], out: &mut Vec<Entry>) {
        self.entries.clear();
        let pixels = (self.size[0] * self.size[1]) as u32;
        let kept = splats
            .iter()
            .filter(|s| s.channel < self.channels && s.value.iter().all(|v| v.is_finite()));
        for s in kept {
            axis_weights(&self.filter, s.film[0], self.size[0], &mut self.xs);
            axis_weights(&self.filter, s.film[1], self.size[1], &mut self.ys);
            for &(y, wy) in &self.ys {
                for &(x, wx) in &self.xs {
                    let w = self.scale * wx * wy;
                    let pixel = s.channel * pixels + y * self.size[0] as u32 + x;
                    self.entries.push((pixel, s.value.map(|v| v * w)));
                }
            }
        }
        self.entries.sort_unstable_by_key(|e| e.0);
        // Only this path's entries are merged.
        let start = out.len();
        for &(pixel, v) in &self.entries {
            match out[start..].last_mut() {
                Some((last, acc)) if *last == pixel => {
                    *acc = std::array::from_fn(|k| acc[k] + v[k]);
                }
                _ => out.push((pixel, v)),
            }
        }
    }
}

/// The normalised weights along one axis of a splat at film coordinate
/// `t ∈ [0, 1]` on an axis of `n` pixels: `(pixel, w)` for the pixels on
/// the film whose centres lie within the filter's radius `r`,
/// `w = f(i + ½ − tn) / Σ f` over every centre within `r`.
fn axis_weights(filter: &Filter, t: f32, n: usize, out: &mut Vec<(u32, f32)>) {
    out.clear();
    let r = filter.radius();
    // Offsets from pixel centres: pixel i's centre is at i + ½.
    let c = f64::from(t) * n as f64 - 0.5;
    let (lo, hi) = ((c - r).ceil(), (c + r).floor());
    let mut total = 0.0;
    let mut i = lo;
    while i <= hi {
        let w = filter.eval(i - c);
        total += w;
        if i >= 0.0 && i < n as f64 && w > 0.0 {
            out.push((i as u32, w as f32));
        }
        i += 1.0;
    }
    if total > 0.0 {
        let inv = (1.0 / total) as f32;
        out.iter_mut().for_each(|(_, w)| *w *= inv);
    } else {
        out.clear();
    }
}

/// The per-pixel [`Sums`] of a splatting render, one film per block of
/// sample indices.
#[derive(Debug)]
pub struct SplatFilm {
    pixels: usize,
    per_path: bool,
    tree: Tree<Vec<Sums>>,
}

/// A finished splatting film: per pixel its mean and variances (as
/// [`film::finish_pixel`] writes them) and, when asked for, its sums per
/// block.
#[derive(Debug)]
pub struct Developed {
    /// Mean per pixel and channel.
    pub mean: Vec<f32>,
    /// Variance of each pixel's mean per channel.
    pub variance: Vec<f32>,
    /// Variance of each pixel's mean luminance.
    pub luminance_variance: Vec<f32>,
    /// The blocks of sample indices rendered.
    pub blocks: Vec<Block>,
    /// Sums per pixel and block (8 each), or empty.
    pub sums: Vec<f64>,
}

/// The paths of one sample index on a [`SplatFilm`], added entry by entry
/// in a fixed order (the same whatever the threads, so the same bits).
#[derive(Debug)]
pub enum Leaf {
    /// Per pixel, the sums of the paths' values (per-path variance).
    Sums(Vec<Sums>),
    /// Per pixel, the sample index's total (per-sample variance).
    Totals(Vec<[f64; 3]>),
}

impl Leaf {
    /// Adds `entries`.
    pub fn add(&mut self, entries: &[Entry]) {
        match self {
            Leaf::Sums(sums) => {
                for &(pixel, y) in entries {
                    let s = &mut sums[pixel as usize];
                    *s = film::add(s, &film::sums_of(y));
                }
            }
            Leaf::Totals(totals) => {
                for &(pixel, x) in entries {
                    let t = &mut totals[pixel as usize];
                    *t = std::array::from_fn(|k| t[k] + f64::from(x[k]));
                }
            }
        }
    }
}

impl SplatFilm {
    /// An empty film of `pixels` pixels (of all its channels). With
    /// `per_path`, the sums are
    /// those of each path's values `Y` (the module's text); else of each
    /// sample index's total at the pixel, `X_q = Σ_paths Σ c w_q` (whose
    /// mean over the sample indices is the pixel's estimate, and whose
    /// spread over them its variance: for an integrator whose paths
    /// differ from pixel to pixel, as bidirectional path tracing's camera
    /// paths).
    pub fn new(pixels: usize, per_path: bool) -> Self {
        SplatFilm {
            pixels,
            per_path,
            tree: Tree::new(),
        }
    }

    /// An empty leaf for the paths of one sample index.
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when it does not fit in memory.
    pub fn leaf(&self) -> Result<Leaf> {
        const WHAT: &str = "the splatting film";
        Ok(if self.per_path {
            Leaf::Sums(alloc::filled(self.pixels, Sums::default(), WHAT)?)
        } else {
            Leaf::Totals(alloc::filled(self.pixels, [0.0f64; 3], WHAT)?)
        })
    }

    /// Adds `leaf`, the paths of sample index `index`.
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the film does not fit in memory.
    pub fn push(&mut self, index: u64, leaf: Leaf) -> Result<()> {
        let sums = match leaf {
            Leaf::Sums(sums) => sums,
            Leaf::Totals(totals) => alloc::collect(
                totals.iter().map(|t| film::sums_of(t.map(|v| v as f32))),
                "the splatting film",
            )?,
        };
        self.tree.push_into(Block::sample(index), sums, |a, b| {
            a.par_iter_mut()
                .zip(b)
                .for_each(|(a, b)| *a = film::add(a, &b));
        })
    }

    /// The film's estimate, from `paths_per_sample` samples of `Y` per
    /// sample index (`P`, for `N = n·P` in the module's text; 1 for sums
    /// per sample index), with the sums per block when `keep_sums`.
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the outputs do not fit in memory; or
    /// when the thread pool cannot start.
    pub fn develop(self, paths_per_sample: u64, keep_sums: bool) -> Result<Developed> {
        let pixels = self.pixels;
        let nodes = self.tree.nodes();
        let count: u64 = nodes.iter().map(|(b, _)| b.len).sum();
        let per_pixel = if keep_sums { nodes.len() * 8 } else { 0 };
        const WHAT: &str = "the splatting film's image";
        let mut out = Developed {
            mean: alloc::filled(pixels * 3, 0.0f32, WHAT)?,
            variance: alloc::filled(pixels * 3, 0.0f32, WHAT)?,
            luminance_variance: alloc::filled(pixels, 0.0f32, WHAT)?,
            blocks: nodes.iter().map(|(b, _)| *b).collect(),
            sums: alloc::filled(pixels * per_pixel, 0.0f64, WHAT)?,
        };
        let mut sums_rows: Vec<&mut [f64]> = alloc::with_capacity(pixels, WHAT)?;
        if per_pixel > 0 {
            sums_rows.extend(out.sums.chunks_mut(per_pixel));
        } else {
            sums_rows.extend((0..pixels).map(|_| &mut [][..]));
        }
        parallel::install(|| {
            out.mean
                .par_chunks_mut(3)
                .zip(out.variance.par_chunks_mut(3))
                .zip(out.luminance_variance.par_iter_mut())
                .zip(sums_rows.into_par_iter())
                .enumerate()
                .for_each_init(Vec::new, |blocks, (p, (((mean, var), lum), sums))| {
                    blocks.clear();
                    blocks.extend(nodes.iter().map(|(_, film)| film[p]));
                    film::finish_pixel(blocks, count * paths_per_sample, (mean, var), lum, sums);
                });
        })?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_splats_land_in_one_pixel_and_gaussian_weights_sum_to_one_inside() {
        let mut w = Vec::new();
        axis_weights(&Filter::Box, 0.33, 10, &mut w);
        assert_eq!(w, [(3, 1.0)]);
        let g = Filter::gaussian(0.5).unwrap();
        axis_weights(&g, 0.5, 10, &mut w);
        let total: f32 = w.iter().map(|x| x.1).sum();
        assert!((total - 1.0).abs() < 1e-6, "{total}");
        assert!(w.len() == 4 && w.iter().all(|&(i, _)| (3..=6).contains(&i)));
        // At the edge, the weights off the film are lost.
        axis_weights(&g, 0.0, 10, &mut w);
        let total: f32 = w.iter().map(|x| x.1).sum();
        assert!((total - 0.5).abs() < 1e-6, "{total}");
    }

    #[test]
    fn a_path_adds_its_values_at_a_pixel_before_they_are_squared() {
        let mut s = Splatter::new(Filter::Box, (4, 2), 1, 8.0);
        let mut out = Vec::new();
        let at = |x: f32, y: f32, v: f32| Splat {
            film: [x, y],
            value: [v; 3],
            channel: 0,
        };
        s.path(
            &[at(0.9, 0.9, 1.0), at(0.1, 0.1, 2.0), at(0.95, 0.6, 3.0)],
            &mut out,
        );
        // P = 8: pixel 0 gets 2·8, pixel 7 gets (1 + 3)·8.
        assert_eq!(out, [(0, [16.0; 3]), (7, [32.0; 3])]);
        let mut film = SplatFilm::new(8, true);
        let mut leaf = film.leaf().unwrap();
        leaf.add(&out);
        film.push(0, leaf).unwrap();
        film.push(1, film.leaf().unwrap()).unwrap();
        let d = film.develop(8, false).unwrap();
        // 16 paths: pixel 7's mean 32/16 = 2 = (1 + 3)/2 samples.
        assert_eq!(d.mean[21], 2.0);
        // Variance of the mean: (32² − 32²/16)/15/16.
        let expected = (1024.0 - 64.0) / 15.0 / 16.0;
        assert!((d.variance[21] - expected).abs() < 1e-4);
        assert_eq!(d.blocks, [Block { start: 0, len: 2 }]);
    }
}

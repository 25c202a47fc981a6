//! The texels of an environment map and their bilinear interpolation, per
//! [`Mapping`].
//!
//! - Lat-long (as Mitsuba 3): texel column `x` is centred at
//!   `s = (x + ½)/W` and the columns are periodic in `s`; row `y` lies at
//!   `t = y/(H − 1)`, so row 0 is exactly the +Y pole and row `H − 1` the −Y
//!   pole.
//! - Angular and cube faces: texel `(x, y)` is centred at
//!   `((x + ½)/W, (y + ½)/H)` of its square, clamped to the edge texels
//!   beyond the outermost centres; an angular map is black outside its unit
//!   circle.

use super::MAX_TEXELS;
use super::cell::{cell_texels, cell_u32, gather_corner_rows};
use super::mapping::Mapping;
use crate::buffer::Buffer;
use crate::error::{Error, Result, check_at_most};
use crate::math::{Real, luminance};
use crate::simd;

/// RGB texels, row-major, row 0 at the top; a cube map stores its six
/// `R × R` faces one below the other (`height = 6R`).
#[derive(Clone, Debug)]
pub struct Image {
    width: usize,
    height: usize,
    texels: Buffer<[f32; 3]>,
}

/// The four texels around a point and their bilinear weights (all 0
/// where the map has no light), in the float type of the point.
pub type Corners<F> = ([usize; 4], [F; 4]);

/// A lat-long point's cell and bilinear weights, `[x₀, y₀, w₀, w₁, w₂, w₃]`
/// ([`Image::lat_long_place`]).
pub type LatLongPlace<F> = [F; 6];

/// What an image's shape must be, in general.
const ANY_SHAPE: &str = "(H, W, 3) with H, W >= 1";

/// The shape error of an image of `width × height` texels.
fn shape_error(width: usize, height: usize, expected: &str) -> Error {
    Error::Shape {
        arg: "image",
        expected: expected.into(),
        got: format!("({height}, {width}, 3)"),
    }
}

impl Image {
    /// An image of `width × height` RGB texels (`data` row-major, 3 floats
    /// a texel) for `mapping`, checked to be finite and `>= 0`. Lat-long
    /// maps narrower than 2 columns or shorter than 3 rows are padded by
    /// repeating the last column / row (the smallest Mitsuba accepts).
    ///
    /// # Errors
    /// [`Error::Shape`] for an empty image, a non-square angular map or
    /// cube face; [`Error::TooLarge`] above [`MAX_TEXELS`] texels;
    /// [`Error::InvalidWeight`] for a NaN, infinite or negative value, named
    /// `image[y, x, c]` (`image[face, y, x, c]` for cube maps);
    /// [`Error::Memory`] when the texels' memory cannot be had.
    pub fn new(mapping: Mapping, width: usize, height: usize, data: &[f32]) -> Result<Self> {
        let texels = Self::check_shape(mapping, width, height)?;
        if texels.checked_mul(3) != Some(data.len()) {
            return Err(shape_error(width, height, ANY_SHAPE));
        }
        // One branch-free pass for the common case (NaN fails both
        // comparisons); find the index only on failure.
        let valid = |v: f32| (0.0..=f32::MAX).contains(&v);
        let all_valid = data.iter().fold(true, |ok, &v| ok & valid(v));
        let bad = if all_valid {
            None
        } else {
            data.iter().position(|&v| !valid(v))
        };
        if let Some(i) = bad {
            let (pixel, c) = (i / 3, i % 3);
            let (y, x) = (pixel / width, pixel % width);
            let index = match mapping {
                Mapping::Cube => format!("[{}, {}, {x}, {c}]", y / width, y % width),
                _ => format!("[{y}, {x}, {c}]"),
            };
            return Err(Error::InvalidWeight {
                arg: "image",
                index,
                value: f64::from(data[i]),
            });
        }
        let texels = Buffer::from_slice(data.as_chunks::<3>().0, "the texels")?;
        Self::from_texels(mapping, width, height, texels)
    }

    /// The number of texels of a `width × height` image of `mapping`, or
    /// the error [`Image::new`] gives for that shape (not its data's).
    ///
    /// # Errors
    /// [`Error::Shape`] for an empty image, a non-square angular map or
    /// cube face; [`Error::TooLarge`] above [`MAX_TEXELS`] texels.
    pub(super) fn check_shape(mapping: Mapping, width: usize, height: usize) -> Result<usize> {
        let Some(texels) = width.checked_mul(height).filter(|&n| n > 0) else {
            return Err(shape_error(width, height, ANY_SHAPE));
        };
        match mapping {
            Mapping::Angular if width != height => {
                return Err(shape_error(width, height, "(R, R, 3): square"));
            }
            Mapping::Cube if width.checked_mul(6) != Some(height) => {
                return Err(Error::Shape {
                    arg: "image",
                    expected: "(6, R, R, 3)".into(),
                    got: format!("({}, {width}, {width}, 3)", height as f64 / width as f64),
                });
            }
            _ => {}
        }
        check_at_most("image", texels, MAX_TEXELS)?;
        Ok(texels)
    }

    /// The image of `texels` (row-major, finite and `>= 0`, of a shape that
    /// [`Image::check_shape`] passed), padded as [`Image::new`] pads.
    ///
    /// # Errors
    /// [`Error::Shape`] when there are not `width × height` texels;
    /// [`Error::Memory`] when a padded copy's memory cannot be had.
    pub(super) fn from_texels(
        mapping: Mapping,
        width: usize,
        height: usize,
        texels: Buffer<[f32; 3]>,
    ) -> Result<Self> {
        debug_assert!(Self::check_shape(mapping, width, height).is_ok());
        debug_assert!(
            texels
                .iter()
                .flatten()
                .all(|&v| (0.0..=f32::MAX).contains(&v))
        );
        if width.checked_mul(height) != Some(texels.len()) {
            return Err(shape_error(width, height, ANY_SHAPE));
        }
        if mapping != Mapping::LatLong || (width >= 2 && height >= 3) {
            return Ok(Image {
                width,
                height,
                texels,
            });
        }
        // A lat-long map narrower than 2 texels or shorter than 3: a
        // one-column map's column doubled, the last row repeated.
        let (padded_width, padded_height) = (width.max(2), height.max(3));
        let mut padded = Buffer::for_overwrite(padded_width * padded_height, "the texels")?;
        for (k, t) in padded.iter_mut().enumerate() {
            let (y, x) = (k / padded_width, k % padded_width);
            *t = texels[y.min(height - 1) * width + x.min(width - 1)];
        }
        Ok(Image {
            width: padded_width,
            height: padded_height,
            texels: padded,
        })
    }

    /// Columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows (`6R` for a cube map).
    pub fn height(&self) -> usize {
        self.height
    }

    /// All texels, row-major.
    pub fn texels(&self) -> &[[f32; 3]] {
        &self.texels
    }

    /// Texel `i` (row-major index) as `f64`.
    #[inline(always)]
    pub fn texel(&self, i: usize) -> [f64; 3] {
        self.texels[i].map(f64::from)
    }

    /// Luminance of texel `i`.
    #[inline(always)]
    pub fn texel_luminance(&self, i: usize) -> f64 {
        luminance(self.texel(i))
    }

    /// The texels around `p` (in the mapping's domain, lat-long `s` in
    /// `[0, 1]`) and their weights (see the module docs), computed in `F`.
    #[inline(always)]
    pub fn corners<F: Real>(&self, mapping: Mapping, p: [F; 2]) -> Corners<F> {
        let w = self.width;
        let (zero, one) = (F::zero(), F::one());
        match mapping {
            Mapping::LatLong => self.placed_corners(&self.lat_long_place(p)),
            Mapping::Angular | Mapping::Cube => {
                let face_rows = w;
                let (face, t) = match mapping {
                    Mapping::Cube => {
                        let face = p[1].floor_index(5);
                        (face, p[1] - F::c(face as f64))
                    }
                    _ => (0, p[1]),
                };
                let (xs, fx) = clamped_axis(p[0], w);
                let (ys, fy) = clamped_axis(t, face_rows);
                let mut c = quad(xs, ys.map(|y| y + face * face_rows), w, fx, fy);
                if mapping == Mapping::Angular {
                    let two = F::c(2.0);
                    let (a, b) = (two * p[0] - one, one - two * p[1]);
                    if a * a + b * b > one {
                        c.1 = [zero; 4];
                    }
                }
                c
            }
        }
    }

    /// Where the lat-long point `p` (`s` in `[0, 1]`) falls among the
    /// texel centres, as a [`LatLongPlace`]: with `x = ((s − ½/W) mod 1) W`
    /// and `y = clamp(t, 0, 1) (H − 1)`, the cell `x₀ = ⌊x⌋`, `y₀ = ⌊y⌋`
    /// (clamped to `W − 1` and `H − 2` where they are read:
    /// [`Image::place_texel`]) and the fractions `f_x = clamp(x − x₀, 0, 1)`,
    /// `f_y = y − y₀` give the weights `(1 − f_x)(1 − f_y)`, `f_x (1 − f_y)`,
    /// `(1 − f_x) f_y`, `f_x f_y` of the texels `(x₀, y₀)`, `(x₀ + 1, y₀)`
    /// (wrapped), `(x₀, y₀ + 1)`, `(x₀ + 1, y₀ + 1)`. Branch-free and
    /// without indices, so that a batch computes it at SIMD width.
    #[inline(always)]
    pub(crate) fn lat_long_place<F: Real>(&self, p: [F; 2]) -> LatLongPlace<F> {
        let (w, h) = (self.width, self.height);
        let (zero, one) = (F::zero(), F::one());
        // `p[0]` in [0, 1]: one wrap below 0.
        let x = p[0] - F::c(0.5 / w as f64);
        let x = (x + if x < zero { one } else { zero }) * F::c(w as f64);
        let y = p[1].max(zero).min(one) * F::c((h - 1) as f64);
        // (The cell is kept unclamped, so that `floor_u32` clamps it in
        // integers ([`cell_u32`]): in `f32` the last column of a map wider
        // than 2²⁴ has no float of its own. A NaN `x` has the weights of
        // cell 0 there.)
        let (x0, y0) = (x.floor(), y.floor());
        let fx = (x - x0.min(F::c((w - 1) as f64))).max(zero).min(one);
        let fy = y - y0.min(F::c((h - 2) as f64));
        let [w00, w10, w01, w11] = bilinear_weights(fx, fy);
        [x0, y0, w00, w10, w01, w11]
    }

    /// The texels and weights of a lat-long place ([`Image::lat_long_place`]).
    #[inline(always)]
    pub(crate) fn placed_corners<F: Real>(&self, place: &LatLongPlace<F>) -> Corners<F> {
        let (w, k) = (self.width as u32, self.place_texel_u32(place[0], place[1]));
        let texels = cell_texels(k, place[0].floor_u32(w - 1), w);
        (
            texels.map(|t| t as usize),
            [place[2], place[3], place[4], place[5]],
        )
    }

    /// The top-left texel of the cell `(x₀, y₀)` of a lat-long place (which
    /// is also the cell's index).
    #[inline(always)]
    pub(crate) fn place_texel<F: Real>(&self, x0: F, y0: F) -> usize {
        self.place_texel_u32(x0, y0) as usize
    }

    /// [`Image::place_texel`] of each of a block's places (their columns
    /// `x₀` and `y₀`) into `cells`, in a loop that vectorises.
    #[inline(always)]
    pub(crate) fn place_texels<F: Real>(
        &self,
        x0: &[F; simd::BLOCK],
        y0: &[F; simd::BLOCK],
        cells: &mut [u32; simd::BLOCK],
    ) {
        for ((c, &x), &y) in cells.iter_mut().zip(x0).zip(y0) {
            *c = self.place_texel_u32(x, y);
        }
    }

    /// [`Image::place_texel`] in `u32` arithmetic, which holds every texel
    /// index (at most [`MAX_TEXELS`], three times that padded).
    #[inline(always)]
    fn place_texel_u32<F: Real>(&self, x0: F, y0: F) -> u32 {
        const { assert!(3 * MAX_TEXELS <= u32::MAX as usize) };
        let w = self.width as u32;
        let [col, row] = cell_u32(x0, y0, w, self.height as u32 - 1);
        row * w + col
    }

    /// Asks the CPU for the texels of cell `k` (its top-left texel) of a
    /// lat-long place: texels `k`, `k + 1` and the two below (the right
    /// neighbour wrapped at the seam is left to the read).
    #[inline(always)]
    pub(crate) fn prefetch_cell(&self, k: usize) {
        self.prefetch(&[k, k + 1, k + self.width, k + self.width + 1]);
    }

    /// [`Image::blend`] of the corners of each of a block's lat-long places
    /// (the columns `q` of [`Image::lat_long_place`]s; `cells` must be
    /// their top-left texels, as [`Image::place_texels`] of the same `q`
    /// puts them), one column per RGB channel: the four texels of each
    /// found at SIMD width (as [`Image::placed_corners`] finds them), read
    /// by gathers and blended at SIMD width, in the same order as `blend`
    /// (the same bits). On cache-line boundaries, as its loops use it.
    #[inline(always)]
    pub(crate) fn blend_places<F: Real>(
        &self,
        q: &[[F; simd::BLOCK]; 6],
        cells: &[u32; simd::BLOCK],
    ) -> simd::OnLines<[[F; simd::BLOCK]; 3]> {
        let w = self.width as u32;
        let simd::OnLines(texels) = &mut simd::OnLines([[0; simd::BLOCK]; 4]);
        for (i, &k) in cells.iter().enumerate() {
            let col = q[0][i].floor_u32(w - 1);
            debug_assert_eq!(k % w, col, "a cell that is not its place's");
            for (column, t) in texels.iter_mut().zip(cell_texels(k, col, w)) {
                column[i] = t;
            }
        }
        let weights = [&q[2], &q[3], &q[4], &q[5]];
        self.blend_texels(texels, weights)
    }

    /// The texels `texels[j][i]` blended by `weights[j][i]` over the four
    /// corners `j` of each of a block's places `i`, one column per RGB
    /// channel: read by [`gather_corner_rows`] and blended at SIMD width,
    /// in the same order as [`Image::blend`] (the same bits).
    #[inline(always)]
    pub(crate) fn blend_texels<F: Real>(
        &self,
        texels: &[[u32; simd::BLOCK]; 4],
        weights: [&[F; simd::BLOCK]; 4],
    ) -> simd::OnLines<[[F; simd::BLOCK]; 3]> {
        let simd::OnLines(rows) = &gather_corner_rows::<3, 6>(self.texels.as_flattened(), texels);
        let mut blended = simd::OnLines([[F::zero(); simd::BLOCK]; 3]);
        for (j, w) in weights.into_iter().enumerate() {
            let corner = &rows[j / 2][3 * (j % 2)..];
            for (rgb, t) in blended.0.iter_mut().zip(corner) {
                for i in 0..simd::BLOCK {
                    rgb[i] = rgb[i] + w[i] * F::c(f64::from(t[i]));
                }
            }
        }
        blended
    }

    /// The texels of a lat-long map's table cell `(row, col)` (the patch
    /// between texel centres `row, row + 1` and `col, col + 1`, wrapped) and
    /// their weights at fractions `r` of the cell: the corners of the point
    /// there, without locating it again.
    #[inline(always)]
    pub fn cell_corners<F: Real>(&self, (row, col): (usize, usize), r: [F; 2]) -> Corners<F> {
        let next = if col + 1 == self.width { 0 } else { col + 1 };
        quad([col, next], [row, row + 1], self.width, r[0], r[1])
    }

    /// Prefetches the texels at `indices`.
    #[inline(always)]
    pub fn prefetch(&self, indices: &[usize; 4]) {
        for &i in indices {
            simd::prefetch(&self.texels, i);
        }
    }

    /// The bilinearly interpolated RGB value at `p`, computed in `F`.
    #[inline]
    pub fn lookup<F: Real>(&self, mapping: Mapping, p: [F; 2]) -> [F; 3] {
        self.blend(&self.corners(mapping, p))
    }

    /// The texels of `corners` blended by their weights, in `F`.
    #[inline(always)]
    pub fn blend<F: Real>(&self, (idx, wt): &Corners<F>) -> [F; 3] {
        let mut rgb = [F::zero(); 3];
        for (&i, &w) in idx.iter().zip(wt) {
            let t = self.texels[i];
            for k in 0..3 {
                rgb[k] = rgb[k] + w * F::c(f64::from(t[k]));
            }
        }
        rgb
    }
}

/// Texel indices `[x0, x1]` and the fraction toward `x1` along an axis of
/// `n` texels centred at `(x + ½)/n`, clamped at both ends.
#[inline(always)]
fn clamped_axis<F: Real>(s: F, n: usize) -> ([usize; 2], F) {
    let x = (s * F::c(n as f64) - F::c(0.5))
        .max(F::zero())
        .min(F::c((n - 1) as f64));
    let x0 = x.floor_index(n.saturating_sub(2));
    let x1 = (x0 + 1).min(n - 1);
    ([x0, x1], x - F::c(x0 as f64))
}

#[inline(always)]
fn quad<F: Real>(xs: [usize; 2], ys: [usize; 2], width: usize, fx: F, fy: F) -> Corners<F> {
    (
        [
            ys[0] * width + xs[0],
            ys[0] * width + xs[1],
            ys[1] * width + xs[0],
            ys[1] * width + xs[1],
        ],
        bilinear_weights(fx, fy),
    )
}

/// The weights of the texels `(x₀, y₀)`, `(x₁, y₀)`, `(x₀, y₁)`, `(x₁, y₁)`
/// at fractions `(f_x, f_y)` of the way from `(x₀, y₀)` to `(x₁, y₁)`.
#[inline(always)]
pub(super) fn bilinear_weights<F: Real>(fx: F, fy: F) -> [F; 4] {
    let one = F::one();
    [
        (one - fx) * (one - fy),
        fx * (one - fy),
        (one - fx) * fy,
        fx * fy,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(w: usize, h: usize) -> Vec<f32> {
        (0..w * h).flat_map(|i| [i as f32, 0.0, 0.0]).collect()
    }

    #[test]
    fn lookups_at_texel_centres_poles_edges_and_the_angular_circle() {
        // Lat-long 4 × 3: texel centres and pole rows, periodic in s (s = 0
        // is half way between the last column and the first). Angular 2 × 2:
        // clamped edges, 0 outside the circle.
        let cases = [
            (Mapping::LatLong, (4, 3), [0.125, 0.0], 0.0),
            (Mapping::LatLong, (4, 3), [0.375, 0.5], 5.0),
            (Mapping::LatLong, (4, 3), [0.875, 1.0], 11.0),
            (Mapping::LatLong, (4, 3), [0.0, 0.0], 1.5),
            (Mapping::Angular, (2, 2), [0.25, 0.25], 0.0),
            (Mapping::Angular, (2, 2), [0.5, 0.5], 1.5),
            (Mapping::Angular, (2, 2), [0.0, 0.0], 0.0),
            (Mapping::Angular, (2, 2), [0.99, 0.99], 0.0),
            (Mapping::Angular, (2, 2), [0.8, 0.5], 2.0),
        ];
        for (mapping, (w, h), p, value) in cases {
            let img = Image::new(mapping, w, h, &ramp(w, h)).unwrap();
            assert_eq!(img.lookup(mapping, p)[0], value, "{mapping:?} at {p:?}");
        }
    }

    #[test]
    fn a_latlong_cell_has_the_corners_of_its_points() {
        // The table cell (row, col) spans texel centres row..row + 1 and
        // col..col + 1 (wrapped); its point at fractions r lies at domain
        // s = (col + ½ + r0)/W, t = (row + r1)/(H − 1).
        let (w, h) = (5, 4);
        let img = Image::new(Mapping::LatLong, w, h, &ramp(w, h)).unwrap();
        for (row, col) in [(0, 0), (1, 3), (2, 4)] {
            for r in [[0.0, 0.0], [0.3, 0.8], [0.999, 0.5]] {
                let s = (col as f64 + 0.5 + r[0]) / w as f64;
                let p = [s - s.floor(), (row as f64 + r[1]) / (h - 1) as f64];
                let (a, b) = (
                    img.blend(&img.cell_corners((row, col), r)),
                    img.lookup(Mapping::LatLong, p),
                );
                assert!(
                    (a[0] - b[0]).abs() < 1e-12,
                    "cell ({row}, {col}), r = {r:?}: {a:?} against {b:?}"
                );
            }
        }
    }

    /// The lat-long arm of `corners` before the cell and weights were
    /// found branch-free (b8c2b78), kept to show the same bits.
    fn former_lat_long_corners<F: Real>(img: &Image, p: [F; 2]) -> Corners<F> {
        let (w, h) = (img.width, img.height);
        let (zero, one) = (F::zero(), F::one());
        let x = p[0] - F::c(0.5 / w as f64);
        let x = (x + if x < zero { one } else { zero }) * F::c(w as f64);
        let y = p[1].max(zero).min(one) * F::c((h - 1) as f64);
        let (x0, y0) = (x.floor_index(w - 1), y.floor_index(h - 2));
        let fx = (x - F::c(x0 as f64)).max(zero).min(one);
        let fy = y - F::c(y0 as f64);
        let x1 = if x0 + 1 == w { 0 } else { x0 + 1 };
        quad([x0, x1], [y0, y0 + 1], w, fx, fy)
    }

    /// Lat-long maps under 2 × 3 texels: each texel of a one-column map
    /// doubled, then the last row repeated up to 3 rows (the former
    /// padding, written out); other maps and mappings kept as they are.
    #[test]
    fn tiny_lat_long_maps_are_padded_as_before() {
        for (w, h) in [(1, 1), (1, 2), (1, 5), (2, 1), (3, 2), (2, 3), (4, 4)] {
            let data: Vec<f32> = (0..3 * w * h).map(|i| i as f32).collect();
            let mut former: Vec<[f32; 3]> = data.as_chunks::<3>().0.to_vec();
            let mut width = w;
            if w < 2 {
                former = former.iter().flat_map(|&t| [t, t]).collect();
                width = 2;
            }
            for _ in h..3 {
                former.extend_from_within((h - 1) * width..h * width);
            }
            let image = Image::new(Mapping::LatLong, w, h, &data).unwrap();
            assert_eq!(
                (image.width(), image.height()),
                (width, h.max(3)),
                "{w} × {h}"
            );
            assert_eq!(image.texels(), &former[..], "{w} × {h}");
        }
        let cube = Image::new(Mapping::Cube, 1, 6, &[0.5; 18]).unwrap();
        assert_eq!((cube.width(), cube.height()), (1, 6));
        assert_eq!(cube.texels(), &[[0.5; 3]; 6][..]);
        let angular = Image::new(Mapping::Angular, 1, 1, &[1.0, 2.0, 3.0]).unwrap();
        assert_eq!((angular.width(), angular.height()), (1, 1));
        assert_eq!(angular.texels(), &[[1.0, 2.0, 3.0]][..]);
    }

    /// Sizes whose product overflows are a shape error, not a wrap.
    #[test]
    fn overflowing_sizes_are_shape_errors() {
        let huge = Image::new(Mapping::LatLong, 1 << 62, 8, &[]);
        assert!(matches!(huge, Err(Error::Shape { .. })), "{huge:?}");
        let cube = Image::new(Mapping::Cube, usize::MAX / 3, 1, &[]);
        assert!(matches!(cube, Err(Error::Shape { .. })), "{cube:?}");
    }

    #[test]
    fn lat_long_places_give_the_former_corners() {
        // Random points, the seam, the poles, points off the domain and
        // NaN, on a padded 1 × 1 map and a 32 × 17 one, in f32 and f64.
        fn check<F: Real>(img: &Image, p: [F; 2]) {
            let (new, old) = (
                img.corners(Mapping::LatLong, p),
                former_lat_long_corners(img, p),
            );
            assert_eq!(new.0, old.0, "{p:?}");
            let bits = |c: Corners<F>| c.1.map(|v| v.f64().to_bits());
            assert_eq!(bits(new), bits(old), "{p:?}");
        }
        let mut rng = crate::rng::Rng::new(5, 2);
        for (w, h) in [(1, 1), (32, 17)] {
            let img = Image::new(Mapping::LatLong, w, h, &ramp(w, h)).unwrap();
            let half = 0.5 / img.width() as f64;
            let special = [
                0.0,
                -0.0,
                1.0,
                half,
                half - 1e-12,
                half + 1e-12,
                1.0 - half,
                -0.5,
                1.5,
                f64::NAN,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ];
            let mut points: Vec<[f64; 2]> = (0..2000)
                .map(|_| [rng.next_float(), rng.next_float()])
                .collect();
            for &s in &special {
                points.extend(special.iter().map(|&t| [s, t]));
            }
            for p in points {
                check(&img, p);
                check(&img, p.map(|v| v as f32));
                let (s32, next) = (p[0] as f32, f32::from_bits((p[0] as f32).to_bits() + 1));
                check(&img, [next, p[1] as f32]);
                check(&img, [s32, p[1] as f32]);
            }
        }
    }

    #[test]
    fn tiny_latlong_maps_are_padded_and_bad_texels_named() {
        let img = Image::new(Mapping::LatLong, 1, 1, &[1.0, 2.0, 3.0]).unwrap();
        assert_eq!((img.width(), img.height()), (2, 3));
        assert_eq!(img.lookup(Mapping::LatLong, [0.7, 0.9]), [1.0, 2.0, 3.0]);
        let mut data = ramp(2, 12);
        data[3 * 9 + 1] = f32::NAN;
        let e = Image::new(Mapping::Cube, 2, 12, &data).unwrap_err();
        assert_eq!(
            e.to_string(),
            "image[2, 0, 1, 1] = NaN: image must be finite and >= 0"
        );
        assert!(Image::new(Mapping::Angular, 3, 2, &ramp(3, 2)).is_err());
    }
}

//! Resampling an [`EnvMap`] into another mapping or resolution, and where
//! each texel of an image sits in its mapping's domain.

use super::image::Image;
use super::mapping::Mapping;
use super::{EnvMap, Options, Sampling};
use crate::buffer::Buffer;
use crate::error::Result;
use crate::parallel;
use rayon::prelude::*;

impl EnvMap {
    /// The same light resampled into `mapping` at `width × height` texels
    /// (cube maps: `height = 6·width`): every new texel takes the bilinear
    /// value of this map in its direction. `to_world`, `scale` and
    /// `compensate` are kept; the sampling mode too where the new mapping
    /// has it (else [`Sampling::default_for`] the new mapping).
    ///
    /// The shape is checked and the new texels' memory had before any is
    /// computed; rows are resampled on all cores, straight into the new
    /// map's texels.
    ///
    /// # Errors
    /// As [`EnvMap::new`] for the new shape; [`crate::Error::ThreadPool`]
    /// when the thread pool cannot start.
    pub fn convert(&self, mapping: Mapping, width: usize, height: usize) -> Result<EnvMap> {
        let n = Image::check_shape(mapping, width, height)?;
        let mut texels = Buffer::for_overwrite(n, "the resampled texels")?;
        let resample_row = |(y, row): (usize, &mut [[f32; 3]])| {
            for (x, texel) in row.iter_mut().enumerate() {
                let p = texel_centre(mapping, width, height, x, y);
                let lit = mapping.jacobian(p) > 0.0 || mapping != Mapping::Angular;
                let rgb = if lit {
                    let d = mapping.to_dir(p);
                    self.image
                        .lookup(self.options.mapping, self.options.mapping.from_dir(d))
                } else {
                    [0.0; 3]
                };
                *texel = rgb.map(|v| v as f32);
            }
        };
        parallel::install(|| {
            texels
                .par_chunks_mut(width)
                .enumerate()
                .for_each(resample_row)
        })?;
        let sampling = if self.options.sampling.supports(mapping) {
            self.options.sampling
        } else {
            Sampling::default_for(mapping)
        };
        EnvMap::from_image(
            Image::from_texels(mapping, width, height, texels)?,
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

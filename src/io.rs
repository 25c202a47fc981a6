//! Image files: OpenEXR (read RGB / RGBA with half or float channels, write
//! float or half, ZIP-compressed), Radiance `.hdr` (RGBE, read; signature
//! `#?RADIANCE` or `#?RGBE`) and PNG (write, tone-mapped with an exposure
//! and the sRGB transfer curve).
//!
//! Pixels are linear RGB(A) `f32`, row-major `(height, width, channels)`,
//! row 0 at the top. Every failure is an [`Error::Io`] naming the path.

use crate::alloc;
use crate::error::{Error, Result};
use std::path::Path;

/// Pixels an image read from a file may have: `2^28` (1 GiB a channel of
/// float32), checked on the file's header before anything is decoded.
pub const MAX_PIXELS: usize = 1 << 28;

/// Checks a file's image size, read from its header, before decoding:
/// at most [`MAX_PIXELS`] pixels, and memory for `channels` floats a
/// pixel there to be had.
fn check_size(path: &Path, width: usize, height: usize, channels: usize) -> Result<()> {
    let pixels = width.saturating_mul(height);
    if pixels > MAX_PIXELS {
        return Err(Error::Argument {
            arg: "path",
            message: format!(
                "{}: the image is {width} x {height} = {pixels} pixels; at most 2**28 = {MAX_PIXELS} are supported",
                path.display()
            ),
        });
    }
    alloc::probe::<f32>(pixels * channels, "the image")
}

/// A linear image: `height × width × channels` floats, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    /// Number of columns.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// 3 (RGB) or 4 (RGBA).
    pub channels: usize,
    /// Row-major samples, `channels` per pixel.
    pub data: Vec<f32>,
}

fn io_error(path: &Path, message: impl std::fmt::Display) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

impl Raster {
    fn check(&self, path: &Path) -> Result<()> {
        let expected = self.width * self.height * self.channels;
        if !(3..=4).contains(&self.channels) || self.data.len() != expected {
            return Err(io_error(
                path,
                format!(
                    "image must be height x width x 3 or 4, got {} samples for {}x{}x{}",
                    self.data.len(),
                    self.height,
                    self.width,
                    self.channels
                ),
            ));
        }
        if self.width == 0 || self.height == 0 {
            return Err(io_error(path, "image is empty"));
        }
        Ok(())
    }
}

/// Reads the first RGB layer of an OpenEXR file (half, float or uint
/// channels, converted to `f32`); the result has 4 channels when the file
/// has an `A` channel, else 3.
///
/// # Errors
/// [`Error::Io`] if the file cannot be opened, is not OpenEXR, is truncated,
/// or has no R, G and B channels; [`Error::Argument`] for an image of more
/// than [`MAX_PIXELS`]; [`Error::Memory`].
pub fn read_exr(path: &Path) -> Result<Raster> {
    use exr::prelude::*;
    let cannot = |e: exr::error::Error| io_error(path, format!("cannot read OpenEXR: {e}"));
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(cannot)?;
    for header in &meta.headers {
        check_size(
            path,
            header.layer_size.width(),
            header.layer_size.height(),
            4,
        )?;
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required("R")
        .required("G")
        .required("B")
        .optional("A", 1.0f32)
        .collect_pixels(
            |size: Vec2<usize>, (_, _, _, alpha)| {
                let channels = if alpha.is_some() { 4 } else { 3 };
                Raster {
                    width: size.width(),
                    height: size.height(),
                    channels,
                    data: vec![0.0; size.area() * channels],
                }
            },
            |raster: &mut Raster, pos: Vec2<usize>, (r, g, b, a): (f32, f32, f32, f32)| {
                let start = (pos.y() * raster.width + pos.x()) * raster.channels;
                let px = [r, g, b, a];
                raster.data[start..start + raster.channels].copy_from_slice(&px[..raster.channels]);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(cannot)?;
    Ok(image.layer_data.channel_data.pixels)
}

/// Writes an RGB or RGBA OpenEXR file with `f32` channels, or `f16` when
/// `half` is true (values beyond ±65504 become ±inf).
///
/// # Errors
/// [`Error::Io`] if the raster's size is inconsistent or the file cannot be
/// written.
pub fn write_exr(path: &Path, image: &Raster, half: bool) -> Result<()> {
    use exr::prelude::*;
    image.check(path)?;
    let channels = ["R", "G", "B", "A"][..image.channels]
        .iter()
        .enumerate()
        .map(|(c, &name)| {
            let values = image.data.iter().skip(c).step_by(image.channels).copied();
            let samples = if half {
                FlatSamples::F16(values.map(f16::from_f32).collect())
            } else {
                FlatSamples::F32(values.collect())
            };
            AnyChannel::new(name, samples)
        })
        .collect();
    // ZIP in blocks of 16 scanlines: lossless, and it shrinks float data
    // (RLE, the exr crate's default, barely does).
    let size = (image.width, image.height);
    let result =
        Image::from_encoded_channels(size, Encoding::SMALL_LOSSLESS, AnyChannels::sort(channels))
            .write()
            .to_file(path);
    result.map_err(|e| io_error(path, format!("cannot write OpenEXR: {e}")))
}

/// Reads a Radiance RGBE (`.hdr`) file as 3-channel linear RGB.
///
/// # Errors
/// [`Error::Io`] if the file cannot be opened, is not Radiance HDR or is
/// truncated; [`Error::Argument`] for an image of more than
/// [`MAX_PIXELS`]; [`Error::Memory`].
pub fn read_hdr(path: &Path) -> Result<Raster> {
    use image::ImageDecoder;
    use std::io::{BufRead, Read};
    let cannot = |e: image::ImageError| io_error(path, format!("cannot read Radiance HDR: {e}"));
    let file = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let mut file = std::io::BufReader::new(file);
    // The signature line: `#?RADIANCE`, or `#?RGBE` as Mitsuba and other
    // tools write it (the same format), which the decoder does not know.
    let mut signature = Vec::new();
    (&mut file)
        .take(64)
        .read_until(b'\n', &mut signature)
        .map_err(|e| io_error(path, e))?;
    if signature == b"#?RGBE\n" {
        signature = b"#?RADIANCE\n".to_vec();
    }
    let source = std::io::BufReader::new(std::io::Cursor::new(signature).chain(file));
    let decoder = image::codecs::hdr::HdrDecoder::new(source).map_err(cannot)?;
    let (width, height) = decoder.dimensions();
    check_size(path, width as usize, height as usize, 3)?;
    let decoded = image::DynamicImage::from_decoder(decoder).map_err(cannot)?;
    let rgb = decoded.into_rgb32f();
    Ok(Raster {
        width: rgb.width() as usize,
        height: rgb.height() as usize,
        channels: 3,
        data: rgb.into_raw(),
    })
}

/// The sRGB transfer curve (IEC 61966-2-1) of a linear value in `[0, 1]`.
pub fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// A linear value scaled by `2^exposure`, clamped to `[0, 1]`, sRGB-encoded
/// when `srgb` is true, and quantised to 8 bits. Infinities clamp; NaN is
/// rejected by [`write_png`] before this is called.
pub fn tonemap(linear: f32, exposure: f32, srgb: bool) -> u8 {
    let v = (linear * exposure.exp2()).clamp(0.0, 1.0);
    let v = if srgb { srgb_encode(v) } else { v };
    (v * 255.0 + 0.5) as u8
}

/// Writes an 8-bit PNG of an RGB(A) raster, tone-mapped by [`tonemap`]
/// (alpha is written linearly, unscaled).
///
/// # Errors
/// [`Error::Element`] naming the first NaN sample; [`Error::Io`] if the file
/// cannot be written.
pub fn write_png(path: &Path, image: &Raster, exposure: f32, srgb: bool) -> Result<()> {
    let bytes = encode_png(path, image, exposure, srgb)?;
    std::fs::write(path, bytes).map_err(|e| io_error(path, format!("cannot write PNG: {e}")))
}

/// The PNG file [`write_png`] writes, in memory (`name` only names the
/// image in error messages).
///
/// # Errors
/// [`Error::Element`] naming the first NaN sample; [`Error::Io`] for a
/// raster of the wrong size.
pub fn encode_png(name: &Path, image: &Raster, exposure: f32, srgb: bool) -> Result<Vec<u8>> {
    image.check(name)?;
    if let Some(i) = image.data.iter().position(|v| v.is_nan()) {
        let c = image.channels;
        let (pixel, ch) = (i / c, i % c);
        return Err(Error::Element {
            arg: "image",
            index: format!("[{}, {}, {}]", pixel / image.width, pixel % image.width, ch),
            value: f64::NAN,
            requirement: "a PNG cannot show NaN".into(),
        });
    }
    let tonemapped = image.data.iter().enumerate().map(|(i, &v)| {
        if image.channels == 4 && i % 4 == 3 {
            tonemap(v, 0.0, false)
        } else {
            tonemap(v, exposure, srgb)
        }
    });
    let bytes = alloc::collect(tonemapped, "the PNG's bytes")?;
    let color = if image.channels == 4 {
        image::ExtendedColorType::Rgba8
    } else {
        image::ExtendedColorType::Rgb8
    };
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &bytes,
        image.width as u32,
        image.height as u32,
        color,
    )
    .map_err(|e| io_error(name, format!("cannot encode PNG: {e}")))?;
    Ok(png)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient(channels: usize) -> Raster {
        let (width, height) = (7, 5);
        let data = (0..width * height * channels)
            .map(|i| i as f32 * 0.37 - 3.0)
            .collect();
        Raster {
            width,
            height,
            channels,
            data,
        }
    }

    #[test]
    fn exr_round_trips_rgb_and_rgba_float_and_half() {
        let dir = tempfile::tempdir().unwrap();
        for channels in [3, 4] {
            for half in [false, true] {
                let path = dir.path().join(format!("t{channels}{half}.exr"));
                let image = gradient(channels);
                write_exr(&path, &image, half).unwrap();
                let back = read_exr(&path).unwrap();
                assert_eq!((back.width, back.height, back.channels), (7, 5, channels));
                let tol = if half { 1e-2 } else { 0.0 };
                for (a, b) in image.data.iter().zip(&back.data) {
                    assert!((a - b).abs() <= tol * a.abs().max(1.0), "{a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn truncated_and_missing_files_name_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.exr");
        write_exr(&path, &gradient(3), false).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let err = read_exr(&path).unwrap_err().to_string();
        assert!(err.contains("t.exr"), "{err}");
        let err = read_hdr(&dir.path().join("nope.hdr"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("nope.hdr"), "{err}");
    }

    #[test]
    fn tonemap_curve() {
        assert_eq!(tonemap(0.0, 0.0, true), 0);
        assert_eq!(tonemap(1.0, 0.0, true), 255);
        assert_eq!(tonemap(f32::INFINITY, 0.0, true), 255);
        assert_eq!(tonemap(0.25, 1.0, false), 128);
        assert!((srgb_encode(0.214_041) - 0.5).abs() < 1e-5); // sRGB mid grey
    }

    #[test]
    fn png_rejects_nan_and_writes_rgb() {
        let dir = tempfile::tempdir().unwrap();
        let mut image = gradient(3);
        write_png(&dir.path().join("ok.png"), &image, 0.0, true).unwrap();
        image.data[3 * 7 + 4] = f32::NAN;
        let err = write_png(&dir.path().join("bad.png"), &image, 0.0, true).unwrap_err();
        assert_eq!(
            err.to_string(),
            "image[1, 1, 1] = NaN: a PNG cannot show NaN"
        );
    }
}

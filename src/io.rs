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

/// Reads an OpenEXR file (scanline or tiled, one part or several, half,
/// float or uint channels converted to `f32`, every compression the exr
/// crate decodes; the largest mip level). Channels are grouped by layer:
/// the text before the last `.` of `part.channel` (`diffuse.R` is channel
/// `R` of layer `diffuse`; channels without a dot, in unnamed parts, form
/// the unnamed layer `""`). The image is `layer`'s, or else the unnamed
/// layer's, or else the only layer with colour. A layer's colour is `R`,
/// `G`, `B` (or `r`, `g`, `b`), else luminance `Y` repeated in R, G, B;
/// with `A` (or `a`) the result has 4 channels, else 3.
///
/// # Errors
/// [`Error::Io`] if the file cannot be opened, is not OpenEXR, is truncated,
/// uses a compression the exr crate cannot decode, or has no layer with
/// colour; [`Error::Argument`] naming `layer` when it is not in the file,
/// or when the file has several coloured layers and `layer` is `None`;
/// [`Error::Argument`] for an image of more than [`MAX_PIXELS`];
/// [`Error::Memory`].
pub fn read_exr(path: &Path, layer: Option<&str>) -> Result<Raster> {
    use exr::prelude::*;
    let cannot = |e: exr::error::Error| io_error(path, format!("cannot read OpenEXR: {e}"));
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(cannot)?;
    for header in &meta.headers {
        let size = header.layer_size;
        check_size(path, size.width(), size.height(), 1)?;
    }
    // Every channel of every part is read: memory for all of them.
    let floats = meta
        .headers
        .iter()
        .map(|h| h.layer_size.area() * h.channels.list.len());
    alloc::probe::<f32>(floats.sum(), "the image's channels")?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(cannot)?;
    // Every channel as (layer, name, samples, size), in the file's order.
    let mut channels = Vec::new();
    for part in &image.layer_data {
        let part_name = part.attributes.layer_name.as_ref().map(|t| t.to_string());
        for channel in &part.channel_data.list {
            let full = match &part_name {
                Some(p) => format!("{p}.{}", channel.name),
                None => channel.name.to_string(),
            };
            let (group, name) = full.rsplit_once('.').unwrap_or(("", &full));
            channels.push((
                group.to_string(),
                name.to_string(),
                &channel.sample_data,
                part.size,
            ));
        }
    }
    let mut layers: Vec<&str> = Vec::new();
    for (group, ..) in &channels {
        if !layers.contains(&group.as_str()) {
            layers.push(group);
        }
    }
    let find = |group: &str, names: &[&str]| {
        names.iter().find_map(|n| {
            channels
                .iter()
                .find(|(g, c, ..)| g == group && c == n)
                .map(|(_, _, samples, size)| (*samples, *size))
        })
    };
    let colour = |group: &str| {
        let rgb = [["R", "r"], ["G", "g"], ["B", "b"]].map(|names| find(group, &names));
        match rgb {
            [Some(r), Some(g), Some(b)] => Some(vec![r, g, b]),
            _ => find(group, &["Y", "y"]).map(|y| vec![y, y, y]),
        }
    };
    let named = |list: &[&str]| {
        list.iter()
            .map(|l| format!("'{l}'"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let coloured: Vec<&str> = layers
        .iter()
        .copied()
        .filter(|l| colour(l).is_some())
        .collect();
    let chosen = match layer {
        Some(l) if layers.contains(&l) => l,
        Some(l) => {
            return Err(crate::error::Error::Argument {
                arg: "layer",
                message: format!(
                    "layer = '{l}': {} has the layers {} ('' is the channels without a layer name)",
                    path.display(),
                    named(&layers)
                ),
            });
        }
        None if coloured.contains(&"") => "",
        None if coloured.len() == 1 => coloured[0],
        None if coloured.is_empty() => "",
        None => {
            return Err(crate::error::Error::Argument {
                arg: "layer",
                message: format!(
                    "{} has several layers with colour, {}: choose one with layer=",
                    path.display(),
                    named(&coloured)
                ),
            });
        }
    };
    let Some(mut planes) = colour(chosen) else {
        let names: Vec<String> = channels
            .iter()
            .map(|(g, c, ..)| {
                if g.is_empty() {
                    c.clone()
                } else {
                    format!("{g}.{c}")
                }
            })
            .collect();
        return Err(io_error(
            path,
            format!(
                "layer '{chosen}' has no R, G and B (or Y) channels; the file has: {}",
                names.join(", ")
            ),
        ));
    };
    planes.extend(find(chosen, &["A", "a"]));
    let size = planes[0].1;
    if planes.iter().any(|(_, s)| *s != size) {
        return Err(io_error(
            path,
            format!("layer '{chosen}': its channels differ in size"),
        ));
    }
    let (width, height, count) = (size.width(), size.height(), planes.len());
    let mut data = alloc::filled(width * height * count, 0.0f32, "the image")?;
    if planes
        .iter()
        .any(|(samples, _)| samples.len() != width * height)
    {
        return Err(io_error(
            path,
            format!("layer '{chosen}': subsampled channels (x/y sampling above 1) are not read"),
        ));
    }
    for (c, (samples, _)) in planes.iter().enumerate() {
        for (out, value) in data
            .iter_mut()
            .skip(c)
            .step_by(count)
            .zip(samples.values_as_f32())
        {
            *out = value;
        }
    }
    Ok(Raster {
        width,
        height,
        channels: count,
        data,
    })
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

/// Reads an 8- or 16-bit PNG as linear RGB (its sRGB values decoded, as
/// Mitsuba's `Bitmap` decodes them for rendering), 4 channels with alpha.
///
/// # Errors
/// [`Error::Io`] if the file cannot be opened or is not a PNG;
/// [`Error::Argument`] for an image of more than [`MAX_PIXELS`];
/// [`Error::Memory`].
pub fn read_png(path: &Path) -> Result<Raster> {
    use image::ImageDecoder;
    let cannot = |e: image::ImageError| io_error(path, format!("cannot read PNG: {e}"));
    let file = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let decoder =
        image::codecs::png::PngDecoder::new(std::io::BufReader::new(file)).map_err(cannot)?;
    let (width, height) = decoder.dimensions();
    let alpha = decoder.color_type().has_alpha();
    let channels = if alpha { 4 } else { 3 };
    check_size(path, width as usize, height as usize, channels)?;
    let decoded = image::DynamicImage::from_decoder(decoder).map_err(cannot)?;
    let mut data = if alpha {
        decoded.into_rgba32f().into_raw()
    } else {
        decoded.into_rgb32f().into_raw()
    };
    for (i, v) in data.iter_mut().enumerate() {
        if !(alpha && i % 4 == 3) {
            *v = srgb_decode(*v);
        }
    }
    Ok(Raster {
        width: width as usize,
        height: height as usize,
        channels,
        data,
    })
}

/// Reads an image file of any kind mcsample reads, told by its first bytes:
/// OpenEXR ([`read_exr`], with `layer`), Radiance HDR ([`read_hdr`]) or PNG
/// ([`read_png`]).
///
/// # Errors
/// Those of the reader; [`Error::Io`] for a file of another kind, and
/// [`Error::Argument`] naming `layer` when it is given for a file without
/// layers.
pub fn read_image(path: &Path, layer: Option<&str>) -> Result<Raster> {
    use std::io::Read;
    let mut magic = [0u8; 4];
    let mut file = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let got = file.read(&mut magic).map_err(|e| io_error(path, e))?;
    let exr = magic == [0x76, 0x2f, 0x31, 0x01];
    if layer.is_some() && !exr {
        return Err(Error::Argument {
            arg: "layer",
            message: format!(
                "layer: {} is not an OpenEXR file, it has no layers",
                path.display()
            ),
        });
    }
    match &magic[..got] {
        _ if exr => read_exr(path, layer),
        [b'#', b'?', ..] => read_hdr(path),
        [0x89, b'P', b'N', b'G'] => read_png(path),
        _ => Err(io_error(
            path,
            "not an OpenEXR, Radiance HDR or PNG file (by its first bytes)",
        )),
    }
}

/// The linear value of an sRGB-encoded one in `[0, 1]` (IEC 61966-2-1).
pub fn srgb_decode(encoded: f32) -> f32 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
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
                let back = read_exr(&path, None).unwrap();
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
        let err = read_exr(&path, None).unwrap_err().to_string();
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

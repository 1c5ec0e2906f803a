//! Reading images for comparison (docs/design.md §5 "Inputs", §7): EXR (linear float; channels `R`,
//! `G`, `B`, or `LAYER.R/G/B`) and PNG (8 or 16 bit, sRGB-decoded to linear; grey PNGs are
//! replicated into R, G, B; alpha is ignored). Every error names the file.

use super::RgbImage;
use crate::color::srgb_to_linear_f32;
use crate::error::{PgtError, Result};
use std::path::Path;

/// An image as read, with the number of colour channels the file had (1 for a grey PNG, 3
/// otherwise), so that a comparison can refuse pairs whose channel counts differ.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadImage {
    pub image: RgbImage,
    pub channels: usize,
}

/// Reads an image as linear RGB: EXR channels `R`, `G`, `B` (of the unnamed layer) or a PNG
/// (8 or 16 bit, sRGB-decoded).
pub fn read_image(path: &Path) -> Result<RgbImage> {
    read_image_layer(path, None).map(|r| r.image)
}

/// Reads an image; for EXR, `layer` selects the channels `LAYER.R/G/B` (`None` or `""`: the
/// unnamed `R`, `G`, `B`). A layer given for a PNG is an error.
pub fn read_image_layer(path: &Path, layer: Option<&str>) -> Result<ReadImage> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("exr") => {
            read_exr_layer(path, layer.unwrap_or("")).map(|image| ReadImage { image, channels: 3 })
        }
        Some("png") => {
            if layer.is_some_and(|l| !l.is_empty()) {
                return Err(PgtError::in_file(
                    path,
                    "a PNG has no layers; --layer applies to EXR files only",
                ));
            }
            read_png(path)
        }
        _ => Err(PgtError::in_file(path, "expected an .exr or .png image")),
    }
}

/// A file that cannot be opened (missing, a folder, no permission) is an I/O error naming it,
/// not a malformed image.
fn check_readable(path: &Path) -> Result<()> {
    std::fs::File::open(path)
        .map(drop)
        .map_err(|e| PgtError::io(path, e))
}

fn read_png(path: &Path) -> Result<ReadImage> {
    check_readable(path)?;
    let img =
        image::open(path).map_err(|e| PgtError::in_file(path, format!("cannot read PNG: {e}")))?;
    let (width, height) = (img.width(), img.height());
    let channels = if img.color().has_color() { 3 } else { 1 };
    let pixels = match img.color().bytes_per_pixel() / img.color().channel_count().max(1) {
        1 => decode_through_table(img.into_rgb8().pixels().map(|p| p.0.map(usize::from)), 8),
        2 => decode_through_table(img.into_rgb16().pixels().map(|p| p.0.map(usize::from)), 16),
        _ => img
            .to_rgb32f()
            .pixels()
            .map(|p| p.0.map(srgb_to_linear_f32))
            .collect(),
    };
    Ok(ReadImage {
        image: RgbImage {
            width,
            height,
            pixels,
        },
        channels,
    })
}

/// Linear values of 8- or 16-bit sRGB samples through a table of every code: the value of each
/// code is the one the general path computes (the image crate's conversion to f32, then
/// [`srgb_to_linear_f32`]), found by running that path on an image of all codes, so the pixels
/// are bit-identical to it; but one decode per code instead of one `powf` per sample (a 4K PNG
/// has 25 million).
fn decode_through_table(samples: impl Iterator<Item = [usize; 3]>, bits: u32) -> Vec<[f32; 3]> {
    let codes = 1u32 << bits;
    let all = if bits == 8 {
        image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(codes, 1, |x, _| {
            image::Rgb([x as u8; 3])
        }))
    } else {
        image::DynamicImage::ImageRgb16(image::ImageBuffer::from_fn(codes, 1, |x, _| {
            image::Rgb([x as u16; 3])
        }))
    };
    let table: Vec<f32> = all
        .to_rgb32f()
        .pixels()
        .map(|p| srgb_to_linear_f32(p.0[0]))
        .collect();
    samples.map(|p| p.map(|c| table[c])).collect()
}

/// Reads the `R`, `G`, `B` channels of an EXR, prefixed by `layer.` unless `layer` is empty.
/// The channels may be in any part of a multi-part file; a missing channel is an error that
/// lists the channels the file has.
pub fn read_exr_layer(path: &Path, layer: &str) -> Result<RgbImage> {
    use exr::prelude::*;
    check_readable(path)?;
    let img = read_all_flat_layers_from_file(path)
        .map_err(|e| PgtError::in_file(path, format!("cannot read EXR: {e}")))?;
    if img.layer_data.is_empty() {
        return Err(PgtError::in_file(path, "EXR has no layers"));
    }
    let name = |c: &str| {
        if layer.is_empty() {
            c.to_string()
        } else {
            format!("{layer}.{c}")
        }
    };
    let wanted: Vec<String> = ["R", "G", "B"].iter().map(|c| name(c)).collect();
    let part = img.layer_data.iter().find(|l| {
        wanted.iter().all(|w| {
            l.channel_data
                .list
                .iter()
                .any(|ch| ch.name.to_string() == *w)
        })
    });
    let Some(part) = part else {
        let available: Vec<String> = img
            .layer_data
            .iter()
            .flat_map(|l| l.channel_data.list.iter().map(|ch| ch.name.to_string()))
            .collect();
        let what = if layer.is_empty() {
            "channels R, G, B".to_string()
        } else {
            format!("layer '{layer}' (channels {})", wanted.join(", "))
        };
        return Err(PgtError::in_file(
            path,
            format!("EXR has no {what}; it has: {}", available.join(", ")),
        ));
    };
    let (w, h) = (part.size.0, part.size.1);
    let mut planes = Vec::new();
    for want in &wanted {
        let ch = part
            .channel_data
            .list
            .iter()
            .find(|ch| ch.name.to_string() == *want)
            .ok_or_else(|| PgtError::in_file(path, format!("EXR has no channel '{want}'")))?;
        let plane: Vec<f32> = ch.sample_data.values_as_f32().collect();
        if plane.len() != w * h {
            return Err(PgtError::in_file(
                path,
                format!("EXR channel '{want}' has {} samples for {w}x{h} pixels (subsampled channels are not supported)", plane.len()),
            ));
        }
        planes.push(plane);
    }
    let pixels = (0..w * h)
        .map(|i| [planes[0][i], planes[1][i], planes[2][i]])
        .collect();
    Ok(RgbImage {
        width: w as u32,
        height: h as u32,
        pixels,
    })
}

/// The reference's per-pixel error estimate (docs/design.md §3, §7): the `err` layer of a
/// reference EXR, when the whole image is compared (no layer chosen) and the file has one;
/// `None` for a PNG, a scene, or an EXR without it.
pub fn read_reference_estimate(reference: &Path, layer: Option<&str>) -> Option<RgbImage> {
    let is_exr = reference
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr || layer.is_some_and(|l| !l.is_empty()) {
        return None;
    }
    read_exr_layer(reference, "err").ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table decode equals the general path (f32 conversion, then one sRGB decode per
    /// sample) bit for bit, for every 8-bit code and a spread of 16-bit ones.
    #[test]
    fn table_decode_equals_the_general_path() {
        let general = |img: image::DynamicImage| -> Vec<[f32; 3]> {
            img.to_rgb32f()
                .pixels()
                .map(|p| p.0.map(srgb_to_linear_f32))
                .collect()
        };
        let img8 = image::RgbImage::from_fn(256, 2, |x, y| {
            image::Rgb([x as u8, (x as u8).wrapping_mul(7), y as u8])
        });
        let got = decode_through_table(img8.pixels().map(|p| p.0.map(usize::from)), 8);
        assert_eq!(got, general(image::DynamicImage::ImageRgb8(img8)));
        let img16 = image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::from_fn(4096, 1, |x, _| {
            image::Rgb([(x * 16) as u16, (x * 16 + 15) as u16, 65535 - x as u16])
        });
        let got = decode_through_table(img16.pixels().map(|p| p.0.map(usize::from)), 16);
        assert_eq!(got, general(image::DynamicImage::ImageRgb16(img16)));
    }
}

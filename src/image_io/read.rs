//! Reading images for comparison (DESIGN.md §5 "Inputs", §7): EXR (linear float; channels `R`,
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

fn read_png(path: &Path) -> Result<ReadImage> {
    let img =
        image::open(path).map_err(|e| PgtError::in_file(path, format!("cannot read PNG: {e}")))?;
    let (width, height) = (img.width(), img.height());
    let channels = if img.color().has_color() { 3 } else { 1 };
    let rgb = img.to_rgb32f();
    let pixels = rgb.pixels().map(|p| p.0.map(srgb_to_linear_f32)).collect();
    Ok(ReadImage {
        image: RgbImage {
            width,
            height,
            pixels,
        },
        channels,
    })
}

/// Reads the `R`, `G`, `B` channels of an EXR, prefixed by `layer.` unless `layer` is empty.
/// The channels may be in any part of a multi-part file; a missing channel is an error that
/// lists the channels the file has.
pub fn read_exr_layer(path: &Path, layer: &str) -> Result<RgbImage> {
    use exr::prelude::*;
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

use super::RgbImage;
use crate::error::{PgtError, Result};
use std::path::Path;

/// sRGB decoding (IEC 61966-2-1) of a value in [0, 1].
fn srgb_to_linear(s: f32) -> f32 {
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads an image as linear RGB: EXR channels `R`, `G`, `B` (of the unnamed layer) or a PNG
/// (8 or 16 bit, sRGB-decoded).
pub fn read_image(path: &Path) -> Result<RgbImage> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("exr") => read_exr_layer(path, ""),
        Some("png") => read_png(path),
        _ => Err(PgtError::in_file(path, "expected an .exr or .png image")),
    }
}

fn read_png(path: &Path) -> Result<RgbImage> {
    let img =
        image::open(path).map_err(|e| PgtError::in_file(path, format!("cannot read PNG: {e}")))?;
    let (width, height) = (img.width(), img.height());
    let rgb = img.to_rgb32f();
    let pixels = rgb.pixels().map(|p| p.0.map(srgb_to_linear)).collect();
    Ok(RgbImage {
        width,
        height,
        pixels,
    })
}

/// Reads the `R`, `G`, `B` channels of an EXR, prefixed by `layer.` unless `layer` is empty.
pub fn read_exr_layer(path: &Path, layer: &str) -> Result<RgbImage> {
    use exr::prelude::*;
    let img = read_all_flat_layers_from_file(path)
        .map_err(|e| PgtError::in_file(path, format!("cannot read EXR: {e}")))?;
    let l = img
        .layer_data
        .first()
        .ok_or_else(|| PgtError::in_file(path, "EXR has no layers"))?;
    let (w, h) = (l.size.0, l.size.1);
    let name = |c: &str| {
        if layer.is_empty() {
            c.to_string()
        } else {
            format!("{layer}.{c}")
        }
    };
    let mut planes = Vec::new();
    for c in ["R", "G", "B"] {
        let want = name(c);
        let ch = l
            .channel_data
            .list
            .iter()
            .find(|ch| ch.name.to_string() == want)
            .ok_or_else(|| PgtError::in_file(path, format!("EXR has no channel '{want}'")))?;
        planes.push(ch.sample_data.values_as_f32().collect::<Vec<f32>>());
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

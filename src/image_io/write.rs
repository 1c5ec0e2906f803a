use super::RgbImage;
use crate::error::{PgtError, Result};
use std::io::{BufWriter, Write};
use std::path::Path;

/// Output format, from the extension of `-o`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    Exr,
    Png,
}

impl ImageFormat {
    /// The format named by a path's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<ImageFormat> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("exr") => Ok(ImageFormat::Exr),
            Some("png") => Ok(ImageFormat::Png),
            _ => Err(PgtError::Usage(format!(
                "{}: output must end in .exr or .png",
                path.display()
            ))),
        }
    }
}

/// sRGB encoding (IEC 61966-2-1) of a linear value scaled by 2^exposure, clamped to [0, 1],
/// rounded to 8 bits.
pub fn linear_to_srgb8(v: f32, exposure_scale: f32) -> u8 {
    let v = (v * exposure_scale).clamp(0.0, 1.0);
    let v = if v.is_nan() { 0.0 } else { v };
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// Writes `image` (and, for EXR, the extra layers, each written as `NAME.R/G/B`) to `path`,
/// atomically. PNG ignores the extra layers and applies `exposure` in stops.
pub fn write_image(
    path: &Path,
    image: &RgbImage,
    layers: &[(&str, &RgbImage)],
    exposure: f32,
) -> Result<()> {
    let format = ImageFormat::from_path(path)?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let tmp = tempfile::Builder::new()
        .prefix(".pgt-partial-")
        .tempfile_in(dir)
        .map_err(|e| PgtError::io(dir, e))?;
    match format {
        ImageFormat::Png => {
            write_png(tmp.as_file(), image, exposure).map_err(|e| PgtError::io(path, e))?
        }
        ImageFormat::Exr => {
            write_exr(tmp.as_file(), image, layers).map_err(|e| PgtError::io(path, e))?
        }
    }
    tmp.as_file()
        .sync_all()
        .map_err(|e| PgtError::io(path, e))?;
    tmp.persist(path).map_err(|e| PgtError::io(path, e.error))?;
    Ok(())
}

fn write_png(file: &std::fs::File, image: &RgbImage, exposure: f32) -> std::io::Result<()> {
    let scale = 2f32.powf(exposure);
    let bytes: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|p| p.map(|v| linear_to_srgb8(v, scale)))
        .collect();
    let mut w = BufWriter::new(file);
    image::codecs::png::PngEncoder::new(&mut w)
        .write_image(
            &bytes,
            image.width,
            image.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(std::io::Error::other)?;
    w.flush()
}

use image::ImageEncoder;

fn write_exr(
    file: &std::fs::File,
    image: &RgbImage,
    layers: &[(&str, &RgbImage)],
) -> std::io::Result<()> {
    use exr::prelude::*;
    let size = (image.width as usize, image.height as usize);
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    let mut add = |prefix: &str, img: &RgbImage| {
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            let full = if prefix.is_empty() {
                name.to_string()
            } else {
                format!("{prefix}.{name}")
            };
            let samples: Vec<f32> = img.pixels.iter().map(|p| p[c]).collect();
            channels.push(AnyChannel::new(full.as_str(), FlatSamples::F32(samples)));
        }
    };
    add("", image);
    for (name, layer) in layers {
        add(name, layer);
    }
    let channels = AnyChannels::sort(channels.into_iter().collect());
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        channels,
    );
    let img = Image::from_layer(layer);
    let mut w = BufWriter::new(file);
    img.write()
        .to_buffered(&mut w)
        .map_err(std::io::Error::other)?;
    w.flush()
}

//! Heatmap PNGs (docs/design.md §5): a map of values through a colour map, one image pixel per map
//! pixel. The colour bar and its scale are SVG with real text beside the map in the page
//! (`colorbar.rs`), not pixels drawn into the PNG.

use super::colormap::{ColorMap, Scale};
use crate::error::Result;
use std::path::Path;

/// An 8-bit sRGB image, ready for PNG.
#[derive(Debug, Clone, PartialEq)]
pub struct Srgb8Image {
    pub width: u32,
    pub height: u32,
    /// Row-major RGB triples.
    pub data: Vec<u8>,
}

impl Srgb8Image {
    /// The pixel at (x, y).
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Writes the image as an 8-bit PNG, atomically (a temporary file renamed at the end).
    pub fn write_png(&self, path: &Path) -> Result<()> {
        use image::ImageEncoder;
        crate::image_io::write_atomically(path, |w| {
            image::codecs::png::PngEncoder::new(w)
                .write_image(
                    &self.data,
                    self.width,
                    self.height,
                    image::ExtendedColorType::Rgb8,
                )
                .map_err(std::io::Error::other)
        })
    }
}

/// A heatmap of `values` (row-major, `width`×`height`) on `scale` with `cmap`: one pixel per
/// pixel of the map, so that the report's viewer can lay it over the reference and the
/// approximation pixel for pixel. Its colour bar is SVG with real text
/// ([`super::colorbar::colorbar_svg`]), beside it in the page.
pub fn heatmap(
    values: &[f32],
    width: u32,
    height: u32,
    scale: Scale,
    cmap: ColorMap,
) -> Srgb8Image {
    let mut out = Srgb8Image {
        width,
        height,
        data: Vec::with_capacity(3 * width as usize * height as usize),
    };
    for &v in values.iter().take(width as usize * height as usize) {
        out.data
            .extend_from_slice(&cmap.at(scale.position(v as f64)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heatmap_is_the_map_pixel_for_pixel() {
        let values: Vec<f32> = (0..64 * 48)
            .map(|i| (i % 64) as f32 / 63.0 * 0.02)
            .collect();
        let img = heatmap(
            &values,
            64,
            48,
            Scale { lo: 0.0, hi: 0.01 },
            ColorMap::Magma,
        );
        assert_eq!(
            (img.width, img.height, img.data.len()),
            (64, 48, 64 * 48 * 3)
        );
        // Left column is the low end, values beyond the scale clamp to the top colour, the
        // middle of the scale is the middle of the map.
        assert_eq!(img.get(0, 10), ColorMap::Magma.at(0.0));
        assert_eq!(img.get(63, 10), ColorMap::Magma.at(1.0));
        let mid = (0..64).find(|&x| values[x] >= 0.005).unwrap() as u32;
        assert_eq!(
            img.get(mid, 47),
            ColorMap::Magma.at(values[mid as usize] as f64 / 0.01)
        );
    }
}

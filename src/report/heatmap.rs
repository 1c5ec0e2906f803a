//! Heatmap PNGs with their colour bar and scale drawn into the image (DESIGN.md §5), so that a
//! heatmap read on its own still says what its colours mean: the map on the left, a vertical
//! colour bar on the right labelled with the scale's top, middle and bottom values (a built-in
//! 3×5 pixel font; no font files needed).

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
    fn filled(width: u32, height: u32, color: [u8; 3]) -> Self {
        Srgb8Image {
            width,
            height,
            data: color.repeat(width as usize * height as usize),
        }
    }

    fn set(&mut self, x: u32, y: u32, color: [u8; 3]) {
        if x < self.width && y < self.height {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            self.data[i..i + 3].copy_from_slice(&color);
        }
    }

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

/// Background of the colour-bar panel.
const PANEL: [u8; 3] = [255, 255, 255];
/// Colour of the labels and the bar's frame.
const INK: [u8; 3] = [0, 0, 0];

/// A heatmap of `values` (row-major, `width`×`height`) on `scale` with `cmap`, and its colour bar
/// with labels to the right.
pub fn heatmap(
    values: &[f32],
    width: u32,
    height: u32,
    scale: Scale,
    cmap: ColorMap,
) -> Srgb8Image {
    // Font and bar grow with the image so that the labels stay readable.
    let s = (height / 96).clamp(1, 8);
    let labels = [scale.hi, 0.5 * (scale.lo + scale.hi), scale.lo].map(format_label);
    let label_chars = labels
        .iter()
        .map(|l| l.chars().count() as u32)
        .max()
        .unwrap_or(1);
    let gap = 4 * s;
    let bar_w = 10 * s;
    let glyph_w = 4 * s;
    let margin_y = 3 * s; // room for half a label above the top and below the bottom of the bar
    let panel_w = gap + bar_w + gap + label_chars * glyph_w + gap;
    let total_h = height.max(5 * s * 3 + 2 * margin_y);
    let mut out = Srgb8Image::filled(width + panel_w, total_h, PANEL);
    for y in 0..height {
        for x in 0..width {
            let v = values[y as usize * width as usize + x as usize] as f64;
            out.set(x, y, cmap.at(scale.position(v)));
        }
    }
    // The bar: top = hi, bottom = lo, spanning the rows margin_y .. total_h − margin_y.
    let bar_x = width + gap;
    let (top, bottom) = (margin_y, total_h - margin_y);
    let span = (bottom - top).max(2) - 1;
    for y in top..bottom {
        let t = 1.0 - (y - top) as f64 / span as f64;
        for x in bar_x..bar_x + bar_w {
            out.set(x, y, cmap.at(t));
        }
    }
    for x in bar_x.saturating_sub(1)..=bar_x + bar_w {
        out.set(x, top.saturating_sub(1), INK);
        out.set(x, bottom, INK);
    }
    for y in top.saturating_sub(1)..=bottom {
        out.set(bar_x.saturating_sub(1), y, INK);
        out.set(bar_x + bar_w, y, INK);
    }
    let text_x = bar_x + bar_w + gap;
    let glyph_h = 5 * s;
    let middle = top + span / 2;
    let show_middle = bottom - top >= 3 * glyph_h + 4 * s;
    for (i, label) in labels.iter().enumerate() {
        let centre = [top, middle, bottom][i];
        if i == 1 && !show_middle {
            continue;
        }
        // Tick mark, then the label centred on it (kept inside the image).
        for x in bar_x + bar_w..bar_x + bar_w + gap / 2 + 1 {
            out.set(x, centre, INK);
        }
        let y0 = centre
            .saturating_sub(glyph_h / 2)
            .min(total_h.saturating_sub(glyph_h));
        draw_text(&mut out, text_x, y0, s, label);
    }
    out
}

/// A scale value as the bar shows it: fixed-point where that is short, exponent form otherwise.
pub fn format_label(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if (0.01..1000.0).contains(&a) {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.2e}")
    }
}

/// Rows of a 3×5 glyph, top first, bit 2 = leftmost column.
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b001, 0b001, 0b001],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        '.' => [0b000, 0b000, 0b000, 0b000, 0b010],
        '-' => [0b000, 0b000, 0b111, 0b000, 0b000],
        '+' => [0b000, 0b010, 0b111, 0b010, 0b000],
        'e' => [0b000, 0b111, 0b111, 0b100, 0b111],
        _ => [0b000; 5],
    }
}

fn draw_text(img: &mut Srgb8Image, x0: u32, y0: u32, s: u32, text: &str) {
    for (k, c) in text.chars().enumerate() {
        let rows = glyph(c);
        let gx = x0 + k as u32 * 4 * s;
        for (row, bits) in rows.iter().enumerate() {
            for col in 0..3u32 {
                if bits & (0b100 >> col) != 0 {
                    for dy in 0..s {
                        for dx in 0..s {
                            img.set(gx + col * s + dx, y0 + row as u32 * s + dy, INK);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels() {
        assert_eq!(format_label(0.0), "0");
        assert_eq!(format_label(0.5), "0.5");
        assert_eq!(format_label(0.0125), "0.013");
        assert_eq!(format_label(1e-4), "1.00e-4");
        assert_eq!(format_label(1.0), "1");
    }

    #[test]
    fn heatmap_has_map_bar_and_scale() {
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
        assert!(img.width > 64 + 20);
        assert_eq!(img.height, 48);
        // Left column is the low end, values beyond the scale clamp to the top colour.
        assert_eq!(img.get(0, 10), ColorMap::Magma.at(0.0));
        assert_eq!(img.get(63, 10), ColorMap::Magma.at(1.0));
        // The bar runs from the top colour at its top to the bottom colour at its bottom.
        let bar_x = 64 + 4 + 5;
        assert_eq!(img.get(bar_x, 3), ColorMap::Magma.at(1.0));
        assert_eq!(img.get(bar_x, 44), ColorMap::Magma.at(0.0));
        // Some label ink exists to the right of the bar.
        let ink = (64 + 18..img.width).any(|x| (0..48).any(|y| img.get(x, y) == INK));
        assert!(ink);
    }
}

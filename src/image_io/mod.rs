//! Images in memory and on disk (docs/design.md §7): EXR (linear float32 `R`, `G`, `B`, plus extra
//! layers such as the reference's `err.R/G/B`) and PNG (8-bit sRGB of the linear image).
//! Every write is atomic: a temporary file in the target folder, renamed at the end.

mod folder;
mod pair;
mod read;
mod write;

pub use folder::write_folder_atomically;
pub use pair::{is_scene, load_pair, RenderScene};
pub use read::{read_exr_layer, read_image, read_image_layer, read_reference_estimate, ReadImage};
pub use write::{
    linear_to_srgb8, write_atomically, write_exr_with_header, write_image, ImageFormat,
};

/// Channel names in the order pgt stores them.
pub const CHANNELS: [&str; 3] = ["R", "G", "B"];

/// The first non-finite value of an image, as (x, y, channel).
pub fn first_non_finite(image: &RgbImage) -> Option<(u32, u32, usize)> {
    let w = image.width.max(1) as usize;
    image.pixels.iter().enumerate().find_map(|(i, p)| {
        p.iter()
            .position(|v| !v.is_finite())
            .map(|c| ((i % w) as u32, (i / w) as u32, c))
    })
}

/// A linear RGB image, row-major, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        RgbImage {
            width,
            height,
            pixels: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    /// The pixel at (x, y).
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Whether every value is finite.
    pub fn all_finite(&self) -> bool {
        self.pixels.iter().all(|p| p.iter().all(|v| v.is_finite()))
    }
}

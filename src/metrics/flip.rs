//! FLIP, NVIDIA's perceptual difference metric (Andersson et al. 2020), LDR variant only, through
//! the `nv-flip` bindings to the reference C++ implementation.
//!
//! LDR-FLIP compares two sRGB images in [0, 1]. pgt's images are linear, so each is encoded to
//! 8-bit sRGB first (the same encoding as pgt's PNG output). Images with values above 1 are HDR,
//! for which FLIP needs its HDR variant (exposure bracketing and tone mapping); that is not
//! implemented, and [`flip_ldr`] refuses them rather than clamp silently.
//!
//! Checked against `flip-evaluator` (pip, `evaluate(ref, test, "LDR")`) on committed vectors in
//! tests/compare_flip.rs.

use crate::image_io::{linear_to_srgb8, RgbImage};

/// FLIP's default viewing condition: 0.7 m from a 0.7 m wide 3840-pixel monitor, about 67
/// pixels per degree.
pub const DEFAULT_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// The FLIP error of an image pair.
#[derive(Debug, Clone)]
pub struct Flip {
    /// Mean of the map (the number FLIP reports).
    pub mean: f64,
    /// Per-pixel FLIP error in [0, 1], row-major.
    pub map: Vec<f32>,
    pub pixels_per_degree: f32,
}

/// Why FLIP was not computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlipError {
    #[error("FLIP: inputs have values above 1 (largest {0}); HDR-FLIP is not implemented, LDR-FLIP would need clamping")]
    Hdr(f32),
    #[error("FLIP: images differ in size")]
    SizeMismatch,
    #[error("FLIP: image too large for the nv-flip bindings (3·width·height must fit in 32 bits)")]
    TooLarge,
}

/// LDR-FLIP of two linear images whose values lie in [0, 1] (negative values are clamped to 0 by
/// the sRGB encoding).
pub fn flip_ldr(
    reference: &RgbImage,
    approximation: &RgbImage,
    pixels_per_degree: f32,
) -> Result<Flip, FlipError> {
    if reference.width != approximation.width || reference.height != approximation.height {
        return Err(FlipError::SizeMismatch);
    }
    // nv-flip computes width·height·3 in u32.
    if (reference.width as u64) * (reference.height as u64) * 3 > u32::MAX as u64 {
        return Err(FlipError::TooLarge);
    }
    let largest = reference
        .pixels
        .iter()
        .chain(&approximation.pixels)
        .flatten()
        .fold(0.0f32, |m, &v| m.max(v));
    if largest > 1.0 {
        return Err(FlipError::Hdr(largest));
    }
    let encode = |img: &RgbImage| -> Vec<u8> {
        img.pixels
            .iter()
            .flat_map(|p| p.map(|v| linear_to_srgb8(v, 1.0)))
            .collect()
    };
    let (w, h) = (reference.width, reference.height);
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &encode(reference));
    let a = nv_flip::FlipImageRgb8::with_data(w, h, &encode(approximation));
    let map = nv_flip::flip(r, a, pixels_per_degree).to_vec();
    let mean = map.iter().map(|&v| v as f64).sum::<f64>() / map.len().max(1) as f64;
    Ok(Flip {
        mean,
        map,
        pixels_per_degree,
    })
}

//! Per-pixel maps of docs/design.md §5: absolute error, relative error, SSIM (and FLIP, from
//! [`super::flip`]), as linear RGB images (one value per channel) that are written to EXR, and
//! the scalar reductions that the heatmaps and percentile gates use.

use super::errors::RELATIVE_EPSILON;
use super::ssim::ChannelSsim;
use crate::image_io::RgbImage;
use rayon::prelude::*;

/// |a − r| per pixel and channel.
pub fn abs_error(reference: &RgbImage, approximation: &RgbImage) -> RgbImage {
    zip_map(reference, approximation, |r, a| (a - r).abs())
}

/// |a − r| / (|r| + ε·R) per pixel and channel, ε = [`RELATIVE_EPSILON`] (see `errors.rs`).
pub fn rel_error(reference: &RgbImage, approximation: &RgbImage, data_range: f64) -> RgbImage {
    let eps = RELATIVE_EPSILON * data_range;
    zip_map(reference, approximation, |r, a| {
        ((a as f64 - r as f64).abs() / ((r as f64).abs() + eps)) as f32
    })
}

/// The per-channel SSIM maps as one image (R, G, B = the channels' maps).
pub fn ssim_image(width: u32, height: u32, channels: &[ChannelSsim; 3]) -> RgbImage {
    let pixels = (0..width as usize * height as usize)
        .map(|i| std::array::from_fn(|c| channels[c].map[i] as f32))
        .collect();
    RgbImage {
        width,
        height,
        pixels,
    }
}

/// A scalar map replicated into R, G, B (for EXR layers of scalar maps such as FLIP).
pub fn gray_image(width: u32, height: u32, values: &[f32]) -> RgbImage {
    RgbImage {
        width,
        height,
        pixels: values.iter().map(|&v| [v; 3]).collect(),
    }
}

/// The mean over the three channels of each pixel (how heatmaps and percentile gates reduce a
/// per-channel map to one value per pixel, consistent with "mean" in docs/design.md §5).
pub fn channel_mean(image: &RgbImage) -> Vec<f32> {
    image
        .pixels
        .par_iter()
        .map(|p| ((p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0) as f32)
        .collect()
}

/// Nearest-rank percentile: the smallest value such that at least `p` % of the values are ≤ it
/// (rank ⌈p/100·n⌉, 1-based). `p` in (0, 100]; `None` for an empty slice or a bad `p`.
pub fn percentile(values: &[f32], p: f64) -> Option<f32> {
    if values.is_empty() || !(p > 0.0 && p <= 100.0) {
        return None;
    }
    let n = values.len();
    let rank = ((p / 100.0 * n as f64).ceil() as usize).clamp(1, n);
    let mut v = values.to_vec();
    let (_, nth, _) = v.select_nth_unstable_by(rank - 1, |a, b| a.total_cmp(b));
    Some(*nth)
}

fn zip_map(
    reference: &RgbImage,
    approximation: &RgbImage,
    f: impl Fn(f32, f32) -> f32 + Sync,
) -> RgbImage {
    let pixels = reference
        .pixels
        .par_iter()
        .zip(&approximation.pixels)
        .map(|(r, a)| std::array::from_fn(|c| f(r[c], a[c])))
        .collect();
    RgbImage {
        width: reference.width,
        height: reference.height,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_percentile() {
        let v: Vec<f32> = (1..=100).map(|i| i as f32).collect();
        assert_eq!(percentile(&v, 50.0), Some(50.0));
        assert_eq!(percentile(&v, 99.0), Some(99.0));
        assert_eq!(percentile(&v, 99.5), Some(100.0));
        assert_eq!(percentile(&v, 100.0), Some(100.0));
        assert_eq!(percentile(&v, 0.5), Some(1.0));
        assert_eq!(percentile(&v, 0.0), None);
        assert_eq!(percentile(&[], 50.0), None);
    }
}

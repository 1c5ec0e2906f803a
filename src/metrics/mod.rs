//! Comparison of an approximation with the reference (docs/design.md §5): SSIM, RMSE, PSNR, max / mean
//! absolute and mean relative error, per channel and their mean, FLIP (LDR), and per-pixel maps.
//!
//! "Mean" of a metric is the mean of its per-channel values (the thesis's "Mittelwert").
//! Everything is computed in f64 from the f32 pixels.

pub mod errors;
pub mod flip;
pub mod flip_float;
mod flip_math;
pub mod gate;
pub mod maps;
pub mod ssim;
pub mod temporal;

use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
pub use errors::ChannelErrors;
pub use flip::Flip;
pub use ssim::ChannelSsim;

/// Channel names in the order pgt stores them, and the first non-finite value of an image: the
/// images' own facts ([`crate::image_io`]), which the metrics name too.
pub use crate::image_io::{first_non_finite, CHANNELS};

/// A per-channel value and the mean of the three (docs/design.md §5).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PerChannel {
    #[serde(rename = "R")]
    pub r: f64,
    #[serde(rename = "G")]
    pub g: f64,
    #[serde(rename = "B")]
    pub b: f64,
    pub mean: f64,
}

impl PerChannel {
    /// From the three channel values; the mean is their arithmetic mean.
    pub fn from_channels(v: [f64; 3]) -> Self {
        PerChannel {
            r: v[0],
            g: v[1],
            b: v[2],
            mean: (v[0] + v[1] + v[2]) / 3.0,
        }
    }

    /// Channel 0..3 (R, G, B) or 3 = the mean.
    pub fn get(&self, index: usize) -> f64 {
        [self.r, self.g, self.b, self.mean][index.min(3)]
    }
}

/// Where the SSIM/PSNR data range came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DataRangeSource {
    /// `--data-range` (or the experiment file).
    Given,
    /// LDR inputs (no value above 1): 1 (docs/design.md §5).
    Default,
    /// HDR inputs without a given range: max(reference) − min(0, min(reference)).
    Derived,
}

/// Options of a comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompareOptions {
    /// The data range R of SSIM and PSNR; `None`: 1 for LDR inputs, derived for HDR.
    pub data_range: Option<f64>,
    /// Compute FLIP: LDR-FLIP when no value exceeds 1, HDR-FLIP otherwise.
    pub flip: bool,
    pub pixels_per_degree: f32,
    /// HDR-FLIP's exposure range (start, stop) in stops; `None`: chosen from the reference.
    pub flip_exposures: Option<(f32, f32)>,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            data_range: None,
            flip: true,
            pixels_per_degree: flip::DEFAULT_PIXELS_PER_DEGREE,
            flip_exposures: None,
        }
    }
}

/// Everything measured about one image pair.
#[derive(Debug, Clone)]
pub struct Comparison {
    pub width: u32,
    pub height: u32,
    pub data_range: f64,
    pub data_range_source: DataRangeSource,
    /// Per-channel SSIM, or why it could not be computed (image smaller than the window).
    pub ssim: std::result::Result<[ChannelSsim; 3], ssim::SsimError>,
    pub errors: [ChannelErrors; 3],
    /// FLIP, or why it was not computed (HDR input, or not asked for).
    pub flip: std::result::Result<Flip, String>,
}

impl Comparison {
    /// SSIM per channel and mean, when defined.
    pub fn ssim_values(&self) -> Option<PerChannel> {
        self.ssim
            .as_ref()
            .ok()
            .map(|s| PerChannel::from_channels([s[0].mean, s[1].mean, s[2].mean]))
    }

    /// One statistic of [`ChannelErrors`] per channel and mean.
    pub fn error_values(&self, f: impl Fn(&ChannelErrors) -> f64) -> PerChannel {
        PerChannel::from_channels([f(&self.errors[0]), f(&self.errors[1]), f(&self.errors[2])])
    }

    /// FLIP mean, when computed.
    pub fn flip_mean(&self) -> Option<f64> {
        self.flip.as_ref().ok().map(|f| f.mean)
    }
}

/// Whether every value lies in [0, 1] (an LDR image).
pub fn is_ldr(image: &RgbImage) -> bool {
    image
        .pixels
        .iter()
        .flatten()
        .all(|&v| (0.0..=1.0).contains(&v))
}

/// The data range for SSIM and PSNR (docs/design.md §5): the given one; 1 when both images are LDR;
/// otherwise max(reference) − min(0, min(reference)), the reference's own range.
pub fn resolve_data_range(
    reference: &RgbImage,
    approximation: &RgbImage,
    given: Option<f64>,
) -> Result<(f64, DataRangeSource)> {
    if let Some(r) = given {
        if !(r.is_finite() && r > 0.0) {
            return Err(PgtError::Usage(format!(
                "--data-range must be a finite number > 0, got {r}"
            )));
        }
        return Ok((r, DataRangeSource::Given));
    }
    if is_ldr(reference) && is_ldr(approximation) {
        return Ok((1.0, DataRangeSource::Default));
    }
    let (lo, hi) = reference
        .pixels
        .iter()
        .flatten()
        .fold((0.0f64, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v as f64), hi.max(v as f64))
        });
    let range = hi - lo;
    if !(range.is_finite() && range > 0.0) {
        return Err(PgtError::Usage(
            "cannot derive a data range from the reference (it is constant); pass --data-range"
                .into(),
        ));
    }
    Ok((range, DataRangeSource::Derived))
}

/// Compares `approximation` with `reference` (docs/design.md §5). The images must have the same size
/// and finite values (an error otherwise: NaN or ∞ never pass silently).
pub fn compare(
    reference: &RgbImage,
    approximation: &RgbImage,
    options: &CompareOptions,
) -> Result<Comparison> {
    if (reference.width, reference.height) != (approximation.width, approximation.height) {
        return Err(PgtError::Usage(format!(
            "images differ in size: reference {}x{}, approximation {}x{}",
            reference.width, reference.height, approximation.width, approximation.height
        )));
    }
    if reference.pixels.is_empty() {
        return Err(PgtError::Usage("images have no pixels".into()));
    }
    for (name, img) in [("reference", reference), ("approximation", approximation)] {
        if let Some((x, y, c)) = first_non_finite(img) {
            return Err(PgtError::Usage(format!(
                "{name} has a non-finite value ({}) at pixel ({x}, {y}), channel {}",
                img.get(x, y)[c],
                CHANNELS[c]
            )));
        }
    }
    let (data_range, data_range_source) =
        resolve_data_range(reference, approximation, options.data_range)?;
    let ((ssim, errors), flip) = rayon::join(
        || {
            rayon::join(
                || -> std::result::Result<[ChannelSsim; 3], ssim::SsimError> {
                    Ok([
                        ssim::ssim_channel(reference, approximation, 0, data_range)?,
                        ssim::ssim_channel(reference, approximation, 1, data_range)?,
                        ssim::ssim_channel(reference, approximation, 2, data_range)?,
                    ])
                },
                || errors::channel_errors(reference, approximation, data_range),
            )
        },
        || {
            if !options.flip {
                Err("FLIP not requested".to_string())
            } else if is_ldr(reference) && is_ldr(approximation) {
                flip::flip_ldr(reference, approximation, options.pixels_per_degree)
                    .map_err(|e| e.to_string())
            } else {
                flip::flip_hdr(
                    reference,
                    approximation,
                    options.pixels_per_degree,
                    options.flip_exposures,
                )
                .map_err(|e| e.to_string())
            }
        },
    );
    Ok(Comparison {
        width: reference.width,
        height: reference.height,
        data_range,
        data_range_source,
        ssim,
        errors,
        flip,
    })
}

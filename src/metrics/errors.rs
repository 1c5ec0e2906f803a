//! Pixel error statistics of docs/design.md §5, per channel, in f64: mean squared error, RMSE, PSNR,
//! largest absolute error with the pixel where it occurs, mean absolute error and mean relative
//! error.
//!
//! Definitions (r = reference, a = approximation, one channel, N pixels, R = data range):
//! * MSE = Σ(a − r)²/N, RMSE = √MSE (scikit-image `mean_squared_error`);
//! * PSNR = 10·log10(R²/MSE) dB (scikit-image `peak_signal_noise_ratio`), +∞ for identical images;
//! * max abs = max |a − r|, at the first pixel in row-major order that reaches it;
//! * mean abs = Σ|a − r|/N;
//! * relative error per pixel |a − r| / (|r| + ε) with ε = [`RELATIVE_EPSILON`]·R (so that black
//!   reference pixels do not divide by zero), mean rel = its mean.

use crate::image_io::RgbImage;
use rayon::prelude::*;

/// ε of the relative error, as a fraction of the data range.
pub const RELATIVE_EPSILON: f64 = 0.01;

/// The error statistics of one channel.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ChannelErrors {
    pub mse: f64,
    pub rmse: f64,
    /// dB; `f64::INFINITY` when MSE is 0 (written as `null` in JSON).
    pub psnr: f64,
    pub max_abs: f64,
    /// (x, y) of the first pixel, row-major, where `max_abs` is reached.
    pub max_abs_pixel: (u32, u32),
    pub mean_abs: f64,
    pub mean_rel: f64,
}

/// Sums over one row, combined in row order so results do not depend on the thread count.
#[derive(Clone, Copy)]
struct RowSums {
    sq: [f64; 3],
    abs: [f64; 3],
    rel: [f64; 3],
    max: [(f64, usize); 3],
}

/// Error statistics of the three channels (docs/design.md §5). Sizes must agree (checked by the
/// caller); values must be finite (checked by the caller).
pub fn channel_errors(
    reference: &RgbImage,
    approximation: &RgbImage,
    data_range: f64,
) -> [ChannelErrors; 3] {
    let w = reference.width as usize;
    let eps = RELATIVE_EPSILON * data_range;
    let rows: Vec<RowSums> = reference
        .pixels
        .par_chunks(w.max(1))
        .zip(approximation.pixels.par_chunks(w.max(1)))
        .enumerate()
        .map(|(y, (r_row, a_row))| {
            let mut s = RowSums {
                sq: [0.0; 3],
                abs: [0.0; 3],
                rel: [0.0; 3],
                max: [(-1.0, 0); 3],
            };
            for (x, (r, a)) in r_row.iter().zip(a_row).enumerate() {
                for c in 0..3 {
                    let (rv, av) = (r[c] as f64, a[c] as f64);
                    let d = av - rv;
                    let ad = d.abs();
                    s.sq[c] += d * d;
                    s.abs[c] += ad;
                    s.rel[c] += ad / (rv.abs() + eps);
                    if ad > s.max[c].0 {
                        s.max[c] = (ad, y * w + x);
                    }
                }
            }
            s
        })
        .collect();
    let n = reference.pixels.len().max(1) as f64;
    std::array::from_fn(|c| {
        let (mut sq, mut abs, mut rel, mut max) = (0.0, 0.0, 0.0, (-1.0f64, 0usize));
        for row in &rows {
            sq += row.sq[c];
            abs += row.abs[c];
            rel += row.rel[c];
            if row.max[c].0 > max.0 {
                max = row.max[c];
            }
        }
        let mse = sq / n;
        let psnr = if mse == 0.0 {
            f64::INFINITY
        } else {
            10.0 * (data_range * data_range / mse).log10()
        };
        ChannelErrors {
            mse,
            rmse: mse.sqrt(),
            psnr,
            max_abs: max.0.max(0.0),
            max_abs_pixel: ((max.1 % w.max(1)) as u32, (max.1 / w.max(1)) as u32),
            mean_abs: abs / n,
            mean_rel: rel / n,
        }
    })
}

/// The approximation's error measured against the reference's own uncertainty: the reference's
/// per-pixel quadrature error estimate (its EXR `err` layer, docs/design.md §3).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ReferenceUncertainty {
    /// Largest and mean estimate over all pixels and channels.
    pub max_estimate: f64,
    pub mean_estimate: f64,
    /// Fraction of pixel-channels where |a − r| exceeds the reference's estimate there: the
    /// differences that the reference is sure about.
    pub exceeding_fraction: f64,
}

/// Compares |a − r| with the reference's error estimate `estimate` (same size, checked by the
/// caller).
pub fn reference_uncertainty(
    reference: &RgbImage,
    approximation: &RgbImage,
    estimate: &RgbImage,
) -> ReferenceUncertainty {
    let (mut max, mut sum, mut exceeding) = (0.0f64, 0.0f64, 0usize);
    for ((r, a), e) in reference
        .pixels
        .iter()
        .zip(&approximation.pixels)
        .zip(&estimate.pixels)
    {
        for c in 0..3 {
            let est = (e[c] as f64).abs();
            max = max.max(est);
            sum += est;
            if (a[c] as f64 - r[c] as f64).abs() > est {
                exceeding += 1;
            }
        }
    }
    let n = (3 * reference.pixels.len()).max(1) as f64;
    ReferenceUncertainty {
        max_estimate: max,
        mean_estimate: sum / n,
        exceeding_fraction: exceeding as f64 / n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uncertainty_counts_differences_above_the_estimate() {
        let r = RgbImage::new(2, 1);
        let mut a = RgbImage::new(2, 1);
        a.pixels[0] = [0.1, 0.001, 0.0];
        let mut e = RgbImage::new(2, 1);
        e.pixels = vec![[0.01; 3], [0.03; 3]];
        let u = reference_uncertainty(&r, &a, &e);
        // Only R of pixel 0 (0.1 > 0.01) exceeds its estimate: 1 of 6 pixel-channels.
        assert_eq!(u.exceeding_fraction, 1.0 / 6.0);
        assert_eq!(u.max_estimate, 0.03f32 as f64);
        assert!((u.mean_estimate - 0.02).abs() < 1e-9);
    }
}

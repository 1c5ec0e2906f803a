//! SSIM (Wang et al. 2004) exactly as DESIGN.md §5 defines it, which is scikit-image's
//! `structural_similarity(im1, im2, gaussian_weights=True, sigma=1.5,
//! use_sample_covariance=False, data_range=R)`:
//!
//! * window: Gaussian, σ = 1.5, truncated at `truncate = 3.5` σ, i.e. radius
//!   `int(3.5·1.5 + 0.5) = 5`, an 11×11 window (scipy's `_gaussian_kernel1d`), normalised to sum 1;
//! * local statistics μx, μy, σx², σy², σxy by separable filtering (along axis 0, the vertical,
//!   first, then along axis 1, as `scipy.ndimage.gaussian_filter` does), borders in scipy's `mode='reflect'`
//!   (half-sample symmetric: `d c b a | a b c d | d c b a`);
//! * population covariances (`use_sample_covariance=False`), C1 = (K1·R)², C2 = (K2·R)²,
//!   K1 = 0.01, K2 = 0.03;
//! * S = (2μxμy + C1)(2σxy + C2) / ((μx² + μy² + C1)(σx² + σy² + C2)) per pixel (the SSIM map,
//!   defined at every pixel), and the SSIM index is the mean of S after cropping
//!   `(11 − 1)/2 = 5` pixels from every border.
//!
//! Images smaller than the window on either side are refused, as scikit-image refuses them.
//! The arithmetic mirrors scipy's (`NI_Correlate1D` for symmetric kernels: centre tap first, then
//! the pairs from the outside in), so results agree with scikit-image to ~1e-15; the test budget
//! is 1e-6 (tests/compare_ssim.rs against vectors from `scripts/ssim_vectors.py`).

use crate::image_io::RgbImage;
use rayon::prelude::*;

/// Standard deviation of the Gaussian window, in pixels (DESIGN.md §5).
pub const SIGMA: f64 = 1.5;
/// scipy/scikit-image truncate the Gaussian at this many standard deviations.
pub const TRUNCATE: f64 = 3.5;
/// Window radius: `int(TRUNCATE·SIGMA + 0.5)` = 5 (scipy's rule).
pub const RADIUS: usize = 5;
/// Window side, 2·RADIUS + 1 = 11.
pub const WINDOW: usize = 2 * RADIUS + 1;
/// Luminance stabiliser constant.
pub const K1: f64 = 0.01;
/// Contrast/structure stabiliser constant.
pub const K2: f64 = 0.03;

/// Output rows per parallel work item.
const BAND: usize = 32;

/// The SSIM of one channel.
#[derive(Debug, Clone)]
pub struct ChannelSsim {
    /// Mean of the SSIM map over the image cropped by [`RADIUS`] on every side.
    pub mean: f64,
    /// The SSIM map (row-major, every pixel, borders computed with reflection).
    pub map: Vec<f64>,
}

/// Why SSIM could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SsimError {
    #[error("image is {width}x{height}, smaller than the {WINDOW}x{WINDOW} SSIM window (scikit-image refuses it too)")]
    TooSmall { width: u32, height: u32 },
    #[error("SSIM data range must be finite and > 0, got {0}")]
    BadDataRange(f64),
}

/// scipy's `_gaussian_kernel1d(sigma, 0, radius)`: exp(−x²/(2σ²)) for x = −r..r, divided by its
/// sum. The sum is taken in numpy's pairwise order for 11 elements (eight partial sums combined
/// as a tree, then the last three added), so the weights equal scipy's bit for bit.
pub fn gaussian_window() -> [f64; WINDOW] {
    let sigma2 = SIGMA * SIGMA;
    let mut phi = [0.0f64; WINDOW];
    for (i, p) in phi.iter_mut().enumerate() {
        let x = i as f64 - RADIUS as f64;
        *p = (-0.5 / sigma2 * (x * x)).exp();
    }
    let r = &phi;
    let mut sum = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for v in &r[8..] {
        sum += v;
    }
    phi.map(|p| p / sum)
}

/// scipy `mode='reflect'` index: half-sample symmetric extension of 0..n.
#[inline]
fn reflect(i: isize, n: usize) -> usize {
    let n = n as isize;
    let period = 2 * n;
    let mut m = i.rem_euclid(period);
    if m >= n {
        m = period - 1 - m;
    }
    m as usize
}

/// SSIM of channel `channel` (0 = R, 1 = G, 2 = B) of two images of equal size, with data range
/// `data_range` (DESIGN.md §5). Parallel over bands of rows; the result does not depend on the
/// thread count.
pub fn ssim_channel(
    reference: &RgbImage,
    approximation: &RgbImage,
    channel: usize,
    data_range: f64,
) -> Result<ChannelSsim, SsimError> {
    let (w, h) = (reference.width as usize, reference.height as usize);
    debug_assert_eq!(
        (w, h),
        (approximation.width as usize, approximation.height as usize)
    );
    if w < WINDOW || h < WINDOW {
        return Err(SsimError::TooSmall {
            width: reference.width,
            height: reference.height,
        });
    }
    if !(data_range.is_finite() && data_range > 0.0) {
        return Err(SsimError::BadDataRange(data_range));
    }
    let weights = gaussian_window();
    let c1 = (K1 * data_range).powi(2);
    let c2 = (K2 * data_range).powi(2);
    let bands: Vec<(usize, usize)> = (0..h)
        .step_by(BAND)
        .map(|y0| (y0, (y0 + BAND).min(h)))
        .collect();
    let results: Vec<(Vec<f64>, f64)> = bands
        .par_iter()
        .map(|&(y0, y1)| {
            let stats = Statistics::of_rows(reference, approximation, channel, y0, y1);
            ssim_band(&stats, &weights, (w, h), (y0, y1), (c1, c2))
        })
        .collect();
    let mut map = Vec::with_capacity(w * h);
    let mut sum = 0.0f64;
    for (band_map, band_sum) in results {
        map.extend_from_slice(&band_map);
        sum += band_sum;
    }
    let count = ((w - 2 * RADIUS) * (h - 2 * RADIUS)) as f64;
    Ok(ChannelSsim {
        mean: sum / count,
        map,
    })
}

/// The five per-pixel quantities the local statistics filter, x, y, x², y², xy, as planes
/// (structure of arrays, so that the filters run over contiguous rows and vectorise), for the
/// image rows a band of output rows reads: `lo..hi`, its rows ± [`RADIUS`] within the image
/// (the reflected rows beyond the border are among them, as the image has ≥ [`WINDOW`] rows).
struct Statistics {
    lo: usize,
    width: usize,
    height: usize,
    planes: [Vec<f64>; 5],
}

impl Statistics {
    fn of_rows(
        reference: &RgbImage,
        approximation: &RgbImage,
        channel: usize,
        y0: usize,
        y1: usize,
    ) -> Statistics {
        let (w, h) = (reference.width as usize, reference.height as usize);
        let (lo, hi) = (y0.saturating_sub(RADIUS), (y1 + RADIUS).min(h));
        let n = (hi - lo) * w;
        let mut planes: [Vec<f64>; 5] = std::array::from_fn(|_| Vec::with_capacity(n));
        let rows = lo * w..hi * w;
        for (p, q) in reference.pixels[rows.clone()]
            .iter()
            .zip(&approximation.pixels[rows])
        {
            let (a, b) = (p[channel] as f64, q[channel] as f64);
            for (plane, v) in planes.iter_mut().zip([a, b, a * a, b * b, a * b]) {
                plane.push(v);
            }
        }
        Statistics {
            lo,
            width: w,
            height: h,
            planes,
        }
    }

    /// Row `y` (image coordinates, reflected into the image) of plane `q`.
    #[inline]
    fn row(&self, q: usize, y: isize) -> &[f64] {
        let r = reflect(y, self.height) - self.lo;
        &self.planes[q][r * self.width..(r + 1) * self.width]
    }
}

/// One band of the SSIM map and the sum of its cropped values. The column pass (scipy filters
/// axis 0 first) then the row pass, each as the centre tap times its weight plus the pairs from
/// the outside in (scipy's `NI_Correlate1D` for symmetric kernels), so that every value equals
/// the per-pixel formulation bit for bit; loops run along rows so that the compiler vectorises.
fn ssim_band(
    stats: &Statistics,
    weights: &[f64; WINDOW],
    (w, h): (usize, usize),
    (y0, y1): (usize, usize),
    (c1, c2): (f64, f64),
) -> (Vec<f64>, f64) {
    let padded = w + 2 * RADIUS;
    let mut map = vec![0.0f64; (y1 - y0) * w];
    let mut cropped_sum = 0.0f64;
    let mut line: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0f64; padded]);
    let mut m: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0f64; w]);
    for y in y0..y1 {
        // Column pass into `line`, with RADIUS reflected columns on each side.
        for (q, l) in line.iter_mut().enumerate() {
            let acc = &mut l[RADIUS..RADIUS + w];
            for (d, &c) in acc.iter_mut().zip(stats.row(q, y as isize)) {
                *d = c * weights[RADIUS];
            }
            for j in (1..=RADIUS).rev() {
                let lo = stats.row(q, y as isize - j as isize);
                let hi = stats.row(q, (y + j) as isize);
                let wj = weights[RADIUS - j];
                for ((d, &a), &b) in acc.iter_mut().zip(lo).zip(hi) {
                    *d += (a + b) * wj;
                }
            }
            for k in 0..RADIUS {
                l[k] = l[RADIUS + reflect(k as isize - RADIUS as isize, w)];
                l[RADIUS + w + k] = l[RADIUS + reflect((w + k) as isize, w)];
            }
        }
        // Row pass into `m`.
        for (mq, l) in m.iter_mut().zip(&line) {
            for (d, &c) in mq.iter_mut().zip(&l[RADIUS..RADIUS + w]) {
                *d = c * weights[RADIUS];
            }
            for j in (1..=RADIUS).rev() {
                let wj = weights[RADIUS - j];
                let (lo, hi) = (
                    &l[RADIUS - j..RADIUS - j + w],
                    &l[RADIUS + j..RADIUS + j + w],
                );
                for ((d, &a), &b) in mq.iter_mut().zip(lo).zip(hi) {
                    *d += (a + b) * wj;
                }
            }
        }
        // The SSIM formula, in scikit-image's order of operations.
        let out = &mut map[(y - y0) * w..(y - y0 + 1) * w];
        let mut row_sum = 0.0f64;
        for x in 0..w {
            let (ux, uy, uxx, uyy, uxy) = (m[0][x], m[1][x], m[2][x], m[3][x], m[4][x]);
            let vx = uxx - ux * ux;
            let vy = uyy - uy * uy;
            let vxy = uxy - ux * uy;
            let a1 = 2.0 * ux * uy + c1;
            let a2 = 2.0 * vxy + c2;
            let b1 = ux * ux + uy * uy + c1;
            let b2 = vx + vy + c2;
            let s = (a1 * a2) / (b1 * b2);
            out[x] = s;
            if (RADIUS..w - RADIUS).contains(&x) {
                row_sum += s;
            }
        }
        if (RADIUS..h - RADIUS).contains(&y) {
            cropped_sum += row_sum;
        }
    }
    (map, cropped_sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_is_normalised_symmetric_and_eleven_taps() {
        let w = gaussian_window();
        assert_eq!(w.len(), 11);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        for j in 0..5 {
            assert_eq!(w[j], w[10 - j]);
        }
        assert!(w[5] > w[4] && w[4] > w[0]);
    }

    #[test]
    fn reflect_is_half_sample_symmetric() {
        let n = 6;
        let got: Vec<usize> = (-3..9).map(|i| reflect(i, n)).collect();
        assert_eq!(got, vec![2, 1, 0, 0, 1, 2, 3, 4, 5, 5, 4, 3]);
    }
}

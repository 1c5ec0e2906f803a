//! SSIM (Wang et al. 2004) exactly as docs/design.md §5 defines it, which is scikit-image's
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
//! is 1e-6 (tests/compare/ssim.rs against vectors from `scripts/ssim_vectors.py`).

use crate::image_io::RgbImage;
use rayon::prelude::*;

/// Standard deviation of the Gaussian window, in pixels (docs/design.md §5).
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

/// Output rows per parallel work item (and per partial sum of the index).
const BAND: usize = 32;
/// Output columns per work item at most: the five statistics planes of a block (f64, BAND + 10
/// rows) stay in a core's L2 cache, so the column pass reads from cache, not memory.
const STRIP: usize = 512;
/// Columns the filters accumulate in registers at a time.
const LANES: usize = 8;

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
/// `data_range` (docs/design.md §5). Parallel over blocks of rows and columns; the result does not
/// depend on the block layout or the thread count.
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
    let items: Vec<((usize, usize), (usize, usize))> = (0..h)
        .step_by(BAND)
        .flat_map(|y0| {
            let strips = w.div_ceil(STRIP);
            (0..strips).map(move |s| {
                let xs = (s * w / strips, (s + 1) * w / strips);
                (xs, (y0, (y0 + BAND).min(h)))
            })
        })
        .collect();
    let parts: Vec<Vec<f64>> = items
        .par_iter()
        .map(|&(xs, ys)| {
            let stats = Statistics::of_block(reference, approximation, channel, xs, ys);
            ssim_block_fastest(&stats, &weights, ys, (c1, c2))
        })
        .collect();
    let mut map = vec![0.0f64; w * h];
    for (&((x0, x1), (y0, _)), part) in items.iter().zip(&parts) {
        for (y, src) in (y0..).zip(part.chunks_exact(x1 - x0)) {
            map[y * w + x0..y * w + x1].copy_from_slice(src);
        }
    }
    // The cropped mean summed as before the blocks (per row from left to right, rows into bands
    // of BAND, bands in order), so that the index does not depend on the block layout.
    let mut sum = 0.0f64;
    for band in map.chunks(BAND * w).enumerate() {
        let (b, rows) = band;
        let mut band_sum = 0.0f64;
        for (r, row) in rows.chunks_exact(w).enumerate() {
            if (RADIUS..h - RADIUS).contains(&(b * BAND + r)) {
                band_sum += row[RADIUS..w - RADIUS].iter().fold(0.0, |a, &v| a + v);
            }
        }
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
/// image rows and columns a block of output pixels reads: rows `lo..hi`, its rows ± [`RADIUS`]
/// within the image (the reflected rows beyond the border are among them, as the image has
/// ≥ [`WINDOW`] rows), and its columns ± [`RADIUS`], reflected at the image's sides (the row
/// pass reads them directly).
struct Statistics {
    lo: usize,
    /// Columns of a plane row: the block's plus 2·[`RADIUS`].
    width: usize,
    height: usize,
    planes: [Vec<f64>; 5],
}

impl Statistics {
    fn of_block(
        reference: &RgbImage,
        approximation: &RgbImage,
        channel: usize,
        (x0, x1): (usize, usize),
        (y0, y1): (usize, usize),
    ) -> Statistics {
        let (w, h) = (reference.width as usize, reference.height as usize);
        let (lo, hi) = (y0.saturating_sub(RADIUS), (y1 + RADIUS).min(h));
        let width = x1 - x0 + 2 * RADIUS;
        let n = (hi - lo) * width;
        let mut planes: [Vec<f64>; 5] = std::array::from_fn(|_| Vec::with_capacity(n));
        let columns: Vec<usize> = (0..width)
            .map(|c| reflect(x0 as isize + c as isize - RADIUS as isize, w))
            .collect();
        for y in lo..hi {
            let (r, a) = (
                &reference.pixels[y * w..(y + 1) * w],
                &approximation.pixels[y * w..(y + 1) * w],
            );
            for &x in &columns {
                let (a, b) = (r[x][channel] as f64, a[x][channel] as f64);
                for (plane, v) in planes.iter_mut().zip([a, b, a * a, b * b, a * b]) {
                    plane.push(v);
                }
            }
        }
        Statistics {
            lo,
            width,
            height: h,
            planes,
        }
    }

    /// Row `y` (image coordinates, reflected into the image) of plane `q`.
    #[inline(always)]
    fn row(&self, q: usize, y: isize) -> &[f64] {
        let r = reflect(y, self.height) - self.lo;
        &self.planes[q][r * self.width..(r + 1) * self.width]
    }
}

/// out[x] = rows[R][x]·w[R] + Σ_{j=R..1} (rows[R−j][x] + rows[R+j][x])·w[R−j]: the centre tap
/// first, then the pairs from the outside in (scipy's `NI_Correlate1D` for symmetric kernels), so
/// that every value equals the per-pixel formulation bit for bit; [`LANES`] columns accumulate in
/// registers at a time.
#[inline(always)]
fn symmetric_filter(rows: &[&[f64]; WINDOW], weights: &[f64; WINDOW], out: &mut [f64]) {
    let n = out.len();
    let full = n - n % LANES;
    for x in (0..full).step_by(LANES) {
        let mut acc = [0.0f64; LANES];
        symmetric_taps(rows, weights, x, &mut acc);
        out[x..x + LANES].copy_from_slice(&acc);
    }
    symmetric_taps(rows, weights, full, &mut out[full..]);
}

/// [`symmetric_filter`] at columns x.. (as many as `acc` holds). A function, not a closure, so
/// that it inlines into the AVX2 build.
#[inline(always)]
fn symmetric_taps(rows: &[&[f64]; WINDOW], weights: &[f64; WINDOW], x: usize, acc: &mut [f64]) {
    let len = acc.len();
    for (d, &c) in acc.iter_mut().zip(&rows[RADIUS][x..x + len]) {
        *d = c * weights[RADIUS];
    }
    for j in (1..=RADIUS).rev() {
        let (lo, hi) = (&rows[RADIUS - j][x..x + len], &rows[RADIUS + j][x..x + len]);
        for ((d, &a), &b) in acc.iter_mut().zip(lo).zip(hi) {
            *d += (a + b) * weights[RADIUS - j];
        }
    }
}

/// One block of the SSIM map (rows y0..y1 of the block's columns): the column pass (scipy
/// filters axis 0 first) into a line with the block's reflected or neighbouring columns on
/// each side, then the row pass, then the SSIM formula in scikit-image's order of operations.
#[inline(always)]
fn ssim_block(
    stats: &Statistics,
    weights: &[f64; WINDOW],
    (y0, y1): (usize, usize),
    (c1, c2): (f64, f64),
) -> Vec<f64> {
    let padded = stats.width;
    let w = padded - 2 * RADIUS;
    let mut map = vec![0.0f64; (y1 - y0) * w];
    let mut line: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0f64; padded]);
    let mut m: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0f64; w]);
    for (y, out) in (y0..y1).zip(map.chunks_exact_mut(w)) {
        for (q, (l, mq)) in line.iter_mut().zip(&mut m).enumerate() {
            let rows = std::array::from_fn(|k| stats.row(q, (y + k) as isize - RADIUS as isize));
            symmetric_filter(&rows, weights, l);
            let shifted = std::array::from_fn(|k| &l[k..k + w]);
            symmetric_filter(&shifted, weights, mq);
        }
        for (x, s) in out.iter_mut().enumerate() {
            let (ux, uy, uxx, uyy, uxy) = (m[0][x], m[1][x], m[2][x], m[3][x], m[4][x]);
            let vx = uxx - ux * ux;
            let vy = uyy - uy * uy;
            let vxy = uxy - ux * uy;
            let a1 = 2.0 * ux * uy + c1;
            let a2 = 2.0 * vxy + c2;
            let b1 = ux * ux + uy * uy + c1;
            let b2 = vx + vy + c2;
            *s = (a1 * a2) / (b1 * b2);
        }
    }
    map
}

/// [`ssim_block`] compiled for AVX2 when the CPU has it (checked at run time; pgt's build targets
/// baseline x86-64): the same operations in the same order on 4 f64 lanes instead of SSE2's 2,
/// so the map is the same bit for bit (Rust never fuses a multiply and an add by itself; tested
/// below).
fn ssim_block_fastest(
    stats: &Statistics,
    weights: &[f64; WINDOW],
    ys: (usize, usize),
    c: (f64, f64),
) -> Vec<f64> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above), the one condition for calling a
        // function compiled with `target_feature(enable = "avx2")`.
        return unsafe { ssim_block_avx2(stats, weights, ys, c) };
    }
    ssim_block(stats, weights, ys, c)
}

/// [`ssim_block`], inlined into a function compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn ssim_block_avx2(
    stats: &Statistics,
    weights: &[f64; WINDOW],
    ys: (usize, usize),
    c: (f64, f64),
) -> Vec<f64> {
    ssim_block(stats, weights, ys, c)
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

    /// The AVX2 build of a block gives the baseline's map bit for bit.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_equals_baseline_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        let (w, h) = (203u32, 61u32);
        let mut state = 5u32;
        let mut noise = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut r = RgbImage::new(w, h);
        let mut a = RgbImage::new(w, h);
        for (p, q) in r.pixels.iter_mut().zip(&mut a.pixels) {
            *p = [noise(), noise(), noise()];
            *q = p.map(|v| v + 0.1 * noise());
        }
        let stats = Statistics::of_block(&r, &a, 1, (3, 190), (0, 40));
        let weights = gaussian_window();
        let base = ssim_block(&stats, &weights, (0, 40), (1e-4, 9e-4));
        // SAFETY: AVX2 is present (checked above).
        let wide = unsafe { ssim_block_avx2(&stats, &weights, (0, 40), (1e-4, 9e-4)) };
        assert!(base
            .iter()
            .zip(&wide)
            .all(|(x, y)| x.to_bits() == y.to_bits()));
    }

    #[test]
    fn reflect_is_half_sample_symmetric() {
        let n = 6;
        let got: Vec<usize> = (-3..9).map(|i| reflect(i, n)).collect();
        assert_eq!(got, vec![2, 1, 0, 0, 1, 2, 3, 4, 5, 5, 4, 3]);
    }
}

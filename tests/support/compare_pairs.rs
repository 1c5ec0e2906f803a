//! The image pairs and the second SSIM implementation shared by the comparison's test
//! (tests/compare/ssim.rs) and its benchmark (benches/compare.rs).
#![allow(dead_code)]

use pgt::image_io::RgbImage;
use pgt::metrics::ssim;

/// A reference and an approximation of `w`×`h` pixels: smooth gradients, the approximation with
/// deterministic noise of ±0.02 added (clamped to [0, 1]), both scaled by `scale` (1 for an LDR
/// pair, more for HDR).
pub fn pair(w: u32, h: u32, scale: f32) -> (RgbImage, RgbImage) {
    let mut r = RgbImage::new(w, h);
    let mut a = RgbImage::new(w, h);
    let mut state = 1u32;
    for y in 0..h {
        for x in 0..w {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let n = (state >> 8) as f32 / (1u32 << 24) as f32 - 0.5;
            let i = (y * w + x) as usize;
            let base = [
                x as f32 / w as f32,
                y as f32 / h as f32,
                0.5 + 0.4 * (x as f32 * 0.01).sin(),
            ];
            r.pixels[i] = base.map(|v| v * scale);
            a.pixels[i] = base.map(|v| (v + 0.04 * n).clamp(0.0, 1.0) * scale);
        }
    }
    (r, a)
}

/// scipy `mode='reflect'`.
fn reflect(i: isize, n: usize) -> usize {
    let n = n as isize;
    let period = 2 * n;
    let mut m = i.rem_euclid(period);
    if m >= n {
        m = period - 1 - m;
    }
    m as usize
}

/// SSIM by per-pixel gathers from the RGB image, the plain form of the separable filter in
/// scikit-image's order of operations; returns the channel's mean SSIM. The vectorised
/// `ssim::ssim_channel` equals it bit for bit (tests/compare/ssim.rs), and the compare bench
/// times the two in the same run.
pub fn ssim_channel_gather(
    reference: &RgbImage,
    approximation: &RgbImage,
    channel: usize,
    data_range: f64,
) -> f64 {
    use rayon::prelude::*;
    let (w, h) = (reference.width as usize, reference.height as usize);
    let weights = ssim::gaussian_window();
    let c1 = (ssim::K1 * data_range).powi(2);
    let c2 = (ssim::K2 * data_range).powi(2);
    let x_at = |i: usize| reference.pixels[i][channel] as f64;
    let y_at = |i: usize| approximation.pixels[i][channel] as f64;

    let bands: Vec<(usize, usize)> = (0..h)
        .step_by(32)
        .map(|y0| (y0, (y0 + 32).min(h)))
        .collect();
    let results: Vec<(Vec<f64>, f64)> = bands
        .par_iter()
        .map(|&(y0, y1)| {
            let rows = y1 - y0;
            // Column pass (scipy filters axis 0 first): five statistics for the band's rows,
            // stored with ssim::RADIUS reflected columns on each side for the row pass.
            let padded = w + 2 * ssim::RADIUS;
            let mut col = vec![[0.0f64; 5]; rows * padded];
            for (r, y) in (y0..y1).enumerate() {
                let row_index: [usize; ssim::WINDOW] = std::array::from_fn(|k| {
                    reflect(y as isize + k as isize - ssim::RADIUS as isize, h)
                });
                for x in 0..w {
                    let stats = |i: usize| {
                        let (a, b) = (x_at(i * w + x), y_at(i * w + x));
                        [a, b, a * a, b * b, a * b]
                    };
                    let centre = stats(row_index[ssim::RADIUS]);
                    let mut acc = centre.map(|v| v * weights[ssim::RADIUS]);
                    for j in (1..=ssim::RADIUS).rev() {
                        let lo = stats(row_index[ssim::RADIUS - j]);
                        let hi = stats(row_index[ssim::RADIUS + j]);
                        for q in 0..5 {
                            acc[q] += (lo[q] + hi[q]) * weights[ssim::RADIUS - j];
                        }
                    }
                    col[r * padded + ssim::RADIUS + x] = acc;
                }
                for k in 0..ssim::RADIUS {
                    col[r * padded + k] = col[r * padded
                        + ssim::RADIUS
                        + reflect(k as isize - ssim::RADIUS as isize, w)];
                    col[r * padded + ssim::RADIUS + w + k] =
                        col[r * padded + ssim::RADIUS + reflect((w + k) as isize, w)];
                }
            }
            // Row pass and the SSIM formula, in scikit-image's order of operations.
            let mut map = vec![0.0f64; rows * w];
            let mut cropped_sum = 0.0f64;
            for r in 0..rows {
                let line = &col[r * padded..(r + 1) * padded];
                let y = y0 + r;
                let mut row_sum = 0.0f64;
                for x in 0..w {
                    let c = x + ssim::RADIUS;
                    let mut m = line[c].map(|v| v * weights[ssim::RADIUS]);
                    for j in (1..=ssim::RADIUS).rev() {
                        for q in 0..5 {
                            m[q] += (line[c - j][q] + line[c + j][q]) * weights[ssim::RADIUS - j];
                        }
                    }
                    let [ux, uy, uxx, uyy, uxy] = m;
                    let vx = uxx - ux * ux;
                    let vy = uyy - uy * uy;
                    let vxy = uxy - ux * uy;
                    let a1 = 2.0 * ux * uy + c1;
                    let a2 = 2.0 * vxy + c2;
                    let b1 = ux * ux + uy * uy + c1;
                    let b2 = vx + vy + c2;
                    let s = (a1 * a2) / (b1 * b2);
                    map[r * w + x] = s;
                    if x >= ssim::RADIUS && x < w - ssim::RADIUS {
                        row_sum += s;
                    }
                }
                if y >= ssim::RADIUS && y < h - ssim::RADIUS {
                    cropped_sum += row_sum;
                }
            }
            (map, cropped_sum)
        })
        .collect();
    let mut map = Vec::with_capacity(w * h);
    let mut sum = 0.0;
    for (band_map, band_sum) in results {
        map.extend_from_slice(&band_map);
        sum += band_sum;
    }
    let count = ((w - 2 * ssim::RADIUS) * (h - 2 * ssim::RADIUS)) as f64;
    sum / count
}

//! Timing of the comparison on a 3840×2160 pair (ignored by default; run with
//! `cargo test --release --test compare speed:: -- --ignored --nocapture`). Prints the time of each
//! metric and of the whole `compare` for an LDR and an HDR (float) pair, before (FLIP through
//! nv-flip, single-threaded C++ on 8-bit sRGB, one call per HDR exposure) and after (pgt's float
//! FLIP in parallel bands), measured in the same run. Asserts only generous bounds (SSIM of three
//! 4K channels well under a minute) so that a quadratic or unseparated filter is caught.
//!
//! `write_4k_pairs` (ignored too) writes the same pairs as files for `scripts/compare_timing.sh`,
//! which times whole `pgt compare` commands (reading, metrics, output) of two binaries.

use pgt::image_io::RgbImage;
use pgt::metrics::{compare, errors, flip, ssim, CompareOptions};
use std::time::Instant;

fn pair(w: u32, h: u32, scale: f32) -> (RgbImage, RgbImage) {
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

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// CPU seconds (user + system) of this process so far, from /proc/self/stat (Linux; 0 elsewhere).
/// On a shared machine wall times swing with the load; CPU time measures the work itself.
fn cpu() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(vec![], |(_, rest)| rest.split_whitespace().collect());
    // Fields 14 and 15 of the file (utime, stime) are 11 and 12 after the command name, in
    // USER_HZ = 100 ticks per second.
    let tick = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (tick(11) + tick(12)) / 100.0
}

/// The former `compare`: SSIM and the error statistics beside FLIP through nv-flip.
fn compare_before(r: &RgbImage, a: &RgbImage, range: f64) -> f64 {
    let ldr = pgt::metrics::is_ldr(r) && pgt::metrics::is_ldr(a);
    let ppd = flip::DEFAULT_PIXELS_PER_DEGREE;
    let (_, f) = rayon::join(
        || {
            rayon::join(
                || {
                    (0..3)
                        .map(|c| ssim_channel_before(r, a, c, range))
                        .sum::<f64>()
                },
                || errors::channel_errors(r, a, range),
            )
        },
        || {
            if ldr {
                flip::flip_ldr_8bit(r, a, ppd).unwrap().mean
            } else {
                flip::flip_hdr_8bit(r, a, ppd, None).unwrap().mean
            }
        },
    );
    f
}

/// scipy `mode='reflect'` (a copy of pgt's former private helper).
fn reflect_before(i: isize, n: usize) -> usize {
    let n = n as isize;
    let period = 2 * n;
    let mut m = i.rem_euclid(period);
    if m >= n {
        m = period - 1 - m;
    }
    m as usize
}

/// pgt's former SSIM (per-pixel gathers from the RGB image), kept to time it against the
/// vectorised one in the same run; returns the channel's mean SSIM.
fn ssim_channel_before(
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
                    reflect_before(y as isize + k as isize - ssim::RADIUS as isize, h)
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
                        + reflect_before(k as isize - ssim::RADIUS as isize, w)];
                    col[r * padded + ssim::RADIUS + w + k] =
                        col[r * padded + ssim::RADIUS + reflect_before((w + k) as isize, w)];
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

/// Writes the timing pairs into `$PGT_TIMING_DIR`: `ldr_ref.png`/`ldr_approx.png` (8-bit sRGB)
/// and `hdr_ref.exr`/`hdr_approx.exr` (float, values up to 8), 3840×2160 each.
#[test]
#[ignore]
fn write_4k_pairs() {
    let dir = std::path::PathBuf::from(
        std::env::var_os("PGT_TIMING_DIR").expect("set PGT_TIMING_DIR to the output folder"),
    );
    std::fs::create_dir_all(&dir).unwrap();
    for (name, scale, ext) in [("ldr", 1.0f32, "png"), ("hdr", 8.0, "exr")] {
        let (r, a) = pair(3840, 2160, scale);
        for (image, which) in [(&r, "ref"), (&a, "approx")] {
            let path = dir.join(format!("{name}_{which}.{ext}"));
            pgt::image_io::write_image(&path, image, &[], 0.0).unwrap();
        }
    }
}

#[test]
#[ignore]
fn compare_4k_timings() {
    let threads = rayon::current_num_threads();
    for (name, scale) in [("LDR", 1.0f32), ("HDR", 8.0)] {
        let (r, a) = pair(3840, 2160, scale);
        let range = scale as f64;
        let t = Instant::now();
        let before: Vec<f64> = (0..3)
            .map(|c| ssim_channel_before(&r, &a, c, range))
            .collect();
        let t_ssim_old = secs(t);
        let t = Instant::now();
        let after: Vec<f64> = (0..3)
            .map(|c| ssim::ssim_channel(&r, &a, c, range).unwrap().mean)
            .collect();
        let t_ssim = secs(t);
        assert_eq!(
            before, after,
            "the vectorised SSIM must equal the former one"
        );
        let t = Instant::now();
        let _ = errors::channel_errors(&r, &a, range);
        let t_err = secs(t);
        let ppd = flip::DEFAULT_PIXELS_PER_DEGREE;
        let t = Instant::now();
        let old = if scale == 1.0 {
            flip::flip_ldr_8bit(&r, &a, ppd).unwrap()
        } else {
            flip::flip_hdr_8bit(&r, &a, ppd, None).unwrap()
        };
        let t_flip_old = secs(t);
        let t = Instant::now();
        let new = if scale == 1.0 {
            flip::flip_ldr(&r, &a, ppd).unwrap()
        } else {
            flip::flip_hdr(&r, &a, ppd, None).unwrap()
        };
        let t_flip_new = secs(t);
        let (t, c) = (Instant::now(), cpu());
        compare_before(&r, &a, range);
        let (t_before, c_before) = (secs(t), cpu() - c);
        let options = CompareOptions {
            data_range: Some(range),
            ..CompareOptions::default()
        };
        let (t, c) = (Instant::now(), cpu());
        compare(&r, &a, &options).unwrap();
        let (t_after, c_after) = (secs(t), cpu() - c);
        eprintln!(
            "{name} 3840x2160, {threads} threads: SSIM (3 channels) before {t_ssim_old:.2} s, after {t_ssim:.2} s, \
             RMSE/PSNR/abs/rel {t_err:.2} s, FLIP nv-flip 8-bit {t_flip_old:.2} s (mean {:.6}), \
             FLIP float {t_flip_new:.2} s (mean {:.6}), exposures {:?}; \
             compare before {t_before:.2} s, after {t_after:.2} s: {:.1}x wall; \
             CPU {c_before:.2} s before, {c_after:.2} s after: {:.1}x",
            old.mean,
            new.mean,
            new.exposures,
            t_before / t_after,
            c_before / c_after.max(1e-9)
        );
        assert!(t_ssim < 60.0);
    }
}

//! Timing of the comparison on a 3840×2160 pair (ignored by default; run with
//! `cargo test --test compare_speed -- --ignored --nocapture`). Prints the time of each metric;
//! asserts only a generous bound (SSIM of three 4K channels well under a minute) so that a
//! quadratic or unseparated filter is caught.

use pgt::image_io::RgbImage;
use pgt::metrics::{errors, flip, ssim};
use std::time::Instant;

fn pair(w: u32, h: u32) -> (RgbImage, RgbImage) {
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
            r.pixels[i] = base;
            a.pixels[i] = base.map(|v| (v + 0.04 * n).clamp(0.0, 1.0));
        }
    }
    (r, a)
}

#[test]
#[ignore]
fn compare_4k_timings() {
    let (r, a) = pair(3840, 2160);
    let t = Instant::now();
    for c in 0..3 {
        ssim::ssim_channel(&r, &a, c, 1.0).unwrap();
    }
    let t_ssim = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let _ = errors::channel_errors(&r, &a, 1.0);
    let t_err = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let _ = flip::flip_ldr(&r, &a, flip::DEFAULT_PIXELS_PER_DEGREE).unwrap();
    let t_flip = t.elapsed().as_secs_f64();
    eprintln!(
        "3840x2160, {} threads: SSIM (3 channels) {t_ssim:.2} s, RMSE/PSNR/abs/rel {t_err:.2} s, LDR-FLIP {t_flip:.2} s",
        rayon::current_num_threads()
    );
    assert!(t_ssim < 60.0);
}

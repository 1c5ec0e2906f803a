//! `cargo bench --bench compare`: the comparison on a 3840×2160 pair. Prints the time of each
//! metric and of the whole `compare` for an LDR and an HDR (float) pair, "before" (the baseline:
//! FLIP through nv-flip, single-threaded C++ on 8-bit sRGB, one call per HDR exposure, and SSIM
//! by per-pixel gathers) and "after" (pgt's float FLIP in parallel bands and its vectorised
//! SSIM), measured in the same run. Asserts that both SSIMs agree and only a generous bound on
//! time (SSIM of three 4K channels well under a minute), so that a quadratic or unseparated
//! filter is caught.
//!
//! `cargo bench --bench compare -- --write-pairs DIR` writes the same pairs as files instead, for
//! `scripts/compare_timing.sh`, which times whole `pgt compare` commands (reading, metrics,
//! output) of two binaries.

#[path = "../tests/support/compare_pairs.rs"]
mod compare_pairs;

use compare_pairs::{pair, ssim_channel_gather};
use pgt::image_io::RgbImage;
use pgt::metrics::{compare, errors, flip, ssim, CompareOptions};
use std::path::Path;
use std::time::Instant;

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

/// The baseline `compare`: SSIM by per-pixel gathers and the error statistics beside FLIP
/// through nv-flip.
fn compare_before(r: &RgbImage, a: &RgbImage, range: f64) -> f64 {
    let ldr = pgt::metrics::is_ldr(r) && pgt::metrics::is_ldr(a);
    let ppd = flip::DEFAULT_PIXELS_PER_DEGREE;
    let (_, f) = rayon::join(
        || {
            rayon::join(
                || {
                    (0..3)
                        .map(|c| ssim_channel_gather(r, a, c, range))
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

/// Writes the timing pairs into `dir`: `ldr_ref.png`/`ldr_approx.png` (8-bit sRGB) and
/// `hdr_ref.exr`/`hdr_approx.exr` (float, values up to 8), 3840×2160 each.
fn write_4k_pairs(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for (name, scale, ext) in [("ldr", 1.0f32, "png"), ("hdr", 8.0, "exr")] {
        let (r, a) = pair(3840, 2160, scale);
        for (image, which) in [(&r, "ref"), (&a, "approx")] {
            let path = dir.join(format!("{name}_{which}.{ext}"));
            pgt::image_io::write_image(&path, image, &[], 0.0).unwrap();
        }
    }
}

fn main() {
    // `cargo bench` adds `--bench` to the arguments; only `--write-pairs DIR` is read.
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--write-pairs") {
        let dir = args
            .get(i + 1)
            .expect("--write-pairs needs the output folder");
        write_4k_pairs(Path::new(dir));
        return;
    }
    let threads = rayon::current_num_threads();
    for (name, scale) in [("LDR", 1.0f32), ("HDR", 8.0)] {
        let (r, a) = pair(3840, 2160, scale);
        let range = scale as f64;
        let t = Instant::now();
        let before: Vec<f64> = (0..3)
            .map(|c| ssim_channel_gather(&r, &a, c, range))
            .collect();
        let t_ssim_old = secs(t);
        let t = Instant::now();
        let after: Vec<f64> = (0..3)
            .map(|c| ssim::ssim_channel(&r, &a, c, range).unwrap().mean)
            .collect();
        let t_ssim = secs(t);
        assert_eq!(
            before, after,
            "the vectorised SSIM must equal the per-pixel gathers"
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

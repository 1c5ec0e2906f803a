//! `cargo bench --bench compare`: the comparison on a 3840×2160 LDR and HDR (float) pair. Three
//! modes:
//!
//! - no argument: the time of each metric and of the whole `compare` for both pairs, before
//!   (FLIP through nv-flip, single-threaded C++ on 8-bit sRGB, one call per HDR exposure; the
//!   former SSIM of `tests/compare/former_ssim.rs`) and after (pgt's float FLIP in parallel
//!   bands, the vectorised SSIM), in one run, wall seconds and, for `compare`, CPU seconds
//!   (user + system) with their ratios;
//! - `-- commands OLD_PGT NEW_PGT [DIR] [REPS]`: whole `pgt compare` commands (reading, metrics,
//!   JSON) of two pgt binaries on the same pairs as files, alternately, REPS times each (default
//!   3), wall and CPU seconds per run and the ratio of the medians (the pairs are written to DIR,
//!   default `/tmp/pgt-compare-timing`, when missing);
//! - `-- write-pairs DIR`: writes the pairs as files: `ldr_ref.png`/`ldr_approx.png` (8-bit
//!   sRGB) and `hdr_ref.exr`/`hdr_approx.exr` (float, values up to 8).
//!
//! The machine may be shared: wall times swing with the load, so compare ratios within one run.

#[path = "../tests/compare/former_ssim.rs"]
mod former;

use pgt::image_io::RgbImage;
use pgt::metrics::{compare, errors, flip, ssim, CompareOptions};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// CPU seconds (user + system) of this process so far, from /proc/self/stat (Linux; 0 elsewhere).
/// On a shared machine wall times swing with the load; CPU time measures the work itself.
fn cpu() -> f64 {
    proc_stat_seconds(11, 12)
}

/// CPU seconds (user + system) of the children this process has waited for.
fn children_cpu() -> f64 {
    proc_stat_seconds(13, 14)
}

/// The sum of two tick counts of /proc/self/stat, in seconds.
fn proc_stat_seconds(user: usize, system: usize) -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(vec![], |(_, rest)| rest.split_whitespace().collect());
    // Fields 14 to 17 of the file (utime, stime, cutime, cstime) are 11 to 14 after the
    // command name, in USER_HZ = 100 ticks per second.
    let tick = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (tick(user) + tick(system)) / 100.0
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
                        .map(|c| former::ssim_channel_before(r, a, c, range))
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

/// The metrics one by one and the whole `compare`, before and after, on the 4K pairs.
fn metric_timings() {
    let threads = rayon::current_num_threads();
    for (name, scale) in [("LDR", 1.0f32), ("HDR", 8.0)] {
        let (r, a) = former::pair(3840, 2160, scale);
        let range = scale as f64;
        let t = Instant::now();
        let before: Vec<f64> = (0..3)
            .map(|c| former::ssim_channel_before(&r, &a, c, range))
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
        println!(
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
    }
}

/// Writes the pairs into `dir` (see the module doc).
fn write_pairs(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for (name, scale, ext) in [("ldr", 1.0f32, "png"), ("hdr", 8.0, "exr")] {
        let (r, a) = former::pair(3840, 2160, scale);
        for (image, which) in [(&r, "ref"), (&a, "approx")] {
            let path = dir.join(format!("{name}_{which}.{ext}"));
            pgt::image_io::write_image(&path, image, &[], 0.0).unwrap();
        }
    }
}

fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    v[(v.len() - 1) / 2]
}

/// One `pgt compare` command: which pair, which binary, and its wall and CPU seconds.
struct Run {
    pair: &'static str,
    binary: &'static str,
    wall: f64,
    cpu: f64,
}

/// Whole `pgt compare` commands of two binaries on the pairs in `dir`, alternately.
fn command_timings(old: &Path, new: &Path, dir: &Path, reps: usize) {
    if !dir.join("hdr_approx.exr").exists() {
        write_pairs(dir);
    }
    let mut runs: Vec<Run> = Vec::new();
    for rep in 1..=reps {
        for (name, ext) in [("ldr", "png"), ("hdr", "exr")] {
            for (which, bin) in [("old", old), ("new", new)] {
                let (t, c) = (Instant::now(), children_cpu());
                let out = Command::new(bin)
                    .arg("compare")
                    .arg(dir.join(format!("{name}_ref.{ext}")))
                    .arg(dir.join(format!("{name}_approx.{ext}")))
                    .arg("--json")
                    .arg(dir.join(format!("{name}_{which}.json")))
                    .output()
                    .unwrap_or_else(|e| panic!("{}: {e}", bin.display()));
                let (wall, cpu) = (secs(t), children_cpu() - c);
                // Exit 1 is a failed gate (none is set here); 2 is an error, which times nothing.
                assert!(
                    matches!(out.status.code(), Some(0 | 1)),
                    "{} compare failed on the {name} pair: {}",
                    bin.display(),
                    String::from_utf8_lossy(&out.stderr)
                );
                println!("run {rep} {name} {which}: wall {wall:.2} s, cpu {cpu:.2} s");
                runs.push(Run {
                    pair: name,
                    binary: which,
                    wall,
                    cpu,
                });
            }
        }
    }
    for name in ["ldr", "hdr"] {
        let pick = |which: &str, f: fn(&Run) -> f64| -> f64 {
            let v: Vec<f64> = runs
                .iter()
                .filter(|r| r.pair == name && r.binary == which)
                .map(f)
                .collect();
            median(&v)
        };
        let (wo, wn) = (pick("old", |r| r.wall), pick("new", |r| r.wall));
        let (co, cn) = (pick("old", |r| r.cpu), pick("new", |r| r.cpu));
        println!(
            "{name} median: wall {wo:.2} -> {wn:.2} s ({:.2}x), cpu {co:.2} -> {cn:.2} s ({:.2}x)",
            wo / wn,
            co / cn.max(1e-9)
        );
    }
}

fn main() {
    // `cargo bench` adds `--bench`; the rest are this bench's own arguments.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    match args
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>()
        .as_slice()
    {
        [] => metric_timings(),
        ["write-pairs", dir] => write_pairs(Path::new(dir)),
        ["commands", old, new, rest @ ..] if rest.len() <= 2 => {
            let dir = rest
                .first()
                .map_or_else(|| PathBuf::from("/tmp/pgt-compare-timing"), PathBuf::from);
            let reps = rest
                .get(1)
                .map_or(3, |r| r.parse().expect("REPS is a number"));
            command_timings(Path::new(old), Path::new(new), &dir, reps);
        }
        _ => {
            eprintln!(
                "usage: cargo bench --bench compare [-- write-pairs DIR | -- commands OLD_PGT NEW_PGT [DIR] [REPS]]"
            );
            std::process::exit(2);
        }
    }
}

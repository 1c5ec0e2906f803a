//! Temporal error of a frame sequence (docs/design.md §10): the change between two frames that the
//! approximation shows and the truth does not.
//!
//! For frame t ≥ 1, with A the approximation and R the exact reference, per pixel x and channel c:
//!
//!   e_t(x, c) = |(A_t(x, c) − A_{t−1}(x, c)) − (R_t(x, c) − R_{t−1}(x, c))|
//!
//! computed in f64 from the f32 pixels (the map is stored as f32). A method that is wrong by the
//! same amount in both frames has e = 0: only a change of its error counts (popping when two
//! particles swap sorting order, flicker, shimmer). No optical flow is needed because R is exact
//! in every frame: a pixel whose truth changes (a particle moving over it) changes R and A alike.
//!
//! Reductions of one frame's map, per channel and (as everywhere in docs/design.md §5) "mean" =
//! the mean of the three channel values:
//! * `mean`: Σₓ e_t(x, c) / N over the N pixels;
//! * `p99`: the nearest-rank 99th percentile of e_t(·, c) ([`super::maps::percentile`]: the
//!   smallest value such that at least 99 % of the pixels are ≤ it);
//! * `pops`: the number of pixels with max_c e_t(x, c) > threshold (a pixel pops when any of its
//!   channels jumps by more than the threshold).

use super::maps::percentile;
use super::PerChannel;
use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use rayon::prelude::*;

/// The percentile of [`TemporalError::p99`].
pub const TEMPORAL_PERCENTILE: f64 = 99.0;

/// The temporal error of one frame t (against frame t − 1).
#[derive(Debug, Clone, PartialEq)]
pub struct TemporalError {
    /// e_t per pixel and channel.
    pub map: RgbImage,
    /// Mean of e_t over the pixels, per channel.
    pub mean: PerChannel,
    /// Nearest-rank 99th percentile of e_t over the pixels, per channel.
    pub p99: PerChannel,
    /// Pixels whose largest channel of e_t exceeds [`TemporalError::threshold`].
    pub pops: usize,
    /// The threshold `pops` counts against (radiance units, as the images).
    pub threshold: f64,
}

/// The four images of a temporal error: frames t − 1 and t of the reference and of the
/// approximation, all of one size.
#[derive(Debug, Clone, Copy)]
pub struct FramePair<'a> {
    pub reference_previous: &'a RgbImage,
    pub reference: &'a RgbImage,
    pub approximation_previous: &'a RgbImage,
    pub approximation: &'a RgbImage,
}

impl FramePair<'_> {
    /// The images with the names messages use.
    fn named(&self) -> [(&'static str, &RgbImage); 4] {
        [
            ("the reference of frame t − 1", self.reference_previous),
            ("the reference of frame t", self.reference),
            (
                "the approximation of frame t − 1",
                self.approximation_previous,
            ),
            ("the approximation of frame t", self.approximation),
        ]
    }

    /// Same size everywhere and finite values, or a message naming the image.
    fn check(&self) -> Result<()> {
        let (w, h) = (self.reference.width, self.reference.height);
        for (name, image) in self.named() {
            if (image.width, image.height) != (w, h) {
                return Err(PgtError::Usage(format!(
                    "temporal error: {name} is {}x{}, the reference of frame t is {w}x{h}",
                    image.width, image.height
                )));
            }
            if image.pixels.len() != w as usize * h as usize {
                return Err(PgtError::Usage(format!(
                    "temporal error: {name} holds {} pixels, not {w}x{h}",
                    image.pixels.len()
                )));
            }
            if !image.all_finite() {
                return Err(PgtError::Usage(format!(
                    "temporal error: {name} has a non-finite pixel value"
                )));
            }
        }
        Ok(())
    }
}

/// e_t(x, c) = |(A_t − A_{t−1}) − (R_t − R_{t−1})| of one pixel value, in f64.
#[inline]
pub fn temporal_difference(r_prev: f32, r: f32, a_prev: f32, a: f32) -> f64 {
    ((a as f64 - a_prev as f64) - (r as f64 - r_prev as f64)).abs()
}

/// The temporal error of frame t: its map, mean, 99th percentile and pop count (see the module
/// doc). Sizes must agree and values be finite, else a usage error naming the image.
pub fn temporal_error(frames: FramePair<'_>, threshold: f64) -> Result<TemporalError> {
    if !(threshold.is_finite() && threshold >= 0.0) {
        return Err(PgtError::Usage(format!(
            "temporal error: the pop threshold must be finite and ≥ 0, got {threshold}"
        )));
    }
    frames.check()?;
    let e: Vec<[f64; 3]> = frames
        .reference
        .pixels
        .par_iter()
        .zip(&frames.reference_previous.pixels)
        .zip(&frames.approximation.pixels)
        .zip(&frames.approximation_previous.pixels)
        .map(|(((r, rp), a), ap)| {
            std::array::from_fn(|c| temporal_difference(rp[c], r[c], ap[c], a[c]))
        })
        .collect();
    let n = e.len().max(1) as f64;
    let mean: [f64; 3] = std::array::from_fn(|c| e.iter().map(|p| p[c]).sum::<f64>() / n);
    let p99: [f64; 3] = std::array::from_fn(|c| {
        let channel: Vec<f32> = e.iter().map(|p| p[c] as f32).collect();
        percentile(&channel, TEMPORAL_PERCENTILE).map_or(0.0, f64::from)
    });
    let pops = e
        .iter()
        .filter(|p| p.iter().copied().fold(0.0, f64::max) > threshold)
        .count();
    Ok(TemporalError {
        map: RgbImage {
            width: frames.reference.width,
            height: frames.reference.height,
            pixels: e.iter().map(|p| p.map(|v| v as f32)).collect(),
        },
        mean: PerChannel::from_channels(mean),
        p99: PerChannel::from_channels(p99),
        pops,
        threshold,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(usize) -> [f32; 3]) -> RgbImage {
        RgbImage {
            width: w,
            height: h,
            pixels: (0..(w * h) as usize).map(f).collect(),
        }
    }

    fn pair<'a>(
        r0: &'a RgbImage,
        r1: &'a RgbImage,
        a0: &'a RgbImage,
        a1: &'a RgbImage,
    ) -> FramePair<'a> {
        FramePair {
            reference_previous: r0,
            reference: r1,
            approximation_previous: a0,
            approximation: a1,
        }
    }

    #[test]
    fn hand_computed_two_pixels() {
        // Pixel 0: R goes 0.2 → 0.5 (+0.3), A goes 0.1 → 0.6 (+0.5): e = 0.2 in R; G and B:
        // R +0, A +0.25 → 0.25; pixel 1 constant error (A = R + 0.1 in both frames) → 0.
        let r0 = image(2, 1, |i| if i == 0 { [0.2, 0.0, 1.0] } else { [0.4; 3] });
        let r1 = image(2, 1, |i| if i == 0 { [0.5, 0.0, 1.0] } else { [0.4; 3] });
        let a0 = image(2, 1, |i| if i == 0 { [0.1, 0.0, 1.0] } else { [0.5; 3] });
        let a1 = image(2, 1, |i| if i == 0 { [0.6, 0.25, 1.25] } else { [0.5; 3] });
        let t = temporal_error(pair(&r0, &r1, &a0, &a1), 0.21).expect("ok");
        let e0 = t.map.pixels[0];
        assert!(
            (e0[0] - 0.2).abs() < 1e-6 && (e0[1] - 0.25).abs() < 1e-7,
            "{e0:?}"
        );
        assert!((e0[2] - 0.25).abs() < 1e-7, "{e0:?}");
        assert!(
            t.map.pixels[1].iter().all(|&v| v.abs() < 1e-7),
            "{:?}",
            t.map.pixels[1]
        );
        assert!((t.mean.r - 0.1).abs() < 1e-6 && (t.mean.g - 0.125).abs() < 1e-7);
        assert!((t.mean.mean - (0.1 + 0.125 + 0.125) / 3.0).abs() < 1e-6);
        // Nearest rank of 99 % of 2 values is the larger one.
        assert!((t.p99.g - 0.25).abs() < 1e-7);
        // Pixel 0 exceeds 0.21 in G and B; pixel 1 does not.
        assert_eq!(t.pops, 1);
        let none = temporal_error(pair(&r0, &r1, &a0, &a1), 0.3).expect("ok");
        assert_eq!(none.pops, 0);
    }

    #[test]
    fn matches_brute_force_on_a_pseudo_random_sequence() {
        // A deterministic pseudo-random 7×5 image quartet against a plain loop.
        let mut s = 12345u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32) / (1u64 << 24) as f32
        };
        let (w, h) = (7u32, 5u32);
        let mut imgs: Vec<RgbImage> = Vec::new();
        for _ in 0..4 {
            let px: Vec<[f32; 3]> = (0..w * h).map(|_| [next(), next(), next()]).collect();
            imgs.push(RgbImage {
                width: w,
                height: h,
                pixels: px,
            });
        }
        let t = temporal_error(pair(&imgs[0], &imgs[1], &imgs[2], &imgs[3]), 0.5).expect("ok");
        let mut sums = [0.0f64; 3];
        let mut per: [Vec<f64>; 3] = Default::default();
        let mut pops = 0;
        for i in 0..(w * h) as usize {
            let mut worst = 0.0f64;
            for c in 0..3 {
                let e = ((imgs[3].pixels[i][c] as f64 - imgs[2].pixels[i][c] as f64)
                    - (imgs[1].pixels[i][c] as f64 - imgs[0].pixels[i][c] as f64))
                    .abs();
                sums[c] += e;
                per[c].push(e);
                worst = worst.max(e);
                assert_eq!(t.map.pixels[i][c], e as f32);
            }
            if worst > 0.5 {
                pops += 1;
            }
        }
        assert_eq!(t.pops, pops);
        for c in 0..3 {
            assert!((t.mean.get(c) - sums[c] / 35.0).abs() < 1e-12);
            per[c].sort_by(f64::total_cmp);
            // ⌈0.99·35⌉ = 35: the largest value.
            assert_eq!(t.p99.get(c), per[c][34] as f32 as f64);
        }
    }

    #[test]
    fn identical_sequences_have_zero_error_and_a_constant_offset_too() {
        let r0 = image(3, 3, |i| [i as f32 * 0.1, 0.3, 0.0]);
        let r1 = image(3, 3, |i| [i as f32 * 0.2, 0.1, 0.5]);
        let t = temporal_error(pair(&r0, &r1, &r0, &r1), 0.0).expect("ok");
        assert_eq!((t.mean.mean, t.p99.mean, t.pops), (0.0, 0.0, 0));
        let shift = |im: &RgbImage| image(3, 3, |i| im.pixels[i].map(|v| v + 0.25));
        let (a0, a1) = (shift(&r0), shift(&r1));
        let t = temporal_error(pair(&r0, &r1, &a0, &a1), 1e-6).expect("ok");
        assert!(t.p99.mean < 1e-6, "{:?}", t.p99);
        assert_eq!(t.pops, 0);
    }

    #[test]
    fn bad_inputs_are_errors_naming_the_image() {
        let a = image(2, 2, |_| [0.0; 3]);
        let b = image(3, 2, |_| [0.0; 3]);
        let e = temporal_error(pair(&a, &a, &a, &b), 0.1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("approximation of frame t is 3x2"), "{e}");
        let n = image(2, 2, |i| if i == 3 { [f32::NAN; 3] } else { [0.0; 3] });
        let e = temporal_error(pair(&n, &a, &a, &a), 0.1)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("reference of frame t − 1") && e.contains("non-finite"),
            "{e}"
        );
        let e = temporal_error(pair(&a, &a, &a, &a), -1.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("threshold"), "{e}");
    }
}

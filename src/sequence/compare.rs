//! Comparing two sequences of frames (docs/design.md §10): per frame the metrics of
//! docs/design.md §5, and for every frame after the first the temporal error
//! ([`crate::metrics::temporal`]) against the frame before it.
//!
//! A sequence is a folder (its `.exr` and `.png` files, each named with a frame number: the
//! last run of digits in the name) or a printf pattern (`out/frame_%04d.exr`: the files of that
//! folder that the pattern matches). Both sequences must hold the same frame numbers; frame t's
//! temporal error compares it with the previous frame of the list. Only two frames of each
//! sequence are held at a time.

use super::SequencePattern;
use crate::error::{PgtError, Result};
use crate::image_io::{read_image, RgbImage};
use crate::metrics::temporal::{temporal_error, FramePair, TemporalError};
use crate::metrics::{compare, CompareOptions, Comparison, PerChannel};
use std::path::{Path, PathBuf};

/// Whether a compare argument names a sequence (a folder or a pattern with one `%d`, `%0Nd` or
/// `*` in its file name) rather than one image.
pub fn is_sequence(path: &Path) -> bool {
    path.is_dir() || SequencePattern::parse(path).is_ok()
}

/// The frames of a sequence argument: (frame number, file), sorted by frame.
pub fn list_sequence(arg: &Path) -> Result<Vec<(usize, PathBuf)>> {
    if !arg.is_dir() {
        return Ok(SequencePattern::parse(arg)?
            .numbered_files()?
            .into_iter()
            .map(|(n, p)| (n as usize, p))
            .collect());
    }
    let entries = std::fs::read_dir(arg).map_err(|e| PgtError::io(arg, e))?;
    let mut frames = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| PgtError::io(arg, e))?;
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        let lower = name.to_ascii_lowercase();
        if !(lower.ends_with(".exr") || lower.ends_with(".png")) || name.starts_with('.') {
            continue;
        }
        if let Some(n) = last_number(name) {
            frames.push((n, arg.join(name)));
        }
    }
    frames.sort();
    if let Some(w) = frames.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(PgtError::Usage(format!(
            "{}: two files hold frame {}: {} and {}",
            arg.display(),
            w[0].0,
            w[0].1.display(),
            w[1].1.display()
        )));
    }
    if frames.is_empty() {
        return Err(PgtError::in_file(
            arg,
            "no frame found (a folder of .exr/.png files named with frame numbers, or a pattern such as out/frame_%04d.exr)",
        ));
    }
    Ok(frames)
}

/// The last run of ASCII digits in a file name, as a number.
fn last_number(name: &str) -> Option<usize> {
    let end = name.rfind(|c: char| c.is_ascii_digit())? + 1;
    let start = name[..end]
        .rfind(|c: char| !c.is_ascii_digit())
        .map_or(0, |i| i + 1);
    name[start..end].parse().ok()
}

/// A frame in both sequences.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePairPaths {
    pub frame: usize,
    pub reference: PathBuf,
    pub approximation: PathBuf,
}

/// The frames of both sequences side by side; frames in one and not the other are an error
/// that lists them.
pub fn pair_sequences(reference: &Path, approximation: &Path) -> Result<Vec<FramePairPaths>> {
    let r = list_sequence(reference)?;
    let a = list_sequence(approximation)?;
    let numbers = |s: &[(usize, PathBuf)]| s.iter().map(|(n, _)| *n).collect::<Vec<_>>();
    let (rn, an) = (numbers(&r), numbers(&a));
    if rn != an {
        let only = |x: &[usize], y: &[usize]| -> Vec<usize> {
            x.iter()
                .filter(|n| y.binary_search(n).is_err())
                .copied()
                .collect()
        };
        let show = |v: Vec<usize>| -> String {
            let n = v.len();
            let mut s: Vec<String> = v.into_iter().take(10).map(|f| f.to_string()).collect();
            if n > 10 {
                s.push(format!("… ({n} in all)"));
            }
            s.join(", ")
        };
        let (missing_a, missing_r) = (only(&rn, &an), only(&an, &rn));
        let mut parts = vec![format!(
            "the sequences differ: {} holds {} frame(s), {} holds {}",
            reference.display(),
            rn.len(),
            approximation.display(),
            an.len()
        )];
        if !missing_a.is_empty() {
            parts.push(format!(
                "missing from {}: frame(s) {}",
                approximation.display(),
                show(missing_a)
            ));
        }
        if !missing_r.is_empty() {
            parts.push(format!(
                "missing from {}: frame(s) {}",
                reference.display(),
                show(missing_r)
            ));
        }
        return Err(PgtError::Usage(parts.join("; ")));
    }
    Ok(r.into_iter()
        .zip(a)
        .map(|((frame, reference), (_, approximation))| FramePairPaths {
            frame,
            reference,
            approximation,
        })
        .collect())
}

/// The temporal error of a frame, without its map.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TemporalSummary {
    pub mean: PerChannel,
    pub p99: PerChannel,
    pub pops: usize,
}

/// One frame's figures.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FrameFigures {
    pub frame: usize,
    /// Mean SSIM over the channels (`None` where undefined: an image smaller than the window).
    pub ssim: Option<f64>,
    pub rmse: f64,
    pub max_abs: f64,
    /// Mean FLIP (`None` where not computed).
    pub flip: Option<f64>,
    /// Against the previous frame of the list; `None` for the first.
    pub temporal: Option<TemporalSummary>,
}

/// What one frame hands to a caller that keeps more than the figures (a report's images).
pub struct FrameView<'a> {
    pub figures: &'a FrameFigures,
    pub reference: &'a RgbImage,
    pub approximation: &'a RgbImage,
    pub comparison: &'a Comparison,
    pub temporal: Option<&'a TemporalError>,
}

/// The figures of every frame, in frame order, and the pop threshold used.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SequenceComparison {
    pub frames: Vec<FrameFigures>,
    /// The threshold of the pop counts (radiance units, as the images).
    pub pop_threshold: f64,
    /// The data range of SSIM and PSNR (of the first frame where not given).
    pub data_range: f64,
}

impl SequenceComparison {
    /// The frame with the largest mean temporal p99, if there are two frames.
    pub fn worst_temporal(&self) -> Option<&FrameFigures> {
        self.frames
            .iter()
            .filter(|f| f.temporal.is_some())
            .max_by(|a, b| {
                let p = |f: &FrameFigures| f.temporal.as_ref().map_or(0.0, |t| t.p99.mean);
                p(a).total_cmp(&p(b))
            })
    }

    /// The frame with the lowest SSIM, where SSIM is defined.
    pub fn worst_ssim(&self) -> Option<&FrameFigures> {
        self.frames
            .iter()
            .filter(|f| f.ssim.is_some())
            .min_by(|a, b| a.ssim.unwrap_or(1.0).total_cmp(&b.ssim.unwrap_or(1.0)))
    }
}

/// The default pop threshold: this share of the data range (1/20 of the range: a jump an eye
/// sees on an LDR display).
pub const POP_THRESHOLD_SHARE: f64 = 0.05;

/// Compares the sequences frame by frame. `pop_threshold` `None` takes
/// [`POP_THRESHOLD_SHARE`] × the data range. `each` sees every frame's images and figures (for a
/// report) before the next is read. Errors name the frame and its files.
pub fn compare_sequences(
    pairs: &[FramePairPaths],
    options: &CompareOptions,
    pop_threshold: Option<f64>,
    each: &mut dyn FnMut(FrameView) -> Result<()>,
) -> Result<SequenceComparison> {
    let mut previous: Option<(RgbImage, RgbImage)> = None;
    let mut out = SequenceComparison {
        frames: Vec::with_capacity(pairs.len()),
        pop_threshold: 0.0,
        data_range: 0.0,
    };
    let mut options = *options;
    for p in pairs {
        let in_frame = |e: PgtError| {
            e.context(format!(
                "frame {} ({} against {})",
                p.frame,
                p.reference.display(),
                p.approximation.display()
            ))
        };
        let (r, a) = rayon::join(|| read_image(&p.reference), || read_image(&p.approximation));
        let (r, a) = (r?, a?);
        let cmp = compare(&r, &a, &options).map_err(in_frame)?;
        if out.frames.is_empty() {
            // Every frame uses the first frame's data range, so the frames' SSIM compare.
            options.data_range = Some(cmp.data_range);
            out.data_range = cmp.data_range;
            out.pop_threshold = pop_threshold.unwrap_or(POP_THRESHOLD_SHARE * cmp.data_range);
        }
        let temporal = match &previous {
            None => None,
            Some((rp, ap)) => Some(
                temporal_error(
                    FramePair {
                        reference_previous: rp,
                        reference: &r,
                        approximation_previous: ap,
                        approximation: &a,
                    },
                    out.pop_threshold,
                )
                .map_err(in_frame)?,
            ),
        };
        let mean = |f: fn(&crate::metrics::errors::ChannelErrors) -> f64| cmp.error_values(f).mean;
        let figures = FrameFigures {
            frame: p.frame,
            ssim: cmp.ssim_values().map(|s| s.mean),
            rmse: mean(|e| e.rmse),
            max_abs: cmp.errors.iter().map(|e| e.max_abs).fold(0.0, f64::max),
            flip: cmp.flip_mean(),
            temporal: temporal.as_ref().map(|t| TemporalSummary {
                mean: t.mean,
                p99: t.p99,
                pops: t.pops,
            }),
        };
        each(FrameView {
            figures: &figures,
            reference: &r,
            approximation: &a,
            comparison: &cmp,
            temporal: temporal.as_ref(),
        })?;
        out.frames.push(figures);
        previous = Some((r, a));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_numbers_are_the_last_digits_of_a_name() {
        assert_eq!(last_number("frame_0042.exr"), Some(42));
        assert_eq!(last_number("run2_f7.png"), Some(7));
        assert_eq!(last_number("f.exr"), None);
        assert_eq!(last_number("12"), Some(12));
    }

    #[test]
    fn sequences_list_and_pair_by_frame_number() {
        let dir = tempfile::tempdir().unwrap();
        let (r, a) = (dir.path().join("r"), dir.path().join("a"));
        std::fs::create_dir_all(&r).unwrap();
        std::fs::create_dir_all(&a).unwrap();
        for f in [0, 1, 2, 10] {
            std::fs::write(r.join(format!("f_{f:03}.exr")), b"").unwrap();
        }
        for f in [0, 1, 10] {
            std::fs::write(a.join(format!("f_{f:03}.exr")), b"").unwrap();
        }
        std::fs::write(r.join("notes.txt"), b"").unwrap();
        let listed = list_sequence(&r).unwrap();
        assert_eq!(
            listed.iter().map(|(n, _)| *n).collect::<Vec<_>>(),
            vec![0, 1, 2, 10]
        );
        let by_pattern = list_sequence(&r.join("f_%03d.exr")).unwrap();
        assert_eq!(by_pattern, listed);
        assert!(list_sequence(&r.join("g_%03d.exr")).is_err());
        assert_eq!(list_sequence(&r.join("f_*.exr")).unwrap(), listed);
        let e = pair_sequences(&r, &a).unwrap_err().to_string();
        assert!(e.contains("4 frame(s)") && e.contains("frame(s) 2"), "{e}");
        std::fs::write(a.join("f_002.exr"), b"").unwrap();
        let pairs = pair_sequences(&r, &a).unwrap();
        assert_eq!(pairs.len(), 4);
        assert_eq!(pairs[3].frame, 10);
        assert!(pairs[3].approximation.ends_with("f_010.exr"));
        std::fs::write(r.join("f_2.png"), b"").unwrap();
        let e = list_sequence(&r).unwrap_err().to_string();
        assert!(e.contains("two files hold frame 2"), "{e}");
    }
}

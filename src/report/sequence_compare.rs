//! The comparison of two sequences of frames (docs/design.md §10), as `pgt compare` and
//! `pgt.compare` run it on two folders or printf patterns: per frame the metrics of
//! docs/design.md §5, the temporal error of every frame after the first, the gate (the
//! per-image thresholds held by every frame, the temporal ones by the worst frame), a JSON
//! summary and a report that plays the sequences.

use crate::metrics::gate::{Gate, GateCheck};
use crate::metrics::CompareOptions;
use crate::report::sequence_page::{write_frame_images, write_sequence_page, SequencePage};
use crate::report::summary::short;
use crate::sequence::compare::{compare_sequences, pair_sequences, SequenceComparison};
use std::path::{Path, PathBuf};

/// The per-image checks of each frame: (frame, its checks).
type FrameChecks = Vec<(usize, Vec<GateCheck>)>;

/// The JSON summary of a sequence comparison.
#[derive(Debug, serde::Serialize)]
struct SequenceSummary<'a> {
    reference: String,
    approximation: String,
    #[serde(flatten)]
    comparison: &'a SequenceComparison,
    checks: &'a [GateCheck],
    /// Frames that failed a per-image threshold.
    failed_frames: Vec<usize>,
    passed: Option<bool>,
}

/// The two sequences to compare (folders or printf patterns of frames) and how.
pub struct SequenceArgs<'a> {
    pub reference: &'a Path,
    pub approximation: &'a Path,
    pub options: CompareOptions,
    pub pop_threshold: Option<f64>,
    pub report: Option<&'a Path>,
}

/// A finished comparison of two sequences.
#[derive(Debug)]
pub struct SequenceOutcome {
    /// The reference and the approximation as given.
    pub reference: String,
    pub approximation: String,
    /// Per frame the metrics and the temporal error.
    pub comparison: SequenceComparison,
    /// The gate's checks: each per-image threshold at its worst frame, then the temporal ones.
    pub checks: Vec<GateCheck>,
    /// Frames that failed a per-image threshold.
    pub failed_frames: Vec<usize>,
    /// Whether the gate passed; `None` without a gate.
    pub passed: Option<bool>,
    /// The one-line verdict `pgt compare` prints.
    pub verdict: String,
    /// The report's page, where one was written.
    pub report_page: Option<PathBuf>,
}

impl SequenceOutcome {
    /// The JSON summary `pgt compare --json` writes (pretty-printed, with a final newline).
    pub fn summary_json(&self) -> serde_json::Result<String> {
        let summary = SequenceSummary {
            reference: self.reference.clone(),
            approximation: self.approximation.clone(),
            comparison: &self.comparison,
            checks: &self.checks,
            failed_frames: self.failed_frames.clone(),
            passed: self.passed,
        };
        Ok(serde_json::to_string_pretty(&summary)? + "\n")
    }
}

/// Compares two sequences of frames (docs/design.md §10): per frame the metrics and the
/// temporal error, the gate's checks, the verdict and, with `args.report`, the report that
/// plays the sequences (written into a temporary folder that takes its place at the end).
pub fn compare_sequence_files(args: &SequenceArgs, gate: &Gate) -> anyhow::Result<SequenceOutcome> {
    let pairs = pair_sequences(args.reference, args.approximation)?;
    let options = args.options;
    let frame_gate = gate.per_frame();
    let mut frame_checks: FrameChecks = Vec::new();
    let run_compare = |dir: Option<&Path>| -> crate::Result<(SequenceComparison, FrameChecks)> {
        let mut checks_of_frames = Vec::new();
        let mut pop_threshold = args.pop_threshold;
        let cmp = compare_sequences(&pairs, &options, args.pop_threshold, &mut |view| {
            if !frame_gate.is_empty() {
                let checks =
                    frame_gate.evaluate(view.comparison, view.reference, view.approximation)?;
                checks_of_frames.push((view.figures.frame, checks));
            }
            if let Some(dir) = dir {
                let threshold = *pop_threshold.get_or_insert(
                    crate::sequence::compare::POP_THRESHOLD_SHARE * view.comparison.data_range,
                );
                write_frame_images(dir, &view, threshold)?;
            }
            Ok(())
        })?;
        Ok((cmp, checks_of_frames))
    };
    let mut report_page = None;
    let cmp = match args.report {
        None => {
            let (cmp, checks) = run_compare(None)?;
            frame_checks = checks;
            cmp
        }
        Some(dir) => {
            let mut out = None;
            let page = crate::image_io::write_folder_atomically(dir, |tmp| {
                let (cmp, per_frame) = run_compare(Some(tmp))?;
                let (checks, failed) = evaluate(gate, &cmp, &per_frame);
                frame_checks = per_frame;
                let verdict = verdict(&cmp, &checks, &failed);
                let page = write_sequence_page(
                    tmp,
                    &cmp,
                    &SequencePage {
                        reference: &args.reference.display().to_string(),
                        approximation: &args.approximation.display().to_string(),
                        verdict: &verdict,
                        checks: &checks,
                    },
                )?;
                out = Some(cmp);
                Ok(page)
            })?;
            report_page = Some(dir.join(page.file_name().unwrap_or_default()));
            out.ok_or_else(|| anyhow::anyhow!("the report was written without a comparison"))?
        }
    };
    let (checks, failed_frames) = evaluate(gate, &cmp, &frame_checks);
    let verdict = verdict(&cmp, &checks, &failed_frames);
    let passed =
        (!gate.is_empty()).then(|| checks.iter().all(|c| c.passed) && failed_frames.is_empty());
    Ok(SequenceOutcome {
        reference: args.reference.display().to_string(),
        approximation: args.approximation.display().to_string(),
        comparison: cmp,
        checks,
        failed_frames,
        passed,
        verdict,
        report_page,
    })
}

/// The gate's checks: each per-image threshold at its worst frame, then the temporal ones at
/// theirs; and the frames that failed a per-image threshold.
fn evaluate(
    gate: &Gate,
    cmp: &SequenceComparison,
    frame_checks: &[(usize, Vec<GateCheck>)],
) -> (Vec<GateCheck>, Vec<usize>) {
    let mut failed = Vec::new();
    // Every frame has the same checks in the same order: keep, per position, the frame
    // furthest on the failing side of the threshold.
    let mut worst: Vec<(usize, GateCheck)> = Vec::new();
    for (frame, list) in frame_checks {
        if list.iter().any(|c| !c.passed) {
            failed.push(*frame);
        }
        for (i, c) in list.iter().enumerate() {
            match worst.get_mut(i) {
                None => worst.push((*frame, c.clone())),
                Some((f, k)) => {
                    let worse = if c.lower_bound {
                        c.value < k.value
                    } else {
                        c.value > k.value
                    };
                    if worse {
                        *f = *frame;
                        *k = c.clone();
                    }
                }
            }
        }
    }
    let mut checks: Vec<GateCheck> = worst
        .into_iter()
        .map(|(frame, c)| GateCheck {
            name: format!("{} (worst frame: {frame})", c.name),
            ..c
        })
        .collect();
    for (name, threshold) in gate.temporal_keys() {
        let value = cmp
            .frames
            .iter()
            .filter_map(|f| f.temporal.as_ref())
            .map(|t| match name {
                "max_temporal_p99" => t.p99.mean,
                "max_temporal_mean" => t.mean.mean,
                _ => t.pops as f64,
            })
            .fold(0.0, f64::max);
        checks.push(GateCheck {
            name: name.to_string(),
            value,
            threshold,
            passed: value <= threshold,
            lower_bound: false,
        });
    }
    (checks, failed)
}

/// The one-line verdict: frames, the worst figures, the gate.
fn verdict(cmp: &SequenceComparison, checks: &[GateCheck], failed: &[usize]) -> String {
    let mut line = format!("{} frames", cmp.frames.len());
    if let Some(f) = cmp.worst_ssim() {
        line += &format!(
            ", lowest SSIM {} (frame {})",
            short(f.ssim.unwrap_or(f64::NAN)),
            f.frame
        );
    }
    if let Some(f) = cmp.worst_temporal() {
        let t = f.temporal.as_ref().map_or(0.0, |t| t.p99.mean);
        line += &format!(", largest temporal p99 {} (frame {})", short(t), f.frame);
    }
    let pops: usize = cmp
        .frames
        .iter()
        .filter_map(|f| f.temporal.as_ref().map(|t| t.pops))
        .sum();
    line += &format!(", {pops} pops above {}", short(cmp.pop_threshold));
    if checks.is_empty() {
        return line;
    }
    let failing: Vec<&GateCheck> = checks.iter().filter(|c| !c.passed).collect();
    if failing.is_empty() {
        format!("PASS: {line}")
    } else {
        let names: Vec<String> = failing
            .iter()
            .map(|c| {
                format!(
                    "{} = {} (threshold {})",
                    c.name,
                    short(c.value),
                    short(c.threshold)
                )
            })
            .collect();
        let frames = if failed.is_empty() {
            String::new()
        } else {
            format!("; {} frame(s) failed a per-frame threshold", failed.len())
        };
        format!("FAIL: {line}; {}{frames}", names.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(name: &str, value: f64, threshold: f64, lower_bound: bool) -> GateCheck {
        let passed = if lower_bound {
            value >= threshold
        } else {
            value <= threshold
        };
        GateCheck {
            name: name.into(),
            value,
            threshold,
            passed,
            lower_bound,
        }
    }

    #[test]
    fn each_check_is_reported_at_its_worst_frame() {
        let frames: FrameChecks = vec![
            (
                0,
                vec![
                    check("channels.min_ssim[R]", 0.99, 0.95, true),
                    check("max_rmse", 0.03, 0.05, false),
                ],
            ),
            (
                1,
                vec![
                    check("channels.min_ssim[R]", 0.90, 0.95, true),
                    check("max_rmse", 0.01, 0.05, false),
                ],
            ),
            (
                2,
                vec![
                    check("channels.min_ssim[R]", 0.97, 0.95, true),
                    check("max_rmse", 0.04, 0.05, false),
                ],
            ),
        ];
        let cmp = SequenceComparison {
            frames: Vec::new(),
            pop_threshold: 0.05,
            data_range: 1.0,
        };
        let (checks, failed) = evaluate(&Gate::default(), &cmp, &frames);
        assert_eq!(failed, vec![1]);
        assert_eq!(checks[0].name, "channels.min_ssim[R] (worst frame: 1)");
        assert!(!checks[0].passed);
        assert_eq!(checks[1].name, "max_rmse (worst frame: 2)");
        assert_eq!(checks[1].value, 0.04);
    }
}

//! One comparison with its inputs, held between measuring and reporting (docs/design.md §5):
//! `pgt compare` and the Python package's `pgt.compare` both measure through
//! [`Compared::new`], gate and summarise through [`Compared::summary`] and write the HTML report
//! through [`Compared::write_report`], so the two give the same numbers and the same pages.

use super::html::{write_report, ReportInputs, ReportOptions};
use super::summary::Summary;
use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use crate::metrics::gate::Gate;
use crate::metrics::{compare, CompareOptions, Comparison};
use std::path::{Path, PathBuf};

/// Checks the options of a comparison and its report that no later step checks: the FLIP
/// viewing condition and fixed heatmap scales must be finite and > 0. Messages name the flags.
pub fn check_options(options: &CompareOptions, report: &ReportOptions) -> Result<()> {
    for (name, v) in [
        ("--error-scale", report.error_scale),
        ("--rel-scale", report.rel_scale),
    ] {
        if v.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
            return Err(PgtError::Usage(format!(
                "{name} must be a finite number > 0"
            )));
        }
    }
    if !(options.pixels_per_degree.is_finite() && options.pixels_per_degree > 0.0) {
        return Err(PgtError::Usage("--ppd must be a finite number > 0".into()));
    }
    Ok(())
}

/// A measured image pair.
#[derive(Debug, Clone)]
pub struct Compared {
    pub reference: RgbImage,
    pub approximation: RgbImage,
    /// The reference's per-pixel error estimate (its EXR `err` layer), kept only when it has the
    /// reference's size.
    pub estimate: Option<RgbImage>,
    pub comparison: Comparison,
    /// How the summary and the report name the inputs (file paths, or "array").
    pub reference_label: String,
    pub approximation_label: String,
}

impl Compared {
    /// Measures `approximation` against `reference` ([`compare`]: same size and finite values,
    /// an error otherwise).
    pub fn new(
        reference: RgbImage,
        approximation: RgbImage,
        estimate: Option<RgbImage>,
        labels: (String, String),
        options: &CompareOptions,
    ) -> Result<Compared> {
        let comparison = compare(&reference, &approximation, options)?;
        let estimate =
            estimate.filter(|e| (e.width, e.height) == (reference.width, reference.height));
        Ok(Compared {
            reference,
            approximation,
            estimate,
            comparison,
            reference_label: labels.0,
            approximation_label: labels.1,
        })
    }

    /// The summary (docs/design.md §7 `--json`) with `gate` evaluated (an empty gate checks
    /// nothing and leaves `passed` unset) and the difference set against the reference's own
    /// error estimate where there is one; `seconds` is the wall time to report.
    pub fn summary(&self, gate: &Gate, seconds: f64) -> Result<Summary> {
        let checks = gate.evaluate(&self.comparison, &self.reference, &self.approximation)?;
        let mut summary = Summary::new(
            &self.reference_label,
            &self.approximation_label,
            &self.comparison,
            checks,
            seconds,
        );
        summary.reference_uncertainty = self.estimate.as_ref().map(|e| {
            crate::metrics::errors::reference_uncertainty(&self.reference, &self.approximation, e)
        });
        Ok(summary)
    }

    /// Writes the report of `summary` into `dir` ([`write_report`]), through a temporary folder
    /// moved into place at the end (docs/design.md §7: a failed or interrupted run leaves no
    /// half-written report); returns the path of the page.
    pub fn write_report(
        &self,
        dir: &Path,
        summary: &Summary,
        options: ReportOptions,
    ) -> Result<PathBuf> {
        let inputs = ReportInputs {
            reference: &self.reference,
            approximation: &self.approximation,
            estimate: self.estimate.as_ref(),
            comparison: &self.comparison,
            summary,
            options,
        };
        let page = crate::image_io::write_folder_atomically(dir, |tmp| write_report(tmp, &inputs))?;
        Ok(dir.join(page.file_name().unwrap_or_default()))
    }
}

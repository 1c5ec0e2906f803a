//! What one run of a sweep measured: its image against the reference and against its
//! baseline run (docs/design.md §5).

use super::experiment::Run;
use crate::image_io::RgbImage;
use crate::metrics::Comparison;

/// A run compared with its baseline run.
#[derive(Debug, Clone)]
pub struct BaselineResult {
    /// The baseline run's label.
    pub label: String,
    /// The run's image against the baseline's (the baseline in the reference's place).
    pub comparison: Comparison,
    /// The same comparison under each of the experiment's `[[conventions]]`: (name, result).
    pub conventions: Vec<(String, Comparison)>,
}

/// The result of one run.
#[derive(Debug, Clone)]
pub struct RunResult {
    pub run: Run,
    /// GPU time for GPU methods, wall time for CPU ones.
    pub seconds: f64,
    /// Against the exact reference.
    pub comparison: Comparison,
    pub baseline: Option<BaselineResult>,
    /// The run's PNG, relative to the sweep's folder.
    pub image_file: String,
    /// |a − r| against the reference, mean over channels, per pixel (for the heatmaps).
    pub abs_error: Vec<f32>,
    /// The run's image (linear float), for the report's pixel probe.
    pub image: RgbImage,
    pub warnings: Vec<String>,
}

//! `pgt.compare` of two sequences of frames (docs/design.md §10): both arguments folders or
//! printf patterns of frames, through the library's `report::sequence_compare`, which
//! `pgt compare` runs too, so the figures, the verdict, the JSON summary and the report are the
//! CLI's.

use crate::compare::gate_of_any_kind;
use crate::errors::{input_error, IntoPy};
use pgt::metrics::CompareOptions;
use pgt::report::sequence_compare::{compare_sequence_files, SequenceArgs, SequenceOutcome};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A finished comparison of two sequences; see `pgt.compare`.
#[pyclass(frozen, module = "pgt")]
pub struct SequenceComparison {
    outcome: SequenceOutcome,
}

#[pymethods]
impl SequenceComparison {
    /// The frames compared.
    #[getter]
    fn frames(&self) -> usize {
        self.outcome.comparison.frames.len()
    }

    /// The one-line verdict `pgt compare` prints.
    #[getter]
    fn verdict(&self) -> &str {
        &self.outcome.verdict
    }

    /// Whether the gate passed; None without a gate.
    #[getter]
    fn passed(&self) -> Option<bool> {
        self.outcome.passed
    }

    /// The report's page, where `report=` asked for one.
    #[getter]
    fn report_page(&self) -> Option<PathBuf> {
        self.outcome.report_page.clone()
    }

    /// The JSON summary `pgt compare --json` writes, as a dict.
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = self
            .outcome
            .summary_json()
            .map_err(|e| input_error(py, e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    fn __repr__(&self) -> String {
        format!("<pgt.SequenceComparison: {}>", self.outcome.verdict)
    }
}

/// Whether a path names a sequence of frames (a folder, or a printf pattern such as
/// `frames/f_%04d.exr`) rather than one image.
#[pyfunction]
pub fn is_sequence(path: PathBuf) -> bool {
    pgt::sequence::compare::is_sequence(&path)
}

/// Compares two sequences of frames (`pgt compare REF_SEQ APPROX_SEQ`); see `pgt.compare`.
#[pyfunction]
#[pyo3(signature = (
    reference, approximation, *, data_range=None, flip=true,
    ppd=pgt::metrics::flip::DEFAULT_PIXELS_PER_DEGREE, flip_exposures=None,
    pop_threshold=None, gate=None, report=None
))]
#[allow(clippy::too_many_arguments)]
pub fn compare_sequences(
    py: Python<'_>,
    reference: PathBuf,
    approximation: PathBuf,
    data_range: Option<f64>,
    flip: bool,
    ppd: f32,
    flip_exposures: Option<(f32, f32)>,
    pop_threshold: Option<f64>,
    gate: Option<&Bound<'_, PyAny>>,
    report: Option<PathBuf>,
) -> PyResult<SequenceComparison> {
    if pop_threshold.is_some_and(|t| !(t.is_finite() && t >= 0.0)) {
        return Err(input_error(py, "pop_threshold must be a finite number ≥ 0"));
    }
    if let Some((a, b)) = flip_exposures {
        if !(a.is_finite() && b.is_finite() && a <= b) {
            return Err(input_error(
                py,
                format!("flip_exposures: expected (start, stop) in stops with start <= stop, got ({a}, {b})"),
            ));
        }
    }
    let gate = gate_of_any_kind(py, gate)?;
    let options = CompareOptions {
        data_range,
        flip,
        pixels_per_degree: ppd,
        flip_exposures,
    };
    pgt::report::compared::check_options(&options, &pgt::report::ReportOptions::default())
        .py_err(py)?;
    let outcome = py
        .detach(|| {
            compare_sequence_files(
                &SequenceArgs {
                    reference: &reference,
                    approximation: &approximation,
                    options,
                    pop_threshold,
                    report: report.as_deref(),
                },
                &gate,
            )
        })
        .py_err(py)?;
    Ok(SequenceComparison { outcome })
}

/// Adds this module's classes and functions to the extension module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<SequenceComparison>()?;
    m.add_function(wrap_pyfunction!(is_sequence, m)?)?;
    m.add_function(wrap_pyfunction!(compare_sequences, m)?)?;
    Ok(())
}

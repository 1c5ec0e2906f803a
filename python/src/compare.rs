//! `pgt.compare`: metrics, maps, gates and the HTML report of an image pair (docs/design.md
//! §5) through the library's `report::Compared`, which `pgt compare` uses too, so the numbers,
//! the gate verdicts and the pages are the CLI's.

use crate::arrays::{image_from_array, image_to_array, vec_to_array};
use crate::errors::{input_error, IntoPy};
use crate::settings;
use numpy::ndarray::Ix2;
use numpy::PyUntypedArray;
use pgt::image_io::RgbImage;
use pgt::metrics::gate::{Gate, GateCheck as LibGateCheck};
use pgt::metrics::{maps, CompareOptions, DataRangeSource, PerChannel as LibPerChannel};
use pgt::report::{Compared, ReportOptions};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Instant;

/// A metric per channel and the mean of the three (docs/design.md §5 "mean").
#[pyclass(frozen, get_all, module = "pgt")]
#[derive(Clone, Copy)]
pub struct PerChannel {
    r: f64,
    g: f64,
    b: f64,
    mean: f64,
}

impl From<LibPerChannel> for PerChannel {
    fn from(p: LibPerChannel) -> Self {
        PerChannel {
            r: p.r,
            g: p.g,
            b: p.b,
            mean: p.mean,
        }
    }
}

#[pymethods]
impl PerChannel {
    fn __repr__(&self) -> String {
        format!(
            "PerChannel(r={}, g={}, b={}, mean={})",
            self.r, self.g, self.b, self.mean
        )
    }

    /// {"R": r, "G": g, "B": b, "mean": mean}, as the JSON summary writes it.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("R", self.r)?;
        d.set_item("G", self.g)?;
        d.set_item("B", self.b)?;
        d.set_item("mean", self.mean)?;
        Ok(d)
    }
}

/// The outcome of one threshold of a gate.
#[pyclass(frozen, get_all, module = "pgt")]
#[derive(Clone)]
pub struct GateCheck {
    /// What was checked, e.g. "min_ssim", "channels.max_rmse[G]", "p99(abs) <= max".
    name: String,
    value: f64,
    threshold: f64,
    passed: bool,
}

#[pymethods]
impl GateCheck {
    fn __repr__(&self) -> String {
        format!(
            "GateCheck({:?}, value={}, threshold={}, passed={})",
            self.name,
            self.value,
            self.threshold,
            if self.passed { "True" } else { "False" }
        )
    }
}

impl From<&LibGateCheck> for GateCheck {
    fn from(c: &LibGateCheck) -> Self {
        GateCheck {
            name: c.name.clone(),
            value: c.value,
            threshold: c.threshold,
            passed: c.passed,
        }
    }
}

/// A gate evaluated on a comparison, as `pgt compare --gate` evaluates it. True in a boolean
/// context when every threshold passed: `assert (g := cmp.gate(...)), g.verdict` in a test
/// (the verdict names the thresholds that failed).
#[pyclass(frozen, module = "pgt")]
pub struct GateResult {
    /// True when every threshold passed, False when one failed, None for an empty gate.
    #[pyo3(get)]
    passed: Option<bool>,
    /// Every threshold with its value, in the order the CLI checks them.
    #[pyo3(get)]
    checks: Vec<GateCheck>,
    /// The CLI's one-line verdict: PASS or FAIL (naming what failed) and the headline metrics.
    #[pyo3(get)]
    verdict: String,
}

#[pymethods]
impl GateResult {
    fn __bool__(&self) -> bool {
        self.passed != Some(false)
    }

    /// The checks that failed.
    #[getter]
    fn failed(&self) -> Vec<GateCheck> {
        self.checks.iter().filter(|c| !c.passed).cloned().collect()
    }

    fn __repr__(&self) -> String {
        format!("<pgt.GateResult {}>", self.verdict)
    }

    /// The verdict, so that an assertion on the result shows which threshold failed.
    fn __str__(&self) -> String {
        self.verdict.clone()
    }
}

/// The gate of a `gate=` argument: a dict with the keys of a gate file, the path of a gate
/// file (TOML), or None for no thresholds. A comparison is of two images, so a threshold on
/// the temporal error of a sequence is refused, as `pgt compare` refuses it on two images.
fn gate_from(py: Python<'_>, gate: Option<&Bound<'_, PyAny>>) -> PyResult<Gate> {
    let gate = gate_of_any_kind(py, gate)?;
    if let Some((name, _)) = gate.temporal_keys().first() {
        return Err(input_error(
            py,
            format!("gate: {name} gates the temporal error of a sequence of frames; a comparison is of two images"),
        ));
    }
    Ok(gate)
}

/// The gate of a `gate=` argument (a dict, the path of a gate file or None), per-image and
/// temporal thresholds alike.
pub fn gate_of_any_kind(py: Python<'_>, gate: Option<&Bound<'_, PyAny>>) -> PyResult<Gate> {
    const NAME: &str = "gate";
    let Some(gate) = gate.filter(|g| !g.is_none()) else {
        return Ok(Gate::default());
    };
    let gate = if let Ok(d) = gate.cast::<PyDict>() {
        let text = settings::text(py, &settings::table(d, NAME)?, NAME)?;
        Gate::parse(&text, Path::new(NAME))
            .map_err(|e| settings::without_location(e, NAME))
            .py_err(py)?
    } else {
        let path: PathBuf = gate.extract().map_err(|_| {
            input_error(
                py,
                "gate: expected a dict of thresholds or the path of a gate file",
            )
        })?;
        Gate::load(&path).py_err(py)?
    };
    Ok(gate)
}

/// One side of a comparison: an image file or an array.
enum Input {
    File(PathBuf),
    Array(RgbImage),
}

fn input(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Input> {
    if obj.cast::<PyUntypedArray>().is_err() {
        if let Ok(path) = obj.extract::<PathBuf>() {
            return Ok(Input::File(path));
        }
    }
    image_from_array(name, obj).map(Input::Array)
}

/// An image pair with everything measured about it; see `pgt.compare`.
#[pyclass(frozen, module = "pgt")]
pub struct Comparison {
    compared: Compared,
    seconds: f64,
    abs_error: OnceLock<Py<PyAny>>,
    rel_error: OnceLock<Py<PyAny>>,
    ssim_map: OnceLock<Py<PyAny>>,
    flip_map: OnceLock<Py<PyAny>>,
}

/// A cached map: computed on first use, then the same read-only array every time.
fn cached<'py>(
    py: Python<'py>,
    cell: &OnceLock<Py<PyAny>>,
    make: impl FnOnce() -> Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    if let Some(v) = cell.get() {
        return Ok(v.bind(py).clone());
    }
    let value = match make() {
        Some(array) => {
            let kwargs = PyDict::new(py);
            kwargs.set_item("write", false)?;
            array.call_method("setflags", (), Some(&kwargs))?;
            array
        }
        None => py.None().into_bound(py),
    };
    let _ = cell.set(value.clone().unbind());
    Ok(cell.get().map_or(value, |v| v.bind(py).clone()))
}

#[pymethods]
impl Comparison {
    /// Image width and height in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.compared.comparison.width
    }

    #[getter]
    fn height(&self) -> u32 {
        self.compared.comparison.height
    }

    /// The data range R of SSIM and PSNR.
    #[getter]
    fn data_range(&self) -> f64 {
        self.compared.comparison.data_range
    }

    /// Where R came from: "given", "default" (1, LDR inputs) or "derived" (HDR: the
    /// reference's range).
    #[getter]
    fn data_range_source(&self) -> &'static str {
        match self.compared.comparison.data_range_source {
            DataRangeSource::Given => "given",
            DataRangeSource::Default => "default",
            DataRangeSource::Derived => "derived",
        }
    }

    /// SSIM per channel and mean (Wang et al. 2004, Gaussian window σ = 1.5); None when the
    /// image is smaller than the window (see `ssim_note`).
    #[getter]
    fn ssim(&self) -> Option<PerChannel> {
        self.compared.comparison.ssim_values().map(Into::into)
    }

    /// Why SSIM is None, or None.
    #[getter]
    fn ssim_note(&self) -> Option<String> {
        self.compared
            .comparison
            .ssim
            .as_ref()
            .err()
            .map(|e| e.to_string())
    }

    /// Root-mean-square error per channel and mean.
    #[getter]
    fn rmse(&self) -> PerChannel {
        self.compared.comparison.error_values(|e| e.rmse).into()
    }

    /// PSNR in dB per channel and mean (inf for identical channels).
    #[getter]
    fn psnr(&self) -> PerChannel {
        self.compared.comparison.error_values(|e| e.psnr).into()
    }

    /// Mean absolute error per channel and mean.
    #[getter]
    fn mean_abs(&self) -> PerChannel {
        self.compared.comparison.error_values(|e| e.mean_abs).into()
    }

    /// Mean relative error per channel and mean.
    #[getter]
    fn mean_rel(&self) -> PerChannel {
        self.compared.comparison.error_values(|e| e.mean_rel).into()
    }

    /// The largest absolute error per channel: a list of (channel, value, (x, y)).
    #[getter]
    fn max_abs(&self) -> Vec<(&'static str, f64, (u32, u32))> {
        self.compared
            .comparison
            .errors
            .iter()
            .zip(pgt::metrics::CHANNELS)
            .map(|(e, c)| (c, e.max_abs, e.max_abs_pixel))
            .collect()
    }

    /// Mean FLIP (LDR-FLIP for values in [0, 1], HDR-FLIP otherwise), or None (see
    /// `flip_note`).
    #[getter]
    fn flip(&self) -> Option<f64> {
        self.compared.comparison.flip_mean()
    }

    /// Why FLIP is None, or None.
    #[getter]
    fn flip_note(&self) -> Option<String> {
        self.compared.comparison.flip.as_ref().err().cloned()
    }

    /// The difference set against the reference's own error estimate (its err layer), when
    /// the reference had one: a dict with "max_estimate", "mean_estimate" and
    /// "exceeding_fraction" (pixel-channels where |a - r| exceeds the estimate).
    #[getter]
    fn reference_uncertainty<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(e) = &self.compared.estimate else {
            return Ok(None);
        };
        let u = pgt::metrics::errors::reference_uncertainty(
            &self.compared.reference,
            &self.compared.approximation,
            e,
        );
        let d = PyDict::new(py);
        d.set_item("max_estimate", u.max_estimate)?;
        d.set_item("mean_estimate", u.mean_estimate)?;
        d.set_item("exceeding_fraction", u.exceeding_fraction)?;
        Ok(Some(d))
    }

    /// Seconds the reading and measuring took.
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    /// |a - r| per pixel and channel, float32 (height, width, 3), read-only.
    #[getter]
    fn abs_error<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = &self.compared;
        cached(py, &self.abs_error, || {
            let map = maps::abs_error(&c.reference, &c.approximation);
            Some(image_to_array(py, map).into_any())
        })
    }

    /// |a - r| / (|r| + 0.01·R) per pixel and channel, float32 (height, width, 3), read-only.
    #[getter]
    fn rel_error<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = &self.compared;
        cached(py, &self.rel_error, || {
            let map = maps::rel_error(&c.reference, &c.approximation, c.comparison.data_range);
            Some(image_to_array(py, map).into_any())
        })
    }

    /// The SSIM map per channel, float32 (height, width, 3), read-only; None without SSIM.
    #[getter]
    fn ssim_map<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = &self.compared.comparison;
        cached(py, &self.ssim_map, || {
            let s = c.ssim.as_ref().ok()?;
            let map = maps::ssim_image(c.width, c.height, s);
            Some(image_to_array(py, map).into_any())
        })
    }

    /// The FLIP map, float32 (height, width) in [0, 1], read-only; None without FLIP.
    #[getter]
    fn flip_map<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = &self.compared.comparison;
        cached(py, &self.flip_map, || {
            let f = c.flip.as_ref().ok()?;
            let shape = Ix2(c.height as usize, c.width as usize);
            Some(vec_to_array(py, f.map.clone(), shape).into_any())
        })
    }

    /// Evaluates a gate as `pgt compare --gate` does: `gate` is a dict with the keys of a gate
    /// file (min_ssim, max_rmse, min_psnr, max_abs, max_mean_abs, max_mean_rel, max_flip,
    /// channels={...}, percentiles=[{map, percentile, max|min}]) or the path of one.
    fn gate(&self, py: Python<'_>, gate: &Bound<'_, PyAny>) -> PyResult<GateResult> {
        let gate = gate_from(py, Some(gate))?;
        let summary = self.compared.summary(&gate, self.seconds).py_err(py)?;
        Ok(GateResult {
            passed: summary.passed,
            checks: summary.gates.iter().map(Into::into).collect(),
            verdict: summary.verdict(),
        })
    }

    /// The JSON summary of `pgt compare --json` as a dict, with `gate` (dict, path or None)
    /// evaluated.
    #[pyo3(signature = (gate = None))]
    fn summary<'py>(
        &self,
        py: Python<'py>,
        gate: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let gate = gate_from(py, gate)?;
        let summary = self.compared.summary(&gate, self.seconds).py_err(py)?;
        let json = serde_json::to_string(&summary)
            .map_err(|e| input_error(py, format!("summary: {e}")))?;
        py.import("json")?.call_method1("loads", (json,))
    }

    /// The one-line verdict of `pgt compare`, with `gate` (dict, path or None) evaluated.
    #[pyo3(signature = (gate = None))]
    fn verdict(&self, py: Python<'_>, gate: Option<&Bound<'_, PyAny>>) -> PyResult<String> {
        let gate = gate_from(py, gate)?;
        Ok(self
            .compared
            .summary(&gate, self.seconds)
            .py_err(py)?
            .verdict())
    }

    /// Writes the HTML report of `pgt compare --report DIR` into `directory` (index.html, the
    /// PNGs, maps.exr, summary.json), with `gate` evaluated and the heatmap scales of
    /// --error-scale and --rel-scale; returns the path of the page. The folder is written
    /// through a temporary folder moved into place at the end.
    #[pyo3(signature = (directory, *, gate=None, error_scale=None, rel_scale=None))]
    fn write_report(
        &self,
        py: Python<'_>,
        directory: PathBuf,
        gate: Option<&Bound<'_, PyAny>>,
        error_scale: Option<f64>,
        rel_scale: Option<f64>,
    ) -> PyResult<PathBuf> {
        let options = ReportOptions {
            error_scale,
            rel_scale,
        };
        pgt::report::compared::check_options(&CompareOptions::default(), &options).py_err(py)?;
        let gate = gate_from(py, gate)?;
        let summary = self.compared.summary(&gate, self.seconds).py_err(py)?;
        let compared = &self.compared;
        py.detach(|| compared.write_report(&directory, &summary, options))
            .py_err(py)
    }

    fn __repr__(&self) -> String {
        let c = &self.compared.comparison;
        let ssim = c
            .ssim_values()
            .map_or("n/a".to_string(), |s| format!("{:.6}", s.mean));
        format!(
            "<pgt.Comparison {}x{}: SSIM {ssim}, RMSE {:.6e}, PSNR {:.2} dB>",
            c.width,
            c.height,
            c.error_values(|e| e.rmse).mean,
            c.error_values(|e| e.psnr).mean
        )
    }
}

/// Compares two images (`pgt compare`); see `pgt.compare` for the arguments.
#[pyfunction]
#[pyo3(signature = (
    reference, approximation, *, reference_err=None, data_range=None, flip=true,
    ppd=pgt::metrics::flip::DEFAULT_PIXELS_PER_DEGREE, flip_exposures=None, layer=None
))]
#[allow(clippy::too_many_arguments)]
pub fn compare(
    py: Python<'_>,
    reference: &Bound<'_, PyAny>,
    approximation: &Bound<'_, PyAny>,
    reference_err: Option<&Bound<'_, PyAny>>,
    data_range: Option<f64>,
    flip: bool,
    ppd: f32,
    flip_exposures: Option<(f32, f32)>,
    layer: Option<String>,
) -> PyResult<Comparison> {
    let start = Instant::now();
    let options = CompareOptions {
        data_range,
        flip,
        pixels_per_degree: ppd,
        flip_exposures,
    };
    pgt::report::compared::check_options(&options, &ReportOptions::default()).py_err(py)?;
    if let Some((a, b)) = flip_exposures {
        if !(a.is_finite() && b.is_finite() && a <= b) {
            return Err(input_error(
                py,
                format!("flip_exposures: expected (start, stop) in stops with start <= stop, got ({a}, {b})"),
            ));
        }
    }
    let reference = input("reference", reference)?;
    let approximation = input("approximation", approximation)?;
    let given_err = reference_err
        .filter(|e| !e.is_none())
        .map(|e| image_from_array("reference_err", e))
        .transpose()?;
    let layer = layer.as_deref();
    let label = |i: &Input| match i {
        Input::File(p) => p.display().to_string(),
        Input::Array(_) => "array".to_string(),
    };
    let labels = (label(&reference), label(&approximation));
    let estimate_path = match (&reference, &given_err) {
        (Input::File(p), None) => Some(p.clone()),
        _ => None,
    };
    let compared = py.detach(|| -> anyhow::Result<Compared> {
        let (pair, estimate) = rayon::join(
            || -> anyhow::Result<(RgbImage, RgbImage)> {
                match (reference, approximation) {
                    (Input::File(r), Input::File(a)) => {
                        pgt::image_io::load_pair(&r, &a, layer, &pgt::reference::render_scene_file)
                    }
                    (r, a) => Ok((read(r, layer)?, read(a, layer)?)),
                }
            },
            || {
                estimate_path
                    .as_deref()
                    .and_then(|p| pgt::image_io::read_reference_estimate(p, layer))
            },
        );
        let (r, a) = pair?;
        Ok(Compared::new(
            r,
            a,
            given_err.or(estimate),
            labels,
            &options,
        )?)
    });
    let compared = compared.py_err(py)?;
    Ok(Comparison {
        compared,
        seconds: start.elapsed().as_secs_f64(),
        abs_error: OnceLock::new(),
        rel_error: OnceLock::new(),
        ssim_map: OnceLock::new(),
        flip_map: OnceLock::new(),
    })
}

/// One side's image: the array as given, or the file read (an EXR's `layer`).
fn read(input: Input, layer: Option<&str>) -> pgt::Result<RgbImage> {
    match input {
        Input::Array(image) => Ok(image),
        Input::File(path) => Ok(pgt::image_io::read_image_layer(&path, layer)?.image),
    }
}

/// Adds this module's classes and functions to the extension module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PerChannel>()?;
    m.add_class::<GateCheck>()?;
    m.add_class::<GateResult>()?;
    m.add_class::<Comparison>()?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    Ok(())
}

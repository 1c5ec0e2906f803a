//! `pgt.approx`: a GPU approximation (docs/design.md §4) through the library's
//! `approx::render_approx`, the function `pgt approx` reaches: a built-in method from the
//! registry or a user's WGSL file, on whatever adapter wgpu finds (lavapipe on a machine
//! without a GPU).

use crate::arrays::image_to_array;
use crate::errors::{input_error, warn, IntoPy};
use crate::scene::Scene;
use numpy::PyArray;
use pgt::approx::{ApproxParams, Method, Timing, METHODS, N_EXACT_ALL};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// A finished GPU approximation.
#[pyclass(frozen, module = "pgt")]
pub struct ApproxResult {
    /// The image: linear RGB, float32, shape (height, width, 3), row 0 at the top.
    #[pyo3(get)]
    image: Py<PyArray<f32, numpy::Ix3>>,
    /// Time of the compute passes in seconds (see `timing`).
    #[pyo3(get)]
    gpu_seconds: f64,
    /// "timestamps" (GPU timestamp queries) or "wall" (wall time around the dispatch).
    #[pyo3(get)]
    timing: &'static str,
    /// The adapter that ran it, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    #[pyo3(get)]
    adapter: String,
    /// The method that ran ("thesis", "sorted-blend", …, or "user shader PATH").
    #[pyo3(get)]
    method: String,
    /// Its parameters with the values used (given or default); "all" is 4294967295.
    #[pyo3(get)]
    params: Vec<(String, u32)>,
    /// Dispatches it took (the thesis method on lavapipe takes several).
    #[pyo3(get)]
    passes: u32,
    /// Pixels whose rays crossed more particles than the GPU keeps (their farthest dropped).
    #[pyo3(get)]
    hit_overflow_pixels: u32,
    /// Pixels whose loops reached lavapipe's loop limit (possibly wrong on a CPU adapter).
    #[pyo3(get)]
    loop_limited_pixels: u32,
}

#[pymethods]
impl ApproxResult {
    fn __repr__(&self) -> String {
        format!(
            "<pgt.ApproxResult {} on {}: {:.3} s GPU, {} pass(es)>",
            self.method, self.adapter, self.gpu_seconds, self.passes
        )
    }
}

/// A parameter value: a non-negative integer or "all" (as `--param NAME=VALUE` takes it).
fn param_value(name: &str, v: &Bound<'_, PyAny>) -> PyResult<u32> {
    if let Ok(s) = v.extract::<String>() {
        if s.eq_ignore_ascii_case("all") {
            return Ok(N_EXACT_ALL);
        }
    }
    v.extract::<u32>().map_err(|_| {
        input_error(
            v.py(),
            format!("{name}: expected a non-negative integer or 'all', got {v}"),
        )
    })
}

/// The GPU approximation (`pgt approx`); see `pgt.approx` for the arguments.
#[pyfunction]
#[pyo3(signature = (scene, method=None, *, shader=None, adapter=None, params=None))]
pub fn approx(
    py: Python<'_>,
    scene: &Scene,
    method: Option<&str>,
    shader: Option<PathBuf>,
    adapter: Option<String>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<ApproxResult> {
    let method = match (shader, method) {
        (Some(_), Some(_)) => {
            return Err(input_error(py, "give a method or a shader, not both"));
        }
        (Some(path), None) => Some(Method::User(path)),
        (None, Some(name)) => Some(Method::named(name).py_err(py)?),
        (None, None) => None,
    };
    let mut values = Vec::new();
    if let Some(params) = params {
        for (k, v) in params.iter() {
            let name: String = k.extract()?;
            values.push((name.clone(), param_value(&name, &v)?));
        }
    }
    let params = ApproxParams {
        method,
        values,
        adapter,
    };
    let scene = &scene.inner;
    let out = py
        .detach(|| pgt::approx::render_approx(scene, &params))
        .py_err(py)?;
    for w in out.warnings() {
        warn(py, &w, 2)?;
    }
    Ok(ApproxResult {
        gpu_seconds: out.gpu_seconds,
        timing: match out.timing {
            Timing::Timestamps => "timestamps",
            Timing::Wall => "wall",
        },
        adapter: out.adapter_name.clone(),
        method: out.method.name(),
        params: out.params.clone(),
        passes: out.passes,
        hit_overflow_pixels: out.hit_overflow_pixels,
        loop_limited_pixels: out.loop_limited_pixels,
        image: image_to_array(py, out.image).unbind(),
    })
}

/// The built-in approximation methods: a list of dicts with "name", "summary" and "params"
/// (each a dict with "name", "default", "min", "max", "doc"), as `pgt approx --list-methods`
/// prints them.
#[pyfunction]
pub fn approx_methods(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let out = PyList::empty(py);
    for m in METHODS {
        let d = PyDict::new(py);
        d.set_item("name", m.name())?;
        d.set_item("summary", m.summary())?;
        let params = PyList::empty(py);
        for p in m.params() {
            let pd = PyDict::new(py);
            pd.set_item("name", p.name)?;
            pd.set_item("default", p.default)?;
            pd.set_item("min", p.min)?;
            pd.set_item("max", p.max)?;
            pd.set_item("doc", p.doc)?;
            params.append(pd)?;
        }
        d.set_item("params", params)?;
        out.append(d)?;
    }
    Ok(out)
}

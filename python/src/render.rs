//! `pgt.render`: the exact reference (docs/design.md §3) through the library's
//! `reference::render_controlled`, the same function `pgt render` reaches, so the values are
//! the CLI's bit for bit.
//!
//! A good citizen of the Python process: the render runs on a thread of its own (and rayon's
//! workers) while the calling thread waits without the GIL, waking every [`POLL`] to run
//! Python's signal handlers and the progress callback. A KeyboardInterrupt (or an exception
//! of the callback) stops the render through its `RenderControl` (each worker finishes the
//! tile it is on), waits for it to end, and propagates: nothing keeps running, nothing is
//! returned or written.

use crate::arrays::image_to_array;
use crate::errors::{input_error, internal_error, to_py, warn};
use crate::scene::Scene;
use numpy::{PyArray, PyUntypedArrayMethods};
use pgt::reference::{Integrator, RenderControl, RenderOptions};
use pyo3::prelude::*;
use std::sync::{Condvar, Mutex};
use std::time::Duration;

/// How often the waiting thread looks at signals and progress.
const POLL: Duration = Duration::from_millis(50);

/// A finished reference render.
#[pyclass(frozen, module = "pgt")]
pub struct RenderResult {
    /// The image: linear RGB, float32, shape (height, width, 3), row 0 at the top.
    #[pyo3(get)]
    image: Py<PyArray<f32, numpy::Ix3>>,
    /// The per-pixel error bound |stored - true| (the EXR's err layer), float32
    /// (height, width, 3); None in opaque mode, which is closed-form.
    #[pyo3(get)]
    err: Option<Py<PyArray<f32, numpy::Ix3>>>,
    /// Wall time of the render in seconds.
    #[pyo3(get)]
    seconds: f64,
    /// Camera rays (pixels times spp²).
    #[pyo3(get)]
    primary_rays: u64,
    /// Shadow rays traced.
    #[pyo3(get)]
    shadow_rays: u64,
    /// The largest and the mean per-pixel, per-channel error estimate (None without one).
    #[pyo3(get)]
    max_error: Option<f64>,
    #[pyo3(get)]
    mean_error: Option<f64>,
    /// Pixels that did not reach tol (reported, not hidden: docs/design.md §3).
    #[pyo3(get)]
    unconverged: u64,
    /// The unconverged pixel with the largest error estimate: (x, y, estimate), or None.
    #[pyo3(get)]
    worst_unconverged: Option<(u32, u32, f64)>,
    /// The tolerance the render was asked for.
    #[pyo3(get)]
    tol: f64,
}

#[pymethods]
impl RenderResult {
    /// Writes the image as `pgt render -o PATH` does: EXR with the err layer (err.R/G/B), or
    /// an 8-bit sRGB PNG with `exposure` in stops.
    #[pyo3(signature = (path, *, exposure = 0.0))]
    fn write(&self, py: Python<'_>, path: std::path::PathBuf, exposure: f32) -> PyResult<()> {
        let image = self.image.bind(py).as_any().clone();
        let err = self.err.as_ref().map(|e| e.bind(py).as_any().clone());
        crate::images::write(py, path, &image, err.as_ref(), exposure)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let shape = self.image.bind(py).shape().to_vec();
        let mut s = format!(
            "<pgt.RenderResult {}x{} in {:.2} s: {} primary + {} shadow rays",
            shape[1], shape[0], self.seconds, self.primary_rays, self.shadow_rays
        );
        if let (Some(max), Some(mean)) = (self.max_error, self.mean_error) {
            s += &format!(", error estimate max {max:.3e} mean {mean:.3e}");
        }
        if self.unconverged > 0 {
            s += &format!(", {} unconverged", self.unconverged);
        }
        s + ">"
    }
}

/// Runs `work` on a thread of its own while this thread waits without the GIL, polling
/// signals and calling `progress(done, total)` every [`POLL`]; stops the work through `control`
/// when either raises, and returns only once the work has ended.
fn run_polled<T: Send>(
    py: Python<'_>,
    control: &RenderControl,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce() -> pgt::Result<T> + Send,
) -> PyResult<pgt::Result<T>> {
    let slot: Mutex<Option<std::thread::Result<pgt::Result<T>>>> = Mutex::new(None);
    let ready = Condvar::new();
    let wait_for = |timeout: Option<Duration>| {
        let guard = slot.lock().unwrap_or_else(|e| e.into_inner());
        let guard = match timeout {
            Some(t) => {
                ready
                    .wait_timeout_while(guard, t, |v| v.is_none())
                    .unwrap_or_else(|e| e.into_inner())
                    .0
            }
            None => ready
                .wait_while(guard, |v| v.is_none())
                .unwrap_or_else(|e| e.into_inner()),
        };
        guard.is_some()
    };
    std::thread::scope(|s| {
        let worker = s.spawn(|| {
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(work));
            *slot.lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
            ready.notify_all();
        });
        // The scope itself waits only for the closure to return; the thread then still runs
        // its thread-locals' destructors (rayon's among them) and exits. Joining it waits for
        // that too, so no thread of this call outlives it (python/tests/test_threads.py counts
        // the process's threads).
        let join = || {
            // The closure catches every panic, so the thread cannot end in one.
            let _ = worker.join();
        };
        let mut shown = (u64::MAX, u64::MAX);
        loop {
            if py.detach(|| wait_for(Some(POLL))) {
                break;
            }
            let mut stop = py.check_signals().err();
            if stop.is_none() {
                if let Some(callback) = progress {
                    let now = control.progress();
                    if now != shown && now.1 > 0 {
                        shown = now;
                        stop = callback.call1(now).err();
                    }
                }
            }
            if let Some(e) = stop {
                control.stop();
                py.detach(join);
                return Err(e);
            }
        }
        py.detach(join);
        if let Some(callback) = progress {
            let now = control.progress();
            if now != shown && now.1 > 0 {
                callback.call1(now)?;
            }
        }
        let result = slot
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
            .expect("the slot is filled before the wait ends");
        result.map_err(|panic| {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            internal_error(
                py,
                format!("internal error: the render panicked ({what}); please report it"),
            )
        })
    })
}

/// The reference render (`pgt render`); see `pgt.render` for the arguments.
#[pyfunction]
#[pyo3(signature = (scene, *, threads=None, spp=1, tol=None, integrator="adaptive", samples=100, progress=None, gpu=false, adapter=None))]
#[allow(clippy::too_many_arguments)]
pub fn render(
    py: Python<'_>,
    scene: &Scene,
    threads: Option<usize>,
    spp: u32,
    tol: Option<f64>,
    integrator: &str,
    samples: u32,
    progress: Option<&Bound<'_, PyAny>>,
    gpu: bool,
    adapter: Option<String>,
) -> PyResult<RenderResult> {
    let integrator = match integrator {
        "adaptive" => Integrator::Adaptive,
        "riemann" if samples == 0 => {
            return Err(input_error(py, "--samples must be at least 1"));
        }
        "riemann" => Integrator::Riemann { samples },
        other => {
            return Err(input_error(
                py,
                format!("integrator: expected 'adaptive' or 'riemann', got '{other}'"),
            ));
        }
    };
    let options = RenderOptions {
        spp,
        threads,
        progress: false,
        integrator,
    };
    let progress = progress.filter(|p| !p.is_none());
    // A different tolerance is a different scene (the estimator reads it from the scene).
    let retolled;
    let scene: &pgt::Scene = match tol {
        Some(t) => {
            let mut s = (*scene.inner).clone();
            s.render.tol = pgt::scene::checked_tol_override(t).map_err(|e| to_py(py, e))?;
            retolled = s;
            &retolled
        }
        None => &scene.inner,
    };
    let control = RenderControl::default();
    let out = run_polled(py, &control, progress, || {
        if gpu {
            // docs/design.md §12: the same reference on the GPU in f64 (not stoppable midway).
            pgt::reference::gpu::render(scene, &options, adapter.as_deref())
        } else {
            pgt::reference::render_controlled(scene, &options, &control)
        }
    })?
    .map_err(|e| to_py(py, e))?;
    let s = out.stats;
    if let Some(w) = pgt::reference::unconverged_warning(&s, scene.render.tol) {
        warn(py, &w, 2)?;
    }
    let above_tol = out.error.as_ref().and_then(|err| {
        pgt::reference::err_above_tol_warning(&out.image, err, scene.render.tol, scene)
    });
    if let Some(w) = above_tol {
        warn(py, &w, 2)?;
    }
    Ok(RenderResult {
        image: image_to_array(py, out.image).unbind(),
        err: out.error.map(|e| image_to_array(py, e).unbind()),
        seconds: s.seconds,
        primary_rays: s.primary_rays,
        shadow_rays: s.shadow_rays,
        max_error: s.max_error,
        mean_error: s.mean_error,
        unconverged: s.unconverged,
        worst_unconverged: s.worst_unconverged,
        tol: scene.render.tol,
    })
}

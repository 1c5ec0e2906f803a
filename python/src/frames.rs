//! `pgt.Frames`: a scene over frames (docs/design.md §10) through the library's
//! `scene::SceneFrames`, the loader `pgt info` uses for frames: MMPLD frames, PDB/mmCIF models,
//! multi-frame XYZ, numbered sequences and DCD/XTC trajectories, and camera orbits and
//! keyframes. Frame t is built on demand as a `pgt.Scene`, to render or export like any other.

use crate::errors::{input_error, IntoPy};
use crate::scene::{scene_load_options, warn_all, Scene};
use pgt::scene::SceneFrames;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

/// A scene whose particles or camera change from frame to frame; build one with
/// `pgt.load_frames`. `frame(t)` is the scene of frame t.
#[pyclass(frozen, module = "pgt")]
pub struct Frames {
    inner: SceneFrames,
}

/// Loads a scene over frames with the overrides of `load_scene`.
#[pyfunction]
#[pyo3(signature = (path, *, size=None, mode=None, model=None, tol=None, format=None))]
pub fn load_frames(
    py: Python<'_>,
    path: PathBuf,
    size: Option<&Bound<'_, PyAny>>,
    mode: Option<&str>,
    model: Option<&str>,
    tol: Option<f64>,
    format: Option<&str>,
) -> PyResult<Frames> {
    let options = scene_load_options(py, size, mode, model, tol, format)?;
    let frames = py
        .detach(|| SceneFrames::load(&path, &options))
        .py_err(py)?;
    warn_all(py, frames.first(), 2)?;
    Ok(Frames { inner: frames })
}

#[pymethods]
impl Frames {
    /// The number of frames; None when no particle source plays frames (only the camera
    /// moves, for any number of frames).
    #[getter]
    fn frame_count(&self) -> Option<usize> {
        self.inner.frame_count()
    }

    /// Picoseconds between frames where the trajectory says (XTC, DCD), else None.
    #[getter]
    fn time_step_ps(&self) -> Option<f64> {
        self.inner.frame_info().and_then(|i| i.time_step_ps)
    }

    /// The scene of frame `index` (0-based): the particles of that frame of every playing
    /// source, the others as in frame 0, the camera of the camera path. A frame past the end
    /// raises InputError naming the file and the frame.
    fn frame(&self, py: Python<'_>, index: i64) -> PyResult<Scene> {
        let index = usize::try_from(index).map_err(|_| {
            input_error(
                py,
                format!("index: expected a frame number >= 0, got {index}"),
            )
        })?;
        let frames = &self.inner;
        let scene = py.detach(|| frames.frame(index)).py_err(py)?;
        warn_all(py, &scene, 2)?;
        Ok(Scene {
            inner: Arc::new(scene),
        })
    }

    /// The number of frames (TypeError when it is open: see `frame_count`).
    fn __len__(&self) -> PyResult<usize> {
        self.inner.frame_count().ok_or_else(|| {
            pyo3::exceptions::PyTypeError::new_err(
                "the scene's frame count is open (no particle source plays frames); give frame numbers to frame()",
            )
        })
    }

    fn __repr__(&self) -> String {
        let first = self.inner.first();
        let count = self
            .inner
            .frame_count()
            .map_or("open".to_string(), |n| n.to_string());
        format!(
            "<pgt.Frames {}: {count} frames, {} particles in frame 0, {}x{}>",
            first.source.display(),
            first.particles.len(),
            first.camera.width,
            first.camera.height
        )
    }
}

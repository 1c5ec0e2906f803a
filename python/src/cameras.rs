//! `pgt.dataset_cameras`: the cameras of a dataset (a COLMAP model, a `transforms.json`, a 3DGS
//! `cameras.json`) as a splatting rasteriser takes them, read by pgt's own readers
//! (`pgt::formats::cameras`, docs/design.md §1 "Cameras of datasets") and written out as
//! `pgt camera --json` writes a camera (`pgt::geometry::projection::CameraJson`).

use crate::arrays::vec_to_array;
use crate::errors::IntoPy;
use glam::DVec3;
use numpy::ndarray::{Ix1, Ix2};
use pgt::geometry::projection::CameraJson;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Every image's camera of the dataset at `path`, in the order the format plays them (COLMAP
/// sorted by image name, the JSON files in their own order): per image a dict of "name",
/// "width", "height", "K" (3, 3) in pixels with pixel centres at +0.5, the OpenCV
/// world-to-camera "R" (3, 3) and "t" (3,), "viewmat" (4, 4) = [[R, t], [0, 0, 0, 1]] (gsplat's
/// `viewmats`), "eye" (3,) and the nerfstudio "camera_to_world" (4, 4).
#[pyfunction]
pub fn dataset_cameras<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let cameras = py
        .detach(|| pgt::formats::cameras::read(&path))
        .py_err(py)?;
    cameras
        .iter()
        .map(|c| {
            let json = CameraJson::new(&c.camera, std::iter::empty(), DVec3::ZERO);
            let out = PyDict::new(py);
            let rows3 = |m: &[[f64; 3]; 3]| {
                vec_to_array(py, m.iter().flatten().copied().collect(), Ix2(3, 3))
            };
            let rows4 = |m: &[[f64; 4]; 4]| {
                vec_to_array(py, m.iter().flatten().copied().collect(), Ix2(4, 4))
            };
            let mut viewmat = [[0.0; 4]; 4];
            for (row, (r, t)) in viewmat.iter_mut().zip(json.r.iter().zip(json.t)) {
                row[..3].copy_from_slice(r);
                row[3] = t;
            }
            viewmat[3][3] = 1.0;
            out.set_item("name", &c.name)?;
            out.set_item("width", json.width)?;
            out.set_item("height", json.height)?;
            out.set_item("K", rows3(&json.k))?;
            out.set_item("R", rows3(&json.r))?;
            out.set_item("t", vec_to_array(py, json.t.to_vec(), Ix1(3)))?;
            out.set_item("viewmat", rows4(&viewmat))?;
            out.set_item("eye", vec_to_array(py, json.eye.to_vec(), Ix1(3)))?;
            out.set_item("camera_to_world", rows4(&json.nerfstudio_camera_to_world))?;
            Ok(out)
        })
        .collect()
}

//! Image files (docs/design.md §7) through the library's `image_io`: EXR (linear float32
//! R, G, B and named layers such as the reference's err.R/G/B) and PNG (8-bit sRGB of the
//! linear image, written atomically).

use crate::arrays::{image_from_array, image_to_array};
use crate::errors::{input_error, IntoPy};
use numpy::PyArray;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Reads an image as linear RGB float32 of shape (height, width, 3): an EXR's R, G, B (or
/// the channels LAYER.R/G/B, e.g. layer="err" for the reference's error bound), or a PNG
/// (8 or 16 bit, sRGB-decoded).
#[pyfunction]
#[pyo3(signature = (path, *, layer=None))]
pub fn read_image(
    py: Python<'_>,
    path: PathBuf,
    layer: Option<String>,
) -> PyResult<Bound<'_, PyArray<f32, numpy::Ix3>>> {
    let read = py
        .detach(|| pgt::image_io::read_image_layer(&path, layer.as_deref()))
        .py_err(py)?;
    Ok(image_to_array(py, read.image))
}

/// Writes `image` (and an `err` layer, EXR only) as `pgt render -o PATH` writes its output.
pub fn write(
    py: Python<'_>,
    path: PathBuf,
    image: &Bound<'_, PyAny>,
    err: Option<&Bound<'_, PyAny>>,
    exposure: f32,
) -> PyResult<()> {
    if !exposure.is_finite() {
        return Err(input_error(py, "--exposure must be a finite number"));
    }
    let image = image_from_array("image", image)?;
    let err = err
        .filter(|e| !e.is_none())
        .map(|e| image_from_array("err", e))
        .transpose()?;
    if let Some(e) = &err {
        if (e.width, e.height) != (image.width, image.height) {
            return Err(input_error(
                py,
                format!(
                    "err: expected the image's shape ({}, {}, 3), got ({}, {}, 3)",
                    image.height, image.width, e.height, e.width
                ),
            ));
        }
    }
    py.detach(|| {
        let layers: Vec<(&str, &pgt::image_io::RgbImage)> =
            err.iter().map(|e| ("err", e)).collect();
        pgt::image_io::write_image(&path, &image, &layers, exposure)
    })
    .py_err(py)
}

/// Writes an image: EXR (float32 R, G, B, and the err layer err.R/G/B when `err` is given) or
/// PNG (8-bit sRGB of the linear values scaled by 2**exposure), by the path's extension;
/// atomically (a temporary file renamed at the end).
#[pyfunction]
#[pyo3(signature = (path, image, *, err=None, exposure=0.0))]
pub fn write_image(
    py: Python<'_>,
    path: PathBuf,
    image: &Bound<'_, PyAny>,
    err: Option<&Bound<'_, PyAny>>,
    exposure: f32,
) -> PyResult<()> {
    write(py, path, image, err, exposure)
}

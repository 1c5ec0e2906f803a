//! The `cameras.json` that 3D Gaussian splatting training writes (graphdeco-inria
//! `gaussian-splatting`, `utils/camera_utils.py` `camera_to_JSON`; docs/design.md §1 "Cameras of
//! datasets"): an array of `{id, img_name, width, height, position, rotation, fx, fy}`.
//! `position` is the eye; `rotation` is the camera-to-world rotation in OpenCV camera axes (its
//! columns are the camera's x right, y down, z forward in the world), so the world-to-camera R
//! is its transpose. 3DGS has no principal point: cx = W/2, cy = H/2. Cameras play in the file's
//! order.

use super::{image_side, DatasetCamera};
use crate::error::{PgtError, Result};
use crate::geometry::{check_rotation, Camera, Intrinsics, Lens};
use glam::{DMat3, DVec3};
use serde::Deserialize;
use std::path::Path;

/// One entry, as 3DGS writes it (other keys are ignored).
#[derive(Deserialize)]
struct Entry {
    img_name: String,
    width: f64,
    height: f64,
    position: [f64; 3],
    rotation: [[f64; 3]; 3],
    fx: f64,
    fy: f64,
}

/// The cameras of a `cameras.json` (`text`, read from `path`).
pub fn parse(text: &str, path: &Path) -> Result<Vec<DatasetCamera>> {
    let entries: Vec<Entry> = serde_json::from_str(text).map_err(|e| {
        PgtError::at_line(
            path,
            e.line().max(1),
            format!("not a 3DGS cameras.json: {e}"),
        )
    })?;
    let mut out = Vec::with_capacity(entries.len());
    for (i, e) in entries.into_iter().enumerate() {
        let err = |m: String| {
            let line = text
                .match_indices("\"img_name\"")
                .nth(i)
                .map_or(1, |(o, _)| crate::error::line_of(text, o));
            PgtError::at_line(path, line, format!("camera {i} ({:?}): {m}", e.img_name))
        };
        let (Some(w), Some(h)) = (image_side(e.width), image_side(e.height)) else {
            return Err(err(format!(
                "size {}x{} is not an image size",
                e.width, e.height
            )));
        };
        if !(e.fx > 0.0 && e.fy > 0.0 && e.fx.is_finite() && e.fy.is_finite()) {
            return Err(err(format!(
                "fx = {}, fy = {} must be finite and > 0",
                e.fx, e.fy
            )));
        }
        let eye = DVec3::from(e.position);
        if !eye.is_finite() {
            return Err(err("position is not finite".into()));
        }
        // `rotation` row by row is camera-to-world; R = its transpose: rows r, −u, f.
        let rotation = DMat3::from_cols_array_2d(&e.rotation);
        check_rotation(rotation).map_err(|m| err(format!("rotation {m}")))?;
        let k = Intrinsics {
            fx: e.fx,
            fy: e.fy,
            cx: 0.5 * w as f64,
            cy: 0.5 * h as f64,
        };
        let camera = Camera::from_rotation(eye, rotation, Lens::Pinhole(k), w, h);
        out.push(DatasetCamera {
            name: e.img_name,
            camera,
        });
    }
    Ok(out)
}

//! NeRF's `transforms.json` (docs/design.md §1 "Cameras of datasets") in its three dialects:
//!
//! | dialect | intrinsics | image size |
//! |---|---|---|
//! | Blender (NeRF synthetic) | `camera_angle_x` (radians, full horizontal angle): fx = fy = (W/2)/tan(angle/2) | from the image `file_path` names (`.png` added when it has no extension) |
//! | nerfstudio | `fl_x`, `fl_y`, `cx`, `cy` (pixels) | `w`, `h` |
//! | instant-ngp | as nerfstudio, or `camera_angle_x`/`camera_angle_y` | `w`, `h` |
//!
//! Every key may sit at the top level or in a frame, the frame's winning. fy is `fl_y`, else
//! (H/2)/tan(`camera_angle_y`/2), else fx; cx, cy default to W/2, H/2 (pixel centres at +0.5,
//! as in pgt). Each frame's `transform_matrix` is camera-to-world in OpenGL camera axes (x right,
//! y up, z back): its columns are r, u, −f and the eye. Lens distortion (`k1`…`k4`, `p1`, `p2`
//! non-zero) and a `camera_model` other than `OPENCV` or `PINHOLE` are refused by name. Frames
//! play in the file's order.

use super::{image_side, DatasetCamera};
use crate::error::{PgtError, Result};
use crate::geometry::{check_rotation, Camera, Intrinsics};
use glam::{DMat3, DVec3};
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};

/// Distortion coefficients that must be zero (or absent) for the pinhole to be exact.
const DISTORTION: [&str; 6] = ["k1", "k2", "k3", "k4", "p1", "p2"];

/// The size of the image at `path` from its header (PNG, the format the NeRF files use).
pub fn image_size(path: &Path) -> Option<(u32, u32)> {
    image::image_dimensions(path).ok()
}

/// The cameras of a `transforms.json` (`text`, read from `path`); `image_size` gives the size of
/// a frame's image where the file does not (the Blender dialect).
pub fn parse(
    text: &str,
    path: &Path,
    image_size: &dyn Fn(&Path) -> Option<(u32, u32)>,
) -> Result<Vec<DatasetCamera>> {
    let top: Map<String, Value> = serde_json::from_str(text).map_err(|e| {
        PgtError::at_line(path, e.line().max(1), format!("not a transforms.json: {e}"))
    })?;
    let Some(Value::Array(frames)) = top.get("frames") else {
        return Err(PgtError::in_file(
            path,
            "not a transforms.json: no \"frames\" array",
        ));
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let empty = Map::new();
    let mut out = Vec::with_capacity(frames.len());
    for (i, frame) in frames.iter().enumerate() {
        let at = |m: String| match frame_line(text, i) {
            Some(line) => PgtError::at_line(path, line, format!("frames[{i}]: {m}")),
            None => PgtError::in_file(path, format!("frames[{i}]: {m}")),
        };
        let frame = frame.as_object().unwrap_or(&empty);
        let name = match frame.get("file_path") {
            Some(Value::String(s)) => s.clone(),
            _ => return Err(at("no \"file_path\" string".into())),
        };
        let camera = frame_camera(frame, &top, dir, &name, image_size).map_err(at)?;
        out.push(DatasetCamera { name, camera });
    }
    Ok(out)
}

/// The 1-based line of frame `i`'s `transform_matrix` key (the i-th in the text), if any.
fn frame_line(text: &str, i: usize) -> Option<usize> {
    let (offset, _) = text.match_indices("\"transform_matrix\"").nth(i)?;
    Some(crate::error::line_of(text, offset))
}

/// A number of the frame or, failing that, of the top level.
fn number(
    frame: &Map<String, Value>,
    top: &Map<String, Value>,
    key: &str,
) -> Result<Option<f64>, String> {
    match frame.get(key).or_else(|| top.get(key)) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::Number(n)) => n
            .as_f64()
            .filter(|v| v.is_finite())
            .map(Some)
            .ok_or_else(|| format!("\"{key}\" is not a finite number")),
        Some(_) => Err(format!("\"{key}\" is not a number")),
    }
}

/// One frame's camera.
fn frame_camera(
    frame: &Map<String, Value>,
    top: &Map<String, Value>,
    dir: &Path,
    name: &str,
    image_size: &dyn Fn(&Path) -> Option<(u32, u32)>,
) -> Result<Camera, String> {
    if let Some(model) = frame
        .get("camera_model")
        .or_else(|| top.get("camera_model"))
    {
        if !matches!(model.as_str(), Some("OPENCV" | "PINHOLE")) {
            return Err(format!("camera_model {model} is not a pinhole (OPENCV or PINHOLE without distortion); pgt renders pinhole cameras only"));
        }
    }
    for key in DISTORTION {
        if let Some(v) = number(frame, top, key)?.filter(|v| *v != 0.0) {
            return Err(format!("lens distortion {key} = {v}: pgt renders pinhole cameras only (undistort the images first)"));
        }
    }
    let (w, h) = match (number(frame, top, "w")?, number(frame, top, "h")?) {
        (Some(w), Some(h)) => match (image_side(w), image_side(h)) {
            (Some(w), Some(h)) => (w, h),
            _ => return Err(format!("image size w = {w}, h = {h} is not a size")),
        },
        _ => {
            let image = image_path(dir, name);
            image_size(&image).ok_or_else(|| {
                format!(
                    "no image size: no \"w\" and \"h\", and the image {} cannot be read",
                    image.display()
                )
            })?
        }
    };
    let k = intrinsics(frame, top, w, h)?;
    let m = matrix(frame.get("transform_matrix"))?;
    let col = |j: usize| DVec3::new(m[0][j], m[1][j], m[2][j]);
    let (right, up, forward, eye) = (col(0), col(1), -col(2), col(3));
    check_rotation(DMat3::from_cols(right, -up, forward).transpose())
        .map_err(|e| format!("transform_matrix's rotation {e}"))?;
    Ok(Camera::from_axes(eye, [right, up, forward], k, w, h))
}

/// The intrinsics of a frame (the module doc's rules).
fn intrinsics(
    frame: &Map<String, Value>,
    top: &Map<String, Value>,
    w: u32,
    h: u32,
) -> Result<Intrinsics, String> {
    let (wf, hf) = (w as f64, h as f64);
    let fx = match (number(frame, top, "fl_x")?, number(frame, top, "camera_angle_x")?) {
        (Some(f), _) => f,
        (None, Some(a)) => 0.5 * wf / (0.5 * a).tan(),
        (None, None) => return Err("no intrinsics: neither \"fl_x\" nor \"camera_angle_x\" (in the frame or at the top level)".into()),
    };
    let fy = match (
        number(frame, top, "fl_y")?,
        number(frame, top, "camera_angle_y")?,
    ) {
        (Some(f), _) => f,
        (None, Some(a)) => 0.5 * hf / (0.5 * a).tan(),
        (None, None) => fx,
    };
    let k = Intrinsics {
        fx,
        fy,
        cx: number(frame, top, "cx")?.unwrap_or(0.5 * wf),
        cy: number(frame, top, "cy")?.unwrap_or(0.5 * hf),
    };
    if !(k.fx > 0.0 && k.fy > 0.0 && k.fx.is_finite() && k.fy.is_finite()) {
        return Err(format!(
            "the focal lengths must be finite and > 0, got fx = {}, fy = {}",
            k.fx, k.fy
        ));
    }
    Ok(k)
}

/// A frame's image: `file_path` relative to the file's folder, `.png` added without extension.
fn image_path(dir: &Path, name: &str) -> PathBuf {
    let p = dir.join(name);
    if p.extension().is_none() {
        p.with_extension("png")
    } else {
        p
    }
}

/// `transform_matrix`: 3 or 4 rows of 4 finite numbers.
fn matrix(v: Option<&Value>) -> Result<[[f64; 4]; 3], String> {
    let bad = || "\"transform_matrix\" must be 3 or 4 rows of 4 finite numbers".to_string();
    let rows = v.and_then(Value::as_array).ok_or_else(bad)?;
    if rows.len() != 3 && rows.len() != 4 {
        return Err(bad());
    }
    let mut m = [[0.0; 4]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        let r = rows[i]
            .as_array()
            .filter(|r| r.len() == 4)
            .ok_or_else(bad)?;
        for (j, x) in row.iter_mut().enumerate() {
            *x = r[j].as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
        }
    }
    Ok(m)
}

/// nerfstudio's `dataparser_transforms.json`, written beside a trained model: the transform
/// (3×4, rotation and translation) and the scale its dataparser applied to the dataset's
/// camera-to-world matrices before training (nerfstudio `DataparserOutputs.save_dataparser_transform`).
/// A camera of the dataset lands in the trained model's frame as c2w' = [transform; 0 0 0 1]·c2w,
/// its translation then multiplied by the scale ([`Dataparser::apply`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dataparser {
    /// The rows of the 3×4 transform.
    pub transform: [[f64; 4]; 3],
    pub scale: f64,
}

impl Dataparser {
    /// Reads the file at `path`: an error names it (and the line where JSON fails).
    pub fn read(path: &Path) -> Result<Dataparser> {
        Dataparser::parse(&super::read_text(path)?, path)
    }

    /// Parses a `dataparser_transforms.json` (`text`, read from `path`): `"transform"` 3 rows of
    /// 4 finite numbers (or 4 rows, the last 0 0 0 1) whose 3×3 part is a rotation, `"scale"` a
    /// finite number > 0.
    pub fn parse(text: &str, path: &Path) -> Result<Dataparser> {
        let what = "a nerfstudio dataparser_transforms.json";
        let top: Map<String, Value> = serde_json::from_str(text)
            .map_err(|e| PgtError::at_line(path, e.line().max(1), format!("not {what}: {e}")))?;
        let bad = |m: String| PgtError::in_file(path, format!("not {what}: {m}"));
        let rows = top.get("transform");
        let transform = matrix(rows).map_err(|_| {
            bad("\"transform\" must be 3 rows of 4 finite numbers (or 4, the last 0 0 0 1)".into())
        })?;
        let last = rows.and_then(Value::as_array).and_then(|r| r.get(3));
        if let Some(last) = last {
            let unit = last.as_array().is_some_and(|r| {
                r.iter().map(Value::as_f64).collect::<Vec<_>>()
                    == [Some(0.0), Some(0.0), Some(0.0), Some(1.0)]
            });
            if !unit {
                return Err(bad(format!(
                    "the fourth row of \"transform\" must be 0 0 0 1, got {last}"
                )));
            }
        }
        let rotation =
            DMat3::from_cols_array_2d(&transform.map(|r| [r[0], r[1], r[2]])).transpose();
        check_rotation(rotation).map_err(|e| bad(format!("the 3×3 part of \"transform\" {e}")))?;
        let scale = match top.get("scale") {
            Some(Value::Number(n)) => n.as_f64().filter(|s| s.is_finite() && *s > 0.0),
            _ => None,
        };
        let Some(scale) = scale else {
            return Err(bad(format!(
                "\"scale\" must be a finite number > 0, got {}",
                top.get("scale")
                    .map_or("nothing".to_string(), Value::to_string)
            )));
        };
        Ok(Dataparser { transform, scale })
    }

    /// `camera` (a dataset camera, camera-to-world) in the trained model's frame: the eye
    /// scale·(R·eye + t), the axes R·r, R·u, R·f; size and intrinsics unchanged.
    pub fn apply(&self, camera: &Camera) -> Camera {
        let m = &self.transform;
        let rotation = DMat3::from_cols_array_2d(&m.map(|r| [r[0], r[1], r[2]])).transpose();
        let t = DVec3::new(m[0][3], m[1][3], m[2][3]);
        Camera {
            position: self.scale * (rotation * camera.position + t),
            right: rotation * camera.right,
            up: rotation * camera.up,
            forward: rotation * camera.forward,
            ..*camera
        }
    }
}

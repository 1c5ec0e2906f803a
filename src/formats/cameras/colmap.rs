//! COLMAP sparse models (docs/design.md §1 "Cameras of datasets"): `cameras.txt` + `images.txt`
//! or `cameras.bin` + `images.bin`, COLMAP's own layouts (`src/colmap/scene/reconstruction_io.cc`;
//! COLMAP ≥ 3.12's `rigs.bin` and `frames.bin` beside them are not read).
//!
//! | file | per record |
//! |---|---|
//! | `cameras.txt` | `CAMERA_ID MODEL WIDTH HEIGHT PARAMS…` |
//! | `images.txt` | `IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME`, then one line of 2D points (skipped) |
//! | `cameras.bin` | u64 count; per camera u32 id, i32 model id, u64 width, u64 height, f64 params |
//! | `images.bin` | u64 count; per image u32 id, 4 f64 qvec, 3 f64 tvec, u32 camera id, NUL-ended name, u64 n, n × 24 bytes of points |
//!
//! All little-endian. qvec = (w, x, y, z) is the unit quaternion of the world-to-camera rotation
//! R and tvec its translation t (x_cam = R·x_world + t, OpenCV axes: x right, y down, z forward),
//! so the eye is −Rᵀt. Pixel centres are at +0.5 in COLMAP as in pgt, so cx, cy are taken as
//! they are. `SIMPLE_PINHOLE` (f, cx, cy) and `PINHOLE` (fx, fy, cx, cy) are exact; a model with
//! lens distortion is refused by name when an image uses it. Images play sorted by name.

use super::{image_side, DatasetCamera};
use crate::error::{Location, PgtError, Result};
use crate::geometry::{check_rotation, Camera, Intrinsics, Lens};
use glam::{DMat3, DQuat, DVec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// COLMAP's camera models by id (`src/colmap/sensor/models.h`), with their parameter counts.
const MODELS: [(&str, usize); 12] = [
    ("SIMPLE_PINHOLE", 3),
    ("PINHOLE", 4),
    ("SIMPLE_RADIAL", 4),
    ("RADIAL", 5),
    ("OPENCV", 8),
    ("OPENCV_FISHEYE", 8),
    ("FULL_OPENCV", 12),
    ("FOV", 5),
    ("SIMPLE_RADIAL_FISHEYE", 4),
    ("RADIAL_FISHEYE", 5),
    ("THIN_PRISM_FISHEYE", 12),
    ("RAD_TAN_THIN_PRISM_FISHEYE", 16),
];

/// Bytes of one 2D point in `images.bin`: f64 x, f64 y, u64 point id.
const POINT2D_BYTES: u64 = 24;

/// A camera of `cameras.*` as written, turned into intrinsics when an image uses it.
#[derive(Debug, Clone)]
struct ModelCamera {
    model: &'static str,
    width: u64,
    height: u64,
    params: Vec<f64>,
    location: Location,
}

/// An image of `images.*`: its pose and camera id.
#[derive(Debug, Clone)]
struct ModelImage {
    name: String,
    qvec: [f64; 4],
    tvec: [f64; 3],
    camera_id: u32,
    location: Location,
}

/// The model in the folder `dir`: binary when `cameras.bin` is there, else text.
pub fn read_model(dir: &Path) -> Result<Vec<DatasetCamera>> {
    let (cameras, images) = if dir.join("cameras.bin").is_file() {
        (dir.join("cameras.bin"), dir.join("images.bin"))
    } else if dir.join("cameras.txt").is_file() {
        (dir.join("cameras.txt"), dir.join("images.txt"))
    } else {
        return Err(PgtError::in_file(
            dir,
            "not a COLMAP model: the folder has neither cameras.bin nor cameras.txt",
        ));
    };
    let c = super::super::read_input(&cameras)?;
    let i = super::super::read_input(&images)?;
    if cameras.extension().is_some_and(|e| e == "bin") {
        parse_binary(&c, &cameras, &i, &images)
    } else {
        let text = |b: Vec<u8>, p: &Path| {
            String::from_utf8(b).map_err(|e| {
                PgtError::at_byte(p, e.utf8_error().valid_up_to() as u64, "not UTF-8 text")
            })
        };
        parse_text(&text(c, &cameras)?, &cameras, &text(i, &images)?, &images)
    }
}

/// A text model: `cameras.txt` and `images.txt` as read from `cameras_path` and `images_path`.
pub fn parse_text(
    cameras: &str,
    cameras_path: &Path,
    images: &str,
    images_path: &Path,
) -> Result<Vec<DatasetCamera>> {
    let mut table = HashMap::new();
    for (i, line) in cameras.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let err = |m: String| PgtError::at_line(cameras_path, i + 1, m);
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() < 4 {
            return Err(err(format!(
                "a camera line has CAMERA_ID MODEL WIDTH HEIGHT PARAMS…, got {line:?}"
            )));
        }
        let id: u32 = f[0]
            .parse()
            .map_err(|_| err(format!("CAMERA_ID {:?} is not an integer", f[0])))?;
        let (model, count) = MODELS
            .iter()
            .find(|(name, _)| *name == f[1])
            .copied()
            .ok_or_else(|| {
                err(format!(
                    "unknown camera model {:?} (COLMAP's models: {})",
                    f[1],
                    model_names()
                ))
            })?;
        let side = |k: usize, what: &str| {
            f[k].parse::<u64>()
                .map_err(|_| err(format!("{what} {:?} is not an integer", f[k])))
        };
        let (width, height) = (side(2, "WIDTH")?, side(3, "HEIGHT")?);
        let params = f[4..]
            .iter()
            .map(|p| {
                p.parse::<f64>()
                    .map_err(|_| err(format!("parameter {p:?} is not a number")))
            })
            .collect::<Result<Vec<f64>>>()?;
        if params.len() != count {
            return Err(err(format!(
                "{model} has {count} parameters, the line gives {}",
                params.len()
            )));
        }
        let location = Location::Line(i + 1);
        table.insert(
            id,
            ModelCamera {
                model,
                width,
                height,
                params,
                location,
            },
        );
    }
    let mut list = Vec::new();
    let mut lines = images.lines().enumerate();
    while let Some((i, line)) = lines.next() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        list.push(image_line(line, i + 1, images_path)?);
        // The next line holds the image's 2D points, which pgt does not need (it may be empty).
        lines.next();
    }
    cameras_of(&table, cameras_path, list, images_path)
}

/// One `IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME` line.
fn image_line(line: &str, number: usize, path: &Path) -> Result<ModelImage> {
    let err = |m: String| PgtError::at_line(path, number, m);
    let f: Vec<&str> = line.split_whitespace().collect();
    if f.len() < 10 {
        return Err(err(format!(
            "an image line has IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, got {line:?}"
        )));
    }
    let mut v = [0.0; 7];
    for (k, x) in v.iter_mut().enumerate() {
        *x = f[k + 1]
            .parse()
            .map_err(|_| err(format!("{:?} is not a number", f[k + 1])))?;
    }
    let camera_id = f[8]
        .parse()
        .map_err(|_| err(format!("CAMERA_ID {:?} is not an integer", f[8])))?;
    Ok(ModelImage {
        name: f[9].to_string(),
        qvec: [v[0], v[1], v[2], v[3]],
        tvec: [v[4], v[5], v[6]],
        camera_id,
        location: Location::Line(number),
    })
}

/// Little-endian reads from a binary file, with the byte offset in every error.
struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
    path: &'a Path,
}

impl<'a> Bytes<'a> {
    fn take(&mut self, n: u64, what: &str) -> Result<&'a [u8]> {
        let left = (self.data.len() - self.at) as u64;
        if n > left {
            return Err(PgtError::at_byte(
                self.path,
                self.at as u64,
                format!("truncated: {what} needs {n} bytes, the file ends {left} bytes later"),
            ));
        }
        let s = &self.data[self.at..self.at + n as usize];
        self.at += n as usize;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> Result<u32> {
        Ok(u32::from_le_bytes(
            self.take(4, what)?.try_into().unwrap_or_default(),
        ))
    }
    fn u64(&mut self, what: &str) -> Result<u64> {
        Ok(u64::from_le_bytes(
            self.take(8, what)?.try_into().unwrap_or_default(),
        ))
    }
    fn f64(&mut self, what: &str) -> Result<f64> {
        Ok(f64::from_le_bytes(
            self.take(8, what)?.try_into().unwrap_or_default(),
        ))
    }
    fn err(&self, at: usize, m: String) -> PgtError {
        PgtError::at_byte(self.path, at as u64, m)
    }
}

/// A binary model: the bytes of `cameras.bin` and `images.bin`.
pub fn parse_binary(
    cameras: &[u8],
    cameras_path: &Path,
    images: &[u8],
    images_path: &Path,
) -> Result<Vec<DatasetCamera>> {
    let mut b = Bytes {
        data: cameras,
        at: 0,
        path: cameras_path,
    };
    let count = b.u64("the camera count")?;
    let mut table = HashMap::new();
    for k in 0..count {
        let start = b.at;
        let id = b.u32(&format!("camera {k}"))?;
        let model_id = b.u32(&format!("camera {k}"))?;
        let Some(&(model, n)) = MODELS.get(model_id as usize) else {
            return Err(b.err(
                start,
                format!(
                    "camera {id}: unknown camera model id {model_id} (COLMAP's models: 0 to {})",
                    MODELS.len() - 1
                ),
            ));
        };
        let width = b.u64(&format!("camera {id}"))?;
        let height = b.u64(&format!("camera {id}"))?;
        let params = (0..n)
            .map(|_| b.f64(&format!("camera {id}'s parameters")))
            .collect::<Result<Vec<f64>>>()?;
        let location = Location::Byte(start as u64);
        table.insert(
            id,
            ModelCamera {
                model,
                width,
                height,
                params,
                location,
            },
        );
    }
    let mut b = Bytes {
        data: images,
        at: 0,
        path: images_path,
    };
    let count = b.u64("the image count")?;
    let mut list = Vec::with_capacity(count.min(images.len() as u64 / 64) as usize);
    for k in 0..count {
        let start = b.at;
        let what = format!("image {k}");
        let _id = b.u32(&what)?;
        let mut v = [0.0; 7];
        for x in v.iter_mut() {
            *x = b.f64(&what)?;
        }
        let camera_id = b.u32(&what)?;
        let rest = &b.data[b.at..];
        let Some(end) = rest.iter().position(|&c| c == 0) else {
            return Err(b.err(
                b.at,
                format!("truncated: image {k}'s name has no terminating NUL byte"),
            ));
        };
        let name = std::str::from_utf8(&rest[..end])
            .map_err(|_| b.err(b.at, format!("image {k}'s name is not UTF-8")))?
            .to_string();
        b.at += end + 1;
        let points = b.u64(&format!("image {name:?}'s point count"))?;
        let bytes = points.saturating_mul(POINT2D_BYTES);
        b.take(bytes, &format!("image {name:?}'s {points} 2D points"))?;
        list.push(ModelImage {
            name,
            qvec: [v[0], v[1], v[2], v[3]],
            tvec: [v[4], v[5], v[6]],
            camera_id,
            location: Location::Byte(start as u64),
        });
    }
    cameras_of(&table, cameras_path, list, images_path)
}

/// "SIMPLE_PINHOLE, PINHOLE, …".
fn model_names() -> String {
    MODELS
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Every image's camera, sorted by image name.
fn cameras_of(
    table: &HashMap<u32, ModelCamera>,
    cameras_path: &Path,
    images: Vec<ModelImage>,
    images_path: &Path,
) -> Result<Vec<DatasetCamera>> {
    let mut out = Vec::with_capacity(images.len());
    for im in images {
        let at = |m: String| PgtError::Input {
            path: images_path.to_path_buf(),
            location: im.location.clone(),
            message: format!("image {:?}: {m}", im.name),
        };
        let model = table.get(&im.camera_id).ok_or_else(|| {
            at(format!(
                "its CAMERA_ID {} is not in {}",
                im.camera_id,
                cameras_path.display()
            ))
        })?;
        let (k, w, h) = intrinsics(model, cameras_path)?;
        let [qw, qx, qy, qz] = im.qvec;
        let q = DQuat::from_xyzw(qx, qy, qz, qw);
        if !q.is_finite() || q.length() == 0.0 {
            return Err(at(format!(
                "qvec {:?} is not a non-zero finite quaternion",
                im.qvec
            )));
        }
        let t = DVec3::from(im.tvec);
        if !t.is_finite() {
            return Err(at(format!("tvec {:?} is not finite", im.tvec)));
        }
        let rotation = DMat3::from_quat(q.normalize());
        check_rotation(rotation).map_err(|m| at(format!("qvec {:?}: its R {m}", im.qvec)))?;
        let camera = Camera::from_rotation(
            Camera::eye_of(rotation, t),
            rotation,
            Lens::Pinhole(k),
            w,
            h,
        );
        out.push(DatasetCamera {
            name: im.name,
            camera,
        });
    }
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

/// The intrinsics and size of a pinhole camera; a distortion model is refused by name.
fn intrinsics(c: &ModelCamera, path: &Path) -> Result<(Intrinsics, u32, u32)> {
    let err = |m: String| PgtError::Input {
        path: PathBuf::from(path),
        location: c.location.clone(),
        message: m,
    };
    let k = match (c.model, c.params.as_slice()) {
        ("SIMPLE_PINHOLE", &[f, cx, cy]) => Intrinsics { fx: f, fy: f, cx, cy },
        ("PINHOLE", &[fx, fy, cx, cy]) => Intrinsics { fx, fy, cx, cy },
        (model, _) => {
            return Err(err(format!(
                "camera model {model} has lens distortion, which pgt does not render; SIMPLE_PINHOLE and PINHOLE are exact (undistort the images and the model first: colmap image_undistorter)"
            )))
        }
    };
    if !(k.fx > 0.0
        && k.fy > 0.0
        && k.fx.is_finite()
        && k.fy.is_finite()
        && k.cx.is_finite()
        && k.cy.is_finite())
    {
        return Err(err(format!(
            "{}: the focal lengths must be finite and > 0 and the principal point finite, got {:?}",
            c.model, c.params
        )));
    }
    let side = |v: u64| u32::try_from(v).ok().and_then(|v| image_side(v as f64));
    let (Some(w), Some(h)) = (side(c.width), side(c.height)) else {
        return Err(err(format!(
            "image size {}x{} is not a size",
            c.width, c.height
        )));
    };
    Ok((k, w, h))
}

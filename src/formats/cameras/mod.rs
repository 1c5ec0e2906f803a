//! Cameras of real datasets (docs/design.md §1 "Cameras of datasets"): a COLMAP sparse model
//! ([`colmap`], text or binary), a NeRF `transforms.json` ([`transforms`]: Blender, nerfstudio,
//! instant-ngp) or the `cameras.json` that 3D Gaussian splatting training writes
//! ([`cameras_json`]). Each reader gives every image's camera in pgt's convention (docs/design.md
//! §1: eye, r, u, f, and pinhole intrinsics in pixels with centres at +0.5), or an error naming
//! the file and the line or byte.

pub mod cameras_json;
pub mod colmap;
pub mod transforms;

use crate::error::{PgtError, Result};
use crate::geometry::Camera;
use std::path::Path;

/// One image of a dataset and its camera.
#[derive(Debug, Clone, PartialEq)]
pub struct DatasetCamera {
    /// The image's name as the file gives it (COLMAP `NAME`, `file_path`, `img_name`).
    pub name: String,
    pub camera: Camera,
}

/// The cameras of the dataset at `path`: a folder is a COLMAP model (`cameras.bin` and
/// `images.bin`, else `cameras.txt` and `images.txt`); a JSON file is a `cameras.json` when it
/// holds an array and a `transforms.json` when it holds an object. In the order the format
/// plays them: COLMAP sorted by image name, the JSON files in their own order.
pub fn read(path: &Path) -> Result<Vec<DatasetCamera>> {
    if path.is_dir() {
        return colmap::read_model(path);
    }
    let text = read_text(path)?;
    match text.trim_start().as_bytes().first() {
        Some(b'[') => cameras_json::parse(&text, path),
        Some(b'{') => transforms::parse(&text, path, &|p| transforms::image_size(p)),
        _ => Err(PgtError::in_file(
            path,
            "not a camera file: a COLMAP model folder, a transforms.json (an object) or a cameras.json (an array)",
        )),
    }
}

/// Whether `path` is a `transforms.json` as [`read`] tells it: a file whose JSON is an object.
pub fn is_transforms_json(path: &Path) -> bool {
    !path.is_dir()
        && read_text(path).is_ok_and(|t| t.trim_start().as_bytes().first() == Some(&b'{'))
}

/// The camera of the image `name` (exactly as the file writes it, or a `file_path` without its
/// leading "./" or its extension), or an error that names the file and a few of its images.
pub fn find<'a>(
    cameras: &'a [DatasetCamera],
    name: &str,
    path: &Path,
) -> Result<&'a DatasetCamera> {
    let bare = |s: &str| {
        let s = s.strip_prefix("./").unwrap_or(s);
        Path::new(s)
            .with_extension("")
            .to_string_lossy()
            .into_owned()
    };
    cameras
        .iter()
        .find(|c| c.name == name)
        .or_else(|| cameras.iter().find(|c| bare(&c.name) == bare(name)))
        .ok_or_else(|| {
            let some: Vec<&str> = cameras.iter().take(5).map(|c| c.name.as_str()).collect();
            PgtError::in_file(
                path,
                format!(
                    "no image named {name:?} among its {} image(s) ({}{})",
                    cameras.len(),
                    some.join(", "),
                    if cameras.len() > 5 { ", …" } else { "" }
                ),
            )
        })
}

/// A camera file as text (refusing a file over [`super::MAX_FILE_BYTES`] or not UTF-8).
pub(crate) fn read_text(path: &Path) -> Result<String> {
    let bytes = super::read_input(path)?;
    String::from_utf8(bytes)
        .map_err(|e| PgtError::at_byte(path, e.utf8_error().valid_up_to() as u64, "not UTF-8 text"))
}

/// An image side read from a file: an integer in [1, 2³²).
pub(crate) fn image_side(v: f64) -> Option<u32> {
    (v.fract() == 0.0 && v >= 1.0 && v <= u32::MAX as f64).then_some(v as u32)
}

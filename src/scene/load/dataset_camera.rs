//! `[camera] from = "…"` (docs/design.md §1 "Cameras of datasets"): a dataset's cameras
//! ([`crate::formats::cameras`]) as one fixed camera (`image = "…"`) or as a sequence, one
//! frame per image. The file gives pose, intrinsics and image size; `--size` scales the
//! intrinsics to another size ([`crate::geometry::Intrinsics::scaled`]); `dataparser` maps the
//! cameras of a `transforms.json` into a nerfstudio model's frame
//! ([`crate::formats::cameras::transforms::Dataparser`]).

use super::super::file::CameraTable;
use super::super::SceneLoadOptions;
use crate::error::{At, PgtError, Result, SourceText};
use crate::formats::cameras;
use crate::geometry::{Camera, CameraPath};
use std::path::Path;

/// An image size, checked against the limits (`scene::check_image_size`).
fn check_size(at: &At, w: i64, h: i64) -> Result<(u32, u32)> {
    super::super::check_image_size(w, h).map_err(|e| at.err(e))
}

/// The camera path of a `[camera]` table with `from`.
pub(super) fn path(
    source: &SourceText,
    table_at: &At,
    t: &CameraTable,
    options: &SceneLoadOptions,
) -> Result<CameraPath> {
    let set = [
        ("position", t.position.is_some()),
        ("look_at", t.look_at.is_some()),
        ("up", t.up.is_some()),
        ("fov_y", t.fov_y.is_some()),
        ("focal_length", t.focal_length.is_some()),
        ("fx", t.fx.is_some()),
        ("fy", t.fy.is_some()),
        ("cx", t.cx.is_some()),
        ("cy", t.cy.is_some()),
        ("R", t.r.is_some()),
        ("t", t.t.is_some()),
        ("width", t.width.is_some()),
        ("height", t.height.is_some()),
        ("orbit", t.orbit.is_some()),
        ("keyframes", !t.keyframes.is_empty()),
        ("interpolation", t.interpolation.is_some()),
    ];
    if let Some((key, _)) = set.iter().find(|(_, s)| *s) {
        return Err(table_at.err(format!(
            "camera.{key}: camera.from gives the cameras (pose, intrinsics and size); remove camera.{key} (`--size` scales the image)"
        )));
    }
    let from = t.from.as_deref().unwrap_or_default();
    let dataset = source.path.parent().unwrap_or(Path::new(".")).join(from);
    if !dataset.exists() {
        return Err(table_at.err(format!("camera.from: {} does not exist", dataset.display())));
    }
    let mut all = cameras::read(&dataset)?;
    if all.is_empty() {
        return Err(PgtError::in_file(&dataset, "the file lists no images"));
    }
    if let Some(dp) = &t.dataparser {
        if !cameras::is_transforms_json(&dataset) {
            return Err(table_at.err(format!(
                "camera.dataparser applies to a transforms.json (nerfstudio's dataparser transform of its cameras); camera.from is {}",
                dataset.display()
            )));
        }
        let dp = source.path.parent().unwrap_or(Path::new(".")).join(dp);
        let dataparser = cameras::transforms::Dataparser::read(&dp)?;
        for c in &mut all {
            c.camera = dataparser.apply(&c.camera);
        }
    }
    let sized = |c: &Camera| -> Result<Camera> {
        check_size(&At::whole(&dataset), c.width as i64, c.height as i64)?;
        let Some((w, h)) = options.size else {
            return Ok(*c);
        };
        check_size(&source.whole(), w as i64, h as i64)?;
        let k = c.pinhole().scaled((c.width, c.height), (w, h));
        Ok(Camera {
            width: w,
            height: h,
            ..*c
        }
        .with_intrinsics(k))
    };
    match &t.image {
        Some(name) => Ok(CameraPath::Fixed(sized(
            &cameras::find(&all, name, &dataset)?.camera,
        )?)),
        None => Ok(CameraPath::Sequence(
            all.iter()
                .map(|c| sized(&c.camera))
                .collect::<Result<_>>()?,
        )),
    }
}

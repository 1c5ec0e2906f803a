//! The two images of a comparison (docs/design.md §5): read (or a scene rendered on the fly) and
//! checked to be comparable, with messages that name the files.
//!
//! Rendering is not this module's: the caller hands over the renderer of a scene file
//! ([`RenderScene`], `crate::reference::render_scene_file` for `pgt compare` and Python).

use super::{first_non_finite, read_image_layer, ReadImage, RgbImage, CHANNELS};
use std::path::Path;

/// Renders a scene file into the image a comparison reads in its place.
pub type RenderScene = dyn Fn(&Path) -> anyhow::Result<RgbImage> + Sync;

/// Whether a path names a scene (`.toml`) rather than an image.
pub fn is_scene(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}

/// An image file, or a scene file (`.toml`) rendered on the fly by `render_scene` (docs/design.md
/// §5 "Inputs: … or scenes rendered on the fly").
fn read_or_render(
    path: &Path,
    layer: Option<&str>,
    render_scene: &RenderScene,
) -> anyhow::Result<ReadImage> {
    if !is_scene(path) {
        return Ok(read_image_layer(path, layer)?);
    }
    if layer.is_some_and(|l| !l.is_empty()) {
        anyhow::bail!(
            "{}: --layer applies to EXR files, not to a scene",
            path.display()
        );
    }
    Ok(ReadImage {
        image: render_scene(path)?,
        channels: 3,
    })
}

/// Reads both images (or renders scenes with `render_scene`) and checks that they can be
/// compared: the same size and channel count, every value finite (an error naming the files
/// otherwise).
pub fn load_pair(
    reference: &Path,
    approximation: &Path,
    layer: Option<&str>,
    render_scene: &RenderScene,
) -> anyhow::Result<(RgbImage, RgbImage)> {
    // Two files are read at once (a 4K pair: half the reading time on two cores); a scene
    // renders alone, with its progress bar, and only once the reference is there.
    let (r, a) = if is_scene(reference) || is_scene(approximation) {
        let r = read_or_render(reference, layer, render_scene)?;
        (r, read_or_render(approximation, layer, render_scene)?)
    } else {
        let (r, a) = rayon::join(
            || read_or_render(reference, layer, render_scene),
            || read_or_render(approximation, layer, render_scene),
        );
        (r?, a?)
    };
    if (r.image.width, r.image.height) != (a.image.width, a.image.height) {
        anyhow::bail!(
            "images differ in size: {} is {}x{}, {} is {}x{}",
            reference.display(),
            r.image.width,
            r.image.height,
            approximation.display(),
            a.image.width,
            a.image.height
        );
    }
    if r.channels != a.channels {
        anyhow::bail!(
            "images differ in channel count: {} has {}, {} has {}",
            reference.display(),
            r.channels,
            approximation.display(),
            a.channels
        );
    }
    for (path, img) in [(reference, &r.image), (approximation, &a.image)] {
        if let Some((x, y, c)) = first_non_finite(img) {
            anyhow::bail!(
                "{}: non-finite value ({}) at pixel ({x}, {y}), channel {}; NaN and infinity cannot be compared",
                path.display(),
                img.get(x, y)[c],
                CHANNELS[c]
            );
        }
    }
    Ok((r.image, a.image))
}

//! The summary of a file that `pgt info` prints (docs/design.md §7): a particle file in any
//! format pgt reads, a trajectory, or a scene file loaded and validated with [`crate::scene::Scene::load`]'s
//! steps (so its includes count too). The summary itself is the formats'
//! ([`crate::formats::summary`]).

use crate::formats::frames::open_frames;
use crate::formats::summary::{summarize, Info};
use crate::formats::topology::trajectory_summary;
use crate::formats::{format_of, load_bytes, read_input, Format, IncludeSpec};
use crate::scene::{SceneFrames, SceneLoadOptions};

/// Loads a file and summarises it: a scene (`.toml`) through [`crate::scene::Scene::load`], a particle file
/// through the one loading path of [`crate::formats`] (so an empty file is refused here too),
/// with the format's name and [`Format::details`] from the table of formats. `format` is
/// `--format`, for a particle file whatever its extension.
pub fn info_of(path: &std::path::Path, format: Option<&'static Format>) -> crate::Result<Info> {
    let is_toml = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    let name = path.display().to_string();
    if is_toml {
        let options = SceneLoadOptions {
            format,
            ..SceneLoadOptions::default()
        };
        let frames = SceneFrames::load(path, &options)?;
        let scene = frames.first();
        let it = scene
            .particles
            .iter()
            .map(|p| (p.center, p.radius, Some(p.color)));
        let mut info = summarize(name, "scene".into(), it, scene.warnings.clone());
        info.frames = frames.frame_info();
        return Ok(info);
    }
    if let Some(format) = Format::trajectory_of(path) {
        let (frames, first, warnings) = trajectory_summary(path)?;
        let mut info = summarize(
            name,
            format.name.to_string(),
            first.iter().map(|&c| (c, 0.0, None)),
            warnings,
        );
        info.radius = None;
        info.frames = Some(frames);
        return Ok(info);
    }
    let spec = IncludeSpec {
        format,
        ..IncludeSpec::bare(path)
    };
    let format: &Format = format_of(&spec)?;
    let bytes = read_input(path)?;
    let loaded = load_bytes(&spec, format, &bytes)?;
    let it = loaded.records.iter().map(|r| (r.center, r.radius, r.color));
    let mut info = summarize(name, format.name.to_string(), it, loaded.warnings);
    if let Some(details) = format.details {
        info.details = details(path, &bytes)?;
    }
    if format.frames.is_some() {
        let frames = open_frames(&spec)?.info();
        info.frames = (frames.count > 1).then_some(frames);
    }
    Ok(info)
}

//! Sequences of frames on disk (docs/design.md §10): which frames a command renders
//! (`--frames`, with the syntax of an include's `frames`), the files of a sequence (named by a
//! [`SequencePattern`] such as `out/frame_%04d.exr`, as an include's `sequence`), the render of
//! every frame ([`render`]), which resumes an interrupted sequence by the render hash that each
//! frame's EXR carries, and the comparison of two sequences ([`compare`]).

pub mod compare;
pub mod render;

use crate::error::{PgtError, Result};
pub use crate::formats::frames::{FrameRange, SequencePattern};
use std::path::Path;

/// The frames of `range` (`--frames`, the syntax of an include's `frames`) in a scene of
/// `count` frames (`None`: no include plays, only the camera moves, so the range needs its end),
/// or an error naming the scene.
pub fn frames_in(range: FrameRange, scene: &Path, count: Option<usize>) -> Result<Vec<usize>> {
    let end = match (range.end, count) {
        (Some(end), Some(n)) if end > n => {
            return Err(PgtError::in_file(
                scene,
                format!(
                    "--frames asks for frames up to {} but the scene has {n} frame(s), 0 to {}",
                    end - 1,
                    n - 1
                ),
            ))
        }
        (Some(end), _) => end,
        (None, Some(n)) => n,
        (None, None) => {
            return Err(PgtError::in_file(
                scene,
                "no include of the scene plays frames (only the camera can move), so --frames needs an end: A..B",
            ))
        }
    };
    if range.start >= end {
        return Err(PgtError::in_file(
            scene,
            format!(
                "--frames starts at frame {} but the scene has {end} frame(s)",
                range.start
            ),
        ));
    }
    Ok((range.start..end).collect())
}

/// The scene of frame `frame` of a scene file (`--frame K` of `pgt camera` and `pgt export`), or
/// the scene as `pgt render` loads it without one; a frame past the end is an error naming the
/// scene and its frame count.
pub fn scene_at_frame(
    scene: &Path,
    options: &crate::scene::SceneLoadOptions,
    frame: Option<usize>,
) -> Result<crate::scene::Scene> {
    match frame {
        None => crate::scene::Scene::load(scene, options),
        Some(k) => crate::scene::SceneFrames::load(scene, options)?.frame(k),
    }
}

/// The frames of part `part` of a list (`--part I/N` with `--frames`): the frames at positions
/// k with k mod N = I, as the rows of an image part (`crate::parts`).
pub fn frames_of_part(frames: &[usize], part: crate::parts::PartOf) -> Vec<usize> {
    frames
        .iter()
        .skip(part.index as usize)
        .step_by(part.count as usize)
        .copied()
        .collect()
}

/// The text attributes of an existing EXR's header, or `None` when the file is absent or not
/// an EXR that can be read (a frame written by something else is rendered again).
pub fn exr_text_attributes(path: &Path) -> Option<std::collections::BTreeMap<String, String>> {
    use exr::meta::attribute::AttributeValue;
    let meta = exr::meta::MetaData::read_from_file(path, false).ok()?;
    let mut out = std::collections::BTreeMap::new();
    for h in meta.headers.iter() {
        for (k, v) in h
            .shared_attributes
            .other
            .iter()
            .chain(h.own_attributes.other.iter())
        {
            if let AttributeValue::Text(t) = v {
                out.insert(k.to_string(), t.to_string());
            }
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parts::PartOf;
    use std::path::PathBuf;

    #[test]
    fn a_range_is_checked_against_the_scene() {
        let p = Path::new("s.toml");
        let r = |t: &str| t.parse::<FrameRange>().unwrap();
        assert_eq!(frames_in(r("2.."), p, Some(5)).unwrap(), vec![2, 3, 4]);
        let e = frames_in(r("2.."), p, None).unwrap_err().to_string();
        assert!(e.contains("needs an end"), "{e}");
        let e = frames_in(r("0..9"), p, Some(5)).unwrap_err().to_string();
        assert!(e.contains("s.toml") && e.contains("5 frame(s)"), "{e}");
        assert!(frames_in(r("5.."), p, Some(5)).is_err());
        assert_eq!(frames_in(r("0..3"), p, None).unwrap(), vec![0, 1, 2]);
    }

    #[test]
    fn parts_split_frames_like_rows() {
        let frames: Vec<usize> = (10..20).collect();
        let part = |index, count| frames_of_part(&frames, PartOf { index, count });
        assert_eq!(part(0, 3), vec![10, 13, 16, 19]);
        assert_eq!(part(2, 3), vec![12, 15, 18]);
        let mut all: Vec<usize> = (0..3).flat_map(|i| part(i, 3)).collect();
        all.sort();
        assert_eq!(all, frames);
    }

    #[test]
    fn output_patterns_name_every_frame() {
        let p = |t: &str| SequencePattern::parse(Path::new(t)).unwrap();
        assert_eq!(
            p("out/frame_%04d.exr").path_for(7).unwrap(),
            PathBuf::from("out/frame_0007.exr")
        );
        assert_eq!(
            p("f%d.png").path_for(123).unwrap(),
            PathBuf::from("f123.png")
        );
        assert_eq!(
            p("x_%02d.exr").path_for(123).unwrap(),
            PathBuf::from("x_123.exr")
        );
        assert_eq!(
            p("100%%_%02d.exr").path_for(3).unwrap(),
            PathBuf::from("100%_03.exr")
        );
        assert!(p("f_*.exr").path_for(1).is_err());
        assert!(p("f_%3d.exr").path_for(1).is_err());
        let q = p("d/f_%04d.exr");
        assert_eq!(
            q.number_of(
                &q.path_for(77)
                    .unwrap()
                    .file_name()
                    .unwrap()
                    .to_string_lossy()
            ),
            Some(77)
        );
    }
}

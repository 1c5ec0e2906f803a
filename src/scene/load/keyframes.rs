//! `[[camera.keyframes]]` (docs/design.md §10 "Cameras that move"): at least two keyframes, in
//! order, interpolated between; each keyframe's camera is checked where it is written.

use super::super::file::{CameraTable, KeyframeTable};
use crate::error::{At, Result, SourceText};
use crate::geometry::{CameraPath, Keyframe};

/// `[[camera.keyframes]]`: at least two, frames ≥ 0 and strictly increasing; `up` and `fov_y`
/// default to the `[camera]` table's (`fov_y` already resolved). Each keyframe's camera is
/// checked (an error names its line and key).
pub(super) fn path(
    source: &SourceText,
    table_at: &At,
    t: &CameraTable,
    fov_y: f64,
    (width, height): (u32, u32),
) -> Result<CameraPath> {
    if t.keyframes.len() < 2 {
        return Err(table_at.err(format!(
            "camera.keyframes: a keyframe path needs at least two keyframes, got {}",
            t.keyframes.len()
        )));
    }
    let default_up = t.up.unwrap_or([0.0, 1.0, 0.0]);
    let mut keys: Vec<Keyframe> = Vec::with_capacity(t.keyframes.len());
    for (i, k) in t.keyframes.iter().enumerate() {
        let k_at = source.at(k.span());
        let key = keyframe(&k_at, i, k.get_ref(), default_up, fov_y)?;
        if let Some(prev) = keys.last() {
            if key.frame <= prev.frame {
                return Err(k_at.err(format!(
                    "camera.keyframes[{i}].frame = {} must be greater than the previous keyframe's frame {} (keyframes in order)",
                    key.frame, prev.frame
                )));
            }
        }
        let single = CameraPath::Keyframes {
            keys: vec![
                key,
                Keyframe {
                    frame: key.frame + 1,
                    ..key
                },
            ],
            interpolation: Default::default(),
            width,
            height,
        };
        single
            .camera_at(key.frame as usize)
            .map_err(|m| k_at.err(format!("camera.keyframes[{i}]: {m}")))?;
        keys.push(key);
    }
    Ok(CameraPath::Keyframes {
        keys,
        interpolation: t.interpolation.unwrap_or_default(),
        width,
        height,
    })
}

/// One keyframe's values, checked.
fn keyframe(
    at: &At,
    i: usize,
    k: &KeyframeTable,
    default_up: [f64; 3],
    fov_y: f64,
) -> Result<Keyframe> {
    let name = |f: &str| format!("camera.keyframes[{i}].{f}");
    let frame = u64::try_from(k.frame)
        .map_err(|_| at.err(format!("{} must be ≥ 0, got {}", name("frame"), k.frame)))?;
    let fov = match k.fov_y {
        Some(f) => at.in_range(
            &name("fov_y"),
            f,
            f64::MIN_POSITIVE,
            179.999_999,
            "in (0, 180) degrees",
        )?,
        None => fov_y,
    };
    Ok(Keyframe {
        frame,
        position: at.vec3(&name("position"), k.position)?,
        look_at: at.vec3(&name("look_at"), k.look_at)?,
        up: at.direction(&name("up"), k.up.unwrap_or(default_up))?,
        fov_y: fov,
    })
}

#[cfg(test)]
mod tests {
    use crate::geometry::CameraPath;
    use crate::scene::{Scene, SceneLoadOptions};
    use glam::DVec3;
    use std::path::Path;

    const HEAD: &str =
        "[render]\nmodel = \"emission\"\n[camera]\nfov_y = 30.0\nwidth = 8\nheight = 8\n";

    fn key(frame: i64, x: f64) -> String {
        format!("[[camera.keyframes]]\nframe = {frame}\nposition = [{x}, 0.0, -10.0]\nlook_at = [0.0, 0.0, 0.0]\n")
    }

    fn load(text: &str) -> crate::error::Result<Scene> {
        Scene::from_toml_str(text, Path::new("s.toml"), &SceneLoadOptions::default())
    }

    #[test]
    fn keyframes_start_the_path_and_take_the_tables_fov() {
        let s = load(&format!("{HEAD}{}{}", key(0, 1.0), key(4, 3.0))).unwrap();
        assert_eq!(s.camera.position, DVec3::new(1.0, 0.0, -10.0));
        assert!((s.camera.tan_half_fov - 15f64.to_radians().tan()).abs() < 1e-12);
    }

    #[test]
    fn bad_keyframes_name_their_own_line() {
        // Keyframes out of order: the second one's line (7 + 4 = 11).
        let e = load(&format!("{HEAD}{}{}", key(4, 1.0), key(2, 3.0)))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s.toml:11: camera.keyframes[1].frame = 2 must be greater"),
            "{e}"
        );
        let e = load(&format!("{HEAD}{}{}", key(0, 1.0), key(-1, 3.0)))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s.toml:11: camera.keyframes[1].frame must be ≥ 0"),
            "{e}"
        );
        // A keyframe whose eye is its look_at.
        let bad = "[[camera.keyframes]]\nframe = 9\nposition = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\n";
        let e = load(&format!("{HEAD}{}{bad}", key(0, 1.0)))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("s.toml:11: camera.keyframes[1]: "), "{e}");
        // One keyframe is not a path; keyframes and a position or an orbit exclude each other.
        let e = load(&format!("{HEAD}{}", key(0, 1.0)))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s.toml:3: camera.keyframes: a keyframe path needs at least two"),
            "{e}"
        );
        let e = load(&format!(
            "{HEAD}position = [0.0, 0.0, 1.0]\n{}{}",
            key(0, 1.0),
            key(1, 2.0)
        ))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("camera.position: the keyframes set the camera's position"),
            "{e}"
        );
        let orbit = "[camera.orbit]\naxis = [0.0, 1.0, 0.0]\ndegrees_per_frame = 1.0\n";
        let e = load(&format!("{HEAD}{}{}{orbit}", key(0, 1.0), key(1, 2.0)))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("set [camera.orbit] or [[camera.keyframes]], not both"),
            "{e}"
        );
    }

    #[test]
    fn the_path_keeps_every_keyframe_and_the_interpolation() {
        let s = format!(
            "{HEAD}interpolation = \"catmull-rom\"\n{}{}{}",
            key(0, 1.0),
            key(2, 2.0),
            key(5, 3.0)
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("k.toml");
        std::fs::write(&path, s).unwrap();
        let f = crate::scene::SceneFrames::load(&path, &SceneLoadOptions::default()).unwrap();
        let CameraPath::Keyframes {
            keys,
            interpolation,
            ..
        } = f.camera_path()
        else {
            panic!("{:?}", f.camera_path())
        };
        assert_eq!(keys.iter().map(|k| k.frame).collect::<Vec<_>>(), [0, 2, 5]);
        assert_eq!(*interpolation, crate::geometry::Interpolation::CatmullRom);
    }
}

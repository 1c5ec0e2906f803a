//! `[camera.orbit]` (docs/design.md §10 "Cameras that move"): the fixed camera turned about an
//! axis, a fixed angle per frame.

use super::super::file::OrbitTable;
use super::super::framing::bounding_sphere;
use crate::error::{At, Result};
use crate::geometry::{CameraPath, Intrinsics, Keyframe};
use crate::optics::particle::Particle;

/// The orbit of `orbit`, starting at `start` (the `[camera]` table's camera), about `axis`
/// through `center` (the particles' centre at frame 0 by default), `degrees_per_frame` per
/// frame.
pub(super) fn path(
    at: &At,
    orbit: &OrbitTable,
    start: Keyframe,
    (width, height): (u32, u32),
    intrinsics: Option<Intrinsics>,
    particles: &[Particle],
) -> Result<CameraPath> {
    let axis = at.direction("camera.orbit.axis", orbit.axis)?;
    let degrees_per_frame = at.finite("camera.orbit.degrees_per_frame", orbit.degrees_per_frame)?;
    let center = match orbit.center {
        Some(c) => at.vec3("camera.orbit.center", c)?,
        None => bounding_sphere(particles).0,
    };
    Ok(CameraPath::Orbit {
        start,
        center,
        axis,
        degrees_per_frame,
        width,
        height,
        intrinsics,
    })
}

#[cfg(test)]
mod tests {
    use crate::geometry::CameraPath;
    use crate::scene::{Scene, SceneFrames, SceneLoadOptions};
    use glam::DVec3;
    use std::path::Path;

    const CAMERA: &str = "[render]\nmodel = \"emission\"\n[camera]\nposition = [0.0, 0.0, -10.0]\nlook_at = [0.0, 0.0, 0.0]\nwidth = 8\nheight = 8\n";

    fn frames(text: &str) -> crate::error::Result<SceneFrames> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("orbit.toml");
        std::fs::write(&path, text).unwrap();
        SceneFrames::load(&path, &SceneLoadOptions::default())
    }

    #[test]
    fn the_orbit_turns_the_fixed_camera_about_the_particles_centre() {
        let f = frames(&format!(
            "{CAMERA}[camera.orbit]\naxis = [0.0, 2.0, 0.0]\ndegrees_per_frame = 90.0\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n"
        ))
        .unwrap();
        let CameraPath::Orbit {
            center,
            axis,
            degrees_per_frame,
            ..
        } = f.camera_path()
        else {
            panic!("{:?}", f.camera_path())
        };
        assert_eq!(
            (*center, *axis, *degrees_per_frame),
            (DVec3::ZERO, DVec3::Y, 90.0)
        );
        // A quarter turn about +y takes the eye from −z to ±x, at the same distance.
        let c = f.camera_path().camera_at(1).unwrap();
        assert!(
            (c.position.length() - 10.0).abs() < 1e-9,
            "{:?}",
            c.position
        );
        assert!(
            c.position.z.abs() < 1e-9 && (c.position.x.abs() - 10.0).abs() < 1e-9,
            "{:?}",
            c.position
        );
    }

    #[test]
    fn orbit_errors_name_the_orbit_table_line() {
        let e = Scene::from_toml_str(
            &format!("{CAMERA}[camera.orbit]\naxis = [0.0, 0.0, 0.0]\ndegrees_per_frame = 1.0\n"),
            Path::new("s.toml"),
            &SceneLoadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("s.toml:8: camera.orbit.axis must be a non-zero vector"),
            "{e}"
        );
        let e = Scene::from_toml_str(
            &format!("{CAMERA}[camera.orbit]\naxis = [0.0, 1.0, 0.0]\ndegrees_per_frame = nan\ncenter = [0.0, 0.0, 0.0]\n"),
            Path::new("s.toml"),
            &SceneLoadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("camera.orbit.degrees_per_frame must be a finite number"),
            "{e}"
        );
    }
}

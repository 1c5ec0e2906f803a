//! Cameras that move (docs/design.md §10, issue 32): the scene file's `[camera.orbit]` and
//! `[[camera.keyframes]]`, checked against values computed here independently, their errors, and
//! `pgt info` on sources with frames.

use crate::support::shared_or_skip;
use glam::DVec3;
use pgt::scene::{Scene, SceneFrames, SceneLoadOptions};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pgt-cam-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("mkdir");
    dir
}

fn frames_of(name: &str, text: &str) -> pgt::Result<SceneFrames> {
    let path = scratch(name).join("s.toml");
    std::fs::write(&path, text).expect("write");
    SceneFrames::load(&path, &SceneLoadOptions::default())
}

const PARTICLES: &str = "[[particles]]\ncenter = [2.0, 0.0, 0.0]\nradius = 1.0\n[[particles]]\ncenter = [4.0, 0.0, 0.0]\nradius = 1.0\n";

#[test]
fn an_orbit_turns_about_the_particles_centre_and_frame_zero_is_the_fixed_camera() {
    let fixed = "[camera]\nposition = [3.0, 0.0, -10.0]\nlook_at = [3.0, 0.0, 0.0]\nwidth = 8\nheight = 8\n";
    let orbit = format!(
        "{fixed}[camera.orbit]\naxis = [0.0, 1.0, 0.0]\ndegrees_per_frame = 30.0\n{PARTICLES}"
    );
    let frames = frames_of("orbit", &orbit).expect("loads");
    let still = frames_of("still", &format!("{fixed}{PARTICLES}")).expect("loads");
    assert_eq!(frames.frame(0).expect("0").camera, still.first().camera);
    // The centre of the particles' bounding box is (3, 0, 0); the camera starts 10 in front of
    // it on −z. After k frames it has turned 30k° about +y: position c + 10·(−sin, 0, −cos).
    for k in [1usize, 3, 7, 12] {
        let cam = frames.frame(k).expect("frame").camera;
        let a = (30.0 * k as f64).to_radians();
        let expected = DVec3::new(3.0 - 10.0 * a.sin(), 0.0, -10.0 * a.cos());
        assert!(
            (cam.position - expected).length() < 1e-12,
            "frame {k}: {}",
            cam.position
        );
        let to_centre = (DVec3::new(3.0, 0.0, 0.0) - cam.position).normalize();
        assert!((cam.forward - to_centre).length() < 1e-12, "frame {k}");
    }
    // Without a moving include the frame count is open.
    assert_eq!(frames.frame_count(), None);
}

#[test]
fn keyframes_interpolate_linearly_or_by_catmull_rom() {
    let keys = "[[camera.keyframes]]\nframe = 0\nposition = [0.0, 0.0, -10.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 30.0\n\
                [[camera.keyframes]]\nframe = 10\nposition = [10.0, 0.0, -10.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 50.0\n\
                [[camera.keyframes]]\nframe = 20\nposition = [10.0, 10.0, -10.0]\nlook_at = [0.0, 0.0, 0.0]\n";
    let linear = frames_of(
        "lin",
        &format!("[camera]\nwidth = 8\nheight = 8\n{keys}{PARTICLES}"),
    )
    .expect("loads");
    let c = linear.frame(4).expect("frame 4").camera;
    assert!(
        (c.position - DVec3::new(4.0, 0.0, -10.0)).length() < 1e-12,
        "{}",
        c.position
    );
    // fov 30 → 50 over 10 frames: 38° at frame 4.
    assert!((c.tan_half_fov - (38.0f64.to_radians() / 2.0).tan()).abs() < 1e-12);
    // The third keyframe takes the [camera] fov_y default (40°); after it the camera holds.
    let c = linear.frame(25).expect("frame 25").camera;
    assert!((c.position - DVec3::new(10.0, 10.0, -10.0)).length() < 1e-12);
    assert!((c.tan_half_fov - 20.0f64.to_radians().tan()).abs() < 1e-12);
    let spline = frames_of(
        "cr",
        &format!(
            "[camera]\nwidth = 8\nheight = 8\ninterpolation = \"catmull-rom\"\n{keys}{PARTICLES}"
        ),
    )
    .expect("loads");
    // Segment 0→10 at s = 0.5 with tangents m0 = (P1 − P0)/10 and m1 = (P2 − P0)/20 (per frame):
    // P = h00·P0 + h10·10·m0 + h01·P1 + h11·10·m1, h = (0.5, 0.125, 0.5, −0.125).
    let (p0, p1, p2) = (
        DVec3::new(0.0, 0.0, -10.0),
        DVec3::new(10.0, 0.0, -10.0),
        DVec3::new(10.0, 10.0, -10.0),
    );
    let expected = 0.5 * p0 + 0.125 * (p1 - p0) + 0.5 * p1 - 0.125 * 10.0 * (p2 - p0) / 20.0;
    let c = spline.frame(5).expect("frame 5").camera;
    assert!(
        (c.position - expected).length() < 1e-12,
        "{} vs {expected}",
        c.position
    );
    for (k, p) in [(0usize, p0), (10, p1), (20, p2)] {
        assert!((spline.frame(k).expect("key").camera.position - p).length() < 1e-12);
    }
}

#[test]
fn camera_path_errors_name_the_key_and_line() {
    let key = |frame: i64, x: f64| {
        format!("[[camera.keyframes]]\nframe = {frame}\nposition = [{x}, 0.0, -10.0]\nlook_at = [0.0, 0.0, 0.0]\n")
    };
    let cases = [
        (format!("[camera]\n{}", key(0, 0.0)), "s.toml:1", "at least two keyframes, got 1"),
        (format!("[camera]\n{}{}", key(5, 0.0), key(5, 1.0)), "s.toml:6", "camera.keyframes[1].frame = 5 must be greater"),
        (format!("[camera]\n{}{}", key(0, 0.0), key(-3, 1.0)), "s.toml:6", "camera.keyframes[1].frame must be ≥ 0"),
        (format!("[camera]\nposition = [0.0, 0.0, 1.0]\n{}{}", key(0, 0.0), key(3, 1.0)), "s.toml:1", "camera.position"),
        (format!("[camera]\n[camera.orbit]\naxis = [0.0, 1.0, 0.0]\ndegrees_per_frame = 1.0\n{}{}", key(0, 0.0), key(3, 1.0)), "s.toml:1", "not both"),
        ("[camera]\ninterpolation = \"linear\"\n".to_string(), "s.toml:1", "camera.interpolation"),
        ("[camera]\n[camera.orbit]\naxis = [0.0, 0.0, 0.0]\ndegrees_per_frame = 1.0\n".to_string(), "s.toml:2", "camera.orbit.axis"),
        ("[camera]\n[camera.orbit]\naxis = [0.0, 1.0, 0.0]\n".to_string(), "s.toml", "degrees_per_frame"),
        (
            format!("[camera]\n{}[[camera.keyframes]]\nframe = 4\nposition = [0.0, 0.0, -10.0]\nlook_at = [0.0, 0.0, -10.0]\n", key(0, 0.0)),
            "s.toml:6",
            "camera.keyframes[1]: the camera's look_at equals its position",
        ),
    ];
    for (text, at, expected) in cases {
        let e = frames_of("err", &format!("{text}{PARTICLES}"))
            .expect_err("an error")
            .to_string();
        assert!(e.contains(at) && e.contains(expected), "{text}\n→ {e}");
        let e2 = Scene::from_toml_str(
            &format!("{text}{PARTICLES}"),
            std::path::Path::new("s.toml"),
            &SceneLoadOptions::default(),
        )
        .expect_err("an error")
        .to_string();
        assert_eq!(
            e,
            e2.replace("s.toml", &scratch_path_name()),
            "the static and the framed loader agree"
        );
    }
}

/// The scene path `frames_of("err", …)` writes, as messages print it.
fn scratch_path_name() -> String {
    std::env::temp_dir()
        .join(format!("pgt-cam-err-{}", std::process::id()))
        .join("s.toml")
        .display()
        .to_string()
}

#[test]
fn info_reports_frames_atoms_and_the_time_step() {
    let xtc = shared_or_skip!("trajectories/ngl_md.xtc");
    let gro = shared_or_skip!("trajectories/ngl_md.gro");
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_pgt"))
            .args(args)
            .output()
            .expect("runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let text = run(&["info", xtc.to_str().expect("utf-8")]);
    assert!(
        text.contains("frames:    51 (17411 atoms per frame, time step 20 ps)"),
        "{text}"
    );
    let dir = scratch("info");
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        format!(
            "[camera]\nwidth = 8\nheight = 8\n[[include]]\npath = \"{}\"\ntrajectory = \"{}\"\nframes = \"1..51\"\nframe_step = 5\n",
            gro.display(),
            xtc.display()
        ),
    )
    .expect("write");
    let json: serde_json::Value =
        serde_json::from_str(&run(&["info", scene.to_str().expect("utf-8"), "--json"]))
            .expect("json");
    assert_eq!(json["frames"]["count"], 10);
    assert_eq!(json["frames"]["atoms_per_frame"], 17411);
    assert_eq!(json["frames"]["time_step_ps"], 100.0);
    assert_eq!(json["particles"], 17411);
}

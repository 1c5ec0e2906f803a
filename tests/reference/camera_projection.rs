//! `pgt camera --json` against the reference's camera (docs/design.md §1 "Camera convention"): for
//! several scenes, square and not, points along the ray the reference sends through a pixel
//! centre must project, through each API's view and projection matrices as the JSON gives them,
//! to that pixel centre (px + 0.5, py + 0.5), and points anywhere in the view must project to
//! the continuous image coordinate whose ray passes through them. Budget 1e-6 pixels: the
//! matrices are printed in f64 shortest round-trip form, so the only error is f64 rounding
//! (~1e-12); a half-pixel offset, a flipped axis or a wrong aspect is ≥ 0.5 pixels.

use glam::{DMat4, DVec3, DVec4};
use pgt::geometry::projection::CameraJson;
use pgt::geometry::Camera;
use pgt::scene::{Scene, SceneLoadOptions};
use std::path::{Path, PathBuf};
use std::process::Command;

const PIXEL_BUDGET: f64 = 1e-6;

fn pgt_camera(scene: &Path, size: Option<&str>) -> CameraJson {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_pgt"));
    cmd.arg("camera").arg(scene).arg("--json");
    if let Some(s) = size {
        cmd.args(["--size", s]);
    }
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "pgt camera failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn reference_camera(scene: &Path, size: Option<(u32, u32)>) -> Scene {
    let options = SceneLoadOptions {
        size,
        ..SceneLoadOptions::default()
    };
    Scene::load(scene, &options).unwrap()
}

/// Window coordinates of a world point in pgt's pixel frame (x right, y down from the top-left
/// corner), following each API's viewport transform as its specification states it.
fn to_pixel(api: &str, cam: &CameraJson, p: DVec3) -> (f64, f64, f64) {
    let view = DMat4::from_cols_array(&cam.view.column_major);
    let proj = DMat4::from_cols_array(&cam.projection[api].matrix.column_major);
    let clip: DVec4 = proj * view * p.extend(1.0);
    assert!(clip.w > 0.0, "{api}: point behind the eye");
    let ndc = clip.truncate() / clip.w;
    let (w, h) = (cam.width as f64, cam.height as f64);
    let x = (ndc.x + 1.0) * 0.5 * w;
    let y = match api {
        // glViewport: window y = (ndc.y + 1)/2·H counted from the bottom row.
        "opengl" => h - (ndc.y + 1.0) * 0.5 * h,
        // Vulkan: framebuffer y = (ndc.y + 1)/2·H from the top (the matrix flipped y).
        "vulkan" => (ndc.y + 1.0) * 0.5 * h,
        // WebGPU and Direct3D viewports: y = (1 − ndc.y)/2·H from the top.
        "webgpu" | "direct3d" => (1.0 - ndc.y) * 0.5 * h,
        other => panic!("unknown API {other}"),
    };
    (x, y, ndc.z)
}

fn write_scene(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Deterministic numbers in [0, 1) (SplitMix64).
fn uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    (z ^ (z >> 31)) as f64 / 2f64.powi(64)
}

fn check_scene(scene: &Path, size: Option<(u32, u32)>) {
    let size_arg = size.map(|(w, h)| format!("{w}x{h}"));
    let json = pgt_camera(scene, size_arg.as_deref());
    let reference = reference_camera(scene, size);
    let cam: &Camera = &reference.camera;
    assert_eq!((json.width, json.height), (cam.width, cam.height));
    assert!(json.near > 0.0 && json.far > json.near);
    let (w, h) = (cam.width, cam.height);
    let pixels = [
        (0, 0),
        (w - 1, 0),
        (0, h - 1),
        (w - 1, h - 1),
        (w / 2, h / 2),
        (w / 3, (2 * h) / 3),
    ];
    let mut state = 7u64;
    for api in ["opengl", "vulkan", "webgpu", "direct3d"] {
        let (z_lo, z_hi) = (
            json.projection[api].depth_range[0],
            json.projection[api].depth_range[1],
        );
        for &(px, py) in &pixels {
            let ray = cam.pixel_ray(px, py);
            // Points on the ray between near and far, measured along f.
            for s in [0.0, 0.25, 0.5, 1.0] {
                let depth = json.near + s * (json.far - json.near);
                let t = depth / ray.direction.dot(cam.forward);
                let (x, y, z) = to_pixel(api, &json, ray.origin + t * ray.direction);
                assert!(
                    (x - (px as f64 + 0.5)).abs() < PIXEL_BUDGET
                        && (y - (py as f64 + 0.5)).abs() < PIXEL_BUDGET,
                    "{}: {api}: pixel ({px}, {py}) projected to ({x}, {y})",
                    scene.display()
                );
                assert!(z >= z_lo - 1e-9 && z <= z_hi + 1e-9, "{api}: depth {z}");
            }
        }
        // Random points in the view: the ray through their projection passes through them.
        for _ in 0..50 {
            let (sx, sy) = (uniform(&mut state), uniform(&mut state));
            let depth = json.near + uniform(&mut state) * (json.far - json.near);
            let ray = cam.ray_at(sx * w as f64, sy * h as f64);
            let p = ray.origin + (depth / ray.direction.dot(cam.forward)) * ray.direction;
            let (x, y, _) = to_pixel(api, &json, p);
            let back = cam.ray_at(x, y);
            let miss = (p - back.origin).cross(back.direction).length();
            assert!(
                miss < 1e-9 * (1.0 + depth),
                "{api}: ray through ({x}, {y}) misses the point by {miss}"
            );
        }
    }
}

#[test]
fn matrices_send_points_to_the_pixel_the_reference_ray_goes_through() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    // Examples as shipped (160×120: not square; the camera inside a sphere), and overridden.
    check_scene(&root.join("examples/inside.toml"), None);
    check_scene(&root.join("examples/shadows.toml"), None);
    check_scene(&root.join("examples/shadows.toml"), Some((37, 91)));
    // An oblique camera with a tilted up vector and a focal length, 300×17.
    let oblique = write_scene(
        dir.path(),
        "oblique.toml",
        r#"
[camera]
position = [3.0, -2.0, 7.5]
look_at  = [0.2, 0.4, -0.3]
up       = [0.3, 1.0, 0.2]
focal_length = 1.7
width    = 300
height   = 17
[[particles]]
center = [0.0, 0.0, 0.0]
radius = 1.0
[[particles]]
center = [1.0, 2.0, -3.0]
radius = 0.5
"#,
    );
    check_scene(&oblique, None);
    // Default framing (no [camera]): square and tall.
    let framed = write_scene(
        dir.path(),
        "framed.toml",
        r#"
[[particles]]
center = [10.0, 0.0, 0.0]
radius = 2.0
[[particles]]
center = [14.0, 3.0, 1.0]
radius = 1.0
"#,
    );
    check_scene(&framed, None);
    check_scene(&framed, Some((64, 200)));
    // Intrinsics (docs/design.md §1): fx ≠ fy, an off-centre principal point, the pose as R
    // and t; and the same scaled by --size.
    let intrinsics = write_scene(
        dir.path(),
        "intrinsics.toml",
        r#"
[camera]
fx = 70.0
fy = 52.5
cx = 19.25
cy = 27.75
R = [[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [-1.0, 0.0, 0.0]]
t = [0.5, -0.25, 9.0]
width = 48
height = 40
[[particles]]
center = [0.0, 0.0, 0.0]
radius = 1.0
"#,
    );
    check_scene(&intrinsics, None);
    check_scene(&intrinsics, Some((96, 30)));
}

#[test]
fn the_json_gives_k_the_opencv_pose_colmaps_qvec_and_nerfstudios_camera_to_world() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("examples/shadows.toml");
    let json = pgt_camera(&scene, None);
    let cam = reference_camera(&scene, None).camera;
    // A fov_y camera: fx = fy = (H/2)/tan(fov_y/2), the principal point at the centre.
    let f = 0.5 * cam.height as f64 / cam.tan_half_fov;
    assert_eq!((json.fx, json.fy), (f, f));
    assert_eq!(
        (json.cx, json.cy),
        (0.5 * cam.width as f64, 0.5 * cam.height as f64)
    );
    assert_eq!(
        json.k,
        [[f, 0.0, json.cx], [0.0, f, json.cy], [0.0, 0.0, 1.0]]
    );
    // R's rows are r, −u, f; t = −R·eye; qvec turns into R; the camera-to-world's columns are
    // r, u, −f and the eye.
    let r = glam::DMat3::from_cols_array_2d(&json.r).transpose();
    assert_eq!(r.row(0), cam.right);
    assert_eq!(r.row(1), -cam.up);
    assert_eq!(r.row(2), cam.forward);
    let t = DVec3::from(json.t);
    assert!((r * cam.position + t).length() < 1e-12);
    assert_eq!(json.colmap_tvec, json.t);
    let [w, x, y, z] = json.colmap_qvec;
    assert!(w >= 0.0);
    let q = glam::DMat3::from_quat(glam::DQuat::from_xyzw(x, y, z, w));
    assert!(q.abs_diff_eq(r, 1e-12), "{q} vs {r}");
    let c2w = glam::DMat4::from_cols_array_2d(&json.nerfstudio_camera_to_world).transpose();
    assert_eq!(c2w.x_axis.truncate(), cam.right);
    assert_eq!(c2w.y_axis.truncate(), cam.up);
    assert_eq!(c2w.z_axis.truncate(), -cam.forward);
    assert_eq!(c2w.w_axis, cam.position.extend(1.0));
}

#[test]
fn text_output_names_every_api_and_the_conventions() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(["camera"])
        .arg(root.join("examples/shadows.toml"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for word in [
        "opengl", "vulkan", "webgpu", "direct3d", "column", "row", "near/far", "+ 0.5",
    ] {
        assert!(text.contains(word), "missing '{word}' in:\n{text}");
    }
}

#[test]
fn missing_scene_is_an_error_with_exit_2() {
    let out = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(["camera", "/nonexistent/scene.toml", "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/scene.toml"));
}

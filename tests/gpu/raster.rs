//! The rasterising example (`examples/raster_impostors.rs`) end to end, headless on whatever
//! adapter wgpu finds (lavapipe in CI): `pgt camera --json` and `pgt export` feed it, `pgt render`
//! draws the reference of the same scene with the emission model, and pgt's metrics compare them.
//!
//! * Disjoint spheres: the impostors compute exactly the reference's emission closed form
//!   L = L_bg·T + C·(1 − T) per sphere; what remains is the Rgba16Float target (relative error
//!   2⁻¹¹), f32 ray–sphere against f64 (a pixel centre within ~1e-6 of a silhouette may flip) —
//!   budget RMSE 5e-4 and SSIM ≥ 0.9999 (measured on lavapipe: RMSE 5.1e-5, SSIM 1.000000);
//!   a half-pixel shift or a mirrored axis costs ≥ 0.02 RMSE.
//! * Overlapping spheres: sorted-by-centre blending is not the exact interval integration, so
//!   the error is real; the test prints it (the README quotes it; measured RMSE 1.8e-2, SSIM
//!   0.9896, max 0.142) and bounds it loosely.
//!
//! Without an adapter the test skips with a message, except under `CI=true`, where it fails.

#[allow(dead_code)]
#[path = "../../examples/raster_impostors.rs"]
mod raster_impostors;

use pgt::image_io::{read_image, RgbImage};
use pgt::metrics::{compare, CompareOptions};
use std::path::Path;
use std::process::Command;

fn pgt(args: &[&std::ffi::OsStr]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "pgt {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Runs the example's renderer on a scene through pgt's own outputs, and the reference; `None`
/// when no adapter exists outside CI.
fn impostors_and_reference(dir: &Path, scene_text: &str) -> Option<(RgbImage, RgbImage)> {
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, scene_text).unwrap();
    let camera = pgt(&["camera".as_ref(), scene.as_os_str(), "--json".as_ref()]);
    let csv = dir.join("particles.csv");
    pgt(&[
        "export".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        csv.as_os_str(),
    ]);
    let camera = raster_impostors::parse_camera(&camera).unwrap();
    let particles =
        raster_impostors::parse_particles(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    let frame = match raster_impostors::render(&camera, &particles) {
        Ok(f) => f,
        Err(e) if e.starts_with("no GPU adapter") => {
            if std::env::var("CI").is_ok_and(|v| v == "true") {
                panic!("CI=true and no GPU adapter: {e}");
            }
            crate::support::skipped(&e);
            return None;
        }
        Err(e) => panic!("{e}"),
    };
    // Through the example's own writer, as a user would get it.
    let out = dir.join("impostors.exr");
    raster_impostors::write(&frame, &out).unwrap();
    let reference = dir.join("reference.exr");
    pgt(&[
        "render".as_ref(),
        scene.as_os_str(),
        "--model".as_ref(),
        "emission".as_ref(),
        "-o".as_ref(),
        reference.as_os_str(),
    ]);
    eprintln!("impostors drawn on {}", frame.adapter);
    Some((read_image(&reference).unwrap(), read_image(&out).unwrap()))
}

const CAMERA: &str = r#"
[camera]
position = [2.0, 1.5, -9.0]
look_at  = [0.2, -0.1, 0.0]
up       = [0.0, 1.0, 0.0]
fov_y    = 45.0
width    = 96
height   = 64
[render]
model = "emission"
background = [0.05, 0.1, 0.2]
"#;

/// Error metrics: (RMSE mean over channels, SSIM mean, max abs error).
fn measure(reference: &RgbImage, approximation: &RgbImage) -> (f64, f64, f64) {
    let options = CompareOptions {
        flip: false,
        data_range: Some(1.0),
        ..CompareOptions::default()
    };
    let c = compare(reference, approximation, &options).unwrap();
    (
        c.error_values(|e| e.rmse).mean,
        c.ssim_values().unwrap().mean,
        c.error_values(|e| e.max_abs).mean,
    )
}

#[test]
fn disjoint_spheres_match_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let scene = format!(
        "{CAMERA}{}",
        r#"
[[particles]]
center = [-2.5, 0.0, 0.0]
radius = 1.2
color  = [1.0, 0.3, 0.2]
opacity = 0.6
[[particles]]
center = [0.5, 1.0, 2.0]
radius = 1.0
color  = [0.2, 0.9, 0.3]
opacity = 1.0
[[particles]]
center = [2.2, -1.2, -1.0]
radius = 0.8
color  = [0.3, 0.4, 1.0]
opacity = 0.3
"#
    );
    let Some((reference, impostors)) = impostors_and_reference(dir.path(), &scene) else {
        return;
    };
    let (rmse, ssim, max) = measure(&reference, &impostors);
    eprintln!("disjoint spheres: RMSE {rmse:.3e}, SSIM {ssim:.6}, max abs {max:.3e}");
    assert!(rmse < 5e-4, "RMSE {rmse}");
    assert!(ssim > 0.9999, "SSIM {ssim}");
}

#[test]
fn overlapping_spheres_show_the_sorted_blend_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = format!(
        "{CAMERA}{}",
        r#"
[[particles]]
center = [-0.6, 0.0, 0.0]
radius = 1.5
color  = [1.0, 0.3, 0.2]
opacity = 0.7
[[particles]]
center = [0.6, 0.3, 0.4]
radius = 1.5
color  = [0.2, 0.4, 1.0]
opacity = 0.7
[[particles]]
center = [0.0, -0.8, -0.5]
radius = 1.0
color  = [0.9, 0.9, 0.2]
opacity = 0.5
"#
    );
    let Some((reference, impostors)) = impostors_and_reference(dir.path(), &scene) else {
        return;
    };
    let (rmse, ssim, max) = measure(&reference, &impostors);
    eprintln!("overlapping spheres: RMSE {rmse:.3e}, SSIM {ssim:.6}, max abs {max:.3e}");
    // The method is wrong where spheres overlap, but not wildly.
    assert!(rmse > 1e-3, "overlap must cost something: RMSE {rmse}");
    assert!(rmse < 0.1 && ssim > 0.8, "RMSE {rmse}, SSIM {ssim}");
}

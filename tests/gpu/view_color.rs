//! The view-dependent colour follows the camera in the GPU methods as in the reference
//! (docs/design.md §9, "3D Gaussian splatting PLY"): each frame of a camera sequence, as
//! `pgt frames --method` builds it, draws the SH colour of its own eye (the closed form written
//! out in `support::splat`).

use crate::support::gpu::*;
use crate::support::splat::{sh_two_eyes_color, sh_two_eyes_scene};
use pgt::approx::{render_approx_with, ApproxParams};
use pgt::scene::{SceneFrames, SceneLoadOptions};

#[test]
fn each_frame_of_a_camera_sequence_draws_the_sh_colour_of_its_own_eye() {
    let Some(ctx) = gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let path = sh_two_eyes_scene(dir.path());
    let frames = SceneFrames::load(&path, &SceneLoadOptions::default()).unwrap();
    for method in ["splat", "gauss-ray"] {
        let params = ApproxParams::for_method(method, &[]).unwrap();
        for (k, z_dir) in [(0, 1.0), (1, -1.0)] {
            let scene = frames.frame(k).unwrap();
            let image = render_approx_with(ctx, &scene, &params)
                .unwrap_or_else(|e| panic!("{method}: {e}"))
                .image;
            // The centre pixel is the projected centre of the isotropic Gaussian: 3DGS's
            // α = min(0.99, o·G) with G = 1 and o = ½, on black the pixel is ½·C.
            let got = image.get(4, 4);
            let want = 0.5 * sh_two_eyes_color(z_dir);
            for c in 0..3 {
                assert!(
                    (got[c] as f64 - want[c]).abs() < 1e-4,
                    "{method} frame {k} channel {c}: {} vs {}",
                    got[c],
                    want[c]
                );
            }
        }
    }
}

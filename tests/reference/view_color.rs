//! The view-dependent colour follows the camera (docs/design.md §9, "3D Gaussian splatting
//! PLY"): a Gaussian with a strong degree-1 SH term seen by a sequence of two cameras on opposite
//! sides renders, in each frame, the colour 3DGS computes for that frame's eye (the closed form
//! written out in `support::splat`), not the colour of frame 0's eye.

use crate::support::splat::{sh_two_eyes_color, sh_two_eyes_scene};
use glam::DVec3;
use pgt::reference::{render, RenderOptions};
use pgt::scene::{SceneFrames, SceneLoadOptions};

#[test]
fn each_frame_of_a_camera_sequence_has_the_sh_colour_of_its_own_eye() {
    let dir = tempfile::tempdir().unwrap();
    let path = sh_two_eyes_scene(dir.path());
    let frames = SceneFrames::load(&path, &SceneLoadOptions::default()).unwrap();
    assert_eq!(frames.frame_count(), Some(2));
    let mut centre = Vec::new();
    for (k, eye_z, z_dir) in [(0, -5.0, 1.0), (1, 5.0, -1.0)] {
        let scene = frames.frame(k).unwrap();
        assert!((scene.camera.position - DVec3::new(0.0, 0.0, eye_z)).length() < 1e-12);
        let want_color = sh_two_eyes_color(z_dir);
        let got_color = scene.particles[0].color;
        assert!(
            (got_color - want_color).length() < 1e-12,
            "frame {k}: colour {got_color} vs {want_color}"
        );
        // The centre pixel's ray passes through the centre of the isotropic Gaussian: its
        // opacity is α = sigmoid(0) = ½, on black the pixel is ½·C.
        let out = render(&scene, &RenderOptions::default()).unwrap();
        let err = out.error.unwrap().get(4, 4);
        let got = out.image.get(4, 4);
        for c in 0..3 {
            let want = 0.5 * want_color[c];
            assert!(
                (got[c] as f64 - want).abs() <= err[c] as f64 + 1e-6,
                "frame {k} channel {c}: {} vs {want} (err {})",
                got[c],
                err[c]
            );
        }
        centre.push(got);
    }
    // The two eyes see different colours: red bright from a.jpg, dim from b.jpg.
    assert!(centre[0][0] - centre[1][0] > 0.3, "{centre:?}");
    assert!(centre[1][1] - centre[0][1] > 0.2, "{centre:?}");
    // Scene::load (a still render) is frame 0.
    let still = pgt::Scene::load(&path, &SceneLoadOptions::default()).unwrap();
    assert_eq!(still.particles, frames.frame(0).unwrap().particles);
}

/// The render hash that ties parts and skipped frames to one render (`pgt::parts`) sees the SH
/// coefficients through the colours they give each frame: a file that differs in one degree-1
/// coefficient hashes differently in the frame whose eye sees it, the same file the same.
#[test]
fn the_render_hash_follows_the_sh_coefficients() {
    let dir = tempfile::tempdir().unwrap();
    let path = sh_two_eyes_scene(dir.path());
    let hash = |k: usize| {
        let frames = SceneFrames::load(&path, &SceneLoadOptions::default()).unwrap();
        pgt::parts::render_hash(&frames.frame(k).unwrap(), &RenderOptions::default())
    };
    let before = [hash(0), hash(1)];
    assert_eq!(before, [hash(0), hash(1)]);
    // Red's z coefficient 0.75 → 0.5 (the only 0.75 of the file).
    let ply = dir.path().join("g.ply");
    let mut bytes = std::fs::read(&ply).unwrap();
    let at = bytes
        .windows(4)
        .position(|w| w == 0.75f32.to_le_bytes())
        .unwrap();
    bytes[at..at + 4].copy_from_slice(&0.5f32.to_le_bytes());
    std::fs::write(&ply, bytes).unwrap();
    assert_ne!(hash(0), before[0]);
    assert_ne!(hash(1), before[1]);
}

/// An include that plays numbered PLY files (`sequence`) keeps the coefficients of every frame
/// it reads: frame 1's Gaussian has the colour of the eye, not the DC colour its records carry.
#[test]
fn a_sequence_of_ply_files_keeps_the_view_colour_in_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    sh_two_eyes_scene(dir.path());
    for k in 0..2 {
        std::fs::copy(
            dir.path().join("g.ply"),
            dir.path().join(format!("g_{k}.ply")),
        )
        .unwrap();
    }
    let path = dir.path().join("seq.toml");
    std::fs::write(
        &path,
        "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n[render]\nmodel = \"emission\"\n[[include]]\nsequence = \"g_%d.ply\"\nsh = \"view\"\ndensity = \"gaussian\"\n",
    )
    .unwrap();
    let frames = SceneFrames::load(&path, &SceneLoadOptions::default()).unwrap();
    assert_eq!(frames.frame_count(), Some(2));
    let want = sh_two_eyes_color(-1.0);
    for k in 0..2 {
        let got = frames.frame(k).unwrap().particles[0].color;
        assert!((got - want).length() < 1e-12, "frame {k}: {got} vs {want}");
    }
}

//! The GPU reference over sequences and cluster parts (docs/design.md §12 "Frames and parts"):
//! `pgt render --gpu --frames` gives frames within err_gpu + err_cpu of the CPU's, `--gpu --part`
//! parts merge into the whole `--gpu` image bit for bit, and the render hash tells a GPU render
//! from a CPU one, so neither is skipped or merged for the other.

use super::reference::gpu64;
use pgt::image_io::{read_exr_layer, read_image, RgbImage};
use pgt::parts::{render_hash, render_hash_on};
use pgt::reference::{Device, RenderOptions};
use pgt::scene::{Scene, SceneLoadOptions};
use std::path::{Path, PathBuf};
use std::process::Output;

fn pgt(args: &[&str]) -> Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .output()
        .expect("pgt runs")
}

/// Runs pgt, asserts success, returns its stderr.
fn ok(args: &[&str]) -> String {
    let out = pgt(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "pgt {args:?} failed: {err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A scene of two overlapping spheres and an ellipsoid-free XYZ trajectory of three atoms that
/// move from frame to frame, `frames` frames.
fn sequence_scene(dir: &Path, frames: usize) -> PathBuf {
    let mut xyz = String::new();
    for f in 0..frames {
        xyz += "3\nframe\n";
        for (a, el) in ["C", "O", "N"].iter().enumerate() {
            let x = a as f64 * 1.1 - 1.1 + 0.4 * f as f64;
            xyz += &format!("{el} {x:.3} {:.3} 0.0\n", 0.3 * a as f64);
        }
    }
    std::fs::write(dir.join("traj.xyz"), xyz).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        r#"[render]
mode = "volume"
model = "emission"
background = [0.05, 0.1, 0.2]

[camera]
position = [0, 0, 10]
look_at = [0, 0, 0]
width = 22
height = 18

[defaults]
opacity = 0.7

[[include]]
path = "traj.xyz"
"#,
    )
    .unwrap();
    scene
}

fn image_and_err(path: &Path) -> (RgbImage, RgbImage) {
    (
        read_image(path).unwrap(),
        read_exr_layer(path, "err").unwrap(),
    )
}

fn same_bits(a: &RgbImage, b: &RgbImage) -> bool {
    (a.width, a.height) == (b.width, b.height)
        && a.pixels
            .iter()
            .flatten()
            .zip(b.pixels.iter().flatten())
            .all(|(x, y)| x.to_bits() == y.to_bits())
}

fn hash_of(path: &Path) -> String {
    pgt::sequence::exr_text_attributes(path).unwrap()[pgt::parts::RENDER_HASH_ATTRIBUTE].clone()
}

#[test]
fn gpu_frames_agree_with_the_cpu_s_within_both_errs_and_are_not_taken_for_them() {
    if gpu64().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = sequence_scene(dir.path(), 2);
    let cpu = dir.path().join("cpu/f_%d.exr");
    let gpu = dir.path().join("gpu/f_%d.exr");
    ok(&["render", s(&scene), "--frames", "0..2", "-o", s(&cpu)]);
    let err = ok(&[
        "render",
        s(&scene),
        "--gpu",
        "--frames",
        "0..2",
        "-o",
        s(&gpu),
    ]);
    assert!(
        err.contains("rendered 2 frame(s)") && err.contains(" on "),
        "{err}"
    );
    let mut frames_differ = false;
    for f in 0..2 {
        let (c, g) = (
            dir.path().join(format!("cpu/f_{f}.exr")),
            dir.path().join(format!("gpu/f_{f}.exr")),
        );
        let ((ci, ce), (gi, ge)) = (image_and_err(&c), image_and_err(&g));
        for i in 0..ci.pixels.len() {
            for k in 0..3 {
                let d = (gi.pixels[i][k] as f64 - ci.pixels[i][k] as f64).abs();
                let allowed = ge.pixels[i][k] as f64 + ce.pixels[i][k] as f64;
                assert!(
                    d <= allowed,
                    "frame {f} pixel {i} channel {k}: {d:e} > {allowed:e}"
                );
            }
        }
        assert_ne!(
            hash_of(&c),
            hash_of(&g),
            "frame {f}: GPU and CPU share a hash"
        );
        frames_differ |= !same_bits(&gi, &image_and_err(&dir.path().join("gpu/f_0.exr")).0);
    }
    assert!(frames_differ, "the two frames should show different scenes");
    // The GPU into the CPU's files renders every frame again (another hash), then skips them.
    let err = ok(&[
        "render",
        s(&scene),
        "--gpu",
        "--frames",
        "0..2",
        "-o",
        s(&cpu),
    ]);
    assert!(err.contains("rendered 2 frame(s)"), "{err}");
    let err = ok(&[
        "render",
        s(&scene),
        "--gpu",
        "--frames",
        "0..2",
        "-o",
        s(&cpu),
    ]);
    assert!(
        err.contains("rendered 0 frame(s)") && err.contains("skipped 2"),
        "{err}"
    );
    for f in 0..2 {
        let name = format!("f_{f}.exr");
        let (a, b) = (
            dir.path().join("cpu").join(&name),
            dir.path().join("gpu").join(&name),
        );
        assert!(same_bits(&image_and_err(&a).0, &image_and_err(&b).0));
        assert!(same_bits(&image_and_err(&a).1, &image_and_err(&b).1));
    }
}

#[test]
fn gpu_parts_merge_into_the_whole_gpu_render_bit_for_bit() {
    if gpu64().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = sequence_scene(dir.path(), 1);
    let whole = dir.path().join("whole.exr");
    ok(&["render", s(&scene), "--gpu", "-o", s(&whole)]);
    let mut parts = Vec::new();
    for i in 0..3 {
        let part = dir.path().join(format!("part_{i}.exr"));
        let which = format!("{i}/3");
        let err = ok(&[
            "render",
            s(&scene),
            "--gpu",
            "--part",
            &which,
            "-o",
            s(&part),
        ]);
        assert!(err.contains(" on "), "the summary names the adapter: {err}");
        parts.push(part);
    }
    let merged = dir.path().join("merged.exr");
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(|p| s(p)));
    args.extend(["-o", s(&merged)]);
    ok(&args);
    let ((wi, we), (mi, me)) = (image_and_err(&whole), image_and_err(&merged));
    assert!(
        same_bits(&wi, &mi),
        "merged GPU parts differ from the whole GPU image"
    );
    assert!(
        same_bits(&we, &me),
        "merged GPU err differs from the whole GPU err"
    );
    // A CPU part is another render: the merge refuses it by name.
    let cpu_part = dir.path().join("cpu_part_1.exr");
    ok(&["render", s(&scene), "--part", "1/3", "-o", s(&cpu_part)]);
    let out = pgt(&[
        "merge",
        s(&parts[0]),
        s(&cpu_part),
        s(&parts[2]),
        "-o",
        s(&merged),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("cpu_part_1.exr") && err.contains("render hash"),
        "{err}"
    );
}

#[test]
fn the_render_hash_names_the_gpu() {
    let Some(ctx) = gpu64() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(&sequence_scene(dir.path(), 1), &SceneLoadOptions::default()).unwrap();
    let o = RenderOptions::default();
    assert_eq!(
        render_hash_on(&scene, &o, Device::Cpu),
        render_hash(&scene, &o)
    );
    assert_ne!(
        render_hash_on(&scene, &o, Device::Gpu(ctx)),
        render_hash(&scene, &o)
    );
    // Still every option and bit of the scene.
    let spp = RenderOptions { spp: 2, ..o };
    assert_ne!(
        render_hash_on(&scene, &o, Device::Gpu(ctx)),
        render_hash_on(&scene, &spp, Device::Gpu(ctx))
    );
}

#[test]
fn what_the_gpu_cannot_render_is_refused_by_name_for_frames_and_parts_too() {
    let dir = tempfile::tempdir().unwrap();
    let scene = sequence_scene(dir.path(), 2);
    let frames = dir.path().join("out/f_%d.exr");
    let part = dir.path().join("part.exr");
    for args in [
        vec![
            "render",
            s(&scene),
            "--gpu",
            "--model",
            "lit",
            "--frames",
            "0..2",
            "-o",
            s(&frames),
        ],
        vec![
            "render",
            s(&scene),
            "--gpu",
            "--integrator",
            "riemann",
            "--part",
            "0/2",
            "-o",
            s(&part),
        ],
    ] {
        let out = pgt(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("--gpu") && !err.contains("panicked"),
            "{args:?}: {err}"
        );
        assert!(
            !dir.path().join("out/f_0.exr").exists() && !part.exists(),
            "{args:?}"
        );
    }
}

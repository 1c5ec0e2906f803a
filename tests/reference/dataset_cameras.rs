//! Cameras of datasets and cameras with intrinsics (docs/design.md §1 "Intrinsics", "Cameras of
//! datasets"): each reader's conventions pinned on a hand-made file whose answer is known, the
//! shared real files read, text and binary COLMAP equal, one camera given three ways rendering
//! the same bits, an off-centre principal point with fx ≠ fy against the closed form of one
//! sphere, and every refusal exiting 2 with the file named.

use crate::support::shared_or_skip;
use glam::DVec3;
use pgt::formats::cameras::{self, DatasetCamera};
use pgt::reference::{render, RenderOptions};
use pgt::scene::{Scene, SceneLoadOptions};
use std::path::{Path, PathBuf};
use std::process::Command;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).length() < 1e-12
}

/// A COLMAP text model: one PINHOLE camera and two images, one turned 90° about the camera's z.
fn colmap_text(dir: &Path) -> PathBuf {
    let model = dir.join("sparse");
    std::fs::create_dir_all(&model).unwrap();
    write(
        &model,
        "cameras.txt",
        "# comment\n1 PINHOLE 48 32 60 40 13.3 20.7\n",
    );
    let s = std::f64::consts::FRAC_1_SQRT_2;
    write(
        &model,
        "images.txt",
        &format!(
            "# IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME\n2 {s} 0 0 {s} 0 0 5 1 b.jpg\n\n1 1 0 0 0 -0.3 0.2 5 1 a.jpg\n1.0 2.0 -1\n"
        ),
    );
    model
}

#[test]
fn colmap_qvec_is_the_world_to_camera_rotation_in_opencv_axes() {
    let dir = tempfile::tempdir().unwrap();
    let cams = cameras::read(&colmap_text(dir.path())).unwrap();
    // Sorted by name; the empty points line of b.jpg is skipped like any other.
    assert_eq!(
        cams.iter().map(|c| c.name.as_str()).collect::<Vec<_>>(),
        ["a.jpg", "b.jpg"]
    );
    // Identity R, t = (−0.3, 0.2, 5): the eye is −t, looking down +z with image y down (u = −y).
    let a = &cams[0].camera;
    assert!(close(a.position, DVec3::new(0.3, -0.2, -5.0)), "{a:?}");
    assert_eq!((a.forward, a.right, a.up), (DVec3::Z, DVec3::X, -DVec3::Y));
    let k = a.intrinsics.unwrap();
    assert_eq!(
        (k.fx, k.fy, k.cx, k.cy, a.width, a.height),
        (60.0, 40.0, 13.3, 20.7, 48, 32)
    );
    // qvec (cos 45°, 0, 0, sin 45°) is R = Rz(90°): rows (0, −1, 0), (1, 0, 0), (0, 0, 1).
    let b = &cams[1].camera;
    assert!(
        close(b.right, -DVec3::Y) && close(b.up, -DVec3::X) && close(b.forward, DVec3::Z),
        "{b:?}"
    );
    assert!(close(b.position, DVec3::new(0.0, 0.0, -5.0)));
}

#[test]
fn colmap_text_and_binary_give_identical_cameras() {
    let text = shared_or_skip!("cameras/colmap/kapture_maupertuis_txt");
    let binary = shared_or_skip!("cameras/colmap/kapture_maupertuis_bin_pycolmap");
    let t = cameras::read(&text).unwrap();
    let b = cameras::read(&binary).unwrap();
    assert_eq!(t, b);
    assert_eq!(
        t.iter().map(|c| c.name.as_str()).collect::<Vec<_>>(),
        ["00.jpg", "01.jpg", "02.jpg", "03.jpg"]
    );
    let c = &t[0].camera;
    let k = c.intrinsics.unwrap();
    assert_eq!(
        (c.width, c.height, k.fx, k.fy, k.cx, k.cy),
        (1919, 1079, 1847.53, 1847.53, 959.5, 539.5)
    );
}

#[test]
fn transforms_json_is_camera_to_world_in_opengl_axes() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "transforms.json",
        r#"{"fl_x": 30, "w": 40, "h": 20, "cy": 9.5,
            "frames": [{"file_path": "x.png", "transform_matrix": [[1,0,0,1],[0,1,0,2],[0,0,1,3],[0,0,0,1]]},
                       {"file_path": "y.png", "fl_x": 50, "fl_y": 45, "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]}"#,
    );
    let cams = cameras::read(&p).unwrap();
    let a = &cams[0].camera;
    assert_eq!(
        (a.position, a.right, a.up, a.forward),
        (DVec3::new(1.0, 2.0, 3.0), DVec3::X, DVec3::Y, -DVec3::Z)
    );
    let k = a.intrinsics.unwrap();
    assert_eq!((k.fx, k.fy, k.cx, k.cy), (30.0, 30.0, 20.0, 9.5));
    let k = cams[1].camera.intrinsics.unwrap();
    assert_eq!((k.fx, k.fy), (50.0, 45.0));
}

#[test]
fn blender_lego_takes_its_width_from_the_png_and_brush_its_frame_intrinsics() {
    let lego = shared_or_skip!("cameras/transforms/nerfstudio_lego_test_transforms_train.json");
    let png = shared_or_skip!("cameras/transforms/nerfstudio_lego_test_train_r_0.png");
    // The frame names ./train/r_0: give it a folder of its own with the PNG there.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("train")).unwrap();
    std::fs::copy(&png, dir.path().join("train/r_0.png")).unwrap();
    let copy = dir.path().join("transforms_train.json");
    std::fs::copy(&lego, &copy).unwrap();
    let cams = cameras::read(&copy).unwrap();
    let c = &cams[0].camera;
    let f = 25.0 / (0.6911112070083618f64 / 2.0).tan();
    let k = c.intrinsics.unwrap();
    assert_eq!(
        (c.width, c.height, k.fx, k.fy, k.cx, k.cy),
        (50, 50, f, f, 25.0, 25.0)
    );
    // Without its image the size is unknown: refused, naming the file and the image.
    let e = cameras::read(&lego).unwrap_err().to_string();
    assert!(
        e.contains("nerfstudio_lego_test_transforms_train.json:7: frames[0]: no image size"),
        "{e}"
    );
    let brush = shared_or_skip!("cameras/transforms/brush_c_test_dataset_transforms.json");
    let b = cameras::read(&brush).unwrap();
    let k = b[0].camera.intrinsics.unwrap();
    assert_eq!(
        (b[0].camera.width, k.fx, k.fy, k.cx, k.cy),
        (50, 50.0, 50.0, 25.0, 25.0)
    );
    // Both are the same pose: the same eye.
    assert_eq!(b[0].camera.position, c.position);
}

#[test]
fn cameras_json_rotation_is_camera_to_world_in_opencv_axes() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "cameras.json",
        r#"[{"id": 0, "img_name": "a", "width": 30, "height": 20, "position": [1, 2, 3],
             "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], "fx": 40, "fy": 41}]"#,
    );
    let c = cameras::read(&p).unwrap()[0].camera;
    // The columns of `rotation` are the camera's x (right), y (down), z (forward) in the world.
    assert_eq!(
        (c.position, c.right, c.up, c.forward),
        (DVec3::new(1.0, 2.0, 3.0), DVec3::Y, DVec3::X, DVec3::Z)
    );
    let k = c.intrinsics.unwrap();
    assert_eq!((k.fx, k.fy, k.cx, k.cy), (40.0, 41.0, 15.0, 10.0));
    let real = shared_or_skip!("cameras/cameras_json/antimatter15_splat_train_cameras.json");
    let cams = cameras::read(&real).unwrap();
    assert_eq!(cams.len(), 10);
    let k = cams[0].camera.intrinsics.unwrap();
    assert_eq!((cams[0].camera.width, cams[0].camera.height), (1959, 1090));
    assert!(k.fx != k.fy);
}

const SPHERE: &str = "[render]\nmodel = \"emission\"\n[[particles]]\ncenter = [0.3, -0.2, 0.0]\nradius = 1.0\ncolor = [1.0, 1.0, 1.0]\nopacity = 0.5\n";

fn render_bits(scene: &Scene) -> Vec<u32> {
    let out = render(scene, &RenderOptions::default()).unwrap();
    out.image
        .pixels
        .iter()
        .flatten()
        .map(|v| v.to_bits())
        .collect()
}

#[test]
fn a_colmap_camera_its_scene_intrinsics_and_its_json_fed_back_render_the_same_bits() {
    let dir = tempfile::tempdir().unwrap();
    colmap_text(dir.path());
    let from = write(
        dir.path(),
        "from.toml",
        &format!("[camera]\nfrom = \"sparse\"\nimage = \"b.jpg\"\n{SPHERE}"),
    );
    let a = Scene::load(&from, &SceneLoadOptions::default()).unwrap();
    // The same camera written as intrinsics, R and t in a scene.
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let q = glam::DQuat::from_xyzw(0.0, 0.0, s, s).normalize();
    let r = glam::DMat3::from_quat(q).transpose().to_cols_array_2d();
    let by_hand = write(
        dir.path(),
        "hand.toml",
        &format!("[camera]\nfx = 60.0\nfy = 40.0\ncx = 13.3\ncy = 20.7\nwidth = 48\nheight = 32\nR = {r:?}\nt = [0.0, 0.0, 5.0]\n{SPHERE}"),
    );
    let b = Scene::load(&by_hand, &SceneLoadOptions::default()).unwrap();
    assert_eq!(a.camera, b.camera);
    // `pgt camera --json`'s K, R and eye fed back.
    let out = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(["camera", "--json"])
        .arg(&from)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let fed = write(
        dir.path(),
        "fed.toml",
        &format!(
            "[camera]\nfx = {}\nfy = {}\ncx = {}\ncy = {}\nwidth = {}\nheight = {}\nR = {}\nposition = {}\n{SPHERE}",
            j["fx"], j["fy"], j["cx"], j["cy"], j["width"], j["height"], j["R"], j["eye"]
        ),
    );
    let c = Scene::load(&fed, &SceneLoadOptions::default()).unwrap();
    assert_eq!(a.camera, c.camera);
    let bits = render_bits(&a);
    assert!(bits.iter().any(|&v| v != 0), "the sphere is in view");
    assert_eq!(bits, render_bits(&b));
    assert_eq!(bits, render_bits(&c));
}

#[test]
fn an_off_centre_principal_point_and_unequal_focal_lengths_render_the_closed_form() {
    // R = identity: the eye at the origin looks down +z, image x along +x, y along +y; pixel
    // (x, y) sees along d = ((x − cx)/fx, (y − cy)/fy, 1). A sphere (c, ρ) covers the pixel iff
    // the line's distance to c is below ρ: its silhouette is an ellipse in the image.
    let (fx, fy, cx, cy) = (60.0, 40.0, 13.3, 20.7);
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "s.toml",
        &format!(
            "[camera]\nfx = {fx}\nfy = {fy}\ncx = {cx}\ncy = {cy}\nwidth = 48\nheight = 32\nR = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]\nposition = [0.0, 0.0, 0.0]\n[render]\nmodel = \"emission\"\n[[particles]]\ncenter = [0.5, -0.6, 5.0]\nradius = 1.0\ncolor = [1.0, 1.0, 1.0]\nopacity = 0.5\n"
        ),
    );
    let scene = Scene::load(&p, &SceneLoadOptions::default()).unwrap();
    let out = render(&scene, &RenderOptions::default()).unwrap();
    let err = out.error.unwrap();
    let (c, rho) = (DVec3::new(0.5, -0.6, 5.0), 1.0f64);
    let sigma = -(0.5f64.ln()) / 2.0;
    let (mut inside, mut outside) = (0, 0);
    for py in 0..32u32 {
        for px in 0..48u32 {
            let d = DVec3::new(
                (px as f64 + 0.5 - cx) / fx,
                (py as f64 + 0.5 - cy) / fy,
                1.0,
            )
            .normalize();
            let dist = c.cross(d).length();
            let i = (py * 48 + px) as usize;
            let got = out.image.pixels[i][0] as f64;
            if dist > rho * (1.0 + 1e-6) {
                assert_eq!(got, 0.0, "pixel ({px}, {py}) outside the ellipse");
                outside += 1;
            } else if dist < rho * (1.0 - 1e-6) {
                let chord = 2.0 * (rho * rho - dist * dist).sqrt();
                let want = 1.0 - (-sigma * chord).exp();
                let e = err.pixels[i][0] as f64;
                assert!(
                    (got - want).abs() <= e + 1e-6,
                    "pixel ({px}, {py}): {got} vs {want} (err {e})"
                );
                assert!(got > 0.0);
                inside += 1;
            }
        }
    }
    assert!(inside > 50 && outside > 50, "{inside} {outside}");
}

/// A nerfstudio transforms.json of one frame: eye (1, 2, 3), the identity rotation, fx = fy = 30,
/// 40×20 pixels.
const ONE_FRAME_AT_1_2_3: &str = r#"{"fl_x": 30, "w": 40, "h": 20,
    "frames": [{"file_path": "x.png", "transform_matrix": [[1,0,0,1],[0,1,0,2],[0,0,1,3],[0,0,0,1]]}]}"#;

/// nerfstudio's dataparser transform, worked by hand: transform = Rz(90°) with translation
/// (0.5, −0.25, 0.1), scale 0.5, on the camera-to-world of eye (1, 2, 3) with the identity
/// rotation. c2w' = [T; 0 0 0 1]·c2w: the eye 0.5·(Rz·(1, 2, 3) + t) = 0.5·((−2, 1, 3) +
/// (0.5, −0.25, 0.1)) = (−0.75, 0.375, 1.55); the axes Rz·x = y (right), Rz·y = −x (up),
/// forward −z as before; the intrinsics unchanged.
#[test]
fn a_nerfstudio_dataparser_transform_maps_the_cameras_into_the_models_frame() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "transforms.json", ONE_FRAME_AT_1_2_3);
    write(
        d,
        "dp.json",
        r#"{"transform": [[0, -1, 0, 0.5], [1, 0, 0, -0.25], [0, 0, 1, 0.1]], "scale": 0.5}"#,
    );
    let scene = write(
        d,
        "s.toml",
        "[camera]\nfrom = \"transforms.json\"\ndataparser = \"dp.json\"\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n",
    );
    let c = Scene::load(&scene, &SceneLoadOptions::default())
        .unwrap()
        .camera;
    assert!(close(c.position, DVec3::new(-0.75, 0.375, 1.55)), "{c:?}");
    assert!(close(c.right, DVec3::Y) && close(c.up, -DVec3::X), "{c:?}");
    assert!(close(c.forward, -DVec3::Z), "{c:?}");
    let k = c.intrinsics.unwrap();
    assert_eq!(
        (k.fx, k.fy, k.cx, k.cy, c.width, c.height),
        (30.0, 30.0, 20.0, 10.0, 40, 20)
    );
    // Without the key the camera is the file's.
    let plain = write(
        d,
        "plain.toml",
        "[camera]\nfrom = \"transforms.json\"\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n",
    );
    let c = Scene::load(&plain, &SceneLoadOptions::default())
        .unwrap()
        .camera;
    assert!(close(c.position, DVec3::new(1.0, 2.0, 3.0)), "{c:?}");
}

/// A malformed dataparser file, or one given where it does not apply, exits 2 naming the file.
#[test]
fn a_bad_dataparser_file_exits_2_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "transforms.json", ONE_FRAME_AT_1_2_3);
    let pgt_camera = |toml: &str| {
        let scene = write(d, "dp.toml", toml);
        let out = Command::new(env!("CARGO_BIN_EXE_pgt"))
            .arg("camera")
            .arg(&scene)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{toml}");
        assert!(out.stdout.is_empty(), "{toml}: no output");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let with = "[camera]\nfrom = \"transforms.json\"\ndataparser = \"dp.json\"\n";
    for (text, words) in [
        (
            "{\"transform\": [[1, 0, 0, 0]\n, }",
            "dp.json:2: not a nerfstudio dataparser_transforms.json",
        ),
        (
            r#"{"transform": [[1, 0, 0, 0], [0, 1, 0, 0]], "scale": 1}"#,
            "\"transform\" must be 3 rows",
        ),
        (
            r#"{"transform": [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], "scale": 1}"#,
            "is not a rotation",
        ),
        (
            r#"{"transform": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}"#,
            "\"scale\" must be a finite number > 0",
        ),
        (
            r#"{"transform": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], "scale": -2}"#,
            "got -2",
        ),
        (
            r#"{"transform": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]], "scale": 1}"#,
            "fourth row",
        ),
    ] {
        write(d, "dp.json", text);
        let e = pgt_camera(with);
        assert!(e.contains("dp.json") && e.contains(words), "{text}: {e}");
    }
    std::fs::remove_file(d.join("dp.json")).unwrap();
    let e = pgt_camera(with);
    assert!(e.contains("dp.json"), "a missing file: {e}");
    // Without camera.from, and with a COLMAP model.
    let e = pgt_camera("[camera]\ndataparser = \"dp.json\"\n");
    assert!(e.contains("dp.toml:1: camera.dataparser"), "{e}");
    colmap_text(d);
    let e = pgt_camera("[camera]\nfrom = \"sparse\"\ndataparser = \"dp.json\"\n");
    assert!(
        e.contains("camera.dataparser applies to a transforms.json"),
        "{e}"
    );
}

/// `pgt camera SCENE` on a scene whose `[camera] from` is `dataset`: exit 2 and stderr.
fn refusal(dir: &Path, from: &str, image: Option<&str>) -> String {
    let image = image.map_or(String::new(), |i| format!("image = \"{i}\"\n"));
    let scene = write(
        dir,
        "refuse.toml",
        &format!("[camera]\nfrom = \"{from}\"\n{image}"),
    );
    let out = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .arg("camera")
        .arg(&scene)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn every_refusal_exits_2_naming_the_file_and_line_or_byte() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = colmap_text(d);
    // An image the model does not have.
    let e = refusal(d, "sparse", Some("zz.jpg"));
    assert!(
        e.contains("sparse: no image named \"zz.jpg\"") && e.contains("a.jpg"),
        "{e}"
    );
    // An unknown model, and a distortion model, named with the line.
    write(
        &model,
        "cameras.txt",
        "1 PINHOLE 48 32 60 40 13.3 20.7\n2 WEIRD 4 4 1\n",
    );
    let e = refusal(d, "sparse", None);
    assert!(
        e.contains("cameras.txt:2: unknown camera model \"WEIRD\""),
        "{e}"
    );
    write(
        &model,
        "cameras.txt",
        "1 OPENCV 48 32 60 40 13.3 20.7 0.1 0 0 0\n",
    );
    let e = refusal(d, "sparse", None);
    assert!(
        e.contains("cameras.txt:1: camera model OPENCV has lens distortion"),
        "{e}"
    );
    // A camera id the cameras file lacks.
    write(&model, "cameras.txt", "7 PINHOLE 48 32 60 40 13.3 20.7\n");
    let e = refusal(d, "sparse", None);
    assert!(
        e.contains("images.txt:2: image \"b.jpg\": its CAMERA_ID 1 is not in"),
        "{e}"
    );
    // A truncated binary model, named with the byte.
    let bin = d.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let mut cams = 1u64.to_le_bytes().to_vec();
    cams.extend(1u32.to_le_bytes());
    cams.extend(1u32.to_le_bytes());
    cams.extend(48u64.to_le_bytes());
    cams.extend(32u64.to_le_bytes());
    cams.extend(60f64.to_le_bytes());
    std::fs::write(bin.join("cameras.bin"), &cams).unwrap();
    std::fs::write(bin.join("images.bin"), 0u64.to_le_bytes()).unwrap();
    let e = refusal(d, "bin", None);
    assert!(e.contains("cameras.bin (byte 40): truncated"), "{e}");
    // A transforms.json without intrinsics, and a malformed one.
    write(d, "t.json", "{\"w\": 4, \"h\": 4, \"frames\": [\n{\"file_path\": \"a\",\n\"transform_matrix\": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]}");
    let e = refusal(d, "t.json", None);
    assert!(e.contains("t.json:3: frames[0]: no intrinsics"), "{e}");
    write(d, "t.json", "{\"frames\": [\n{,}]}");
    let e = refusal(d, "t.json", None);
    assert!(e.contains("t.json:2: not a transforms.json"), "{e}");
    // A cameras.json whose rotation is no rotation.
    write(d, "c.json", "[{\"img_name\": \"a\", \"width\": 4, \"height\": 4, \"position\": [0,0,0], \"rotation\": [[2,0,0],[0,1,0],[0,0,1]], \"fx\": 1, \"fy\": 1}]");
    let e = refusal(d, "c.json", None);
    assert!(
        e.contains("c.json:1: camera 0 (\"a\"): rotation is not a rotation"),
        "{e}"
    );
}

#[test]
fn a_camera_sequence_plays_one_frame_per_image() {
    let dir = tempfile::tempdir().unwrap();
    colmap_text(dir.path());
    let p = write(
        dir.path(),
        "seq.toml",
        &format!("[camera]\nfrom = \"sparse\"\n{SPHERE}"),
    );
    let frames = pgt::scene::SceneFrames::load(&p, &SceneLoadOptions::default()).unwrap();
    assert_eq!(frames.frame_count(), Some(2));
    let all: Vec<DatasetCamera> = cameras::read(&dir.path().join("sparse")).unwrap();
    for (i, c) in all.iter().enumerate() {
        assert_eq!(frames.frame(i).unwrap().camera, c.camera);
    }
    assert!(frames.frame(2).is_err());
    // --size scales the intrinsics: half the size, half fx and cx.
    let half = SceneLoadOptions {
        size: Some((24, 16)),
        ..SceneLoadOptions::default()
    };
    let s = Scene::load(&p, &half).unwrap();
    let k = s.camera.intrinsics.unwrap();
    assert_eq!((k.fx, k.fy, k.cx, k.cy), (30.0, 20.0, 6.65, 10.35));
}

//! End-to-end tests of `pgt render`: real files in, real files out, exit codes (docs/design.md §7).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn pgt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .env_remove("RAYON_NUM_THREADS")
        .output()
        .expect("the pgt binary runs")
}

fn example(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().expect("temp dir")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn renders_an_example_to_exr_and_png_and_they_read_back_alike() {
    let dir = tmp();
    let exr = dir.path().join("shadows.exr");
    let png = dir.path().join("shadows.png");
    let out = pgt(&[
        "render",
        &example("shadows.toml"),
        "-o",
        s(&exr),
        "--size",
        "64x48",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary = String::from_utf8_lossy(&out.stderr);
    assert!(
        summary.contains("64x48") && summary.contains("4 spheres") && summary.contains("rays/s"),
        "{summary}"
    );
    let out = pgt(&[
        "render",
        &example("shadows.toml"),
        "-o",
        s(&png),
        "--size",
        "64x48",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let e = pgt::image_io::read_image(&exr).unwrap();
    let p = pgt::image_io::read_image(&png).unwrap();
    assert_eq!((e.width, e.height), (64, 48));
    assert_eq!((p.width, p.height), (64, 48));
    assert!(e.all_finite());
    // The image is not flat: shadows and lit surfaces both appear.
    let lum: Vec<f32> = e.pixels.iter().map(|c| c[0] + c[1] + c[2]).collect();
    let max = lum.iter().cloned().fold(0.0, f32::max);
    let min = lum.iter().cloned().fold(f32::INFINITY, f32::min);
    assert!(max > 0.5 && min < 0.2, "min {min} max {max}");
    // The PNG is the 8-bit sRGB encoding of the EXR: decoded back, within half a code value.
    for (a, b) in e.pixels.iter().zip(&p.pixels) {
        for c in 0..3 {
            let expected = pgt::image_io::linear_to_srgb8(a[c], 1.0);
            let got = pgt::image_io::linear_to_srgb8(b[c], 1.0);
            assert!(expected.abs_diff(got) <= 1, "{a:?} vs {b:?}");
        }
    }
}

#[test]
fn the_image_is_bit_identical_for_one_and_two_threads() {
    let dir = tmp();
    let one = dir.path().join("one.exr");
    let two = dir.path().join("two.exr");
    for (threads, path) in [("1", &one), ("2", &two)] {
        let out = pgt(&[
            "render",
            &example("shadows.toml"),
            "-o",
            s(path),
            "--size",
            "96x64",
            "--spp",
            "2",
            "--threads",
            threads,
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let a = pgt::image_io::read_image(&one).unwrap();
    let b = pgt::image_io::read_image(&two).unwrap();
    let bits = |img: &pgt::image_io::RgbImage| -> Vec<u32> {
        img.pixels.iter().flatten().map(|v| v.to_bits()).collect()
    };
    assert_eq!(bits(&a), bits(&b));
}

/// Writes `text` as a scene file and renders it; returns the output, the scene path and whether
/// an output image was left behind.
fn render_scene_text(text: &str) -> (Output, PathBuf, bool) {
    let dir = tmp();
    let scene = dir.path().join("bad.toml");
    std::fs::write(&scene, text).unwrap();
    let image = dir.path().join("out.png");
    let out = pgt(&["render", s(&scene), "-o", s(&image)]);
    let leftovers = std::fs::read_dir(dir.path()).unwrap().count() > 1;
    (out, scene, image.exists() || leftovers)
}

#[test]
fn every_kind_of_bad_scene_exits_2_naming_file_and_line_without_output() {
    let valid_particle = "[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";
    let cases: Vec<(String, usize, &str)> = vec![
        (format!("{valid_particle}\n[[particles]]\ncenter = [1.0, 0.0, 0.0]\nradius = -2.0\n"), 5, "radius must be > 0"),
        (format!("{valid_particle}\n[[particles]]\ncenter = [1.0, 0.0, 0.0]\nradius = 0.0\n"), 5, "radius must be > 0"),
        ("[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nopacity = 1.5\n".into(), 1, "opacity must be in [0, 1]"),
        ("[[particles]]\ncenter = [0.0, nan, 0.0]\nradius = 1.0\n".into(), 1, "finite"),
        ("[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = inf\n".into(), 1, "finite"),
        ("[[particles]]\ncenter = [0.0, 0.0]\nradius = 1.0\n".into(), 2, "center"),
        ("[[particles]]\ncentre = [0.0, 0.0, 0.0]\nradius = 1.0\n".into(), 2, "centre"),
        ("[render]\nmodel = \"glowing\"\n".into(), 2, "glowing"),
        ("[render]\nmode = \"solid\"\n".into(), 2, "solid"),
        ("[render]\nlambda = 0.0\n".into(), 1, "lambda"),
        ("[render]\ntol = -1e-5\n".into(), 1, "tol"),
        ("\n\n[camera]\nwidth = 0\n".into(), 3, "image size"),
        ("[camera]\nposition = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\n".into(), 1, "look_at"),
        ("[camera]\nposition = [0.0, 0.0, -5.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, 1.0]\n".into(), 1, "parallel"),
        ("[camera]\nfov_y = 40.0\nfocal_length = 2.0\n".into(), 1, "not both"),
        ("[camera]\nfov_y = 180.0\n".into(), 1, "fov_y"),
        ("\n[[lights]]\ntype = \"directional\"\ndirection = [0.0, 0.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n".into(), 2, "non-zero"),
        ("[[lights]]\ntype = \"spot\"\nposition = [0.0, 0.0, 0.0]\n".into(), 2, "spot"),
        ("[[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 0.0]\n".into(), 1, "lights[0].intensity is required"),
        ("[[lights]]\ntype = \"directional\"\ndirection = [0.0, 1.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\nposition = [0.0, 0.0, 0.0]\n".into(), 1, "does not apply"),
        ("[[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 0.0]\nintensity = [-1.0, 1.0, 1.0]\n".into(), 1, "intensity"),
        ("[[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 0.0]\nintensity = [1.0, 1.0, 1.0]\nfalloff = \"cubic\"\n".into(), 5, "cubic"),
        ("[defaults]\nopacity = 0.5\nkappa = 1.0\n".into(), 1, "not both"),
        ("[render\nmodel = \"lit\"\n".into(), 1, ""),
        ("this is not toml at all".into(), 1, ""),
    ];
    for (text, line, needle) in cases {
        let (out, scene, wrote) = render_scene_text(&text);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "scene:\n{text}\nstderr: {err}");
        let location = format!("{}:{line}:", scene.display());
        assert!(
            err.contains(&location),
            "expected '{location}' in: {err}\nscene:\n{text}"
        );
        assert!(err.contains(needle), "expected '{needle}' in: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!wrote, "an output file was left behind for:\n{text}");
    }
}

#[test]
fn bad_command_lines_exit_2_without_output() {
    let dir = tmp();
    let png = dir.path().join("x.png");
    let missing = dir.path().join("missing.toml");
    for args in [
        vec!["render", s(&missing), "-o", s(&png)],
        vec![
            "render",
            &example("shadows.toml"),
            "-o",
            s(&dir.path().join("x.jpg")),
        ],
        vec![
            "render",
            &example("shadows.toml"),
            "-o",
            s(&png),
            "--size",
            "0x10",
        ],
        vec![
            "render",
            &example("shadows.toml"),
            "-o",
            s(&png),
            "--size",
            "big",
        ],
        vec![
            "render",
            &example("shadows.toml"),
            "-o",
            s(&png),
            "--spp",
            "0",
        ],
        vec![
            "render",
            &example("shadows.toml"),
            "-o",
            s(&png),
            "--spp",
            "100000",
        ],
        vec![
            "render",
            &example("shadows.toml"),
            "-o",
            s(&png),
            "--size",
            "30000x30000",
        ],
        vec![
            "render",
            &example("shadows.toml"),
            "-o",
            s(&png),
            "--tol",
            "nan",
        ],
        vec![
            "render",
            &example("shadows.toml"),
            "-o",
            s(&png),
            "--mode",
            "wireframe",
        ],
        vec!["render", &example("shadows.toml")],
    ] {
        let out = pgt(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!png.exists());
    }
}

#[test]
fn an_empty_scene_renders_the_background_with_a_warning() {
    let dir = tmp();
    let scene = dir.path().join("empty.toml");
    std::fs::write(&scene, "[render]\nmode = \"opaque\"\nbackground = [0.25, 0.5, 1.0]\n[camera]\nwidth = 8\nheight = 4\n").unwrap();
    let exr = dir.path().join("e.exr");
    let out = pgt(&["render", s(&scene), "-o", s(&exr)]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning"));
    let img = pgt::image_io::read_image(&exr).unwrap();
    assert!(img.pixels.iter().all(|p| *p == [0.25, 0.5, 1.0]));
}

#[test]
fn an_unwritable_output_exits_2() {
    // A file where a folder would have to be: unwritable for anyone, root included (a missing
    // folder is made, as for `--report`).
    let dir = tmp();
    let file = dir.path().join("file");
    std::fs::write(&file, "x").unwrap();
    let out = pgt(&[
        "render",
        &example("shadows.toml"),
        "-o",
        s(&file.join("x.png")),
        "--size",
        "8x8",
    ]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn model_names_come_from_the_registry() {
    let dir = tmp();
    let exr = dir.path().join("m.exr");
    let out = pgt(&[
        "render",
        &example("inside.toml"),
        "-o",
        s(&exr),
        "--model",
        "glowing",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for name in pgt::optics::models::ALL.iter().map(|m| m.name()) {
        assert!(err.contains(name), "'{name}' not listed in: {err}");
    }
    assert!(!exr.exists());
    for model in pgt::optics::models::ALL {
        let out = pgt(&[
            "render",
            &example("inside.toml"),
            "-o",
            s(&exr),
            "--model",
            model.name(),
            "--size",
            "8x6",
            "--tol",
            "1e-3",
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{model}: {err}");
        assert!(exr.exists(), "{model}");
    }
}

#[test]
fn gaussian_particles_render_exactly_and_what_cannot_draw_them_exits_2() {
    let dir = tmp();
    let exr = dir.path().join("gaussians.exr");
    let scene = example("gaussians.toml");
    let out = pgt(&["render", &scene, "-o", s(&exr), "--size", "24x24"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("error estimate max") && err.contains("5 Gaussians"),
        "{err}"
    );
    let err_layer = pgt::image_io::read_exr_layer(&exr, "err").expect("the err layer");
    assert!(err_layer
        .pixels
        .iter()
        .flatten()
        .all(|&e| e > 0.0 && e <= 1e-5));
    // Exported, the Gaussians carry their standard deviations and peak σ but not their
    // profile: export says so, and the CSV included with density = "gaussian" renders the
    // same image within the two errs.
    let csv = dir.path().join("gaussians.csv");
    let out = pgt(&["export", &scene, "-o", s(&csv)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("density = \"gaussian\""), "{err}");
    let text = std::fs::read_to_string(&scene).expect("the example");
    let settings = &text[..text.find("[defaults]").expect("a [defaults] table")];
    let again = dir.path().join("again.toml");
    std::fs::write(
        &again,
        format!("{settings}\n[[include]]\npath = \"gaussians.csv\"\ndensity = \"gaussian\"\n"),
    )
    .expect("write the scene");
    let exr2 = dir.path().join("again.exr");
    let out = pgt(&["render", s(&again), "-o", s(&exr2), "--size", "24x24"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (a, b) = (
        pgt::image_io::read_exr_layer(&exr, "").expect("first"),
        pgt::image_io::read_exr_layer(&exr2, "").expect("again"),
    );
    let err2 = pgt::image_io::read_exr_layer(&exr2, "err").expect("the err layer");
    let mut lit = 0;
    for i in 0..a.pixels.len() {
        for c in 0..3 {
            let bound = err_layer.pixels[i][c] + err2.pixels[i][c];
            assert!(
                (a.pixels[i][c] - b.pixels[i][c]).abs() <= bound,
                "pixel {i} channel {c}: {} against {}",
                a.pixels[i][c],
                b.pixels[i][c]
            );
            if a.pixels[i][c] > 0.2 {
                lit += 1;
            }
        }
    }
    assert!(lit > 20, "the Gaussians hardly show");
    // Single-scatter with a = 1 and a sun: Q = E + α·E_l·T_l/4π ≥ E at every point, so every
    // pixel is at least the emission image's (within the two errs), and brighter where lit.
    let sunny = dir.path().join("sunny.toml");
    std::fs::write(
        &sunny,
        format!("{text}\n[[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, 0.4]\nirradiance = [6.0, 6.0, 6.0]\n"),
    )
    .expect("write the scene");
    let scattered = dir.path().join("scattered.exr");
    let out = pgt(&[
        "render",
        s(&sunny),
        "--model",
        "single-scatter",
        "-o",
        s(&scattered),
        "--size",
        "24x24",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let c = pgt::image_io::read_exr_layer(&scattered, "").expect("single-scatter");
    let c_err = pgt::image_io::read_exr_layer(&scattered, "err").expect("its err layer");
    let mut brighter = 0;
    for i in 0..a.pixels.len() {
        for ch in 0..3 {
            assert!(
                c_err.pixels[i][ch] <= 1e-5,
                "pixel {i}: err {}",
                c_err.pixels[i][ch]
            );
            let bound = err_layer.pixels[i][ch] + c_err.pixels[i][ch];
            assert!(
                c.pixels[i][ch] >= a.pixels[i][ch] - bound,
                "pixel {i} channel {ch}: {} below the emission image's {}",
                c.pixels[i][ch],
                a.pixels[i][ch]
            );
            if c.pixels[i][ch] > a.pixels[i][ch] + 0.01 {
                brighter += 1;
            }
        }
    }
    assert!(brighter > 20, "the sun hardly shows");
    for (args, words) in [
        (vec!["render", &scene, "--model", "lit"], "lit model"),
        (vec!["render", &scene, "--mode", "opaque"], "no surface"),
        (
            vec!["approx", &scene, "--method", "emission"],
            "Gaussian particles",
        ),
    ] {
        let target = dir.path().join("refused.exr");
        let mut full = args.clone();
        full.extend(["-o", s(&target), "--size", "8x8"]);
        let out = pgt(&full);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(words), "{args:?}: {err}");
        assert!(!target.exists(), "{args:?} left a file behind");
    }
}

//! End-to-end tests of `pgt compare` (docs/design.md §5, §7): the real binary, exit codes 0 / 1 / 2,
//! the verdict, the JSON summary, gate files and the report folder.

use pgt::image_io::{write_image, RgbImage};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn pgt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .output()
        .expect("pgt runs")
}

fn code(o: &Output) -> i32 {
    o.status.code().expect("exit code")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A smooth test image with a small deterministic perturbation of amplitude `noise`.
fn image(w: u32, h: u32, noise: f32) -> RgbImage {
    let mut img = RgbImage::new(w, h);
    let mut state = 12345u32;
    for y in 0..h {
        for x in 0..w {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let n = (state >> 8) as f32 / (1u32 << 24) as f32 - 0.5;
            let base = [x as f32 / w as f32, y as f32 / h as f32, 0.5];
            img.pixels[(y * w + x) as usize] =
                base.map(|v| (v * 0.8 + 0.1 + noise * n).clamp(0.0, 1.0));
        }
    }
    img
}

fn save(dir: &Path, name: &str, img: &RgbImage) -> String {
    let p: PathBuf = dir.join(name);
    write_image(&p, img, &[], 0.0).unwrap();
    p.to_string_lossy().into_owned()
}

#[test]
fn passing_pair_exits_0_with_pass_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let r = save(dir.path(), "r.exr", &image(40, 30, 0.0));
    let a = save(dir.path(), "a.exr", &image(40, 30, 0.01));
    let o = pgt(&[
        "compare",
        &r,
        &a,
        "--min-ssim",
        "0.9",
        "--max-rmse",
        "0.05",
        "--max-flip",
        "0.5",
    ]);
    assert_eq!(code(&o), 0, "stderr: {}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.starts_with("PASS (3 gates)"), "{out}");
    assert_eq!(out.lines().count(), 1, "one-line verdict: {out}");
}

#[test]
fn failing_pair_exits_1_naming_the_metric() {
    let dir = tempfile::tempdir().unwrap();
    let r = save(dir.path(), "r.exr", &image(40, 30, 0.0));
    let a = save(dir.path(), "a.exr", &image(40, 30, 0.3));
    let o = pgt(&["compare", &r, &a, "--min-ssim", "0.99", "--max-rmse", "1.0"]);
    assert_eq!(code(&o), 1, "stderr: {}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.starts_with("FAIL min_ssim"), "{out}");
    assert!(
        !out.contains("max_rmse ="),
        "only failing metrics are named: {out}"
    );
    // A FLIP gate fails by name too, and --json F writes the summary while stdout keeps the verdict.
    let json = dir.path().join("s.json");
    let o = pgt(&[
        "compare",
        &r,
        &a,
        "--max-flip",
        "0.001",
        "--json",
        &json.to_string_lossy(),
    ]);
    assert_eq!(code(&o), 1);
    assert!(
        text(&o.stdout).starts_with("FAIL max_flip"),
        "{}",
        text(&o.stdout)
    );
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(v["passed"], false);
    assert_eq!(v["gates"][0]["name"], "max_flip");
    assert_eq!(v["gates"][0]["passed"], false);
}

#[test]
fn broken_inputs_exit_2_with_a_message_naming_the_files() {
    let dir = tempfile::tempdir().unwrap();
    let r = save(dir.path(), "r.exr", &image(40, 30, 0.0));
    let small = save(dir.path(), "small.exr", &image(20, 30, 0.0));
    // Different sizes: both files named.
    let o = pgt(&["compare", &r, &small]);
    assert_eq!(code(&o), 2);
    let err = text(&o.stderr);
    assert!(
        err.contains("r.exr") && err.contains("small.exr") && err.contains("size"),
        "{err}"
    );
    // Missing file.
    let o = pgt(&[
        "compare",
        &r,
        &dir.path().join("nope.exr").to_string_lossy(),
    ]);
    assert_eq!(code(&o), 2);
    assert!(text(&o.stderr).contains("nope.exr"));
    // Truncated EXR.
    let bytes = std::fs::read(&r).unwrap();
    let broken = dir.path().join("broken.exr");
    std::fs::write(&broken, &bytes[..bytes.len() / 2]).unwrap();
    let o = pgt(&["compare", &r, &broken.to_string_lossy()]);
    assert_eq!(code(&o), 2);
    assert!(
        text(&o.stderr).contains("broken.exr"),
        "{}",
        text(&o.stderr)
    );
    // NaN in the approximation: an error, never a pass.
    let mut nan = image(40, 30, 0.0);
    nan.pixels[5][2] = f32::NAN;
    // Written with the exr crate: pgt's own writer refuses non-finite values (issue 13).
    let n = dir.path().join("nan.exr");
    exr::prelude::write_rgb_file(&n, 40, 30, |x, y| {
        let p = nan.pixels[y * 40 + x];
        (p[0], p[1], p[2])
    })
    .unwrap();
    let n = n.to_string_lossy().into_owned();
    let o = pgt(&["compare", &r, &n, "--min-ssim", "0.0"]);
    assert_eq!(code(&o), 2);
    assert!(
        text(&o.stderr).contains("non-finite"),
        "{}",
        text(&o.stderr)
    );
    // A layer that does not exist.
    let o = pgt(&["compare", &r, &r, "--layer", "err"]);
    assert_eq!(code(&o), 2);
    assert!(
        text(&o.stderr).contains("layer 'err'"),
        "{}",
        text(&o.stderr)
    );
    // A gate on SSIM of an image below the 11×11 window cannot be decided: error, not pass.
    let tiny = save(dir.path(), "tiny.exr", &image(8, 8, 0.0));
    let o = pgt(&["compare", &tiny, &tiny, "--min-ssim", "0.5"]);
    assert_eq!(code(&o), 2, "{}", text(&o.stdout));
}

#[test]
fn png_channel_count_mismatch_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let rgb = dir.path().join("rgb.png");
    let grey = dir.path().join("grey.png");
    image::RgbImage::from_pixel(16, 16, image::Rgb([10, 20, 30]))
        .save(&rgb)
        .unwrap();
    image::GrayImage::from_pixel(16, 16, image::Luma([20]))
        .save(&grey)
        .unwrap();
    let o = pgt(&["compare", &rgb.to_string_lossy(), &grey.to_string_lossy()]);
    assert_eq!(code(&o), 2);
    let err = text(&o.stderr);
    assert!(
        err.contains("channel count") && err.contains("rgb.png") && err.contains("grey.png"),
        "{err}"
    );
}

#[test]
fn gate_file_per_channel_and_percentiles() {
    let dir = tempfile::tempdir().unwrap();
    let r = save(dir.path(), "r.exr", &image(40, 30, 0.0));
    let mut approx = image(40, 30, 0.0);
    // Only the blue channel of a 3×3 block is off: the mean passes, the blue channel fails.
    for y in 10..13 {
        for x in 10..13 {
            approx.pixels[y * 40 + x][2] += 0.5;
        }
    }
    let a = save(dir.path(), "a.exr", &approx);
    let gate = dir.path().join("gate.toml");
    std::fs::write(
        &gate,
        "max_rmse = 0.5\n[channels]\nmax_abs = [0.1, 0.1, 0.1]\n",
    )
    .unwrap();
    let o = pgt(&["compare", &r, &a, "--gate", &gate.to_string_lossy()]);
    assert_eq!(code(&o), 1, "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains("channels.max_abs[B]") && !out.contains("channels.max_abs[R]"),
        "{out}"
    );
    // 9 of 1200 pixels are off: the 99th percentile of the abs map is 0, the 99.5th is not.
    std::fs::write(
        &gate,
        "[[percentiles]]\nmap = \"abs\"\npercentile = 99.0\nmax = 1e-6\n",
    )
    .unwrap();
    let o = pgt(&["compare", &r, &a, "--gate", &gate.to_string_lossy()]);
    assert_eq!(code(&o), 0, "{} {}", text(&o.stdout), text(&o.stderr));
    std::fs::write(
        &gate,
        "[[percentiles]]\nmap = \"abs\"\npercentile = 99.5\nmax = 1e-6\n",
    )
    .unwrap();
    let o = pgt(&["compare", &r, &a, "--gate", &gate.to_string_lossy()]);
    assert_eq!(code(&o), 1);
    assert!(
        text(&o.stdout).contains("p99.5(abs)"),
        "{}",
        text(&o.stdout)
    );
    // Unknown keys are errors that name the file.
    std::fs::write(&gate, "min_ssim = 0.9\nmax_rsme = 0.1\n").unwrap();
    let o = pgt(&["compare", &r, &a, "--gate", &gate.to_string_lossy()]);
    assert_eq!(code(&o), 2);
    let err = text(&o.stderr);
    assert!(
        err.contains("gate.toml") && err.contains("max_rsme"),
        "{err}"
    );
}

#[test]
fn json_summary_to_stdout_and_identical_images() {
    let dir = tempfile::tempdir().unwrap();
    let img = image(32, 24, 0.05);
    let r = save(dir.path(), "r.exr", &img);
    let a = save(dir.path(), "a.exr", &img);
    let o = pgt(&["compare", &r, &a, "--json", "-"]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is JSON");
    assert_eq!(v["ssim"]["mean"], 1.0);
    assert_eq!(v["ssim"]["G"], 1.0);
    assert_eq!(v["rmse"]["mean"], 0.0);
    assert_eq!(
        v["psnr"]["R"],
        serde_json::Value::Null,
        "infinite PSNR is null"
    );
    assert_eq!(v["flip"], 0.0);
    assert_eq!(v["passed"], serde_json::Value::Null);
    assert_eq!(v["data_range_source"], "default");
    assert!(
        text(&o.stderr).starts_with("compared: SSIM 1.000000"),
        "{}",
        text(&o.stderr)
    );
}

#[test]
fn exr_layer_and_hdr_data_range() {
    let dir = tempfile::tempdir().unwrap();
    let base = image(24, 24, 0.0);
    let hdr = RgbImage {
        pixels: base.pixels.iter().map(|p| p.map(|v| v * 8.0)).collect(),
        ..base.clone()
    };
    let r = dir.path().join("r.exr");
    write_image(&r, &hdr, &[("err", &base)], 0.0).unwrap();
    let a = dir.path().join("a.exr");
    write_image(&a, &hdr, &[("err", &image(24, 24, 0.2))], 0.0).unwrap();
    let (r, a) = (
        r.to_string_lossy().into_owned(),
        a.to_string_lossy().into_owned(),
    );
    // The unnamed layer is identical; the err layers differ.
    let o = pgt(&["compare", &r, &a, "--json", "-"]);
    assert_eq!(code(&o), 0);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["rmse"]["mean"], 0.0);
    assert_eq!(v["data_range_source"], "derived");
    // HDR input: HDR-FLIP, 0 for identical images.
    assert_eq!(v["flip"], 0.0);
    assert_eq!(v["flip_kind"], "hdr");
    assert!(text(&o.stderr).contains("derived"));
    let o = pgt(&[
        "compare",
        &r,
        &a,
        "--layer",
        "err",
        "--json",
        "-",
        "--data-range",
        "1",
    ]);
    assert_eq!(code(&o), 0);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["rmse"]["mean"].as_f64().unwrap() > 0.01);
    assert_eq!(v["data_range_source"], "given");
    assert!(v["reference_uncertainty"].is_null());
}

#[test]
fn report_folder_has_page_maps_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let r = save(dir.path(), "r.exr", &image(48, 32, 0.0));
    let a = save(dir.path(), "a.png", &image(48, 32, 0.1));
    let rep = dir.path().join("rep");
    let o = pgt(&[
        "compare",
        &r,
        &a,
        "--report",
        &rep.to_string_lossy(),
        "--error-scale",
        "0.01",
        "--min-ssim",
        "0.1",
    ]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    for f in [
        "index.html",
        "reference.png",
        "approximation.png",
        "abs_error.png",
        "rel_error.png",
        "ssim.png",
        "flip.png",
        "maps.exr",
        "summary.json",
    ] {
        assert!(rep.join(f).is_file(), "{f} missing");
    }
    let html = std::fs::read_to_string(rep.join("index.html")).unwrap();
    assert!(html.contains("scale 0 … 0.01 (fixed)"));
    // The maps EXR holds the abs error as its main layer and the SSIM map as a layer.
    let abs = pgt::image_io::read_exr_layer(&rep.join("maps.exr"), "").unwrap();
    assert_eq!((abs.width, abs.height), (48, 32));
    let ssim = pgt::image_io::read_exr_layer(&rep.join("maps.exr"), "ssim").unwrap();
    assert!(ssim.pixels.iter().all(|p| p.iter().all(|v| *v <= 1.0)));
    // The heatmap is the map pixel for pixel; its colour bar is SVG with text in the page,
    // labelled up to the fixed scale's top.
    let heat = image::open(rep.join("abs_error.png")).unwrap();
    assert_eq!((heat.width(), heat.height()), (48, 32));
    assert!(html.contains("<svg class=\"colorbar\"") && html.contains(">0.01</text>"));
}

#[test]
fn scene_reference_is_rendered_on_the_fly() {
    let dir = tempfile::tempdir().unwrap();
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/shadows.toml");
    let rendered = dir.path().join("r.exr");
    let o = pgt(&[
        "render",
        &scene.to_string_lossy(),
        "-o",
        &rendered.to_string_lossy(),
    ]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    // The scene rendered on the fly equals the same scene rendered to a file.
    let o = pgt(&[
        "compare",
        &scene.to_string_lossy(),
        &rendered.to_string_lossy(),
        "--json",
        "-",
    ]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["rmse"]["mean"], 0.0);
    assert_eq!(v["ssim"]["mean"], 1.0);
    // A different size is refused, naming both.
    let small = dir.path().join("small.exr");
    let o = pgt(&[
        "render",
        &scene.to_string_lossy(),
        "-o",
        &small.to_string_lossy(),
        "--size",
        "64x48",
    ]);
    assert_eq!(code(&o), 0);
    let o = pgt(&[
        "compare",
        &scene.to_string_lossy(),
        &small.to_string_lossy(),
    ]);
    assert_eq!(code(&o), 2);
    let err = text(&o.stderr);
    assert!(
        err.contains("shadows.toml") && err.contains("small.exr"),
        "{err}"
    );
}

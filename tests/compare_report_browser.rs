//! The HTML report in a real headless browser (DESIGN.md §5 "Reports"): Debian's `chromium`
//! loads the page written by `pgt compare --report`, the page's inline script marks
//! `<body data-pgt-images="ok">` once every `img` has decoded (naturalWidth > 0), `--dump-dom`
//! shows the mark, and a screenshot is taken.
//!
//! Skipped (with a message) only where chromium is absent and `CI` is not set; under `CI=true`
//! a missing chromium fails the test.

use pgt::image_io::{write_image, RgbImage};
use std::path::{Path, PathBuf};
use std::process::Command;

fn chromium() -> Option<PathBuf> {
    for name in ["chromium", "chromium-browser", "google-chrome"] {
        if let Ok(o) = Command::new("sh")
            .args(["-c", &format!("command -v {name}")])
            .output()
        {
            let p = String::from_utf8_lossy(&o.stdout).trim().to_string();
            if o.status.success() && !p.is_empty() {
                return Some(PathBuf::from(p));
            }
        }
    }
    None
}

fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0" && v != "false")
}

fn browser_args(user_data: &Path) -> Vec<String> {
    [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-dev-shm-usage",
        "--virtual-time-budget=5000",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([format!("--user-data-dir={}", user_data.display())])
    .collect()
}

fn test_image(w: u32, h: u32, shift: f32) -> RgbImage {
    let mut img = RgbImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let fx = x as f32 / w as f32;
            let fy = y as f32 / h as f32;
            img.pixels[(y * w + x) as usize] =
                [fx, fy, ((fx * 9.0 + shift).sin() * 0.5 + 0.5) * 0.8];
        }
    }
    img
}

/// Runs chromium on `page` with `extra` arguments, returning stdout.
fn run_chromium(exe: &Path, page: &Path, extra: &[String]) -> String {
    let profile = tempfile::tempdir().unwrap();
    let url = format!("file://{}", page.canonicalize().unwrap().display());
    let out = Command::new(exe)
        .args(browser_args(profile.path()))
        .args(extra)
        .arg(&url)
        .output()
        .expect("chromium runs");
    assert!(
        out.status.success(),
        "chromium failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn report_loads_in_headless_chromium_with_every_image() {
    let Some(exe) = chromium() else {
        if in_ci() {
            panic!("CI is set but chromium is not installed (apt-get install chromium)");
        }
        eprintln!("skipping: chromium not installed (CI not set)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path().join("r.exr");
    let a = dir.path().join("a.exr");
    write_image(&r, &test_image(64, 48, 0.0), &[], 0.0).unwrap();
    write_image(&a, &test_image(64, 48, 0.3), &[], 0.0).unwrap();
    let rep = dir.path().join("report");
    let o = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args([
            "compare",
            &r.to_string_lossy(),
            &a.to_string_lossy(),
            "--report",
            &rep.to_string_lossy(),
        ])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let page = rep.join("index.html");

    let dom = run_chromium(&exe, &page, &["--dump-dom".to_string()]);
    assert!(
        dom.contains("data-pgt-images=\"ok\""),
        "not every image loaded:\n{dom}"
    );
    // Six figures: reference, approximation, abs error, SSIM, rel error, FLIP.
    assert!(dom.contains("data-pgt-image-count=\"6\""), "{dom}");
    assert!(dom.contains("<td>SSIM</td>"));

    // A missing image must be caught by the same mark (the check can fail).
    std::fs::remove_file(rep.join("ssim.png")).unwrap();
    let dom = run_chromium(&exe, &page, &["--dump-dom".to_string()]);
    assert!(
        dom.contains("data-pgt-images=\"missing\"") && dom.contains("ssim.png"),
        "{dom}"
    );

    let shot = dir.path().join("shot.png");
    run_chromium(
        &exe,
        &page,
        &[
            format!("--screenshot={}", shot.display()),
            "--window-size=1200,900".to_string(),
        ],
    );
    let img = image::open(&shot).expect("screenshot is a PNG");
    assert_eq!((img.width(), img.height()), (1200, 900));
}

#[test]
fn sweep_report_loads_in_headless_chromium_with_its_plots() {
    let Some(exe) = chromium() else {
        if in_ci() {
            panic!("CI is set but chromium is not installed (apt-get install chromium)");
        }
        eprintln!("skipping: chromium not installed (CI not set)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/shadows.toml");
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        format!(
            "scene = {:?}\nsize = [40, 30]\n[reference]\nspp = 2\n[[approximations]]\nmethod = \"riemann\"\nsamples = [1, 2]\nspp = [1]\n",
            scene.to_string_lossy()
        ),
    )
    .unwrap();
    let rep = dir.path().join("sweep");
    let o = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args([
            "sweep",
            &exp.to_string_lossy(),
            "--report",
            &rep.to_string_lossy(),
        ])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let dom = run_chromium(&exe, &rep.join("index.html"), &["--dump-dom".to_string()]);
    // Four SVG plots (1 − SSIM, RMSE, time, error against time), the reference, and two runs
    // with their error heatmaps.
    assert!(dom.contains("data-pgt-images=\"ok\""), "{dom}");
    assert!(dom.contains("data-pgt-image-count=\"9\""), "{dom}");
}

/// Copies the committed report `reports/thesis` (without its caches) into `to`.
fn copy_report(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let path = entry.path();
        if entry.file_name() == "cache" {
            continue;
        }
        if path.is_dir() {
            copy_report(&path, &to.join(entry.file_name()));
        } else {
            std::fs::copy(&path, to.join(entry.file_name())).unwrap();
        }
    }
}

/// The `src` of every `<img>` of an HTML page.
fn image_sources(page: &str) -> Vec<String> {
    page.split("<img src=\"")
        .skip(1)
        .filter_map(|s| s.split('"').next().map(str::to_string))
        .collect()
}

#[test]
fn thesis_report_loads_in_headless_chromium_with_every_image_and_plot() {
    let report = Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/thesis");
    let page = report.join("index.html");
    let text = std::fs::read_to_string(&page).expect("reports/thesis/index.html is committed");
    let sources = image_sources(&text);
    // Per data set: the four plots (time and error against samples and time, 1 − SSIM
    // against the GT), the reference and five runs, and the attributions' bars and maps.
    for set in ["1uun", "random"] {
        for plot in [
            "time.svg",
            "error_time.svg",
            "dssim.svg",
            "dssim_baseline.svg",
        ] {
            let src = format!("{set}/{plot}");
            assert!(sources.contains(&src), "{src} is not on the page");
        }
        for cause in ["float32", "n_exact", "overlap", "sampling"] {
            let src = format!("{set}/attribution_thesis_samples_100_n_exact_5_{cause}.png");
            assert!(sources.contains(&src), "{src} is not on the page");
        }
        let bars = format!("{set}/attribution_thesis_samples_100_n_exact_5.svg");
        assert!(sources.contains(&bars), "{bars} is not on the page");
    }
    for src in &sources {
        assert!(
            report.join(src).is_file(),
            "{src} is on the page but not committed"
        );
    }
    let Some(exe) = chromium() else {
        if in_ci() {
            panic!("CI is set but chromium is not installed (apt-get install chromium)");
        }
        eprintln!("skipping the browser: chromium not installed (CI not set)");
        return;
    };
    let dom = run_chromium(&exe, &page, &["--dump-dom".to_string()]);
    assert!(dom.contains("data-pgt-images=\"ok\""), "{dom}");
    let count = format!("data-pgt-image-count=\"{}\"", sources.len());
    assert!(dom.contains(&count), "expected {count}: {dom}");

    // A missing plot is caught by the same mark (the check can fail).
    let dir = tempfile::tempdir().unwrap();
    copy_report(&report, dir.path());
    std::fs::remove_file(dir.path().join("random/error_time.svg")).unwrap();
    let dom = run_chromium(
        &exe,
        &dir.path().join("index.html"),
        &["--dump-dom".to_string()],
    );
    assert!(
        dom.contains("data-pgt-images=\"missing\"") && dom.contains("random/error_time.svg"),
        "{dom}"
    );
}

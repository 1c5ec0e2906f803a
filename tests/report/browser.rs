//! The HTML report in a real headless browser (docs/design.md §5 "Reports"): Debian's `chromium`
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
        crate::support::skipped("chromium not installed (CI not set)");
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
        crate::support::skipped("chromium not installed (CI not set)");
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
    // against the GT), the attributions' bars, maps and their colour bar, the 512² images and
    // the study's plot.
    for set in ["1uun", "cool_random"] {
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
        let scale = format!("{set}/attribution_thesis_samples_100_n_exact_5_scale.svg");
        assert!(sources.contains(&scale), "{scale} is not on the page");
        for src in [
            format!("512/{set}_reference.png"),
            format!("study_{set}.svg"),
        ] {
            assert!(sources.contains(&src), "{src} is not on the page");
        }
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
        crate::support::skipped("the browser part: chromium not installed (CI not set)");
        return;
    };
    let dom = run_chromium(&exe, &page, &["--dump-dom".to_string()]);
    assert!(dom.contains("data-pgt-images=\"ok\""), "{dom}");
    let count = format!("data-pgt-image-count=\"{}\"", sources.len());
    assert!(dom.contains(&count), "expected {count}: {dom}");

    // A missing plot is caught by the same mark (the check can fail).
    let dir = tempfile::tempdir().unwrap();
    copy_report(&report, dir.path());
    std::fs::remove_file(dir.path().join("cool_random/error_time.svg")).unwrap();
    let dom = run_chromium(
        &exe,
        &dir.path().join("index.html"),
        &["--dump-dom".to_string()],
    );
    assert!(
        dom.contains("data-pgt-images=\"missing\"") && dom.contains("cool_random/error_time.svg"),
        "{dom}"
    );
}

use crate::support::webdriver;

/// The probe's cells for `key` (reference, approximation, difference, estimate), parsed.
fn probe_row(s: &webdriver::Session, key: &str) -> Vec<f64> {
    (0..3)
        .map(|c| {
            let t = s.text(&format!("td[data-probe=\"{key}-{c}\"]"));
            t.parse::<f64>()
                .unwrap_or_else(|_| panic!("probe {key}-{c} shows '{t}'"))
        })
        .collect()
}

/// A value shown with six significant digits equals the file's float to that precision.
fn assert_shown(shown: &[f64], expected: [f64; 3], what: &str) {
    for c in 0..3 {
        let tol = 5e-6 * expected[c].abs().max(1e-30);
        assert!(
            (shown[c] - expected[c]).abs() <= tol,
            "{what} channel {c}: probe shows {}, the EXR holds {}",
            shown[c],
            expected[c]
        );
    }
}

/// The bounding box of a pane's canvas (after its zoom and pan) and of its viewport, in CSS
/// pixels of the browser's viewport: [left, top, width, height] each.
fn boxes(s: &webdriver::Session, pane: &str) -> ([f64; 4], [f64; 4]) {
    let v = s.eval(&format!(
        "var c = document.getElementById('pgt-canvas-{pane}').getBoundingClientRect();\
         var v = document.getElementById('pgt-viewport-{pane}').getBoundingClientRect();\
         return [c.left, c.top, c.width, c.height, v.left, v.top, v.width, v.height];"
    ));
    let n: Vec<f64> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    ([n[0], n[1], n[2], n[3]], [n[4], n[5], n[6], n[7]])
}

/// Where the centre of image pixel (x, y) lies on screen in `pane`.
fn pixel_centre(
    s: &webdriver::Session,
    pane: &str,
    (w, h): (u32, u32),
    (x, y): (u32, u32),
) -> (f64, f64) {
    let (c, v) = boxes(s, pane);
    let px = c[0] + (x as f64 + 0.5) * c[2] / w as f64;
    let py = c[1] + (y as f64 + 0.5) * c[3] / h as f64;
    assert!(
        px > v[0] && px < v[0] + v[2] && py > v[1] && py < v[1] + v[3],
        "pixel ({x}, {y}) at ({px}, {py}) is outside pane {pane}'s viewport {v:?}"
    );
    (px, py)
}

/// docs/design.md §5 "Interactive where a browser runs it": in headless chromium driven through
/// chromedriver, the report zooms (buttons and wheel, all panes together, nearest-neighbour
/// pixels), pans, flips A/B by key and button, changes the exposure, and the pixel probe under
/// a hovered pixel shows the reference, approximation, |a − r| and error estimate that the
/// EXR files hold.
#[test]
fn viewer_zooms_flips_and_probes_the_exr_values() {
    let Some((browser, driver)) = webdriver::browser_and_driver() else {
        return;
    };
    let (w, h) = (64u32, 48u32);
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path().join("r.exr");
    let a = dir.path().join("a.exr");
    let mut err = RgbImage::new(w, h);
    for (i, p) in err.pixels.iter_mut().enumerate() {
        *p = [1e-6 * (i as f32 + 1.0), 2e-7 * (i % 7) as f32, 3.5e-5];
    }
    write_image(&r, &test_image(w, h, 0.0), &[("err", &err)], 0.0).unwrap();
    write_image(&a, &test_image(w, h, 0.3), &[], 0.0).unwrap();
    let rep = dir.path().join("report");
    let o = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args([
            "compare",
            &r.to_string_lossy(),
            &a.to_string_lossy(),
            "--report",
        ])
        .arg(&rep)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // What the files hold, read back as any user's tool would.
    let ref_px = pgt::image_io::read_exr_layer(&r, "").unwrap();
    let app_px = pgt::image_io::read_exr_layer(&a, "").unwrap();
    let err_px = pgt::image_io::read_exr_layer(&r, "err").unwrap();
    let at = |img: &RgbImage, (x, y): (u32, u32)| img.get(x, y).map(|v| v as f64);

    let s = webdriver::Session::start(&browser, &driver, 1400, 1000);
    s.open(
        &rep.join("index.html"),
        "document.getElementById('pgt-viewer') && document.getElementById('pgt-viewer').getAttribute('data-ready') === '1'",
    );
    assert_eq!(
        s.eval("return document.getElementById('pgt-viewer').hidden;"),
        false
    );
    assert_eq!(
        s.eval("return getComputedStyle(document.getElementById('pgt-canvas-a')).imageRendering;"),
        "pixelated"
    );
    // The colour bars are SVG with text, not pixels.
    let bar_text = s.eval("return Array.from(document.querySelectorAll('svg.colorbar text')).map(t => t.textContent);");
    assert!(
        bar_text.as_array().is_some_and(|t| t.len() >= 10),
        "{bar_text}"
    );

    // Zoom: twice by button, once by the wheel over pane a; all panes keep the same box.
    let (fit_box, _) = boxes(&s, "a");
    s.click("#pgt-zoom-in");
    s.click("#pgt-zoom-in");
    let (c, v) = boxes(&s, "a");
    s.wheel(v[0] + v[2] / 2.0, v[1] + v[3] / 2.0, -100);
    let (zoomed, _) = boxes(&s, "a");
    let zoom = zoomed[2] / fit_box[2];
    assert!(
        zoom > 3.0 && zoomed[2] > c[2],
        "zoom {zoom}: {fit_box:?} → {c:?} → {zoomed:?}"
    );
    for pane in ["b", "e"] {
        let (cb, vb) = boxes(&s, pane);
        let (ca, va) = boxes(&s, "a");
        for k in 0..4 {
            let rel = |c: [f64; 4], v: [f64; 4]| if k < 2 { c[k] - v[k] } else { c[k] };
            assert!(
                (rel(cb, vb) - rel(ca, va)).abs() < 0.5,
                "pane {pane} not in step with a"
            );
        }
    }

    // Hover a known pixel in pane a, then the same pixel in the error pane.
    let target = (w / 2 + 2, h / 2 - 3);
    for pane in ["a", "e"] {
        let (px, py) = pixel_centre(&s, pane, (w, h), target);
        s.hover(px, py);
        let probe = s.eval("var t = document.getElementById('pgt-probe'); return [t.getAttribute('data-x'), t.getAttribute('data-y')];");
        assert_eq!(
            probe,
            serde_json::json!([target.0.to_string(), target.1.to_string()]),
            "pane {pane}"
        );
        let (rv, av, ev) = (
            at(&ref_px, target),
            at(&app_px, target),
            at(&err_px, target),
        );
        assert_shown(&probe_row(&s, "reference"), rv, "reference");
        assert_shown(&probe_row(&s, "approximation"), av, "approximation");
        assert_shown(
            &probe_row(&s, "difference"),
            [0, 1, 2].map(|c| (av[c] - rv[c]).abs()),
            "|a − r|",
        );
        assert_shown(&probe_row(&s, "estimate"), ev, "error estimate");
    }
    // A different pixel shows different values (the probe follows the pointer).
    let other = (3, 40);
    let (c, _) = boxes(&s, "a");
    s.click("#pgt-zoom-fit");
    let (px, py) = pixel_centre(&s, "b", (w, h), other);
    s.hover(px, py);
    assert_shown(
        &probe_row(&s, "reference"),
        at(&ref_px, other),
        "reference at (3, 40)",
    );
    assert!(boxes(&s, "a").0[2] < c[2], "fit did not zoom out");

    // Pan: dragging pane b moves every pane.
    s.click("#pgt-zoom-in");
    let before = boxes(&s, "e").0;
    let (_, vb) = boxes(&s, "b");
    let centre = (vb[0] + vb[2] / 2.0, vb[1] + vb[3] / 2.0);
    s.drag(centre, (centre.0 - 40.0, centre.1 - 30.0));
    let after = boxes(&s, "e").0;
    assert!(
        (after[0] - before[0] + 40.0).abs() < 2.0 && (after[1] - before[1] + 30.0).abs() < 2.0,
        "{before:?} → {after:?}"
    );

    // A/B flip: key f, then the button.
    let flipped = |s: &webdriver::Session| {
        s.eval("return document.getElementById('pgt-viewer').getAttribute('data-flipped');")
    };
    assert_eq!(flipped(&s), "0");
    assert!(s.text("#pgt-title-a").contains("reference"));
    s.key("f");
    assert_eq!(flipped(&s), "1");
    assert!(s.text("#pgt-title-a").contains("approximation"));
    s.click("#pgt-flip");
    assert_eq!(flipped(&s), "0");

    // Exposure: +1 stop doubles the linear value the reference pane encodes.
    let canvas_px = format!(
        "var d = document.getElementById('pgt-canvas-a').getContext('2d').getImageData({}, {}, 1, 1).data; return [d[0], d[1], d[2]];",
        target.0, target.1
    );
    let srgb = |v: f64| pgt::image_io::linear_to_srgb8(v as f32, 1.0) as i64;
    let shown = |s: &webdriver::Session| -> Vec<i64> {
        s.eval(&canvas_px)
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_i64().unwrap())
            .collect()
    };
    let rv = at(&ref_px, target);
    assert_eq!(shown(&s), rv.map(srgb).to_vec());
    s.eval("var e = document.getElementById('pgt-exposure'); e.value = '1'; e.dispatchEvent(new Event('input')); return 0;");
    assert_eq!(shown(&s), rv.map(|v| srgb(2.0 * v)).to_vec());
}

/// The sweep page's viewer: a run is chosen from a list, and the probe shows the reference's
/// values (as the reference's cached EXR holds them) against the chosen run's.
#[test]
fn sweep_viewer_switches_runs_and_probes_the_reference() {
    let Some((browser, driver)) = webdriver::browser_and_driver() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/shadows.toml");
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        format!(
            "scene = {:?}\nsize = [40, 30]\n[reference]\nspp = 2\n[[approximations]]\nmethod = \"riemann\"\nsamples = [1]\nspp = [1, 2]\n",
            scene.to_string_lossy()
        ),
    )
    .unwrap();
    let rep = dir.path().join("sweep");
    let o = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(["sweep", &exp.to_string_lossy(), "--report"])
        .arg(&rep)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let cache = std::fs::read_dir(rep.join("cache"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "exr"))
        .expect("the cached reference");
    let reference = pgt::image_io::read_exr_layer(&cache, "").unwrap();

    let s = webdriver::Session::start(&browser, &driver, 1400, 1000);
    s.open(
        &rep.join("index.html"),
        "document.getElementById('pgt-viewer') && document.getElementById('pgt-viewer').getAttribute('data-ready') === '1'",
    );
    s.eval("document.getElementById('pgt-viewer').scrollIntoView(); return 0;");
    let options = s.eval(
        "return Array.from(document.querySelectorAll('#pgt-run option')).map(o => o.textContent);",
    );
    assert_eq!(
        options,
        serde_json::json!(["riemann samples=1 spp=1", "riemann samples=1 spp=2"])
    );
    // Choose the run at the reference's own spp: in opaque mode it is the reference, bit for bit.
    s.eval("var r = document.getElementById('pgt-run'); r.value = '1'; r.dispatchEvent(new Event('change')); return 0;");
    assert!(s.text("#pgt-title-b").contains("spp=2"));
    let target = (20, 14);
    let (px, py) = pixel_centre(&s, "a", (40, 30), target);
    s.hover(px, py);
    let rv = reference.get(target.0, target.1).map(|v| v as f64);
    assert_shown(&probe_row(&s, "reference"), rv, "reference");
    assert_shown(&probe_row(&s, "approximation"), rv, "run spp=2");
    assert_eq!(probe_row(&s, "difference"), vec![0.0; 3]);
    // No error estimate in a sweep's cached reference: the row says so.
    assert_eq!(s.text("td[data-probe=\"estimate-0\"]"), "—");
}

/// docs/design.md §10: the committed report of a sequence comparison
/// (`reports/examples/popping/report`) opens from `file://` with every image, shows its player,
/// and steps, plays and jumps to a worst frame: the panes show that frame's files.
#[test]
fn sequence_report_plays_its_frames() {
    let Some((browser, driver)) = webdriver::browser_and_driver() else {
        return;
    };
    let page =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/examples/popping/report/index.html");
    let s = webdriver::Session::start(&browser, &driver, 1200, 900);
    s.open(
        &page,
        "document.body.getAttribute('data-pgt-images') !== 'pending'",
    );
    assert_eq!(
        s.eval("return document.body.getAttribute('data-pgt-images');"),
        serde_json::json!("ok"),
        "broken: {}",
        s.eval("return document.body.getAttribute('data-pgt-broken');")
    );
    assert_eq!(
        s.eval("return document.getElementById('pgt-player').hidden;"),
        serde_json::json!(false)
    );
    assert_eq!(s.text("#pgt-frame"), "frame 0");
    s.click("[data-step='1']");
    assert_eq!(s.text("#pgt-frame"), "frame 1");
    let src = |id: &str| {
        s.eval(&format!(
            "return document.getElementById('{id}').getAttribute('src');"
        ))
        .as_str()
        .unwrap_or_default()
        .to_string()
    };
    assert_eq!(src("pgt-r"), "frames/r_000001.png");
    assert_eq!(src("pgt-a"), "frames/a_000001.png");
    assert_eq!(src("pgt-t"), "frames/t_000001.png");
    s.click("[data-step='-1']");
    assert_eq!(s.text("#pgt-frame"), "frame 0");
    // Play advances the frames; pause stops them.
    s.click("#pgt-play");
    std::thread::sleep(std::time::Duration::from_millis(700));
    s.click("#pgt-play");
    let shown = s.text("#pgt-frame");
    let n: usize = shown.trim_start_matches("frame ").parse().unwrap();
    assert!(n >= 1, "play did not advance: {shown}");
    std::thread::sleep(std::time::Duration::from_millis(500));
    assert_eq!(s.text("#pgt-frame"), shown, "pause did not stop the player");
    // A worst-frame link of the summary table jumps the player to that frame.
    let target = s
        .eval("return document.querySelector('table a[data-frame]').getAttribute('data-frame');")
        .as_str()
        .unwrap()
        .to_string();
    s.click("table a[data-frame]");
    assert_eq!(s.text("#pgt-frame"), format!("frame {target}"));
    assert_eq!(
        src("pgt-r"),
        format!("frames/r_{:06}.png", target.parse::<usize>().unwrap())
    );
    // The probe: a pixel of the approximation pane shows that frame's values (its file loads
    // from file://; sequence_probe_shows_each_frames_values checks them against the EXRs).
    let b = s.eval("var b = document.getElementById('pgt-a').getBoundingClientRect(); return [b.left + b.width / 2, b.top + b.height / 2];");
    let (x, y) = (b[0].as_f64().unwrap(), b[1].as_f64().unwrap());
    s.hover(x, y);
    wait_until(
        &s,
        &format!("document.getElementById('pgt-probe').getAttribute('data-frame') === '{target}'"),
    );
    for key in ["reference", "approximation", "temporal"] {
        let row = sequence_probe_row(&s, key);
        assert!(
            row.iter().all(|v| v.is_some_and(f64::is_finite)),
            "{key}: {row:?}"
        );
    }
}

/// Waits until the JS expression `ready` is true in the page.
fn wait_until(s: &webdriver::Session, ready: &str) {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    while s.eval(&format!("return !!({ready});")) != serde_json::json!(true) {
        assert!(std::time::Instant::now() < deadline, "never true: {ready}");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
}

/// The probe's cells for `key` (reference, approximation, temporal) of the sequence player,
/// parsed; `None` for a cell showing "—".
fn sequence_probe_row(s: &webdriver::Session, key: &str) -> Vec<Option<f64>> {
    (0..3)
        .map(|c| {
            let t = s.text(&format!("#pgt-probe td[data-probe=\"{key}-{c}\"]"));
            (t != "—").then(|| {
                t.parse::<f64>()
                    .unwrap_or_else(|_| panic!("probe {key}-{c} shows '{t}'"))
            })
        })
        .collect()
}

/// A value the probe shows (four significant digits of a float16) equals the file's float.
fn assert_near_half(shown: &[Option<f64>], expected: [f64; 3], what: &str) {
    for c in 0..3 {
        let v = shown[c].unwrap_or_else(|| panic!("{what} channel {c} shows no value"));
        let tol = 1.5e-3 * expected[c].abs() + 1e-6;
        assert!(
            (v - expected[c]).abs() <= tol,
            "{what} channel {c}: probe shows {v}, the files hold {}",
            expected[c]
        );
    }
}

/// docs/design.md §10: the sequence player's pixel probe. Two small sequences written here are
/// compared with `--report`; in headless chromium, hovering a pixel of the reference pane shows
/// that frame's reference and approximation values (no e_t for the first frame); stepping and the
/// slider change the frame under the same pixel, and the probe follows with the new frame's
/// values and its e_t = |(A_t − A_{t−1}) − (R_t − R_{t−1})|; hovering the e_t pane probes there.
#[test]
fn sequence_probe_shows_each_frames_values() {
    let Some((browser, driver)) = webdriver::browser_and_driver() else {
        return;
    };
    let (w, h, n) = (32u32, 24u32, 4usize);
    let dir = tempfile::tempdir().unwrap();
    let (rd, ad) = (dir.path().join("ref"), dir.path().join("approx"));
    std::fs::create_dir_all(&rd).unwrap();
    std::fs::create_dir_all(&ad).unwrap();
    let mut frames = Vec::new();
    for k in 0..n {
        let r = test_image(w, h, 0.4 * k as f32);
        let a = test_image(w, h, 0.4 * k as f32 + 0.15 * (k % 2) as f32);
        write_image(&rd.join(format!("f_{k:03}.exr")), &r, &[], 0.0).unwrap();
        write_image(&ad.join(format!("f_{k:03}.exr")), &a, &[], 0.0).unwrap();
        frames.push((r, a));
    }
    let rep = dir.path().join("report");
    let o = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(["compare", &rd.to_string_lossy(), &ad.to_string_lossy()])
        .args(["--no-flip", "--report", &rep.to_string_lossy()])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let value = |img: &RgbImage, (x, y): (u32, u32)| img.get(x, y).map(|v| v as f64);
    let temporal = |k: usize, (x, y): (u32, u32)| {
        let (r, a) = (&frames[k].0, &frames[k].1);
        let (rp, ap) = (&frames[k - 1].0, &frames[k - 1].1);
        let g = |i: &RgbImage| i.get(x, y).map(|v| v as f64);
        let (r, a, rp, ap) = (g(r), g(a), g(rp), g(ap));
        [0, 1, 2].map(|c| ((a[c] - ap[c]) - (r[c] - rp[c])).abs())
    };

    let s = webdriver::Session::start(&browser, &driver, 1400, 1000);
    s.open(
        &rep.join("index.html"),
        "document.body.getAttribute('data-pgt-images') === 'ok'",
    );
    s.eval("document.getElementById('pgt-player').scrollIntoView(); return 0;");
    let centre = |pane: &str, (x, y): (u32, u32)| -> (f64, f64) {
        let b = s.eval(&format!(
            "var b = document.getElementById('{pane}').getBoundingClientRect(); return [b.left, b.top, b.width, b.height];"
        ));
        let b: Vec<f64> = b
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        (
            b[0] + (x as f64 + 0.5) * b[2] / w as f64,
            b[1] + (y as f64 + 0.5) * b[3] / h as f64,
        )
    };
    let shows_frame = |k: usize| {
        wait_until(
            &s,
            &format!("document.getElementById('pgt-probe').getAttribute('data-frame') === '{k}'"),
        )
    };

    // Frame 0, hovered in the reference pane: its values, no e_t.
    let p = (5, 17);
    let (x, y) = centre("pgt-r", p);
    s.hover(x, y);
    shows_frame(0);
    assert_eq!(
        s.text("#pgt-probe-pixel"),
        format!("frame 0, pixel ({}, {})", p.0, p.1)
    );
    assert_near_half(
        &sequence_probe_row(&s, "reference"),
        value(&frames[0].0, p),
        "reference 0",
    );
    assert_near_half(
        &sequence_probe_row(&s, "approximation"),
        value(&frames[0].1, p),
        "approx 0",
    );
    assert_eq!(sequence_probe_row(&s, "temporal"), vec![None; 3]);

    // A step: the same pixel, frame 1's values and e_t, without moving the mouse.
    s.click("[data-step='1']");
    shows_frame(1);
    assert_near_half(
        &sequence_probe_row(&s, "reference"),
        value(&frames[1].0, p),
        "reference 1",
    );
    assert_near_half(
        &sequence_probe_row(&s, "approximation"),
        value(&frames[1].1, p),
        "approx 1",
    );
    assert_near_half(&sequence_probe_row(&s, "temporal"), temporal(1, p), "e_t 1");

    // The slider to the last frame, then a pixel of the e_t pane.
    s.eval(&format!(
        "var r = document.getElementById('pgt-slider'); r.value = '{}'; r.dispatchEvent(new Event('input')); return 0;",
        n - 1
    ));
    shows_frame(n - 1);
    let q = (28, 3);
    let (x, y) = centre("pgt-t", q);
    s.hover(x, y);
    wait_until(
        &s,
        &format!(
            "document.getElementById('pgt-probe').getAttribute('data-x') === '{}'",
            q.0
        ),
    );
    assert_eq!(
        s.text("#pgt-probe-pixel"),
        format!("frame {}, pixel ({}, {})", n - 1, q.0, q.1)
    );
    assert_near_half(
        &sequence_probe_row(&s, "reference"),
        value(&frames[n - 1].0, q),
        "reference last",
    );
    assert_near_half(
        &sequence_probe_row(&s, "approximation"),
        value(&frames[n - 1].1, q),
        "approx last",
    );
    assert_near_half(
        &sequence_probe_row(&s, "temporal"),
        temporal(n - 1, q),
        "e_t last",
    );
}

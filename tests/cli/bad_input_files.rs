//! Bad gate files, experiment files and user WGSL files get the treatment bad scenes get
//! (docs/design.md §6, issue 13 item 6): exit 2, a message naming the file and line (the file alone
//! where no line is meaningful: bytes that are not text) and the problem, and no output (no
//! JSON summary, no report folder, no image).

use std::path::Path;
use std::process::{Command, Output};

fn pgt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .output()
        .expect("pgt runs")
}

/// Writes `bytes` to `dir/name` and returns the path as a string.
fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p.to_string_lossy().into_owned()
}

/// Asserts exit 2 and a stderr that starts the error at `file:line:` (or `file:` for line 0)
/// and contains `reason`.
fn assert_refused(o: &Output, file: &str, line: usize, reason: &str, case: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{case}: {err}");
    let at = if line == 0 {
        format!("error: {file}: ")
    } else {
        format!("error: {file}:{line}:")
    };
    assert!(err.contains(&at), "{case}: expected `{at}` in: {err}");
    assert!(
        err.contains(reason),
        "{case}: expected `{reason}` in: {err}"
    );
    if case == "not text" {
        // The I/O error is the message's cause and its text: said once, not twice.
        assert_eq!(
            err.matches(reason).count(),
            1,
            "{case}: said twice in: {err}"
        );
    }
}

const NOT_UTF8: &[u8] = b"min_ssim = 0.9\n\xff\xfe\x00\x01garbage";

#[test]
fn bad_gate_files_exit_2_naming_file_and_line_without_output() {
    let dir = tempfile::tempdir().unwrap();
    // Two identical 16×16 images (written by pgt's own writer).
    let image = pgt::image_io::RgbImage::new(16, 16);
    let a = dir.path().join("a.exr");
    pgt::image_io::write_image(&a, &image, &[], 0.0).unwrap();
    let a = a.to_string_lossy().into_owned();
    let cases: &[(&str, &[u8], usize, &str)] = &[
        ("syntax", b"min_ssim = = 0.9\n", 1, "invalid string"),
        (
            "unknown key",
            b"min_ssim = 0.9\nmax_rsme = 0.1\n",
            2,
            "max_rsme",
        ),
        ("type", b"max_rmse = \"low\"\n", 1, "expected f64"),
        (
            "channel count",
            b"[channels]\nmin_ssim = [0.9, 0.9]\n",
            2,
            "length 2",
        ),
        (
            "nan",
            b"max_rmse = 0.1\nmin_ssim = nan\n",
            2,
            "min_ssim must be a finite number",
        ),
        (
            "inf in channels",
            b"[channels]\nmax_abs = [1.0, inf, 1.0]\n",
            2,
            "finite",
        ),
        (
            "unknown map",
            b"[[percentiles]]\nmap = \"foo\"\npercentile = 5\nmax = 1\n",
            2,
            "unknown variant `foo`",
        ),
        (
            "percentile range",
            b"min_ssim = 0.5\n\n[[percentiles]]\nmap = \"abs\"\npercentile = 500\nmax = 1\n",
            3,
            "percentile must be in (0, 100]",
        ),
        (
            "two bounds",
            b"[[percentiles]]\nmap = \"abs\"\npercentile = 5\nmax = 1\nmin = 0\n",
            1,
            "exactly one finite",
        ),
        ("not text", NOT_UTF8, 0, "valid UTF-8"),
    ];
    for (case, text, line, reason) in cases {
        let gate = write(dir.path(), "gate.toml", text);
        let json = dir.path().join("out.json");
        let report = dir.path().join("report");
        let o = pgt(&[
            "compare",
            &a,
            &a,
            "--gate",
            &gate,
            "--json",
            &json.to_string_lossy(),
            "--report",
            &report.to_string_lossy(),
        ]);
        assert_refused(&o, &gate, *line, reason, case);
        assert!(!json.exists() && !report.exists(), "{case}: output written");
    }
}

#[test]
fn bad_experiment_files_exit_2_naming_file_and_line_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/shadows.toml");
    let scene = format!("scene = {:?}\n", scene.to_string_lossy());
    let riemann = "[[approximations]]\nmethod = \"riemann\"\nsamples = [1]\n";
    let long: Vec<String> = (1..=200).map(|n| n.to_string()).collect();
    let long = long.join(", ");
    let spp: Vec<String> = (1..=64).map(|n| n.to_string()).collect();
    let spp = spp.join(", ");
    let cases: Vec<(&str, String, usize, &str)> = vec![
        ("syntax", format!("{scene}size = = 16\n{riemann}"), 2, "invalid"),
        ("no scene", format!("size = [16, 16]\n{riemann}"), 1, "missing field `scene`"),
        ("unknown key", format!("{scene}sise = [16, 16]\n{riemann}"), 2, "sise"),
        ("size", format!("{scene}size = [0, 16]\n{riemann}"), 2, "image size must be between 1"),
        ("data range", format!("{scene}data_range = -1.0\n{riemann}"), 2, "data_range must be a finite number > 0"),
        ("reference spp", format!("{scene}[reference]\nspp = 0\n{riemann}"), 2, "reference.spp must be between 1 and 64"),
        ("reference tol", format!("{scene}[reference]\ntol = nan\n{riemann}"), 2, "reference.tol must be a finite number > 0"),
        ("no method", format!("{scene}[[approximations]]\nsamples = [1]\n"), 3, "needs `method"),
        ("unknown method", format!("{scene}[[approximations]]\nmethod = \"magic\"\n"), 3, "unknown method \"magic\""),
        ("unknown parameter", format!("{scene}{riemann}bogus = 1\n"), 5, "no parameter 'bogus'"),
        ("value range", format!("{scene}[[approximations]]\nmethod = \"riemann\"\nspp = [65]\n"), 4, "expected whole numbers from 1 to 64"),
        ("baseline", format!("{scene}{riemann}baseline = {{ samples = 7 }}\n"), 5, "not one of the experiment's runs"),
        ("too many runs", format!("{scene}[[approximations]]\nmethod = \"riemann\"\nsamples = [{long}]\nspp = [{spp}]\n"), 3, "more than 10000 runs"),
    ];
    for (case, text, line, reason) in &cases {
        let exp = write(dir.path(), "exp.toml", text.as_bytes());
        let report = dir.path().join("report");
        let o = pgt(&["sweep", &exp, "--report", &report.to_string_lossy()]);
        assert_refused(&o, &exp, *line, reason, case);
        assert!(!report.exists(), "{case}: report folder written");
    }
    let exp = write(dir.path(), "exp.toml", NOT_UTF8);
    let report = dir.path().join("report");
    let o = pgt(&["sweep", &exp, "--report", &report.to_string_lossy()]);
    assert_refused(&o, &exp, 0, "valid UTF-8", "not text");
    assert!(!report.exists());
}

#[test]
fn bad_user_shaders_exit_2_naming_their_file_and_line_without_output() {
    // No GPU needed: the WGSL is read and validated before an adapter is opened.
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/inside.toml");
    let head = "// my method\n";
    let cases: Vec<(&str, String, usize, &str)> = vec![
        ("syntax", format!("{head}fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {{\n    let x = ;\n}}\n"), 3, "expected expression"),
        ("unknown name", format!("{head}fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {{\n    return vec3<f32>(no_such_value);\n}}\n"), 3, "no_such_value"),
        ("type", format!("{head}fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {{\n    return 1.0;\n}}\n"), 3, "automatic conversions"),
        ("signature", format!("{head}fn shade(ray: Ray) -> vec3<f32> {{\n    return vec3<f32>(0.0);\n}}\n"), 2, "`shade` must be `fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32>`"),
        ("redefinition", format!("{head}fn camera_ray(pixel: vec2<u32>) -> Ray {{\n    return Ray(vec3<f32>(0.0), vec3<f32>(1.0));\n}}\nfn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {{\n    return vec3<f32>(0.0);\n}}\n"), 2, "redefinition of `camera_ray`"),
        ("no shade", format!("{head}fn helper() -> f32 {{\n    return 1.0;\n}}\n"), 0, "must define `fn shade"),
    ];
    for (case, text, line, reason) in &cases {
        let shader = write(dir.path(), "mine.wgsl", text.as_bytes());
        let out = dir.path().join("out.png");
        let o = pgt(&[
            "approx",
            &scene.to_string_lossy(),
            "--shader",
            &shader,
            "-o",
            &out.to_string_lossy(),
        ]);
        assert_refused(&o, &shader, *line, reason, case);
        assert!(!out.exists(), "{case}: image written");
    }
    let shader = write(dir.path(), "mine.wgsl", b"fn shade(\xff\xfe");
    let o = pgt(&[
        "approx",
        &scene.to_string_lossy(),
        "--shader",
        &shader,
        "-o",
        "x.png",
    ]);
    assert_refused(&o, &shader, 0, "valid UTF-8", "not text");
}

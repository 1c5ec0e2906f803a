//! Sequences of frames from the command line (docs/design.md §10): `render --frames` and
//! `approx --frames` write every frame's file, resume by render hash, split frames over parts;
//! `compare` of two sequences gives the temporal error, and finds sorted-blend's popping at
//! exactly the frames where two overlapping particles' centre depths swap.

use crate::support::gpu;

use pgt::image_io::{read_image, RgbImage};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn pgt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .output()
        .expect("run pgt")
}

fn ok(args: &[&str]) -> String {
    let out = pgt(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "pgt {args:?} failed: {err}");
    err
}

fn fails_with(args: &[&str], code: i32) -> String {
    let out = pgt(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(code), "pgt {args:?}: {err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A multi-frame XYZ of three atoms moving along x, `frames` frames (the last cut short after
/// `cut_last` atom lines when given).
fn write_xyz(path: &Path, frames: usize, cut_last: Option<usize>) {
    let mut text = String::new();
    for f in 0..frames {
        text += "3\nframe\n";
        let atoms = if f + 1 == frames {
            cut_last.unwrap_or(3)
        } else {
            3
        };
        for a in 0..atoms {
            let x = a as f64 * 1.5 - 1.5 + 0.3 * f as f64;
            text += &format!("{} {x:.3} {:.3} 0.0\n", ["C", "O", "N"][a], 0.2 * a as f64);
        }
    }
    std::fs::write(path, text).unwrap();
}

/// A scene that plays the XYZ `traj.xyz` beside it (or shows its frame `pin`).
fn write_scene(dir: &Path, pin: Option<usize>, extra: &str) -> PathBuf {
    let pin = pin.map_or(String::new(), |k| format!("frame = {k}\n"));
    let text = format!(
        r#"[render]
mode = "volume"
model = "emission"
{extra}
[camera]
position = [0, 0, 12]
look_at = [0, 0, 0]
width = 24
height = 20

[defaults]
opacity = 0.7

[[include]]
path = "traj.xyz"
{pin}"#
    );
    let path = dir.join(match pin.is_empty() {
        true => "scene.toml".to_string(),
        false => format!("pinned_{}.toml", pin.trim().replace(' ', "")),
    });
    std::fs::write(&path, text).unwrap();
    path
}

fn image(path: &Path) -> RgbImage {
    read_image(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn every_frame_is_the_render_of_that_frame_alone() {
    let dir = tempfile::tempdir().unwrap();
    write_xyz(&dir.path().join("traj.xyz"), 4, None);
    let scene = write_scene(dir.path(), None, "");
    let pattern = dir.path().join("out/f_%02d.exr");
    let err = ok(&["render", s(&scene), "--frames", "0..4", "-o", s(&pattern)]);
    assert!(err.contains("rendered 4 frame(s)"), "{err}");
    let mut previous: Option<RgbImage> = None;
    for k in 0..4 {
        let pinned = write_scene(dir.path(), Some(k), "");
        let single = dir.path().join(format!("single_{k}.exr"));
        ok(&["render", s(&pinned), "-o", s(&single)]);
        let framed = image(&dir.path().join(format!("out/f_{k:02}.exr")));
        assert_eq!(framed, image(&single), "frame {k}");
        // The atoms move: consecutive frames differ.
        if let Some(p) = previous.replace(framed.clone()) {
            assert_ne!(p, framed, "frames {} and {k} are the same", k - 1);
        }
    }
}

/// The files of `dir` (names) whose names start with `prefix`.
fn files(dir: &Path, prefix: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.starts_with(prefix))
        .collect();
    v.sort();
    v
}

#[test]
fn a_sequence_resumes_by_render_hash() {
    let dir = tempfile::tempdir().unwrap();
    write_xyz(&dir.path().join("traj.xyz"), 4, None);
    let scene = write_scene(dir.path(), None, "");
    let pattern = dir.path().join("out/f_%d.exr");
    ok(&["render", s(&scene), "--frames", "0..4", "-o", s(&pattern)]);
    let f1 = dir.path().join("out/f_1.exr");
    let before = std::fs::read(&f1).unwrap();
    std::fs::remove_file(dir.path().join("out/f_2.exr")).unwrap();
    let err = ok(&["render", s(&scene), "--frames", "0..4", "-o", s(&pattern)]);
    assert!(
        err.contains("rendered 1 frame(s)") && err.contains("skipped 3"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(&f1).unwrap(),
        before,
        "a skipped frame was rewritten"
    );
    // Another tolerance is another render: every frame again.
    let err = ok(&[
        "render",
        s(&scene),
        "--frames",
        "0..4",
        "--tol",
        "1e-6",
        "-o",
        s(&pattern),
    ]);
    assert!(err.contains("rendered 4 frame(s)"), "{err}");
    // A file that is not pgt's is rendered over, not trusted.
    std::fs::write(dir.path().join("out/f_3.exr"), b"not an exr").unwrap();
    let err = ok(&[
        "render",
        s(&scene),
        "--frames",
        "0..4",
        "--tol",
        "1e-6",
        "-o",
        s(&pattern),
    ]);
    assert!(err.contains("rendered 1 frame(s)"), "{err}");
    image(&dir.path().join("out/f_3.exr"));
}

#[test]
fn parts_split_the_frames_and_the_reference_has_no_temporal_error_against_itself() {
    let dir = tempfile::tempdir().unwrap();
    write_xyz(&dir.path().join("traj.xyz"), 5, None);
    let scene = write_scene(dir.path(), None, "");
    let whole = dir.path().join("whole/f_%03d.exr");
    ok(&[
        "render",
        s(&scene),
        "--frames",
        "0..5",
        "--threads",
        "1",
        "-o",
        s(&whole),
    ]);
    let parts = dir.path().join("parts/f_%03d.exr");
    for (i, expect) in [
        (0, vec!["f_000.exr", "f_002.exr", "f_004.exr"]),
        (1, vec!["f_001.exr", "f_003.exr"]),
    ] {
        let before = if i == 0 {
            Vec::new()
        } else {
            files(&dir.path().join("parts"), "f_")
        };
        let part = format!("{i}/2");
        ok(&[
            "render",
            s(&scene),
            "--frames",
            "0..5",
            "--part",
            &part,
            "--threads",
            "2",
            "-o",
            s(&parts),
        ]);
        let now: Vec<String> = files(&dir.path().join("parts"), "f_")
            .into_iter()
            .filter(|n| !before.contains(n))
            .collect();
        assert_eq!(now, expect, "part {part}");
    }
    let json = dir.path().join("self.json");
    let verdict = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args([
            "compare",
            s(&dir.path().join("whole")),
            s(&parts),
            "--max-temporal-p99",
            "0",
            "--max-rmse",
            "0",
            "--json",
            s(&json),
        ])
        .output()
        .unwrap();
    assert!(
        verdict.status.success(),
        "{}",
        String::from_utf8_lossy(&verdict.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    for f in &frames[1..] {
        assert_eq!(f["temporal"]["p99"]["mean"].as_f64(), Some(0.0), "{f}");
        assert_eq!(f["temporal"]["pops"].as_u64(), Some(0), "{f}");
        assert_eq!(f["rmse"].as_f64(), Some(0.0), "{f}");
    }
    assert!(frames[0]["temporal"].is_null());
}

#[test]
fn bad_sequences_fail_before_or_at_the_frame_and_keep_what_was_written() {
    let dir = tempfile::tempdir().unwrap();
    write_xyz(&dir.path().join("traj.xyz"), 4, Some(1));
    let scene = write_scene(dir.path(), None, "");
    let out = dir.path().join("out");
    let pattern = out.join("f_%d.exr");
    // Past the end, no pattern, a range without an end where nothing plays: exit 2, no work.
    let err = fails_with(
        &["render", s(&scene), "--frames", "0..9", "-o", s(&pattern)],
        2,
    );
    assert!(
        err.contains("scene.toml") && err.contains("4 frame(s)"),
        "{err}"
    );
    let err = fails_with(
        &[
            "render",
            s(&scene),
            "--frames",
            "0..2",
            "-o",
            s(&out.join("f.exr")),
        ],
        2,
    );
    assert!(err.contains("%d"), "{err}");
    let err = fails_with(
        &["render", s(&scene), "--frames", "3..1", "-o", s(&pattern)],
        2,
    );
    assert!(err.contains("--frames"), "{err}");
    assert!(!out.exists(), "a refused command wrote {}", out.display());
    // The last frame is cut short: frames 0–2 are written whole, frame 3 is named.
    let err = fails_with(
        &[
            "render",
            s(&scene),
            "--frames",
            "0..4",
            "--threads",
            "1",
            "-o",
            s(&pattern),
        ],
        2,
    );
    assert!(err.contains("frame 3") && err.contains("traj.xyz"), "{err}");
    assert_eq!(files(&out, ""), vec!["f_0.exr", "f_1.exr", "f_2.exr"]);
    for k in 0..3 {
        image(&out.join(format!("f_{k}.exr")));
    }
    // Sequences that differ, and a sequence against one image.
    let other = dir.path().join("other");
    std::fs::create_dir_all(&other).unwrap();
    for k in [0, 1] {
        std::fs::copy(
            out.join(format!("f_{k}.exr")),
            other.join(format!("g_{k}.exr")),
        )
        .unwrap();
    }
    let err = fails_with(&["compare", s(&out), s(&other)], 2);
    assert!(
        err.contains("missing from") && err.contains("frame(s) 2"),
        "{err}"
    );
    let err = fails_with(&["compare", s(&out), s(&other.join("g_0.exr"))], 2);
    assert!(err.contains("one image"), "{err}");
    let err = fails_with(
        &[
            "compare",
            s(&out.join("f_0.exr")),
            s(&other.join("g_0.exr")),
            "--max-temporal-p99",
            "0.1",
        ],
        2,
    );
    assert!(err.contains("max_temporal_p99"), "{err}");
}

/// The scene of the popping demonstration: two overlapping particles of different colours, the
/// camera on an orbit of `STEP` degrees per frame about the origin.
const POP_SCENE: &str = r#"[render]
mode = "volume"
model = "emission"

[camera]
position = [0, 0, 10]
look_at = [0, 0, 0]
width = 48
height = 48
fov_y = 20

[camera.orbit]
axis = [0, 1, 0]
degrees_per_frame = 7
center = [0, 0, 0]

[[particles]]
center = [-0.5, 0, 0.2]
radius = 1.0
color = [1, 0.1, 0.1]
opacity = 0.8

[[particles]]
center = [0.5, 0, 0]
radius = 1.0
color = [0.1, 0.2, 1]
opacity = 0.8
"#;
const STEP_DEGREES: f64 = 7.0;
const POP_FRAMES: usize = 48;

/// The frames t ≥ 1 at which the two particles' centre depths along the view direction swap
/// order between frame t − 1 and t, from the geometry alone: the camera at
/// R_y(tθ)·(0, 0, 10) looks at the origin, so forward f(t) = −(sin tθ, 0, cos tθ).
fn swap_frames() -> Vec<usize> {
    let (a, b) = ([-0.5, 0.0, 0.2], [0.5, 0.0, 0.0]);
    let order = |t: usize| {
        let phi = (t as f64 * STEP_DEGREES).to_radians();
        let eye = [10.0 * phi.sin(), 0.0, 10.0 * phi.cos()];
        let f = [-phi.sin(), 0.0, -phi.cos()];
        let depth = |c: [f64; 3]| (0..3).map(|i| (c[i] - eye[i]) * f[i]).sum::<f64>();
        depth(a) < depth(b)
    };
    (1..POP_FRAMES)
        .filter(|&t| order(t) != order(t - 1))
        .collect()
}

#[test]
fn sorted_blend_pops_exactly_where_centre_depths_swap() {
    if gpu::gpu().is_none() {
        return;
    }
    let swaps = swap_frames();
    assert_eq!(
        swaps.len(),
        2,
        "the orbit should swap the order twice: {swaps:?}"
    );
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("pop.toml");
    std::fs::write(&scene, POP_SCENE).unwrap();
    let range = format!("0..{POP_FRAMES}");
    ok(&[
        "render",
        s(&scene),
        "--frames",
        &range,
        "-o",
        s(&dir.path().join("ref/f_%03d.exr")),
    ]);
    ok(&[
        "approx",
        s(&scene),
        "--frames",
        &range,
        "--method",
        "sorted-blend",
        "-o",
        s(&dir.path().join("sb/f_%03d.exr")),
    ]);
    let json = dir.path().join("pop.json");
    let report = dir.path().join("report");
    ok(&[
        "compare",
        s(&dir.path().join("ref")),
        s(&dir.path().join("sb")),
        "--no-flip",
        "--json",
        s(&json),
        "--report",
        s(&report),
    ]);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let p99: Vec<(usize, f64)> = v["frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| !f["temporal"].is_null())
        .map(|f| {
            (
                f["frame"].as_u64().unwrap() as usize,
                f["temporal"]["p99"]["mean"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(p99.len(), POP_FRAMES - 1);
    let steady = p99
        .iter()
        .filter(|(t, _)| !swaps.contains(t))
        .map(|(_, v)| *v)
        .fold(0.0, f64::max);
    for &t in &swaps {
        let spike = p99.iter().find(|(f, _)| *f == t).unwrap().1;
        assert!(
            spike > 5.0 * steady,
            "frame {t}: temporal p99 {spike} is no spike over the steady level {steady}"
        );
    }
    // The report holds the page, the plots and every frame's images.
    let page = std::fs::read_to_string(report.join("index.html")).unwrap();
    for t in &swaps {
        assert!(
            page.contains(&format!("href=\"#frame-{t}\"")),
            "frame {t} is not linked"
        );
    }
    assert!(report.join("temporal_p99.svg").exists());
    assert_eq!(files(&report.join("frames"), "t_").len(), POP_FRAMES - 1);
    assert_eq!(files(&report.join("frames"), "r_").len(), POP_FRAMES);
}

#[test]
fn camera_and_export_show_one_frame_of_a_moving_scene() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("pop.toml");
    std::fs::write(&scene, POP_SCENE).unwrap();
    // The orbit's camera of frame 5: R_y(5θ)·(0, 0, 10).
    let out = pgt(&["camera", s(&scene), "--frame", "5", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let phi = (5.0 * STEP_DEGREES).to_radians();
    let want = [10.0 * phi.sin(), 0.0, 10.0 * phi.cos()];
    for (c, w) in want.iter().enumerate() {
        let got = v["eye"][c].as_f64().unwrap();
        assert!((got - w).abs() < 1e-9, "eye[{c}] = {got}, want {w}");
    }
    // The particles of frame 2 of a trajectory: the XYZ's third frame, shifted by 0.3 a frame.
    write_xyz(&dir.path().join("traj.xyz"), 4, None);
    let moving = write_scene(dir.path(), None, "");
    let csv = dir.path().join("frame2.csv");
    ok(&["export", s(&moving), "--frame", "2", "-o", s(&csv)]);
    let text = std::fs::read_to_string(&csv).unwrap();
    let xs: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(xs, vec![-1.5 + 0.6, 0.0 + 0.6, 1.5 + 0.6]);
    let err = fails_with(&["export", s(&moving), "--frame", "4", "-o", s(&csv)], 2);
    assert!(
        err.contains("frame 4") && err.contains("4 frame(s)"),
        "{err}"
    );
}

/// docs/design.md §10, the sequence report's pixel probe: every frame's probe file holds the
/// frame's reference and approximation as the EXR files hold them and its e_t, each as float16
/// (src/report/sequence_probe.rs), decoded here the way the player decodes them.
#[test]
fn the_sequence_reports_probe_files_hold_each_frames_values() {
    let dir = tempfile::tempdir().unwrap();
    write_xyz(&dir.path().join("traj.xyz"), 4, None);
    let scene = write_scene(dir.path(), None, "");
    let (rd, ad) = (dir.path().join("r"), dir.path().join("a"));
    ok(&[
        "render",
        s(&scene),
        "--frames",
        "0..4",
        "-o",
        s(&rd.join("f_%02d.exr")),
    ]);
    ok(&[
        "render",
        s(&scene),
        "--frames",
        "0..4",
        "--spp",
        "2",
        "-o",
        s(&ad.join("f_%02d.exr")),
    ]);
    let report = dir.path().join("report");
    ok(&[
        "compare",
        s(&rd),
        s(&ad),
        "--no-flip",
        "--report",
        s(&report),
    ]);
    let page = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(page.contains("id=\"pgt-probe\""), "no probe table");
    let half = |v: f64| {
        pgt::report::sequence_probe::f16_bits_to_f32(pgt::report::viewer::f32_to_f16_bits(v as f32))
    };
    let frames: Vec<(RgbImage, RgbImage)> = (0..4)
        .map(|k| {
            (
                image(&rd.join(format!("f_{k:02}.exr"))),
                image(&ad.join(format!("f_{k:02}.exr"))),
            )
        })
        .collect();
    for (k, (r, a)) in frames.iter().enumerate() {
        let path = report.join(format!("frames/p_{k:06}.js"));
        let p = pgt::report::sequence_probe::read_probe_frame(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(p.frame, k);
        for (shown, file, what) in [
            (&p.reference, r, "reference"),
            (&p.approximation, a, "approximation"),
        ] {
            assert_eq!((shown.width, shown.height), (file.width, file.height));
            for (i, (s, f)) in shown.pixels.iter().zip(&file.pixels).enumerate() {
                assert_eq!(*s, f.map(|v| half(v as f64)), "frame {k} {what} pixel {i}");
            }
        }
        let Some(t) = &p.temporal else {
            assert_eq!(k, 0, "frame {k} has no e_t");
            continue;
        };
        assert!(k > 0, "the first frame has an e_t");
        let (rp, ap) = (&frames[k - 1].0, &frames[k - 1].1);
        let mut nonzero = 0;
        for i in 0..t.pixels.len() {
            for c in 0..3 {
                let e = ((a.pixels[i][c] as f64 - ap.pixels[i][c] as f64)
                    - (r.pixels[i][c] as f64 - rp.pixels[i][c] as f64))
                    .abs();
                // e_t is stored as f32 before its float16: at most one float16 step apart.
                let shown = t.pixels[i][c] as f64;
                assert!(
                    (shown - half(e) as f64).abs() <= e * 2f64.powi(-10) + 2f64.powi(-24),
                    "frame {k} e_t pixel {i} channel {c}: {shown}, the frames give {e}"
                );
                nonzero += usize::from(e > 0.0);
            }
        }
        assert!(nonzero > 0, "frame {k}: the test's e_t is zero everywhere");
    }
}

//! 3D Gaussian splatting PLY (docs/design.md §9, "3D Gaussian splatting PLY"): the real files of
//! `../shared/data/splats` against `tests/data/ply_vectors.json` (computed with numpy alone by
//! `scripts/ply_vectors.py`), `pgt info`, the include options, bad files through the CLI (exit 2,
//! the file named, nothing written), and a Gaussian of equal scales rendered as the sphere it is. The load time of a
//! million Gaussians is `cargo bench --bench load`.

use crate::support::splat::splat_file;
use crate::support::*;
use glam::DVec3;
use pgt::formats::{load_particles, IncludeSpec, ShColor};
use std::path::Path;
use std::process::{Command, Output};

fn pgt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .output()
        .expect("pgt runs")
}

/// One Gaussian: centre, f_dc, opacity logit, log scales, quaternion, no f_rest.
fn one(p: [f32; 3], dc: [f32; 3], o: f32, s: [f32; 3], q: [f32; 4]) -> Vec<f32> {
    let mut r = p.to_vec();
    r.extend([0.0; 3]);
    r.extend(dc);
    r.push(o);
    r.extend(s);
    r.extend(q);
    r
}

fn vectors() -> serde_json::Value {
    let text = std::fs::read_to_string(local("ply_vectors.json")).expect("ply_vectors.json");
    serde_json::from_str(&text).expect("json")
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().expect("a number")
}

fn close(a: f64, b: f64, rel: f64, what: &str) {
    assert!(
        (a - b).abs() <= rel * b.abs().max(1e-300),
        "{what}: {a} against {b}"
    );
}

#[test]
fn sample_files_agree_with_the_numpy_vectors() {
    let v = vectors();
    let camera = v["camera"]
        .as_array()
        .expect("camera")
        .iter()
        .map(f)
        .collect::<Vec<_>>();
    for (name, want) in v["files"].as_object().expect("files") {
        let Some(path) = shared(&format!("splats/{name}")) else {
            continue;
        };
        let l = load(&path);
        let n = want["vertices"].as_u64().expect("count") as usize;
        assert_eq!(l.records.len(), n, "{name}");
        let mut view = IncludeSpec::bare(&path);
        view.sh = Some(ShColor::View);
        view.view_from = Some(DVec3::new(camera[0], camera[1], camera[2]));
        let lv = load_particles(&view).expect("sh = view");
        // Sums over every vertex: the numpy sums add in another order (pairwise), 1e-12 covers it.
        let sums = &want["sums"];
        let (mut c, mut a, mut alpha, mut col) = (DVec3::ZERO, DVec3::ZERO, 0.0, DVec3::ZERO);
        for r in &l.records {
            c += r.center;
            a += r.ellipsoid.expect("an ellipsoid").semi_axes;
            alpha += r.opacity.expect("an opacity");
            col += r.color.expect("a colour");
        }
        for k in 0..3 {
            close(
                c[k],
                f(&sums["center"][k]),
                1e-12,
                &format!("{name} Σcenter"),
            );
            close(
                a[k],
                f(&sums["semi_axes"][k]),
                1e-12,
                &format!("{name} Σaxes"),
            );
            close(
                col[k],
                f(&sums["dc_color"][k]),
                1e-12,
                &format!("{name} Σcolour"),
            );
        }
        close(alpha, f(&sums["alpha"]), 1e-12, &format!("{name} Σα"));
        for s in want["samples"].as_array().expect("samples") {
            let i = s["index"].as_u64().expect("index") as usize;
            let r = &l.records[i];
            let e = r.ellipsoid.expect("an ellipsoid");
            let what = format!("{name} vertex {i}");
            for k in 0..3 {
                // serde_json parses decimals to within an ulp (no float_roundtrip feature), and
                // exp in numpy and in Rust may differ in the last bit.
                close(r.center[k], f(&s["center"][k]), 1e-15, &what);
                close(e.semi_axes[k], f(&s["semi_axes"][k]), 1e-14, &what);
                close(r.color.expect("c")[k], f(&s["dc_color"][k]), 1e-14, &what);
            }
            for k in 0..4 {
                let q = f(&s["rotation"][k]);
                assert!(
                    (e.rotation[k] - q).abs() <= 1e-15,
                    "{what}: {:?} {q}",
                    e.rotation
                );
            }
            close(r.opacity.expect("o"), f(&s["alpha"]), 1e-14, &what);
            let vc = lv.records[i].color.expect("view colour");
            match s.get("view_color") {
                Some(want) => {
                    for k in 0..3 {
                        let w = f(&want[k]);
                        assert!((vc[k] - w).abs() <= 1e-12, "{what} view colour {vc} {want}");
                    }
                }
                None => assert_eq!(Some(vc), r.color, "{what}: degree 0 has no view dependence"),
            }
        }
    }
}

/// A still scene with `sh = "view"` colours its Gaussians as 3DGS does from the camera's
/// position: the numpy vectors' view colours (computed with numpy alone), and bit for bit the
/// colour the reader gives for the same eye (what the scene did when it evaluated the SH once
/// at load), whichever the render path (the scene of frame 0 and `Scene::load`).
#[test]
fn a_still_scene_with_sh_view_has_the_numpy_view_colours() {
    let v = vectors();
    let camera: Vec<f64> = v["camera"]
        .as_array()
        .expect("camera")
        .iter()
        .map(f)
        .collect();
    let eye = DVec3::new(camera[0], camera[1], camera[2]);
    let dir = tempfile::tempdir().expect("tempdir");
    for (name, want) in v["files"].as_object().expect("files") {
        let Some(path) = shared(&format!("splats/{name}")) else {
            continue;
        };
        let toml = dir.path().join("still.toml");
        std::fs::write(
            &toml,
            format!(
                "[camera]\nposition = [{}, {}, {}]\nlook_at = [0.0, 0.0, 0.0]\n[render]\nmodel = \"emission\"\n[[include]]\npath = {:?}\nsh = \"view\"\n",
                eye.x,
                eye.y,
                eye.z,
                path.display().to_string()
            ),
        )
        .expect("write");
        let scene =
            pgt::Scene::load(&toml, &pgt::scene::SceneLoadOptions::default()).expect("the scene");
        let frames = pgt::scene::SceneFrames::load(&toml, &Default::default()).expect("frames");
        let frame0 = frames.frame(0).expect("frame 0");
        let mut view = IncludeSpec::bare(&path);
        view.sh = Some(ShColor::View);
        view.view_from = Some(eye);
        let read = load_particles(&view).expect("sh = view");
        assert_eq!(scene.particles.len(), read.records.len(), "{name}");
        for ((p, q), r) in scene
            .particles
            .iter()
            .zip(&frame0.particles)
            .zip(&read.records)
        {
            assert_eq!(
                Some(p.color),
                r.color,
                "{name}: the reader's colour for the eye"
            );
            assert_eq!(p.color, q.color, "{name}: frame 0");
        }
        for s in want["samples"].as_array().expect("samples") {
            let i = s["index"].as_u64().expect("index") as usize;
            if let Some(w) = s.get("view_color") {
                for k in 0..3 {
                    let c = scene.particles[i].color[k];
                    assert!(
                        (c - f(&w[k])).abs() <= 1e-12,
                        "{name} vertex {i}: {c} vs {w}"
                    );
                }
            }
        }
    }
}

fn info_json(path: &Path) -> serde_json::Value {
    let o = pgt(&["info", path.to_str().expect("utf-8"), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("json")
}

#[test]
fn info_reports_count_layout_degree_and_axes() {
    let cases = [
        ("lod3_tile_0.ply", 1971, "standard", 3),
        (
            "fruit_drops_minimal.ply",
            4721,
            "standard with extra properties transform",
            3,
        ),
        (
            "GSHairLoD_donut_fused.ply",
            45624,
            "reduced (no normals)",
            0,
        ),
    ];
    let v = vectors();
    for (name, n, layout, degree) in cases {
        let Some(path) = shared(&format!("splats/{name}")) else {
            continue;
        };
        let j = info_json(&path);
        assert_eq!(j["format"], "ply", "{name}");
        assert_eq!(j["particles"], n, "{name}");
        let d = &j["details"];
        assert_eq!(d["layout"], layout, "{name}");
        assert_eq!(d["sh_degree"], degree, "{name}");
        assert_eq!(d["encoding"], "binary_little_endian", "{name}");
        assert_eq!(
            v["files"][name]["sh_degree"], degree,
            "{name}: the numpy reading agrees"
        );
        let (lo, hi) = (f(&d["semi_axes"]["min"]), f(&d["semi_axes"]["max"]));
        assert!(lo > 0.0 && lo <= hi, "{name}: {d}");
        assert_eq!(f(&j["radius"]["max"]), hi, "{name}");
        assert!(j["bounds"]["min"].is_array(), "{name}");
    }
}

#[test]
fn include_options_reach_the_reader() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rows = vec![one(
        [0.0, 0.0, 0.0],
        [0.2, 0.3, 0.4],
        0.0,
        [0.0, -1.0, 0.5],
        [1.0, 0.0, 0.0, 0.0],
    )];
    std::fs::write(dir.path().join("g.ply"), splat_file(0, rows.into_iter())).expect("write");
    let scene = |include: &str, camera: &str| {
        let p = dir.path().join("s.toml");
        std::fs::write(
            &p,
            format!("{camera}\n[[include]]\npath = \"g.ply\"\n{include}\n"),
        )
        .expect("write");
        pgt::scene::Scene::load(&p, &pgt::scene::SceneLoadOptions::default())
    };
    let fixed = "[camera]\nposition = [0.0, 0.0, -10.0]\nlook_at = [0.0, 0.0, 0.0]\n";
    let s = scene(
        "extent = 2.0\nsh = \"view\"\nsh_order = \"coefficient-major\"",
        fixed,
    )
    .expect("a scene");
    assert_eq!(s.particles.len(), 1);
    assert_eq!(s.particles[0].radius, 2.0 * 0.5f64.exp());
    // A framed camera has an eye too: the colour is evaluated once the framing has placed it
    // (it was refused when the colour was evaluated as the file was read).
    assert!(scene("sh = \"view\"", "").is_ok());
    for (include, camera, want) in [
        ("extent = 0.0", fixed, "include.extent must be > 0"),
        ("extent = -1.0", fixed, "include.extent"),
        ("sh = \"full\"", fixed, "unknown variant `full`"),
        ("sh_order = \"rgb\"", fixed, "unknown variant `rgb`"),
    ] {
        let e = scene(include, camera).expect_err(include).to_string();
        assert!(e.contains("s.toml:") && e.contains(want), "{include}: {e}");
    }
}

/// A PLY written by the test, bad in one way; `pgt render` and `pgt info` exit 2 naming it.
#[test]
fn bad_files_exit_2_naming_the_file_with_no_output() {
    let dir = tempfile::tempdir().expect("tempdir");
    let good = one([0.0; 3], [0.0; 3], 0.0, [0.0; 3], [1.0, 0.0, 0.0, 0.0]);
    let file = |edit: fn(&mut Vec<f32>)| {
        let mut bad = good.clone();
        edit(&mut bad);
        splat_file(0, vec![good.clone(), bad].into_iter())
    };
    let full = splat_file(0, vec![good.clone(), good.clone()].into_iter());
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("short.ply", full[..full.len() - 3].to_vec(), "cut short in vertex 1"),
        ("huge.ply", file(|r| r[10] = 1000.0), "vertex 1: scale_0 = 1000"),
        ("nanscale.ply", file(|r| r[11] = f32::NAN), "vertex 1: scale_1 = NaN"),
        ("zeroq.ply", file(|r| r[13..17].fill(0.0)), "vertex 1: the rotation"),
        ("nanpos.ply", file(|r| r[0] = f32::NAN), "vertex 1: the position"),
        (
            "mesh.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n".to_vec(),
            "property vertex_indices is a list",
        ),
        (
            "points.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n".to_vec(),
            "lacks the 3D Gaussian splatting properties f_dc_0",
        ),
        (
            "type.ply",
            replace_in_header(&full, "property float nx", "property float16 nx"),
            "unknown type `float16`",
        ),
        (
            "list.ply",
            replace_in_header(&full, "property float nx", "property list uchar float nx"),
            "element vertex: property nx is a list",
        ),
        ("syntax.ply", b"ply\nformat binary_little_endian\nend_header\n".to_vec(), "version 1.0"),
        ("utf8.ply", b"ply\nformat ascii 1.0\ncomment \xc3\x28\nend_header\n".to_vec(), "not text"),
        ("empty.ply", Vec::new(), "empty"),
    ];
    for (name, bytes, want) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).expect("write");
        let p = path.to_str().expect("utf-8");
        let out = dir.path().join(format!("{name}.exr"));
        for args in [
            vec![
                "render",
                p,
                "--size",
                "8x8",
                "-o",
                out.to_str().expect("utf-8"),
            ],
            vec!["info", p],
        ] {
            let o = pgt(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{name} {}: {err}", args[0]);
            assert!(
                err.contains(p) && err.contains(want),
                "{name}: expected `{want}` in {err}"
            );
            assert!(!err.contains("panicked"), "{name}: {err}");
            assert!(!out.exists(), "{name}: an image was written");
            if args[0] == "info" {
                assert!(o.stdout.is_empty(), "{name}: info printed");
            }
        }
    }
}

/// `file` with `from` replaced by `to` in its header (the binary data after it kept).
fn replace_in_header(file: &[u8], from: &str, to: &str) -> Vec<u8> {
    let marker = b"end_header\n";
    let end = file
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("a header");
    let header = std::str::from_utf8(&file[..end]).expect("an ASCII header");
    let mut b = header.replace(from, to).into_bytes();
    b.extend(&file[end..]);
    b
}

#[test]
fn a_gaussian_of_equal_scales_renders_as_its_sphere() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (s, o, dc) = (-0.4f32, 0.3f32, [0.6f32, -0.2, 0.1]);
    let q = [0.3f32, -0.5, 0.2, 0.7];
    let rows = vec![one([0.1, -0.2, 0.3], dc, o, [s; 3], q)];
    std::fs::write(dir.path().join("g.ply"), splat_file(0, rows.into_iter())).expect("write");
    let head = "[camera]\nposition = [0.5, 1.0, -4.0]\nlook_at = [0.0, 0.0, 0.0]\nwidth = 24\nheight = 24\n\n[[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, 0.2]\nirradiance = [1.0, 0.8, 0.6]\n\n";
    let radius = 3.0 * f64::from(s).exp();
    let theta = 1.0 / (1.0 + (-f64::from(o)).exp());
    let c0 = 0.282_094_791_773_878_14;
    let color: Vec<f64> = dc
        .iter()
        .map(|&d| (0.5 + c0 * f64::from(d)).max(0.0))
        .collect();
    let sphere = format!(
        "{head}[[particles]]\ncenter = [{:?}, {:?}, {:?}]\nradius = {radius:?}\nopacity = {theta:?}\ncolor = [{:?}, {:?}, {:?}]\n",
        f64::from(0.1f32),
        f64::from(-0.2f32),
        f64::from(0.3f32),
        color[0],
        color[1],
        color[2]
    );
    let gaussian = format!("{head}[[include]]\npath = \"g.ply\"\n");
    let render = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).expect("write");
        let scene =
            pgt::scene::Scene::load(&p, &pgt::scene::SceneLoadOptions::default()).expect("scene");
        pgt::reference::render(&scene, &pgt::reference::RenderOptions::default())
            .expect("render")
            .image
    };
    let a = render("sphere.toml", &sphere);
    let b = render("gaussian.toml", &gaussian);
    assert!(a.pixels.iter().any(|p| p[0] > 0.0), "the sphere is in view");
    assert_eq!(a.pixels, b.pixels);
}

#[test]
fn a_sample_file_renders_from_the_command_line() {
    let path = shared_or_skip!("splats/lod3_tile_0.ply");
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("lod3.exr");
    let o = pgt(&[
        "render",
        path.to_str().expect("utf-8"),
        "--size",
        "8x8",
        "--model",
        "emission",
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.exists());
}

/// `pgt export -o F.ply` reads back as the particles it was written from, bit for bit: spheres
/// (σ = ∞ and σ = 0 among them) and ellipsoids.
#[test]
fn an_export_reads_back_bit_for_bit() {
    let dir = tempfile::tempdir().expect("tempdir");
    let spheres = "[defaults]\nopacity = 0.3\n\n[[particles]]\ncenter = [0.1, 0.2, 0.3]\nradius = 0.7\ncolor = [0.2, 0.4, 0.6]\nopacity = 1.0\n\n[[particles]]\ncenter = [1.0, -2.0, 0.5]\nradius = 1.3\nopacity = 0.0\n\n[[particles]]\ncenter = [-1.0, 0.0, 2.0]\nradius = 0.25\nkappa = 1.7\n";
    let ellipsoids = format!(
        "{spheres}\n[[particles]]\ncenter = [0.0, 1.0, 0.0]\nsemi_axes = [0.5, 1.5, 0.2]\nrotation = [0.9, 0.1, -0.3, 0.2]\n"
    );
    for (name, text) in [("spheres", spheres.to_string()), ("ellipsoids", ellipsoids)] {
        let scene_path = dir.path().join(format!("{name}.toml"));
        std::fs::write(&scene_path, text).expect("write");
        let out = dir.path().join(format!("{name}.ply"));
        let o = pgt(&[
            "export",
            scene_path.to_str().expect("utf-8"),
            "-o",
            out.to_str().expect("utf-8"),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let opts = pgt::scene::SceneLoadOptions::default();
        let want = pgt::scene::Scene::load(&scene_path, &opts).expect("scene");
        let got = pgt::scene::Scene::load(&out, &opts).expect("the export");
        assert_eq!(got.particles.len(), want.particles.len(), "{name}");
        for (a, b) in got.particles.iter().zip(&want.particles) {
            assert_eq!(
                (a.center, a.radius, a.color, a.sigma.to_bits(), a.ellipsoid),
                (b.center, b.radius, b.color, b.sigma.to_bits(), b.ellipsoid),
                "{name}"
            );
        }
        assert_eq!(info_json(&out)["details"]["layout"], "pgt export", "{name}");
    }
}

/// The in-process stand-in for `scripts/fuzz.sh ply`: the fuzz seeds with bytes flipped,
/// replaced, deleted, truncated and header words inserted (SplitMix64, deterministic); every
/// result is Ok or an error naming the file, never a panic.
#[test]
fn mutated_files_give_errors_not_panics() {
    use pgt::formats::random::SplitMix64;
    use pgt::formats::{load_bytes, Format};
    const WORDS: &[&[u8]] = &[
        b"property float f_rest_0\n",
        b"property list uchar int x\n",
        b"element vertex 4000000000\n",
        b"element face 3\n",
        b"format ascii 1.0\n",
        b"end_header\n",
        b"\xff\xff\x7f\x7f",
        b"nan ",
        b"\n",
    ];
    let format = Format::named("ply").expect("ply");
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/ply");
    let mut files: Vec<_> = std::fs::read_dir(&seeds)
        .expect("fuzz/seeds/ply")
        .map(|e| e.expect("entry").path())
        .collect();
    files.sort();
    let mut view = IncludeSpec::bare(Path::new("m.ply"));
    view.sh = Some(ShColor::View);
    view.view_from = Some(DVec3::new(0.0, 0.0, -3.0));
    let specs = [IncludeSpec::bare(Path::new("m.ply")), view];
    let mut rng = SplitMix64::new(34);
    for file in files {
        let input = std::fs::read(&file).expect("read");
        for i in 0..500 {
            let mut b = input.clone();
            for _ in 0..1 + rng.next_u64() % 4 {
                let at = (rng.next_u64() as usize) % b.len().max(1);
                match rng.next_u64() % 5 {
                    0 => b.truncate(at),
                    1 if at < b.len() => {
                        b.remove(at);
                    }
                    2 => {
                        let w = WORDS[(rng.next_u64() as usize) % WORDS.len()];
                        let at = at.min(b.len());
                        b.splice(at..at, w.iter().copied());
                    }
                    _ => {
                        if let Some(x) = b.get_mut(at) {
                            *x = rng.next_u64() as u8;
                        }
                    }
                }
            }
            for spec in &specs {
                let r = std::panic::catch_unwind(|| load_bytes(spec, format, &b));
                match r {
                    Err(_) => panic!("{}: panic at mutation {i}", file.display()),
                    Ok(Err(e)) => assert!(e.to_string().contains("m.ply"), "{e}"),
                    Ok(Ok(_)) => {}
                }
            }
        }
    }
}

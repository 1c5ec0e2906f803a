//! `pgt render --tile I/N` and `pgt merge` (issue 12, docs/design.md §7): the merge of the parts is
//! bit-identical to the one-machine render, in every layer; bad merges exit 2, name the file and
//! the problem, and write nothing.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn pgt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .env_remove("RAYON_NUM_THREADS")
        .output()
        .expect("the pgt binary runs")
}

fn ok(out: &Output) {
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name)
}

/// Every channel of an EXR as the bits of its float32 samples, by channel name.
fn channels(path: &Path) -> BTreeMap<String, Vec<u32>> {
    let img = exr::prelude::read_all_flat_layers_from_file(path).expect("an EXR");
    img.layer_data
        .iter()
        .flat_map(|l| l.channel_data.list.iter())
        .map(|c| {
            let bits = c.sample_data.values_as_f32().map(f32::to_bits).collect();
            (c.name.to_string(), bits)
        })
        .collect()
}

/// A lit volume scene with two point lights (one inverse-square, one without falloff), a
/// directional light and overlapping particles, so that every code path of the lit quadrature
/// (kinks of shadow rays, overlaps) shows in the error layer.
const POINT_LIT: &str = r#"
[camera]
position = [0.0, 0.5, -7.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 45.0
[render]
model = "lit"
background = [0.02, 0.03, 0.05]
tol = 1e-4
[[lights]]
type = "point"
position = [1.5, 2.5, -2.0]
intensity = [6.0, 5.0, 4.0]
[[lights]]
type = "point"
position = [-2.5, -1.0, 1.0]
intensity = [0.3, 0.4, 0.9]
falloff = "none"
[[lights]]
type = "directional"
direction = [0.0, -1.0, 0.3]
irradiance = [0.5, 0.5, 0.5]
[[particles]]
center = [-0.6, 0.0, 0.0]
radius = 1.0
color = [1.0, 0.4, 0.3]
opacity = 0.8
[[particles]]
center = [0.5, 0.3, 0.4]
radius = 0.9
color = [0.3, 0.6, 1.0]
opacity = 0.6
[[particles]]
center = [0.1, -0.9, -0.6]
radius = 0.5
color = [0.9, 0.9, 0.2]
kappa = 3.0
"#;

/// Renders `scene` whole and as `n` parts, merges the parts (given in reverse order), and checks
/// that every bit of every channel agrees, and the PNG of the merge equals the PNG render.
fn whole_equals_merged(scene: &Path, n: u32, extra: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole.exr");
    let mut args = vec!["render", s(scene), "-o", s(&whole)];
    args.extend_from_slice(extra);
    ok(&pgt(&args));
    let mut parts = Vec::new();
    for i in 0..n {
        let part = dir.path().join(format!("part_{i}.exr"));
        let tile = format!("{i}/{n}");
        let threads = (i % 2 + 1).to_string();
        let mut args = vec!["render", s(scene), "--tile", &tile, "-o", s(&part)];
        args.extend_from_slice(&["--threads", &threads]);
        args.extend_from_slice(extra);
        ok(&pgt(&args));
        parts.push(part);
    }
    let merged = dir.path().join("merged.exr");
    let mut args = vec!["merge"];
    args.extend(parts.iter().rev().map(|p| s(p)));
    args.extend_from_slice(&["-o", s(&merged)]);
    ok(&pgt(&args));
    let (a, b) = (channels(&whole), channels(&merged));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "{}",
        scene.display()
    );
    for (name, bits) in &a {
        let diff = bits.iter().zip(&b[name]).filter(|(x, y)| x != y).count();
        assert_eq!(
            diff,
            0,
            "{}: channel {name}: {diff} samples differ",
            scene.display()
        );
        assert_eq!(bits.len(), b[name].len());
    }
    // The PNG of the merge is the PNG of the render.
    let (whole_png, merged_png) = (dir.path().join("w.png"), dir.path().join("m.png"));
    let mut args = vec!["render", s(scene), "-o", s(&whole_png)];
    args.extend_from_slice(extra);
    ok(&pgt(&args));
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(|p| s(p)));
    args.extend_from_slice(&["-o", s(&merged_png)]);
    ok(&pgt(&args));
    assert_eq!(
        std::fs::read(&whole_png).unwrap(),
        std::fs::read(&merged_png).unwrap()
    );
}

#[test]
fn merged_parts_equal_the_whole_render_bit_for_bit_on_every_example() {
    let mut examples: Vec<PathBuf> = std::fs::read_dir(example(""))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    examples.sort();
    assert!(examples.len() >= 3, "{examples:?}");
    for scene in &examples {
        whole_equals_merged(scene, 3, &["--size", "37x29"]);
    }
}

#[test]
fn merged_parts_equal_the_whole_render_on_a_lit_scene_with_point_lights() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("point_lit.toml");
    std::fs::write(&scene, POINT_LIT).unwrap();
    whole_equals_merged(&scene, 3, &["--size", "48x40"]);
    // Options that change pixels travel into the parts: 2×2 samples, Riemann sums.
    whole_equals_merged(&scene, 4, &["--size", "24x20", "--spp", "2"]);
    whole_equals_merged(
        &scene,
        2,
        &[
            "--size",
            "24x20",
            "--integrator",
            "riemann",
            "--samples",
            "7",
        ],
    );
}

/// Parts 0..n of a small scene in `dir`, named `{stem}_{i}.exr`.
fn parts(dir: &Path, scene: &Path, stem: &str, n: u32, extra: &[&str]) -> Vec<PathBuf> {
    (0..n)
        .map(|i| {
            let part = dir.join(format!("{stem}_{i}.exr"));
            let tile = format!("{i}/{n}");
            let mut args = vec!["render", s(scene), "--tile", &tile, "-o", s(&part)];
            args.extend_from_slice(&["--size", "20x12"]);
            args.extend_from_slice(extra);
            ok(&pgt(&args));
            part
        })
        .collect()
}

/// Runs `pgt merge` on `inputs` and checks exit 2, that stderr contains every one of `needles`
/// and that no output (and no temporary file) was written.
fn refused(dir: &Path, inputs: &[&Path], needles: &[&str]) {
    let before: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    let out_path = dir.join("out.exr");
    let mut args = vec!["merge"];
    args.extend(inputs.iter().map(|p| s(p)));
    args.extend_from_slice(&["-o", s(&out_path)]);
    let out = pgt(&args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    let after: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(before, after, "the merge wrote something: {err}");
}

#[test]
fn bad_merges_exit_2_name_the_file_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let lit = example("disjoint_lit.toml");
    let p = parts(d, &lit, "lit", 3, &[]);
    let (p0, p1, p2) = (p[0].as_path(), p[1].as_path(), p[2].as_path());
    // A missing part: the missing index and a file of the set are named.
    refused(d, &[p0, p2], &["part(s) 1 of 3 missing", "lit_0.exr"]);
    // A duplicated part.
    refused(d, &[p0, p1, p2, p1], &["lit_1.exr", "part 1/3 given twice"]);
    // A part of another scene, of other options, of another split.
    let other = parts(d, &example("inside.toml"), "inside", 3, &[]);
    refused(
        d,
        &[p0, &other[1], p2],
        &["inside_1.exr", "different render"],
    );
    let spp = parts(d, &lit, "spp", 3, &["--spp", "2"]);
    refused(d, &[p0, p1, &spp[2]], &["spp_2.exr", "different render"]);
    let tol = parts(d, &lit, "tol", 3, &["--tol", "1e-3"]);
    refused(d, &[&tol[0], p1, p2], &["lit_1.exr", "different render"]);
    let four = parts(d, &lit, "four", 4, &[]);
    refused(
        d,
        &[p0, p1, p2, &four[3]],
        &["four_3.exr", "different renders"],
    );
    // Files that are not parts: a whole render, a PNG, text, nothing at all.
    let whole = d.join("whole.exr");
    ok(&pgt(&[
        "render",
        s(&lit),
        "--size",
        "20x12",
        "-o",
        s(&whole),
    ]));
    refused(
        d,
        &[p0, &whole, p2],
        &["whole.exr", "not a pgt part", "pgtFormat"],
    );
    let png = d.join("whole.png");
    ok(&pgt(&["render", s(&lit), "--size", "20x12", "-o", s(&png)]));
    refused(d, &[&png], &["whole.png", "not a pgt part"]);
    let text = d.join("notes.exr");
    std::fs::write(&text, "not an image").unwrap();
    refused(d, &[p0, p1, &text], &["notes.exr", "not a pgt part"]);
    refused(d, &[p0, p1, &d.join("absent.exr")], &["absent.exr"]);
}

/// Rewrites a part file with one value replaced, keeping its header: what a corrupted or
/// hand-made part looks like.
fn poke(part: &Path, out: &Path, channel: &str, index: usize, value: f32) {
    use exr::prelude::*;
    let mut img = read_all_flat_layers_from_file(part).unwrap();
    for layer in &mut img.layer_data {
        for ch in &mut layer.channel_data.list {
            if ch.name.to_string() == channel {
                match &mut ch.sample_data {
                    FlatSamples::F32(v) => v[index] = value,
                    _ => panic!("float channels"),
                }
            }
        }
    }
    img.write().to_file(out).unwrap();
}

#[test]
fn a_non_finite_value_in_a_part_is_refused_by_the_writer_naming_pixel_and_layer() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let p = parts(d, &example("disjoint_lit.toml"), "lit", 2, &[]);
    // Part 1 holds rows 1, 3, 5, …: its value 20 + 3 is pixel (3, 3) of the whole image.
    let bad = d.join("bad_1.exr");
    poke(&p[1], &bad, "err.G", 20 + 3, f32::NAN);
    refused(
        d,
        &[&p[0], &bad],
        &[
            "out.exr",
            "non-finite",
            "pixel (3, 3)",
            "err.G",
            "layer 'err'",
        ],
    );
    poke(&p[1], &bad, "B", 0, f32::INFINITY);
    refused(
        d,
        &[&p[0], &bad],
        &["pixel (0, 1)", "channel B of the image"],
    );
    // The same to PNG.
    let out = d.join("out.png");
    let o = pgt(&["merge", s(&p[0]), s(&bad), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("pixel (0, 1)"));
    assert!(!out.exists());
}

#[test]
fn tile_options_are_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let scene = example("shadows.toml");
    let png = dir.path().join("part.png");
    let o = pgt(&["render", s(&scene), "--tile", "0/2", "-o", s(&png)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("EXR"));
    let exr = dir.path().join("part.exr");
    for bad in ["2/2", "x", "1/0"] {
        let o = pgt(&["render", s(&scene), "--tile", bad, "-o", s(&exr)]);
        assert_eq!(o.status.code(), Some(2), "{bad}");
    }
    let o = pgt(&[
        "render",
        s(&scene),
        "--size",
        "8x4",
        "--tile",
        "1/5",
        "-o",
        s(&exr),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("at most 4 parts"));
    assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
}

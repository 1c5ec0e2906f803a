//! Ellipsoids as input (docs/design.md §9): inline in scene TOML (`semi_axes`, `rotation`) and
//! as CSV columns (`sx sy sz qw qx qy qz`); bad values exit 2 naming the file, line and field
//! with no output; three equal semi-axes are the sphere bit for bit; `pgt export` writes the
//! ellipsoid columns and reads back; the GPU methods refuse ellipsoids by name.

use pgt::scene::{Scene, SceneLoadOptions};
use std::path::Path;
use std::process::{Command, Output};

fn pgt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .output()
        .expect("pgt runs")
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

const HEAD: &str = "[render]\nmodel = \"emission\"\n\n";

/// Renders `scene` and asserts exit 2, `file:line:` and `reason` in the message, no image.
fn assert_refused(dir: &Path, scene: &str, file: &str, line: usize, reason: &str) {
    let out = dir.join("out.exr");
    let o = pgt(&[
        "render",
        scene,
        "--size",
        "8x8",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{reason}: {err}");
    assert!(err.contains(&format!("{file}:{line}:")), "{reason}: {err}");
    assert!(err.contains(reason), "expected `{reason}` in: {err}");
    assert!(!out.exists(), "{reason}: an image was written");
}

#[test]
fn bad_inline_ellipsoids_exit_2_naming_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let particle =
        |fields: &str| format!("{HEAD}[[particles]]\ncenter = [0.0, 0.0, 0.0]\n{fields}\n");
    let cases = [
        (
            "semi_axes = [1.0, 0.0, 0.5]",
            "particles[0].semi_axes[1] (a semi-axis) must be finite and > 0",
        ),
        (
            "semi_axes = [-1.0, 1.0, 0.5]",
            "particles[0].semi_axes[0] (a semi-axis) must be finite and > 0",
        ),
        ("semi_axes = [1.0, 1.0, nan]", "particles[0].semi_axes[2]"),
        ("semi_axes = [1.0, inf, 1.0]", "particles[0].semi_axes[1]"),
        (
            "semi_axes = [1.0, 1e-320, 1.0]",
            "particles[0].semi_axes[1]",
        ),
        (
            "semi_axes = [1.0, 2.0, 3.0]\nrotation = [0.0, 0.0, 0.0, 0.0]",
            "particles[0].rotation must be a finite, non-zero quaternion",
        ),
        (
            "semi_axes = [1.0, 2.0, 3.0]\nrotation = [1.0, nan, 0.0, 0.0]",
            "particles[0].rotation must be a finite, non-zero quaternion",
        ),
        (
            "radius = 1.0\nsemi_axes = [1.0, 2.0, 3.0]",
            "give radius (a sphere) or semi_axes",
        ),
        (
            "radius = 1.0\nrotation = [1.0, 0.0, 0.0, 0.0]",
            "particles[0].rotation turns an ellipsoid",
        ),
        (
            "color = [1.0, 0.0, 0.0]",
            "give radius = r (a sphere) or semi_axes",
        ),
    ];
    for (fields, reason) in cases {
        let scene = write(dir.path(), "bad.toml", &particle(fields));
        assert_refused(dir.path(), &scene, &scene, 4, reason);
    }
}

#[test]
fn bad_csv_ellipsoids_exit_2_naming_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let header = "x,y,z,sx,sy,sz,qw,qx,qy,qz\n0,0,0,1,0.5,0.2,1,0,0,0\n";
    let cases = [
        (
            "1,1,1,1,0,0.2,1,0,0,0",
            "sy (a semi-axis) must be finite and > 0",
        ),
        (
            "1,1,1,-1,1,0.2,1,0,0,0",
            "sx (a semi-axis) must be finite and > 0",
        ),
        ("1,1,1,1,1,inf,1,0,0,0", "sz is not finite"),
        ("1,1,1,1,1,1e-310,1,0,0,0", "sz (a semi-axis)"),
        (
            "1,1,1,1,2,3,0,0,0,0",
            "the rotation qw, qx, qy, qz must be a finite, non-zero quaternion",
        ),
        ("1,1,1,1,2,3,1,nan,0,0", "qx is not finite"),
        ("1,1,1,1,2,x,1,0,0,0", "expected a number for sz"),
    ];
    for (row, reason) in cases {
        let csv = write(dir.path(), "bad.csv", &format!("{header}{row}\n"));
        assert_refused(dir.path(), &csv, &csv, 3, reason);
    }
    // Headers that cannot be read as one shape.
    for (header, reason) in [
        ("x,y,z,sx,sy\n0,0,0,1,1\n", "but not sz"),
        (
            "x,y,z,radius,sx,sy,sz\n0,0,0,1,1,1,1\n",
            "both radius and the semi-axes",
        ),
        (
            "x,y,z,radius,qw,qx,qy,qz\n0,0,0,1,1,0,0,0\n",
            "but not the semi-axes",
        ),
    ] {
        let csv = write(dir.path(), "bad.csv", header);
        assert_refused(dir.path(), &csv, &csv, 1, reason);
    }
}

#[test]
fn equal_semi_axes_are_the_sphere_bit_for_bit() {
    let load = |text: &str| {
        Scene::from_toml_str(text, Path::new("t.toml"), &SceneLoadOptions::default()).unwrap()
    };
    let sphere = load(&format!(
        "{HEAD}[[particles]]\ncenter = [0.1, 0.2, 0.3]\nradius = 0.7\nopacity = 0.6\n"
    ));
    let equal = load(&format!(
        "{HEAD}[[particles]]\ncenter = [0.1, 0.2, 0.3]\nsemi_axes = [0.7, 0.7, 0.7]\nrotation = [0.3, 0.4, 0.5, 0.6]\nopacity = 0.6\n"
    ));
    assert_eq!(sphere.particles, equal.particles);
    // A real ellipsoid takes σ from its shortest semi-axis: Θmax along the shortest diameter.
    let long = load(&format!(
        "{HEAD}[[particles]]\ncenter = [0.0, 0.0, 0.0]\nsemi_axes = [3.0, 0.7, 1.5]\nopacity = 0.6\n"
    ));
    let p = &long.particles[0];
    assert_eq!(p.sigma, sphere.particles[0].sigma);
    assert_eq!(p.radius, 3.0);
    let e = p.ellipsoid.expect("an ellipsoid");
    assert_eq!(e.rotation(), glam::DQuat::IDENTITY);
    // Unnormalised quaternions are normalised.
    let turned = load(&format!(
        "{HEAD}[[particles]]\ncenter = [0.0, 0.0, 0.0]\nsemi_axes = [3.0, 0.7, 1.5]\nrotation = [2.0, 0.0, 0.0, 2.0]\n"
    ));
    let q = turned.particles[0].ellipsoid.unwrap().rotation();
    assert!((q.length() - 1.0).abs() < 1e-15 && (q.w - q.z).abs() < 1e-15);
}

#[test]
fn export_writes_the_ellipsoid_columns_and_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(
        dir.path(),
        "e.toml",
        &format!(
            "{HEAD}[[particles]]\ncenter = [0.1, 0.2, 0.3]\nsemi_axes = [2.0, 0.1, 0.5]\nrotation = [0.9, 0.1, -0.3, 0.2]\nopacity = 0.8\ncolor = [0.2, 0.4, 0.9]\n\n\
             [[particles]]\ncenter = [1.0, 0.0, 0.0]\nradius = 0.5\nkappa = 1.5\n\n\
             [[particles]]\ncenter = [-1.0, 0.0, 0.0]\nsemi_axes = [0.3, 0.2, 0.1]\nopacity = 1.0\n"
        ),
    );
    let csv = dir.path().join("e.csv");
    let o = pgt(&["export", &scene, "-o", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.starts_with("x,y,z,sx,sy,sz,qw,qx,qy,qz,red,green,blue,opacity,sigma\n"),
        "{text}"
    );
    let options = SceneLoadOptions::default();
    let original = Scene::load(Path::new(&scene), &options).unwrap();
    let back = Scene::load(&csv, &options).unwrap();
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);
    assert_eq!(original.particles.len(), back.particles.len());
    for (a, b) in original.particles.iter().zip(&back.particles) {
        assert_eq!(
            (a.center, a.radius, a.color, a.sigma),
            (b.center, b.radius, b.color, b.sigma)
        );
        match (a.ellipsoid, b.ellipsoid) {
            (None, None) => {}
            (Some(x), Some(y)) => {
                assert_eq!(x.semi_axes(), y.semi_axes());
                // The written quaternion is unit already; normalising it again moves it by
                // rounding at most.
                assert!((x.rotation() - y.rotation()).length() < 1e-15);
            }
            _ => panic!("a sphere came back as an ellipsoid or the reverse"),
        }
    }
    // Exporting what was read back writes the same file.
    let again = dir.path().join("again.csv");
    let o = pgt(&[
        "export",
        csv.to_str().unwrap(),
        "-o",
        again.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    assert_eq!(std::fs::read_to_string(&again).unwrap(), text);
}

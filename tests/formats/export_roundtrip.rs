//! `pgt export` read back: every particle of the loaded scene (centre, radius, linear colour, σ
//! and Θmax = 1 − e^{−2rσ}) must come back bit for bit from the CSV (shortest round-trip
//! decimal notation) and from the binary PLY (f64), including σ = ∞ (`inf` in CSV, IEEE +∞ in
//! PLY) and σ = 0, κ-given particles with λ ≠ 1, and defaults.

use pgt::scene::{Particle, Scene, SceneLoadOptions};
use std::path::{Path, PathBuf};
use std::process::Command;

const SCENE: &str = r#"
[render]
lambda = 0.5
[defaults]
color = [0.25, 0.5, 1.0]
opacity = 0.3
[[particles]]
center = [0.1, -2.0, 3.7]
radius = 1.25
color  = [1.0, 0.2, 0.2]
opacity = 1.0
[[particles]]
center = [1e-7, 123456.789, -0.3]
radius = 0.001
opacity = 0.0
[[particles]]
center = [1.0, 1.0, 1.0]
radius = 2.0
kappa = 0.7
[[particles]]
center = [-1.0, 0.0, 0.0]
radius = 0.5
"#;

fn export(scene: &Path, out: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .arg("export")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "pgt export failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn expected(p: &Particle) -> [f64; 9] {
    let opacity = if p.sigma.is_infinite() {
        1.0
    } else {
        1.0 - (-2.0 * p.radius * p.sigma).exp()
    };
    [
        p.center.x, p.center.y, p.center.z, p.radius, p.color.x, p.color.y, p.color.z, opacity,
        p.sigma,
    ]
}

fn assert_rows(particles: &[Particle], rows: &[Vec<f64>]) {
    assert_eq!(particles.len(), rows.len());
    for (p, row) in particles.iter().zip(rows) {
        let want = expected(p);
        for k in 0..9 {
            if k == 7 {
                // Θmax: computed with expm1 by pgt; 1 − exp here, so a few ulps apart.
                assert!(
                    (row[k] - want[k]).abs() <= 1e-15 + 1e-12 * want[k].abs(),
                    "opacity {} vs {}",
                    row[k],
                    want[k]
                );
            } else {
                assert_eq!(row[k].to_bits(), want[k].to_bits(), "column {k}: {row:?}");
            }
        }
    }
}

fn scene_file(dir: &Path) -> (PathBuf, Scene) {
    let path = dir.join("scene.toml");
    std::fs::write(&path, SCENE).unwrap();
    let scene = Scene::load(&path, &SceneLoadOptions::default()).unwrap();
    assert!(scene.particles[0].sigma.is_infinite());
    assert_eq!(scene.particles[1].sigma, 0.0);
    (path, scene)
}

#[test]
fn csv_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let (path, scene) = scene_file(dir.path());
    let out = dir.path().join("p.csv");
    export(&path, &out);
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "x,y,z,radius,red,green,blue,opacity,sigma"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|c| c.parse::<f64>().unwrap()).collect())
        .collect();
    assert!(
        text.contains(",inf\n"),
        "σ = ∞ must be written inf:\n{text}"
    );
    assert_rows(&scene.particles, &rows);
    // The export is itself a particle file pgt reads, giving the same particles.
    let again = Scene::load(&out, &SceneLoadOptions::default()).unwrap();
    for (a, b) in again.particles.iter().zip(&scene.particles) {
        assert_eq!((a.center, a.radius, a.color), (b.center, b.radius, b.color));
        assert!(a.sigma == b.sigma || (a.sigma - b.sigma).abs() < 1e-12 * b.sigma);
    }
}

#[test]
fn ply_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let (path, scene) = scene_file(dir.path());
    let out = dir.path().join("p.ply");
    export(&path, &out);
    let bytes = std::fs::read(&out).unwrap();
    let marker = b"end_header\n";
    let end = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .unwrap()
        + marker.len();
    let header = std::str::from_utf8(&bytes[..end]).unwrap();
    assert!(header.starts_with("ply\nformat binary_little_endian 1.0\n"));
    assert!(header.contains(&format!("element vertex {}\n", scene.particles.len())));
    let props: Vec<&str> = header
        .lines()
        .filter_map(|l| l.strip_prefix("property double "))
        .collect();
    assert_eq!(
        props,
        ["x", "y", "z", "radius", "red", "green", "blue", "opacity", "sigma"]
    );
    let body = &bytes[end..];
    assert_eq!(body.len(), scene.particles.len() * 9 * 8);
    let rows: Vec<Vec<f64>> = body
        .chunks(72)
        .map(|r| {
            r.chunks(8)
                .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
                .collect()
        })
        .collect();
    assert_rows(&scene.particles, &rows);
}

#[test]
fn unknown_extension_is_an_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = scene_file(dir.path());
    let out = dir.path().join("p.txt");
    let o = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .arg("export")
        .arg(&path)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("p.txt"));
    assert!(!out.exists());
}

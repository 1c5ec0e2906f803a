//! `cargo bench --bench cameras`: reading the cameras of a dataset (docs/design.md §1 "Cameras of
//! datasets"): a COLMAP model of 1,000 images with 1,000 2D points each, text and binary, and a
//! `transforms.json` of 1,000 frames, written to a temporary folder and read with
//! `pgt::formats::cameras::read`. Plain timing (no harness); the target is under 1 s each.

use pgt::formats::cameras;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

const IMAGES: usize = 1000;
const POINTS: usize = 1000;

fn colmap(dir: &Path) {
    let text = dir.join("text");
    let bin = dir.join("bin");
    std::fs::create_dir_all(&text).unwrap();
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::write(
        text.join("cameras.txt"),
        "1 PINHOLE 1920 1080 1500 1490 960.5 540.25\n",
    )
    .unwrap();
    let mut c = 1u64.to_le_bytes().to_vec();
    c.extend(1u32.to_le_bytes());
    c.extend(1u32.to_le_bytes());
    c.extend(1920u64.to_le_bytes());
    c.extend(1080u64.to_le_bytes());
    for v in [1500.0f64, 1490.0, 960.5, 540.25] {
        c.extend(v.to_le_bytes());
    }
    std::fs::write(bin.join("cameras.bin"), c).unwrap();
    let mut t = String::new();
    let mut b = (IMAGES as u64).to_le_bytes().to_vec();
    for i in 0..IMAGES {
        let a = i as f64 * 0.01;
        let q = [(a / 2.0).cos(), 0.0, (a / 2.0).sin(), 0.0];
        let tv = [0.1 * i as f64, -0.5, 4.0];
        let _ = writeln!(
            t,
            "{} {} {} {} {} {} {} {} 1 img_{i:05}.jpg",
            i + 1,
            q[0],
            q[1],
            q[2],
            q[3],
            tv[0],
            tv[1],
            tv[2]
        );
        for p in 0..POINTS {
            let _ = write!(t, "{}.5 {}.25 -1 ", p, p % 1080);
        }
        t.push('\n');
        b.extend((i as u32 + 1).to_le_bytes());
        for v in q.iter().chain(&tv) {
            b.extend(v.to_le_bytes());
        }
        b.extend(1u32.to_le_bytes());
        b.extend(format!("img_{i:05}.jpg\0").bytes());
        b.extend((POINTS as u64).to_le_bytes());
        b.extend(std::iter::repeat_n(0u8, POINTS * 24));
    }
    std::fs::write(text.join("images.txt"), t).unwrap();
    std::fs::write(bin.join("images.bin"), b).unwrap();
}

fn transforms(dir: &Path) {
    let mut t = String::from("{\"fl_x\": 1500, \"fl_y\": 1490, \"cx\": 960.5, \"cy\": 540.25, \"w\": 1920, \"h\": 1080, \"frames\": [\n");
    for i in 0..IMAGES {
        let (s, c) = (i as f64 * 0.01).sin_cos();
        let _ = writeln!(
            t,
            "{}{{\"file_path\": \"images/frame_{i:05}.png\", \"transform_matrix\": [[{c}, 0.0, {s}, {}], [0.0, 1.0, 0.0, 0.5], [{}, 0.0, {c}, 4.0], [0.0, 0.0, 0.0, 1.0]]}}",
            if i == 0 { "" } else { "," },
            0.1 * i as f64,
            -s
        );
    }
    t.push_str("]}\n");
    std::fs::write(dir.join("transforms.json"), t).unwrap();
}

fn time(what: &str, path: &Path) {
    let bytes: u64 = if path.is_dir() {
        std::fs::read_dir(path)
            .unwrap()
            .map(|e| e.unwrap().metadata().unwrap().len())
            .sum()
    } else {
        std::fs::metadata(path).unwrap().len()
    };
    let start = Instant::now();
    let cams = cameras::read(path).unwrap();
    let s = start.elapsed().as_secs_f64();
    assert_eq!(cams.len(), IMAGES);
    println!(
        "{what:<28} {IMAGES} images  {:>8.1} MB  {:>8.1} ms",
        bytes as f64 / 1e6,
        s * 1e3
    );
}

fn main() {
    let dir = tempfile::tempdir().unwrap();
    colmap(dir.path());
    transforms(dir.path());
    time("COLMAP text", &dir.path().join("text"));
    time("COLMAP binary", &dir.path().join("bin"));
    time("transforms.json", &dir.path().join("transforms.json"));
}

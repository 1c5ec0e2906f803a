//! Helpers shared by the format tests: the shared data directory (`../shared/data` beside the
//! clone), which CI provides and a bare checkout may not.
#![allow(dead_code)]

use pgt::formats::{load_particles, LoadedParticles};
use pgt::scene::IncludeSpec;
use std::path::{Path, PathBuf};

/// `../shared/data/<rel>` relative to the crate root, or `None` (with a note on stdout) when absent.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let p = root
        .parent()
        .unwrap_or(root)
        .join("shared")
        .join("data")
        .join(rel);
    if p.exists() {
        Some(p)
    } else {
        println!("skipping: {} is absent", p.display());
        None
    }
}

/// `tests/data/<rel>` in the crate.
pub fn local(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("data")
        .join(rel)
}

/// Loads a file with every option at its default.
pub fn load(path: &Path) -> LoadedParticles {
    load_particles(&IncludeSpec::bare(path)).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Loads with a customised include.
pub fn load_with(path: &Path, f: impl FnOnce(&mut IncludeSpec)) -> pgt::Result<LoadedParticles> {
    let mut spec = IncludeSpec::bare(path);
    f(&mut spec);
    load_particles(&spec)
}

/// 1-based line numbers and text of the lines of a file that satisfy `pred`.
pub fn lines_where(path: &Path, pred: impl Fn(&str) -> bool) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(path).expect("read");
    text.lines()
        .enumerate()
        .filter(|(_, l)| pred(l))
        .map(|(i, l)| (i + 1, l.to_string()))
        .collect()
}

/// sRGB 8-bit hex to linear, written independently of pgt's table code.
pub fn lin(hex: u32) -> [f64; 3] {
    let f = |v: u32| {
        let c = f64::from(v & 0xFF) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    [f(hex >> 16), f(hex >> 8), f(hex)]
}

pub fn close3(a: glam::DVec3, b: [f64; 3], tol: f64) -> bool {
    (a.x - b[0]).abs() <= tol && (a.y - b[1]).abs() <= tol && (a.z - b[2]).abs() <= tol
}

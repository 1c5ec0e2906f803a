//! Shared by every test binary (`#[path = "../support/mod.rs"] mod support;` in each
//! `tests/<group>/main.rs`): the shared data directory (`../shared/data` beside the clone), which
//! CI provides and a bare checkout may not, how a test that cannot run here says so ([`skip`]),
//! and, in the submodules, the GPU context with its scenes and oracles ([`gpu`]), the volume
//! reference's scenes ([`volume`]), the comparison's image pairs and second SSIM
//! ([`compare_pairs`]) and a WebDriver client for the report's browser tests ([`webdriver`]).
//! The benchmarks in `benches/` include it too (`#[path = "../tests/support/mod.rs"]`).
//!
//! A test that needs a file of the shared data gets the path from [`shared`] (or
//! [`shared_or_skip!`]): absent under `CI=true`, that is a failure (a broken setup must not pass
//! as green); elsewhere the test is skipped with a message. No test may return early without
//! going through them.
#![allow(dead_code, unused_macros, unused_imports)]

use pgt::formats::{load_particles, IncludeSpec, LoadedParticles};
use std::path::{Path, PathBuf};

/// The shared data directory: `$PGT_SHARED_DATA` if set (to check that the tests fail without
/// the data: `PGT_SHARED_DATA=/nonexistent CI=true cargo test --test formats`), else
/// `../shared/data` beside the crate root.
pub fn shared_root() -> PathBuf {
    if let Some(dir) = std::env::var_os("PGT_SHARED_DATA") {
        return PathBuf::from(dir);
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    root.parent().unwrap_or(root).join("shared").join("data")
}

/// Whether this is CI (`CI=true`, as `.ci/run` sets it), where missing data is a failure.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// `<shared data>/<rel>`, or, when absent: a panic under `CI=true`, and elsewhere `None` with a
/// message on stderr saying what is skipped.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = shared_root().join(rel);
    if p.exists() {
        return Some(p);
    }
    assert!(
        !in_ci(),
        "CI=true and the test data {} is absent (CI must provide ../shared/data)",
        p.display()
    );
    skipped(&format!("{} is absent (CI is not set)", p.display()));
    None
}

/// `let p = shared_or_skip!("pdb/1rx1.pdb");`: the path of a shared data file, or the end of the
/// test (skipped with [`shared`]'s message; a failure under `CI=true`).
macro_rules! shared_or_skip {
    ($rel:expr) => {
        match $crate::support::shared($rel) {
            Some(path) => path,
            None => return,
        }
    };
}
pub(crate) use shared_or_skip;

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

pub mod compare_pairs;
pub mod gpu;
pub mod skip;
pub mod splat;
pub mod volume;
pub mod webdriver;

pub use skip::skipped;

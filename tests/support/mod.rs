//! Shared by every test binary (`#[path = "../support/mod.rs"] mod support;` in each
//! `tests/<group>/main.rs`): how a test that cannot run here says so ([`skip`]), the shared data
//! directory (`../shared/data` beside the clone), which CI provides and a bare checkout may not,
//! and, in the submodules, the GPU context with its scenes and oracles ([`gpu`]), the volume
//! reference's scenes ([`volume`]) and a WebDriver client for the report's browser tests
//! ([`webdriver`]).
//!
//! A test that needs something absent (a GPU adapter, a browser, Slurm, a data file) goes
//! through [`skip`]: under `CI=true` that is a failure (a broken setup must not pass as green);
//! elsewhere the test says on one line that it skipped, visible without `--nocapture`. No test
//! may return early without going through it.
#![allow(dead_code, unused_macros, unused_imports)]

pub mod gpu;
pub mod volume;
pub mod webdriver;

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

/// Whether this is CI (`CI` set and not empty, `0` or `false`; `.ci/run` sets `CI=true`), where
/// a test that cannot run is a failure.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0" && v != "false")
}

/// Says that the running test skips (part of) its work because `reason` (what is missing and how
/// to provide it): under CI a panic with the reason; elsewhere one line `SKIPPED <test>:
/// <reason>` on the process's standard error. The line is written to the stream itself, not
/// through `eprintln!`, whose output libtest captures and shows only for failing tests: a plain
/// `cargo test` then shows every skip.
pub fn skip(reason: impl std::fmt::Display) {
    if in_ci() {
        panic!("CI is set and this test cannot run: {reason}");
    }
    let thread = std::thread::current();
    let line = format!(
        "SKIPPED {}: {reason}\n",
        thread.name().unwrap_or("(unnamed)")
    );
    // One write of the whole line, so that lines of tests running in parallel do not mix.
    let _ = std::io::Write::write_all(&mut std::io::stderr().lock(), line.as_bytes());
}

/// `<shared data>/<rel>`, or, when absent, `None` after [`skip`] (a panic under CI).
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = shared_root().join(rel);
    if p.exists() {
        return Some(p);
    }
    skip(format!(
        "the test data {} is absent (CI provides ../shared/data beside the clone)",
        p.display()
    ));
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

//! `cargo bench --bench formats`: load times of the largest particle files of the shared data
//! (`$PGT_SHARED_DATA`, else `../shared/data` beside the clone): for each, the particle count and
//! the best of five loads in milliseconds. A missing file is named and left out.

use pgt::formats::{load_particles, IncludeSpec};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn shared_root() -> PathBuf {
    if let Some(dir) = std::env::var_os("PGT_SHARED_DATA") {
        return PathBuf::from(dir);
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    root.parent().unwrap_or(root).join("shared").join("data")
}

fn main() {
    let root = shared_root();
    for rel in [
        "pdb/1aon.pdb",
        "pdb/3SN6.cif",
        "vrml/pymol_1uun_spheres.wrl",
        "vrml/jmol_1rx1_spacefill.wrl",
        "mmpld/part_rnk000000_v103.mmpld",
    ] {
        let path = root.join(rel);
        if !path.exists() {
            println!("{rel}: absent ({} does not exist)", path.display());
            continue;
        }
        let mut best = f64::INFINITY;
        let mut n = 0;
        for _ in 0..5 {
            let t = Instant::now();
            let loaded = load_particles(&IncludeSpec::bare(&path))
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            best = best.min(t.elapsed().as_secs_f64());
            n = loaded.records.len();
        }
        println!("{rel}: {n} particles, best of 5: {:.1} ms", best * 1e3);
    }
}

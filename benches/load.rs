//! `cargo bench --bench load`: load times of the largest files of the shared data
//! (`../shared/data`, or `$PGT_SHARED_DATA`), best of five each. Prints only; timings depend on
//! the machine. A file that is absent is skipped with a line that says so. Then a million 3D
//! Gaussian splatting particles in the standard layout (62 floats a vertex, 248 MB), written here.

#[path = "../tests/support/mod.rs"]
mod support;

fn main() {
    for rel in [
        "pdb/1aon.pdb",
        "pdb/3SN6.cif",
        "vrml/pymol_1uun_spheres.wrl",
        "vrml/jmol_1rx1_spacefill.wrl",
        "mmpld/part_rnk000000_v103.mmpld",
    ] {
        let Some(p) = support::shared(rel) else {
            continue;
        };
        let mut best = f64::INFINITY;
        let mut n = 0;
        for _ in 0..5 {
            let t = std::time::Instant::now();
            n = support::load(&p).records.len();
            best = best.min(t.elapsed().as_secs_f64());
        }
        println!("{rel}: {n} particles, best of 5: {:.1} ms", best * 1e3);
    }
    million_gaussians();
}

/// Reads and converts a million Gaussians of the standard 3DGS layout, best of three.
fn million_gaussians() {
    let n = 1_000_000usize;
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("million.ply");
    let rows = (0..n).map(|i| {
        let t = i as f32 * 1e-6;
        let mut r = vec![t, -t, 2.0 * t, 0.0, 0.0, 0.0, 0.1, 0.2, 0.3];
        r.extend((0..45).map(|k| k as f32 * 1e-3));
        r.extend([t - 0.5, -3.0 + t, -2.5, -2.0, 1.0, t, 0.5, -0.25]);
        r
    });
    let bytes = support::splat::splat_file(45, rows);
    std::fs::write(&path, &bytes).expect("write");
    let megabytes = bytes.len() / 1_000_000;
    drop(bytes);
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let t = std::time::Instant::now();
        let l =
            pgt::formats::load_particles(&pgt::formats::IncludeSpec::bare(&path)).expect("load");
        best = best.min(t.elapsed().as_secs_f64());
        assert_eq!(l.records.len(), n);
    }
    println!("{n} Gaussians (standard 3DGS layout, {megabytes} MB): best of 3: {best:.3} s");
}

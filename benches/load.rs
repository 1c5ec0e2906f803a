//! `cargo bench --bench load`: load times of the largest files of the shared data
//! (`../shared/data`, or `$PGT_SHARED_DATA`), best of five each. Prints only; timings depend on
//! the machine. A file that is absent is skipped with a line that says so.

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
}

//! End-to-end test of `pgt sweep` (DESIGN.md §5, §7): reference once (then from the cache), one
//! approximation per parameter combination, a report with a table and SVG plots, and the GPU
//! method refused with exit 2 while it is not part of the build.

use std::path::Path;
use std::process::Command;

fn sweep(experiment: &Path, report: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args([
            "sweep",
            &experiment.to_string_lossy(),
            "--report",
            &report.to_string_lossy(),
        ])
        .output()
        .unwrap()
}

#[test]
fn riemann_sweep_reports_and_caches_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/shadows.toml");
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        format!(
            "scene = {:?}\nsize = [48, 32]\n[reference]\nspp = 2\n[[approximations]]\nmethod = \"riemann\"\nsamples = [4]\nspp = [1, 2]\n",
            scene.to_string_lossy()
        ),
    )
    .unwrap();
    let rep = dir.path().join("rep");
    let o = sweep(&exp, &rep);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("rendered in"), "{err}");
    for f in [
        "index.html",
        "dssim.svg",
        "rmse.svg",
        "time.svg",
        "reference.png",
        "sweep.json",
    ] {
        assert!(rep.join(f).is_file(), "{f} missing");
    }
    assert!(rep.join("riemann_samples_4_spp_1_abs_error.png").is_file());
    let svg = std::fs::read_to_string(rep.join("rmse.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("against spp"),
        "{svg}"
    );
    let runs: serde_json::Value =
        serde_json::from_slice(&std::fs::read(rep.join("sweep.json")).unwrap()).unwrap();
    let runs = runs.as_array().unwrap();
    assert_eq!(runs.len(), 2);
    // In opaque mode the integrator does not matter: the run at the reference's own spp is the
    // reference, bit for bit, so its SSIM is exactly 1 and its RMSE exactly 0; the 1-spp run
    // differs (aliasing at the silhouettes).
    let at = |spp: u64| runs.iter().find(|r| r["params"]["spp"] == spp).unwrap();
    assert_eq!(at(2)["ssim"]["mean"], 1.0);
    assert_eq!(at(2)["rmse"]["mean"], 0.0);
    let s1 = at(1)["ssim"]["mean"].as_f64().unwrap();
    assert!(s1 < 1.0 && s1 > 0.5, "{s1}");
    let html = std::fs::read_to_string(rep.join("index.html")).unwrap();
    assert!(html.contains("riemann samples=4 spp=1") && html.contains("100.0000%"));
    // The second run takes the reference from the cache.
    let o = sweep(&exp, &rep);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stderr).contains("from the cache"));
}

#[test]
fn gpu_method_and_bad_experiments_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/shadows.toml");
    let exp = dir.path().join("exp.toml");
    let rep = dir.path().join("rep");
    std::fs::write(
        &exp,
        format!("scene = {:?}\n[[approximations]]\nmethod = \"thesis\"\nsamples = [100]\nn_exact = [1, 5]\n", scene.to_string_lossy()),
    )
    .unwrap();
    let o = sweep(&exp, &rep);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("thesis"));
    std::fs::write(
        &exp,
        "scene = \"x.toml\"\n[[approximations]]\nmethod = \"riemann\"\nsamples = [1]\nbogus = 1\n",
    )
    .unwrap();
    let o = sweep(&exp, &rep);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("exp.toml") && err.contains("bogus"), "{err}");
}

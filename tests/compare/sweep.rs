//! End-to-end test of `pgt sweep` (docs/design.md §5, §7): reference once (then from the cache), one
//! approximation per parameter combination, a report with a table and SVG plots, the GPU
//! `thesis` method converging as its samples grow, and bad experiments refused with exit 2.

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

/// [`sweep`], which must succeed (exit 0; its stderr is the failure message otherwise).
fn sweep_ok(experiment: &Path, report: &Path) -> std::process::Output {
    let o = sweep(experiment, report);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
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
    // Each finished run is counted: done/total and its label.
    assert!(
        err.contains("[1/2] riemann samples=4 spp=1:")
            && err.contains("[2/2] riemann samples=4 spp=2:"),
        "{err}"
    );
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
fn a_baseline_run_is_compared_in_the_references_place() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/shadows.toml");
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        format!(
            "scene = {:?}\nsize = [48, 32]\n[reference]\nspp = 2\n[[approximations]]\nmethod = \"riemann\"\nsamples = 4\nspp = [1, 2]\nbaseline = {{ spp = 2 }}\n",
            scene.to_string_lossy()
        ),
    )
    .unwrap();
    let rep = dir.path().join("rep");
    sweep_ok(&exp, &rep);
    let runs: serde_json::Value =
        serde_json::from_slice(&std::fs::read(rep.join("sweep.json")).unwrap()).unwrap();
    let at = |spp: u64| {
        runs.as_array()
            .unwrap()
            .iter()
            .find(|r| r["params"]["spp"] == spp)
            .unwrap()
    };
    // The spp = 2 run is the reference bit for bit (opaque mode), so the spp = 1 run's error
    // against its baseline is its error against the reference, and the baseline against
    // itself is exact.
    assert_eq!(at(1)["baseline"]["run"], "riemann samples=4 spp=2");
    assert_eq!(at(1)["baseline"]["rmse"], at(1)["rmse"]);
    assert!(at(1)["baseline"]["ssim"]["mean"].as_f64().unwrap() < 1.0);
    assert_eq!(at(2)["baseline"]["ssim"]["mean"], 1.0);
    assert_eq!(at(2)["baseline"]["rmse"]["mean"], 0.0);
    assert!(rep.join("dssim_baseline.svg").is_file());
    let html = std::fs::read_to_string(rep.join("index.html")).unwrap();
    assert!(html.contains("against the baseline run"), "{html}");
}

/// The disjoint lit scene of the GPU tests, written into `dir`.
fn disjoint_scene(dir: &Path) {
    std::fs::write(
        dir.join("disjoint.toml"),
        r#"[camera]
position = [0.0, 0.0, -8.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
[render]
model = "lit"
[[lights]]
type = "directional"
direction = [0.3, -1.0, 0.2]
irradiance = [1.0, 0.9, 0.8]
[[lights]]
type = "point"
position = [2.0, 3.0, -4.0]
intensity = [8.0, 8.0, 10.0]
[[particles]]
center = [-1.2, 0.0, 0.0]
radius = 0.9
color = [1.0, 0.3, 0.2]
opacity = 0.7
[[particles]]
center = [1.0, 0.4, 0.5]
radius = 0.8
color = [0.2, 0.5, 1.0]
opacity = 0.9
[[particles]]
center = [0.2, -1.3, -0.5]
radius = 0.5
color = [0.9, 0.9, 0.3]
opacity = 0.5
"#,
    )
    .unwrap();
}

/// Whether a GPU adapter exists; under CI=true its absence fails the test.
fn have_gpu() -> bool {
    if let Err(e) = pgt::approx::GpuContext::new(None) {
        if std::env::var("CI").is_ok_and(|v| v == "true") {
            panic!("CI=true and no GPU adapter: {e}");
        }
        crate::support::skipped(&format!("no GPU adapter: {e}"));
        return false;
    }
    true
}

#[test]
fn thesis_sweep_on_the_gpu_converges_with_samples() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // Disjoint spheres, lit model: the thesis's per-particle scheme converges to the reference
    // as samples grow when n_exact covers every particle (docs/design.md §4).
    disjoint_scene(dir.path());
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        "scene = \"disjoint.toml\"\nsize = [32, 24]\n[[approximations]]\nmethod = \"thesis\"\nsamples = [1, 4, 64]\nn_exact = [100]\n",
    )
    .unwrap();
    let rep = dir.path().join("rep");
    let o = sweep(&exp, &rep);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(0), "{err}");
    let runs: serde_json::Value =
        serde_json::from_slice(&std::fs::read(rep.join("sweep.json")).unwrap()).unwrap();
    let rmse_at = |samples: u64| {
        runs.as_array()
            .unwrap()
            .iter()
            .find(|r| r["params"]["samples"] == samples)
            .map(|r| r["rmse"]["mean"].as_f64().unwrap())
            .unwrap()
    };
    let (r1, r4, r64) = (rmse_at(1), rmse_at(4), rmse_at(64));
    assert!(
        r1 > r4 && r4 > r64,
        "RMSE not falling with samples: {r1} {r4} {r64}"
    );
    assert!(rep.join("thesis_samples_64_n_exact_100.png").is_file());
}

#[test]
fn n_exact_all_is_a_category_and_a_baseline() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    disjoint_scene(dir.path());
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        "scene = \"disjoint.toml\"\nsize = [32, 24]\n[[approximations]]\nmethod = \"thesis\"\nsamples = 4\nn_exact = [1, \"all\"]\nbaseline = { n_exact = \"all\" }\n",
    )
    .unwrap();
    let rep = dir.path().join("rep");
    let o = sweep(&exp, &rep);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("thesis samples=4 n_exact=all:"), "{err}");
    assert!(rep.join("thesis_samples_4_n_exact_all.png").is_file());
    let runs: serde_json::Value =
        serde_json::from_slice(&std::fs::read(rep.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(runs[1]["params"]["n_exact"], "all");
    assert_eq!(runs[0]["baseline"]["run"], "thesis samples=4 n_exact=all");
    assert_eq!(runs[1]["baseline"]["ssim"]["mean"], 1.0);
    // n_exact is the x axis (two values against one), drawn as categories.
    let svg = std::fs::read_to_string(rep.join("dssim.svg")).unwrap();
    assert!(
        svg.contains("against n_exact") && svg.contains("all"),
        "{svg}"
    );
    assert!(
        !svg.contains("4294967295") && !svg.contains("4.29"),
        "{svg}"
    );
}

#[test]
fn bad_experiments_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/shadows.toml");
    let exp = dir.path().join("exp.toml");
    let rep = dir.path().join("rep");
    // The thesis method needs a volume scene; shadows.toml is opaque.
    std::fs::write(
        &exp,
        format!("scene = {:?}\nsize = [16, 16]\n[[approximations]]\nmethod = \"thesis\"\nsamples = [100]\nn_exact = [1, 5]\n", scene.to_string_lossy()),
    )
    .unwrap();
    let o = sweep(&exp, &rep);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("thesis"));
    std::fs::write(
        &exp,
        "scene = \"x.toml\"\n[[approximations]]\nmethod = \"riemann\"\nsamples = [1]\nbogus = 1\n",
    )
    .unwrap();
    let o = sweep(&exp, &rep);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("exp.toml:5:") && err.contains("bogus"),
        "{err}"
    );
    assert!(err.contains("its parameters are samples, spp"), "{err}");
    std::fs::write(
        &exp,
        "scene = \"x.toml\"\n[[approximations]]\nmethod = \"magic\"\n",
    )
    .unwrap();
    let o = sweep(&exp, &rep);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("exp.toml:3: unknown method \"magic\"") && err.contains("riemann"),
        "{err}"
    );
}

/// Reads `summary.json`'s first attribution.
fn first_attribution(rep: &Path) -> serde_json::Value {
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(rep.join("summary.json")).unwrap()).unwrap();
    summary["attribution"][0].clone()
}

#[test]
fn attribution_splits_the_error_into_causes_whose_shares_add_up() {
    let dir = tempfile::tempdir().unwrap();
    disjoint_scene(dir.path());
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        "scene = \"disjoint.toml\"\nsize = [32, 24]\nplot_x = \"samples\"\n[[approximations]]\nmethod = \"thesis-cpu\"\nsamples = 4\nn_exact = [0, \"all\"]\n[[approximations]]\nmethod = \"riemann\"\nsamples = 4\n[[attribution]]\nrun = { method = \"thesis-cpu\", samples = 4, n_exact = 0 }\nsteps = [\n    { cause = \"n_exact\", swap = { n_exact = \"all\" } },\n    { cause = \"overlap\", swap = { method = \"riemann\" } },\n    { cause = \"sampling\", swap = \"reference\" },\n]\n",
    )
    .unwrap();
    let rep = dir.path().join("rep");
    sweep_ok(&exp, &rep);
    let a = first_attribution(&rep);
    assert_eq!(a["run"], "thesis-cpu samples=4 n_exact=0");
    let causes = a["causes"].as_array().unwrap();
    let names: Vec<&str> = causes
        .iter()
        .map(|c| c["cause"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["n_exact", "overlap", "sampling"]);
    // The SSIM shares telescope to exactly 1; the MSE shares plus the interaction are 1.
    let sum = |key: &str| causes.iter().map(|c| c[key].as_f64().unwrap()).sum::<f64>();
    assert!((sum("ssim_share") - 1.0).abs() < 1e-9, "{a}");
    let interaction = a["interaction"].as_f64().unwrap();
    assert!((sum("mse_share") + interaction - 1.0).abs() < 1e-9, "{a}");
    // The particles are disjoint: whole-particle compositing is exact, so the overlap stage
    // (thesis-cpu against the reference with the same Riemann sums) changes nothing but
    // rounding, while N truncation (here N = 0: the emission model only) and sampling do change
    // the image.
    assert!(causes[1]["rmse"].as_f64().unwrap() < 1e-6, "{a}");
    assert!(causes[0]["rmse"].as_f64().unwrap() > 1e-4, "{a}");
    assert!(causes[2]["rmse"].as_f64().unwrap() > 1e-5, "{a}");
    for c in causes {
        assert!(rep.join(c["map"].as_str().unwrap()).is_file(), "{c}");
    }
    let bars = std::fs::read_to_string(rep.join(a["bars"].as_str().unwrap())).unwrap();
    assert!(
        bars.starts_with("<svg") && bars.contains("interaction"),
        "{bars}"
    );
    // The maps' colour bar: a file for other pages (the thesis report) and inline beside each
    // map, with the scale's top as its top label.
    let scale = std::fs::read_to_string(rep.join(a["scale"].as_str().unwrap())).unwrap();
    assert!(scale.starts_with("<svg class=\"colorbar\""), "{scale}");
    let page = std::fs::read_to_string(rep.join("index.html")).unwrap();
    assert!(page.contains("Error attribution") && page.contains("SSIM share"));
    let runs: serde_json::Value =
        serde_json::from_slice(&std::fs::read(rep.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(
        page.matches("<svg class=\"colorbar\"").count(),
        // one per run's heatmap, one per cause's map
        runs.as_array().unwrap().len() + causes.len(),
        "{page}"
    );
    assert!(rep.join("error_time.svg").is_file());

    // A swap to a run the experiment does not list is an error at its line.
    std::fs::write(
        &exp,
        "scene = \"disjoint.toml\"\n[[approximations]]\nmethod = \"thesis-cpu\"\nn_exact = 1\n[[attribution]]\nrun = { method = \"thesis-cpu\", n_exact = 1 }\nsteps = [\n    { cause = \"n_exact\", swap = { n_exact = 2 } },\n]\n",
    )
    .unwrap();
    let o = sweep(&exp, &rep);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("exp.toml:8:") && err.contains("thesis-cpu samples=100 n_exact=2"),
        "{err}"
    );
}

#[test]
fn thesis_on_the_gpu_differs_from_thesis_cpu_by_float32_rounding_only() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    disjoint_scene(dir.path());
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        "scene = \"disjoint.toml\"\nsize = [32, 24]\n[[approximations]]\nmethod = \"thesis\"\nsamples = 8\nn_exact = [1, \"all\"]\n[[approximations]]\nmethod = \"thesis-cpu\"\nsamples = 8\nn_exact = [1, \"all\"]\n[[attribution]]\nrun = { method = \"thesis\", samples = 8, n_exact = 1 }\nsteps = [{ cause = \"float32\", swap = { method = \"thesis-cpu\" } }]\n",
    )
    .unwrap();
    let rep = dir.path().join("rep");
    sweep_ok(&exp, &rep);
    let a = first_attribution(&rep);
    let causes = a["causes"].as_array().unwrap();
    // The chain stops before the reference: the rest is the residual.
    assert_eq!(causes[1]["cause"], "residual");
    let float32 = causes[0]["rmse"].as_f64().unwrap();
    assert!(float32 < 1e-5, "{a}");
    assert!(causes[1]["rmse"].as_f64().unwrap() > 100.0 * float32, "{a}");
}

/// docs/design.md §3: a reference pixel that does not converge is reported, not hidden, in a sweep
/// too: the centre pixel's ray runs exactly through a point light inside gas. The count and the
/// worst pixel are in `summary.json` and on stderr, also when the reference comes from the cache.
#[test]
fn a_sweep_reports_the_references_unconverged_pixels() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("light_inside.toml"),
        "[camera]\nposition = [0.0, 0.0, -5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 40.0\n\
         [render]\nmodel = \"lit\"\ntol = 1e-4\n\
         [[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 0.0]\nintensity = [0.1, 0.1, 0.1]\n\
         [[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\ncolor = [1.0, 1.0, 1.0]\nopacity = 0.5\n",
    )
    .unwrap();
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        "scene = \"light_inside.toml\"\nsize = [3, 3]\n[[approximations]]\nmethod = \"riemann\"\nsamples = 4\n",
    )
    .unwrap();
    let rep = dir.path().join("rep");
    for pass in ["rendered", "from the cache"] {
        let o = sweep_ok(&exp, &rep);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(pass)
                && err.contains("reference pixel(s) did not reach tol; the worst is (1, 1)"),
            "{err}"
        );
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(rep.join("summary.json")).unwrap()).unwrap();
        assert!(
            summary["reference_unconverged"].as_u64().unwrap() >= 1,
            "{summary}"
        );
        let worst = &summary["reference_worst_unconverged"];
        assert_eq!(
            (worst[0].as_u64(), worst[1].as_u64()),
            (Some(1), Some(1)),
            "{summary}"
        );
        assert!(worst[2].as_f64().unwrap() > 1e-4, "{summary}");
    }
}

#[test]
fn conventions_repeat_the_baseline_comparisons_on_prepared_images() {
    let dir = tempfile::tempdir().unwrap();
    disjoint_scene(dir.path());
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        "scene = \"disjoint.toml\"\nsize = [32, 24]\n[[approximations]]\nmethod = \"thesis-cpu\"\nsamples = 4\nn_exact = [0, \"all\"]\nbaseline = { n_exact = \"all\" }\n[[approximations]]\nmethod = \"thesis-cpu\"\nsamples = 4\nn_exact = 0\nrest_model = 1\nbaseline = { n_exact = \"all\", rest_model = 0 }\n[[conventions]]\nname = \"as-is\"\n[[conventions]]\nname = \"max-8bit\"\nnormalize = \"max\"\nquantize = 8\n[[conventions]]\nname = \"channel-max\"\nnormalize = \"channel-max\"\n",
    )
    .unwrap();
    let rep = dir.path().join("rep");
    sweep_ok(&exp, &rep);
    let runs: serde_json::Value =
        serde_json::from_slice(&std::fs::read(rep.join("sweep.json")).unwrap()).unwrap();
    let run = |n: serde_json::Value, rest: u64| {
        runs.as_array()
            .unwrap()
            .iter()
            .find(|r| r["params"]["n_exact"] == n && r["params"]["rest_model"] == rest)
            .unwrap()
            .clone()
    };
    let n0 = run(0.into(), 0);
    let base = &n0["baseline"];
    let conventions = base["conventions"].as_object().unwrap();
    assert_eq!(conventions.len(), 3);
    // A convention that prepares nothing repeats the comparison exactly.
    assert_eq!(conventions["as-is"]["ssim"], base["ssim"]);
    assert_eq!(conventions["as-is"]["rmse"], base["rmse"]);
    // Normalised, the images differ otherwise (the lit and the emission model's maxima are not
    // the same), and SSIM stays a similarity below 1.
    for name in ["max-8bit", "channel-max"] {
        let s = conventions[name]["ssim"]["mean"].as_f64().unwrap();
        assert!(s < 1.0 && s > 0.0, "{name}: {s}");
        assert_ne!(conventions[name]["ssim"], base["ssim"], "{name}");
    }
    // The baseline against itself is exact under every convention.
    let all = run("all".into(), 0);
    for name in ["as-is", "max-8bit", "channel-max"] {
        assert_eq!(all["baseline"]["conventions"][name]["ssim"]["mean"], 1.0);
    }
    // Absorption only past N = 0, on a black background: nothing is emitted, the image is black.
    let absorbed = run(0.into(), 1);
    assert_eq!(
        absorbed["baseline"]["run"],
        "thesis-cpu samples=4 n_exact=all"
    );
    assert_eq!(
        absorbed["image"],
        "thesis-cpu_samples_4_n_exact_0_rest_model_1.png"
    );
    let png = image::open(rep.join(absorbed["image"].as_str().unwrap()))
        .unwrap()
        .to_rgb8();
    assert!(png.pixels().all(|p| p.0 == [0, 0, 0]));
    let emitted = image::open(rep.join(n0["image"].as_str().unwrap()))
        .unwrap()
        .to_rgb8();
    assert!(emitted.pixels().any(|p| p.0 != [0, 0, 0]));
}

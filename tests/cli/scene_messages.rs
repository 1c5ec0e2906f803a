//! What `pgt render` tells the user about a scene it cannot draw or draws black (docs/design.md
//! §1 "Lights", §6 "Bad input"): the refusals of Gaussian particles with a setting name the
//! file and the line that chose the setting (or the flag) and the table that gave the
//! Gaussians; a scene without the lights its model needs renders, with a warning; a missing
//! trajectory is named at its key.

use std::path::Path;
use std::process::{Command, Output};

fn pgt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .env_remove("RAYON_NUM_THREADS")
        .output()
        .expect("the pgt binary runs")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Line 1 `[render]`, the Gaussians' `[[particles]]` table at line 7 (density from
/// `[defaults]` at line 4).
const GAUSSIANS: &str = "[render]\nmodel = \"emission\"\n\n[defaults]\ndensity = \"gaussian\"\n\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";

/// `pgt render SCENE ARGS` into a scratch folder: the exit code, stderr, and whether the image
/// was written.
fn render(scene_text: &str, args: &[&str]) -> (Option<i32>, String, bool, String) {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = dir.path().join("g.toml");
    std::fs::write(&scene, scene_text).expect("write the scene");
    let target = dir.path().join("out.exr");
    let mut full = vec!["render", s(&scene), "-o", s(&target), "--size", "6x6"];
    full.extend(args);
    let out = pgt(&full);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        target.exists(),
        scene.display().to_string(),
    )
}

#[test]
fn a_gaussian_refusal_names_the_line_that_chose_the_setting() {
    // [render] mode = "opaque": the [render] table's line.
    let text = GAUSSIANS.replace(
        "model = \"emission\"",
        "model = \"emission\"\nmode = \"opaque\"",
    );
    let (code, err, written, scene) = render(&text, &[]);
    assert_eq!(code, Some(2), "{err}");
    assert!(!written);
    assert!(
        err.contains(&format!("error: {scene}:1: [render] at line 1 sets mode = \"opaque\": Gaussian particles have no surface")),
        "{err}"
    );
    assert!(
        err.contains("the Gaussians: the [[particles]] table at line 8 ([defaults] at line 5 sets density = \"gaussian\")"),
        "{err}"
    );
    // --mode opaque: the flag, at the Gaussians' line.
    let (code, err, written, scene) = render(GAUSSIANS, &["--mode", "opaque"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(!written);
    assert!(
        err.contains(&format!(
            "error: {scene}:7: --mode opaque: Gaussian particles have no surface"
        )),
        "{err}"
    );
    // The lit model as the default: said to be the default, at the Gaussians' line.
    let (code, err, _, scene) = render(&GAUSSIANS.replace("model = \"emission\"\n", ""), &[]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains(&format!("error: {scene}:6: the lit model (the default: no model is set): the lit model's shadow rays")),
        "{err}"
    );
    // The Riemann integrator: the flag, at the Gaussians' line.
    let (code, err, _, scene) = render(GAUSSIANS, &["--integrator", "riemann"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "error: {scene}:7: --integrator riemann: the Riemann sums apply"
        )),
        "{err}"
    );
}

#[test]
fn mixed_densities_name_both_tables() {
    let text = format!(
        "{GAUSSIANS}\n[[particles]]\ncenter = [3.0, 0.0, 0.0]\nradius = 1.0\ndensity = \"constant\"\n"
    );
    let (code, err, written, scene) = render(&text, &[]);
    assert_eq!(code, Some(2), "{err}");
    assert!(!written);
    assert!(
        err.contains(&format!("error: {scene}:11: this scene mixes particles of constant and Gaussian density: the [[particles]] table at line 11 has constant density (density = \"constant\" there), but the [[particles]] table at line 7 has Gaussian density ([defaults] at line 4 sets density = \"gaussian\")")),
        "{err}"
    );
}

#[test]
fn a_lit_scene_without_lights_renders_with_a_warning() {
    let text = "[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";
    let (code, err, written, scene) = render(text, &[]);
    assert_eq!(code, Some(0), "{err}");
    assert!(written);
    assert!(
        err.contains(&format!("warning: {scene}: the scene has no [[lights]], and the lit model takes its light from them: the particles render black")),
        "{err}"
    );
    // With lights, or a model that needs none, no such warning.
    let lit = format!("{text}[[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n");
    for (text, args) in [
        (lit.as_str(), &[][..]),
        (text, &["--model", "emission"][..]),
    ] {
        let (code, err, _, _) = render(text, args);
        assert_eq!(code, Some(0), "{err}");
        assert!(!err.contains("[[lights]]"), "{err}");
    }
}

#[test]
fn a_missing_trajectory_is_named_at_its_key() {
    let dir = tempfile::tempdir().expect("temp dir");
    let atom = format!(
        "{:>5}{:<5}{:>5}{:>5}{:8.3}{:8.3}{:8.3}",
        1, "SOL", "OW", 1, 0.126, 1.624, 1.679
    );
    std::fs::write(
        dir.path().join("top.gro"),
        format!("t\n    1\n{atom}\n   1.00000   1.00000   1.00000\n"),
    )
    .expect("write the topology");
    let scene = dir.path().join("t.toml");
    std::fs::write(
        &scene,
        "[render]\nmodel = \"emission\"\n\n[[include]]\npath = \"top.gro\"\n\ntrajectory = \"gone.xtc\"\n",
    )
    .expect("write the scene");
    let out = pgt(&["info", s(&scene)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "{}:7: include.trajectory: cannot read {}",
            scene.display(),
            dir.path().join("gone.xtc").display()
        )) && err.contains("(the path `gone.xtc` is taken relative to"),
        "{err}"
    );
}

#[test]
fn a_small_gaussian_cutoff_renders_with_a_warning_that_err_exceeds_tol() {
    // With k = 1 every ray adds the depth of the Gaussian it passes outside 1 σ: err is large
    // everywhere, honestly, and the user is told why.
    let cut = GAUSSIANS.replace("[render]\n", "[render]\ngaussian_cutoff = 1.0\n");
    let (code, err, written, _) = render(&cut, &[]);
    assert_eq!(code, Some(0), "{err}");
    assert!(written);
    assert!(
        err.contains("warning: 36 pixel(s) have err above tol 1e-5")
            && err.contains("gaussian_cutoff = 1 σ"),
        "{err}"
    );
    // The default cut-off keeps err within tol: no such warning.
    let (code, err, _, _) = render(GAUSSIANS, &[]);
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("err above tol"), "{err}");
}

//! `pgt camera SCENE [--json]` (docs/design.md §7): the scene's camera (after default framing) as a
//! rasterising engine wants it: eye, basis, fov, size, the pixel-centre convention, the view
//! matrix and a projection matrix per graphics API with near/far from the scene's bounds
//! ([`crate::geometry::projection`]).

use super::Outcome;
use crate::geometry::projection::{CameraJson, MatrixJson};
use crate::scene::{Scene, SceneLoadOptions};
use clap::Args;
use std::path::PathBuf;

/// Options of `pgt camera`.
#[derive(Debug, Args)]
pub struct CameraArgs {
    /// Scene file (.toml) or a bare particle file.
    pub scene: PathBuf,
    /// Image size WIDTHxHEIGHT, overriding the scene (as `pgt render --size` does).
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<(u32, u32)>,
    /// Print JSON on stdout instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The camera JSON of a loaded scene.
pub fn camera_json(scene: &Scene) -> CameraJson {
    CameraJson::new(
        &scene.camera,
        scene.particles.iter().map(|p| (p.center, p.radius)),
        scene.render.background,
    )
}

fn print_matrix(name: &str, m: &MatrixJson) {
    println!("{name} (row by row):");
    for row in &m.row_major {
        println!(
            "  [{:>14.8}, {:>14.8}, {:>14.8}, {:>14.8}]",
            row[0], row[1], row[2], row[3]
        );
    }
}

/// Runs `pgt camera`.
pub fn run(args: CameraArgs) -> anyhow::Result<Outcome> {
    let options = SceneLoadOptions {
        size: args.size,
        ..SceneLoadOptions::default()
    };
    let scene = Scene::load(&args.scene, &options)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let cam = camera_json(&scene);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&cam)?);
        return Ok(Outcome::Success);
    }
    let v = |a: [f64; 3]| format!("[{:.6}, {:.6}, {:.6}]", a[0], a[1], a[2]);
    println!("eye:      {}", v(cam.eye));
    println!("forward:  {}   (f)", v(cam.forward));
    println!("right:    {}   (r = normalize(f x up))", v(cam.right));
    println!("up:       {}   (u = r x f)", v(cam.up));
    println!(
        "fov:      {:.6} deg vertical, {:.6} deg horizontal",
        cam.fov_y_deg, cam.fov_x_deg
    );
    println!(
        "size:     {}x{} (aspect {:.6})",
        cam.width, cam.height, cam.aspect
    );
    println!("near/far: {:.6} / {:.6}", cam.near, cam.far);
    println!("pixels:   {}", cam.pixel_convention);
    println!("matrices: {}", cam.matrix_convention);
    print_matrix("view", &cam.view);
    for (api, p) in &cam.projection {
        print_matrix(&format!("projection {api}"), &p.matrix);
        println!("  {}", p.convention);
    }
    Ok(Outcome::Success)
}

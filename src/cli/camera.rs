//! `pgt camera SCENE [--json]` (docs/design.md §7): the scene's camera (after default framing) as a
//! rasterising engine wants it: eye, basis, fov, size, the pixel-centre convention, the view
//! matrix and a projection matrix per graphics API with near/far from the scene's bounds
//! ([`pgt::geometry::projection`]).

use super::Outcome;
use clap::Args;
use pgt::geometry::projection::{CameraJson, MatrixJson};
use pgt::scene::SceneLoadOptions;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Options of `pgt camera`.
#[derive(Debug, Args)]
pub struct CameraArgs {
    /// Scene file (.toml) or a bare particle file.
    pub scene: PathBuf,
    /// Image size WIDTHxHEIGHT, overriding the scene (as `pgt render --size` does).
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<(u32, u32)>,
    /// The format of a bare particle file, whatever its extension (a scene file names the
    /// format of each include with `format = "…"`).
    #[arg(long, value_name = "NAME", value_parser = super::format_parser())]
    pub format: Option<&'static pgt::formats::Format>,
    /// The frame (from 0) of a scene that moves: its particles and camera, as `pgt render
    /// --frames` renders it.
    #[arg(long, value_name = "K")]
    pub frame: Option<usize>,
    /// Print JSON on stdout instead of text.
    #[arg(long)]
    pub json: bool,
}

fn write_matrix(t: &mut String, name: &str, m: &MatrixJson) {
    let _ = writeln!(t, "{name} (row by row):");
    for row in &m.row_major {
        let _ = writeln!(
            t,
            "  [{:>14.8}, {:>14.8}, {:>14.8}, {:>14.8}]",
            row[0], row[1], row[2], row[3]
        );
    }
}

/// Runs `pgt camera`.
pub fn run(args: CameraArgs) -> anyhow::Result<Outcome> {
    let options = SceneLoadOptions {
        size: args.size,
        format: args.format,
        ..SceneLoadOptions::default()
    };
    let scene = pgt::sequence::scene_at_frame(&args.scene, &options, args.frame)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let cam = scene.camera_json();
    let text = if args.json {
        serde_json::to_string_pretty(&cam)? + "\n"
    } else {
        text_of(&cam)
    };
    super::print_stdout(&text)?;
    Ok(Outcome::Success)
}

/// The text form of `pgt camera`.
fn text_of(cam: &CameraJson) -> String {
    // Writing into a String cannot fail.
    let mut t = String::new();
    let v = |a: [f64; 3]| format!("[{:.6}, {:.6}, {:.6}]", a[0], a[1], a[2]);
    let _ = writeln!(t, "eye:      {}", v(cam.eye));
    let _ = writeln!(t, "forward:  {}   (f)", v(cam.forward));
    let _ = writeln!(t, "right:    {}   (r = normalize(f x up))", v(cam.right));
    let _ = writeln!(t, "up:       {}   (u = r x f)", v(cam.up));
    let _ = writeln!(
        t,
        "fov:      {:.6} deg vertical, {:.6} deg horizontal",
        cam.fov_y_deg, cam.fov_x_deg
    );
    let _ = writeln!(
        t,
        "size:     {}x{} (aspect {:.6})",
        cam.width, cam.height, cam.aspect
    );
    let _ = writeln!(t, "near/far: {:.6} / {:.6}", cam.near, cam.far);
    let _ = writeln!(t, "pixels:   {}", cam.pixel_convention);
    let _ = writeln!(t, "matrices: {}", cam.matrix_convention);
    write_matrix(&mut t, "view", &cam.view);
    for (api, p) in &cam.projection {
        write_matrix(&mut t, &format!("projection {api}"), &p.matrix);
        let _ = writeln!(t, "  {}", p.convention);
    }
    t
}

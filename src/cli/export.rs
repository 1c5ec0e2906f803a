//! `pgt export SCENE -o particles.csv|.ply` (docs/design.md §7): the resolved particles, exactly
//! as pgt renders them, for an outside renderer. The columns are the scene's
//! ([`pgt::scene::export`]), the file formats the formats' ([`pgt::formats::export`]).

use super::output::{check_outputs, Output, OutputKind};
use super::Outcome;
use clap::Args;
use pgt::formats::export::ExportFormat;
use pgt::image_io::write_atomically;
use pgt::scene::export::write_particles;
use pgt::scene::SceneLoadOptions;
use std::path::PathBuf;

/// Options of `pgt export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// Scene file (.toml) or a bare particle file.
    pub scene: PathBuf,
    /// Output file; the format follows the extension (.csv or .ply).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The format of a bare particle file, whatever its extension (a scene file names the
    /// format of each include with `format = "…"`).
    #[arg(long, value_name = "NAME", value_parser = super::format_parser())]
    pub format: Option<&'static pgt::formats::Format>,
    /// The frame (from 0) of a scene that moves: its particles and camera, as `pgt render
    /// --frames` renders it.
    #[arg(long, value_name = "K")]
    pub frame: Option<usize>,
}

/// Runs `pgt export`.
pub fn run(args: ExportArgs) -> anyhow::Result<Outcome> {
    check_outputs(&[Output::new(
        "--output",
        &args.output,
        OutputKind::File(&["csv", "ply"]),
    )])?;
    let format = ExportFormat::from_path(&args.output)?;
    let options = SceneLoadOptions {
        format: args.format,
        ..SceneLoadOptions::default()
    };
    let scene = pgt::sequence::scene_at_frame(&args.scene, &options, args.frame)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if scene.has_gaussians() {
        // The columns hold a Gaussian's standard deviations and peak density; the profile
        // itself has no column (docs/design.md §7).
        eprintln!(
            "warning: the scene's Gaussian particles are written with their standard deviations and peak σ, but the file does not say they are Gaussians: include it with density = \"gaussian\" to read them back as they are"
        );
    }
    write_atomically(&args.output, |w| {
        write_particles(w, format, &scene.particles)
    })?;
    eprintln!(
        "exported {} particles to {}",
        scene.particles.len(),
        args.output.display()
    );
    Ok(Outcome::Success)
}

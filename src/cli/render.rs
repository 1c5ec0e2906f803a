//! `pgt render SCENE -o OUT`: the exact reference (docs/design.md §3, §7).

use super::output::{check_outputs, Output, OutputKind};
use super::Outcome;
use crate::image_io::write_image;
use crate::parts::PartOf;
use crate::reference::{self, Integrator, RenderOptions};
use crate::scene::{Model, RenderMode, SceneLoadOptions};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IntegratorName {
    /// Adaptive Gauss–Kronrod to `tol` (the exact reference).
    Adaptive,
    /// The thesis's midpoint Riemann sums (`--samples` per interval).
    Riemann,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file (.toml) or a bare particle file.
    pub scene: PathBuf,
    /// Output image; the format follows the extension (.exr or .png).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Image size WIDTHxHEIGHT, overriding the scene.
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<(u32, u32)>,
    /// Render mode, overriding the scene.
    #[arg(long, value_enum)]
    pub mode: Option<RenderMode>,
    /// Optical model of the volume mode, overriding the scene.
    #[arg(long, value_enum)]
    pub model: Option<Model>,
    /// The format of a bare particle file, whatever its extension (a scene file names the
    /// format of each include with `format = "…"`).
    #[arg(long, value_name = "NAME", value_parser = super::format_parser())]
    pub format: Option<&'static crate::formats::Format>,
    /// Absolute radiance tolerance of the quadrature, per pixel and channel.
    #[arg(long)]
    pub tol: Option<f64>,
    /// Stratified k×k samples per pixel.
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// Worker threads (the image is identical for any count).
    #[arg(long)]
    pub threads: Option<usize>,
    /// PNG exposure in stops (2^exposure scales the linear image before encoding).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// How the volume integral is computed.
    #[arg(long, value_enum, default_value = "adaptive")]
    pub integrator: IntegratorName,
    /// Samples per interval for `--integrator riemann`.
    #[arg(long, default_value_t = 100)]
    pub samples: u32,
    /// Render only part I of N (I from 0, as job arrays count; the part holds the rows y with
    /// y mod N = I) into an EXR part file, to be joined by `pgt merge` (see `pgt::parts`).
    #[arg(long, value_parser = crate::parts::parse_part, value_name = "I/N")]
    pub part: Option<PartOf>,
    /// The former name of `--part`: still accepted, with a warning.
    #[arg(long, value_parser = crate::parts::parse_part, value_name = "I/N", hide = true, conflicts_with = "part")]
    pub tile: Option<PartOf>,
}

impl RenderArgs {
    /// `--part`, or the deprecated `--tile` with a one-line warning.
    fn part(&self) -> Option<PartOf> {
        if self.tile.is_some() {
            eprintln!("warning: --tile is deprecated; it is now called --part (same I/N)");
        }
        self.part.or(self.tile)
    }
}

pub fn run(args: RenderArgs) -> anyhow::Result<Outcome> {
    let part = args.part();
    let kind = match part {
        Some(_) => OutputKind::Part,
        None => OutputKind::Image,
    };
    check_outputs(&[Output::new("--output", &args.output, kind)])?;
    let options = SceneLoadOptions {
        size: args.size,
        mode: args.mode,
        model: args.model,
        tol: args.tol,
        format: args.format,
    };
    let scene = super::load_scene_for(&args.scene, &options, args.exposure)?;
    let integrator = match args.integrator {
        IntegratorName::Adaptive => Integrator::Adaptive,
        IntegratorName::Riemann => {
            if args.samples == 0 {
                anyhow::bail!("--samples must be at least 1");
            }
            Integrator::Riemann {
                samples: args.samples,
            }
        }
    };
    let render_options = RenderOptions {
        spp: args.spp,
        threads: args.threads,
        progress: super::stderr_is_terminal(),
        integrator,
    };
    if let Some(part) = part {
        return render_part(&args, &scene, &render_options, part);
    }
    let out = reference::render(&scene, &render_options)?;
    let layers: Vec<(&str, &crate::image_io::RgbImage)> =
        out.error.iter().map(|e| ("err", e)).collect();
    write_image(&args.output, &out.image, &layers, args.exposure)?;
    let s = &out.stats;
    let rays = s.primary_rays + s.shadow_rays;
    let ellipsoids = scene
        .particles
        .iter()
        .filter(|p| p.ellipsoid.is_some())
        .count();
    let particles = match ellipsoids {
        0 => format!("{} spheres", scene.particles.len()),
        n => format!(
            "{} particles, {n} of them ellipsoids",
            scene.particles.len()
        ),
    };
    let mut line = format!(
        "rendered {} ({}x{}, {particles}, {} lights) in {:.2} s: {} primary + {} shadow rays, {:.3} Mrays/s",
        args.output.display(),
        scene.camera.width,
        scene.camera.height,
        scene.lights.len(),
        s.seconds,
        s.primary_rays,
        s.shadow_rays,
        rays as f64 / s.seconds.max(1e-9) / 1e6
    );
    if let (Some(max), Some(mean)) = (s.max_error, s.mean_error) {
        line += &format!(", error estimate max {max:.3e} mean {mean:.3e}");
    }
    eprintln!("{line}");
    if let Some(warning) = unconverged_warning(s, scene.render.tol) {
        eprintln!("warning: {warning}");
    }
    Ok(Outcome::Success)
}

/// docs/design.md §3: a pixel that does not converge is reported, not hidden. The count and the pixel
/// with the largest error estimate, or `None` when every pixel reached `tol`.
pub fn unconverged_warning(stats: &reference::RenderStats, tol: f64) -> Option<String> {
    let (x, y, e) = stats.worst_unconverged?;
    Some(format!(
        "{} pixel(s) did not reach tol {tol:e}; the worst is ({x}, {y}) with error estimate {e:.3e} (its err value says how far off it may be)",
        stats.unconverged
    ))
}

/// `--part I/N`: renders and writes one part (`pgt::parts`), with a one-line summary.
fn render_part(
    args: &RenderArgs,
    scene: &crate::scene::Scene,
    options: &RenderOptions,
    which: PartOf,
) -> anyhow::Result<Outcome> {
    let (part, s) = crate::parts::render_part(scene, options, which)?;
    crate::parts::write_part(&args.output, &part)?;
    eprintln!(
        "rendered part {which} ({} of {} rows of {}x{}) into {} in {:.2} s: {} primary + {} shadow rays",
        part.image.height,
        scene.camera.height,
        scene.camera.width,
        scene.camera.height,
        args.output.display(),
        s.seconds,
        s.primary_rays,
        s.shadow_rays
    );
    Ok(Outcome::Success)
}

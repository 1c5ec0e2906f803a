//! `pgt render SCENE -o OUT`: the exact reference (docs/design.md §3, §7).

use super::output::{check_outputs, Output, OutputKind};
use super::Outcome;
use clap::{Args, ValueEnum};
use pgt::approx::GpuContext;
use pgt::image_io::write_image;
use pgt::parts::PartOf;
use pgt::reference::{self, Device, Integrator, RenderOptions};
use pgt::scene::{Model, RenderMode, SceneLoadOptions};
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
    /// Output image; the format follows the extension (.exr or .png). With --frames, a printf
    /// pattern that names each frame's file: out/frame_%04d.exr.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Render these frames of the scene, one file each: A..B (A to B−1) or A.. (to the last
    /// frame), as an include's `frames`. A frame whose EXR already holds this render (same render hash) is
    /// skipped, so an interrupted sequence resumes; with --part I/N, this task renders every
    /// N-th frame of the range from the I-th.
    #[arg(long, value_name = "RANGE")]
    pub frames: Option<pgt::sequence::FrameRange>,
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
    pub format: Option<&'static pgt::formats::Format>,
    #[command(flatten)]
    pub bare: super::BareFileArgs,
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
    /// With --frames, part I of N is every N-th frame from the I-th, written whole.
    #[arg(long, value_parser = pgt::parts::parse_part, value_name = "I/N")]
    pub part: Option<PartOf>,
    /// Render on the GPU in f64 (docs/design.md §12): the same image and err as the CPU
    /// reference, within both errs. The emission model of spheres, ellipsoids and Gaussians;
    /// an adapter without f64 is refused by name. With --frames and --part too: a GPU render's
    /// hash names the GPU and its adapter, so its frames and parts are never taken for the CPU's.
    #[arg(long)]
    pub gpu: bool,
    /// With --gpu: use the adapter whose name contains this (case-insensitive).
    #[arg(long, requires = "gpu")]
    pub adapter: Option<String>,
    /// The former name of `--part`: still accepted, with a warning.
    #[arg(long, value_parser = pgt::parts::parse_part, value_name = "I/N", hide = true, conflicts_with = "part")]
    pub tile: Option<PartOf>,
}

impl RenderArgs {
    fn load_options(&self) -> SceneLoadOptions {
        self.bare.apply(SceneLoadOptions {
            size: self.size,
            mode: self.mode,
            model: self.model,
            tol: self.tol,
            format: self.format,
            ..SceneLoadOptions::default()
        })
    }

    fn render_options(&self) -> anyhow::Result<RenderOptions> {
        let integrator = match self.integrator {
            IntegratorName::Adaptive => Integrator::Adaptive,
            IntegratorName::Riemann => {
                if self.samples == 0 {
                    anyhow::bail!("--samples must be at least 1");
                }
                Integrator::Riemann {
                    samples: self.samples,
                }
            }
        };
        Ok(RenderOptions {
            spp: self.spp,
            threads: self.threads,
            progress: super::stderr_is_terminal(),
            integrator,
        })
    }

    /// With --gpu, the device that renders `scene` (a scene the GPU reference cannot render is
    /// refused by name before any adapter is opened); `None` for the CPU.
    fn gpu_context(
        &self,
        scene: &pgt::scene::Scene,
        options: &RenderOptions,
    ) -> anyhow::Result<Option<GpuContext>> {
        if !self.gpu {
            return Ok(None);
        }
        reference::gpu::check_supported(scene, options)?;
        Ok(Some(GpuContext::with_f64(self.adapter.as_deref())?))
    }

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
    if let Some(range) = args.frames {
        return render_frames(&args, range, part);
    }
    let kind = match part {
        Some(_) => OutputKind::Part,
        None => OutputKind::Image,
    };
    check_outputs(&[Output::new("--output", &args.output, kind)])?;
    let scene = super::load_scene_for(&args.scene, &args.load_options(), args.exposure)?;
    let render_options = args.render_options()?;
    let ctx = args.gpu_context(&scene, &render_options)?;
    let device = ctx.as_ref().map_or(Device::Cpu, Device::Gpu);
    let on = ctx
        .as_ref()
        .map_or(String::new(), |c| format!(" on {}", c.adapter));
    if let Some(part) = part {
        return render_part(&args, &scene, &render_options, (device, &on), part);
    }
    let out = match device {
        Device::Cpu => reference::render(&scene, &render_options)?,
        Device::Gpu(ctx) => reference::gpu::render_on(ctx, &scene, &render_options)?,
    };
    let layers: Vec<(&str, &pgt::image_io::RgbImage)> =
        out.error.iter().map(|e| ("err", e)).collect();
    write_image(&args.output, &out.image, &layers, args.exposure)?;
    let s = &out.stats;
    let rays = s.primary_rays + s.shadow_rays;
    let particles = scene.particles_text();
    let mut line = format!(
        "rendered {} ({}x{}, {particles}, {} lights){on} in {:.2} s: {} primary + {} shadow rays, {}",
        args.output.display(),
        scene.camera.width,
        scene.camera.height,
        scene.lights.len(),
        s.seconds,
        s.primary_rays,
        s.shadow_rays,
        ray_rate_text(rays, s.seconds)
    );
    if let (Some(max), Some(mean)) = (s.max_error, s.mean_error) {
        line += &format!(", error estimate max {max:.3e} mean {mean:.3e}");
    }
    eprintln!("{line}");
    if let Some(warning) = reference::unconverged_warning(s, scene.render.tol) {
        eprintln!("warning: {warning}");
    }
    let above_tol = out.error.as_ref().and_then(|err| {
        reference::err_above_tol_warning(&out.image, err, scene.render.tol, &scene)
    });
    if let Some(warning) = above_tol {
        eprintln!("warning: {warning}");
    }
    Ok(Outcome::Success)
}

/// `--part I/N`: renders and writes one part (`pgt::parts`), with a one-line summary.
/// `on` names the GPU's adapter in the summary (empty on the CPU).
fn render_part(
    args: &RenderArgs,
    scene: &pgt::scene::Scene,
    options: &RenderOptions,
    (device, on): (Device, &str),
    which: PartOf,
) -> anyhow::Result<Outcome> {
    let (part, s) = pgt::parts::render_part(scene, options, device, which)?;
    pgt::parts::write_part(&args.output, &part)?;
    eprintln!(
        "rendered part {which} ({} of {} rows of {}x{}) into {}{on} in {:.2} s: {} primary + {} shadow rays",
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

/// `--frames`: every frame of the range (or of this task's part of it) into the output pattern,
/// with a progress bar over the frames and a summary line.
fn render_frames(
    args: &RenderArgs,
    range: pgt::sequence::FrameRange,
    part: Option<PartOf>,
) -> anyhow::Result<Outcome> {
    let render_options = args.render_options()?;
    let (frames, list, pattern) = super::frames::open_sequence(
        &args.scene,
        &args.load_options(),
        args.exposure,
        range,
        part,
        &args.output,
    )?;
    let ctx = args.gpu_context(frames.first(), &render_options)?;
    let device = ctx.as_ref().map_or(Device::Cpu, Device::Gpu);
    let progress = super::frames::FrameProgress::new("render", list.len());
    let summary = pgt::sequence::render::render_frames(
        &frames,
        &list,
        &pattern,
        &render_options,
        device,
        args.exposure,
        &progress,
    );
    progress.finish();
    let summary = summary?;
    let (rendered, skipped) = summary.counts();
    let t = summary.totals();
    eprintln!(
        "rendered {rendered} frame(s) of {} into {} ({}x{}){}{}: {:.2} s of rendering, {} primary + {} shadow rays",
        args.scene.display(),
        args.output.display(),
        frames.first().camera.width,
        frames.first().camera.height,
        ctx.as_ref()
            .map_or(String::new(), |c| format!(" on {}", c.adapter)),
        if skipped > 0 {
            format!(", skipped {skipped} already rendered")
        } else {
            String::new()
        },
        t.seconds,
        t.primary_rays,
        t.shadow_rays,
    );
    if let Some((frame, n)) = summary.worst_unconverged() {
        eprintln!(
            "warning: {} pixel(s) over the frames did not reach tol {:e}; frame {frame} has the most ({n}; its err layer says how far off they may be)",
            t.unconverged,
            frames.first().render.tol
        );
    }
    Ok(Outcome::Success)
}
/// Rays per second in words: `R Mrays/s` with three decimals, or `R rays/s` where that would
/// read 0.000 (a slow render of a small image).
fn ray_rate_text(rays: u64, seconds: f64) -> String {
    let rate = rays as f64 / seconds.max(1e-9);
    if rate >= 1e3 {
        format!("{:.3} Mrays/s", rate / 1e6)
    } else {
        format!("{rate:.1} rays/s")
    }
}

#[cfg(test)]
mod tests {
    use super::ray_rate_text;

    #[test]
    fn slow_renders_state_their_rate_in_rays_not_zero_mrays() {
        assert_eq!(ray_rate_text(4_096, 38.8), "105.6 rays/s");
        assert_eq!(ray_rate_text(2_500_000, 2.0), "1.250 Mrays/s");
        assert_eq!(ray_rate_text(1_000, 1.0), "0.001 Mrays/s");
    }
}

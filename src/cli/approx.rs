//! `pgt approx SCENE --method thesis --samples 100 --n-exact 5 -o OUT` (docs/design.md §4, §7): the
//! GPU approximation, or a user's method with `--shader FILE.wgsl`. The methods and their
//! parameters come from the registry (`pgt::approx::methods`); `--list-methods` prints it.

use super::output::{check_outputs, Output, OutputKind};
use super::Outcome;
use clap::builder::PossibleValuesParser;
use clap::Args;
use pgt::approx::{self, methods, ApproxParams, Method, Timing, N_EXACT_ALL};
use pgt::image_io::write_image;
use pgt::scene::{Model, RenderMode, SceneLoadOptions};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// `pgt approx` (docs/design.md §7).
#[derive(Debug, Args)]
pub struct ApproxArgs {
    /// Scene file (.toml) or a bare particle file.
    #[arg(required_unless_present = "list_methods")]
    pub scene: Option<PathBuf>,
    /// Output image; the format follows the extension (.exr or .png). With --frames, a printf
    /// pattern that names each frame's file: out/frame_%04d.exr.
    #[arg(short, long, required_unless_present = "list_methods")]
    pub output: Option<PathBuf>,
    /// Approximate these frames of the scene, one file each: A..B (A to B−1) or A.. (to the last
    /// frame), as an include's `frames`. A frame whose EXR already holds this render (same scene, method,
    /// parameters and adapter) is skipped.
    #[arg(long, value_name = "RANGE")]
    pub frames: Option<pgt::sequence::FrameRange>,
    /// With --frames: approximate only part I of N of the frames (every N-th from the I-th; I
    /// from 0, as job arrays count).
    #[arg(long, value_parser = pgt::parts::parse_part, value_name = "I/N", requires = "frames")]
    pub part: Option<pgt::parts::PartOf>,
    /// Approximation method (see --list-methods) [default: opaque for opaque scenes, thesis
    /// otherwise].
    #[arg(long, value_parser = PossibleValuesParser::new(methods::names()), conflicts_with = "shader")]
    pub method: Option<String>,
    /// Print the methods and their parameters (a Markdown table) and exit.
    #[arg(long)]
    pub list_methods: bool,
    /// A WGSL file defining `fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32>`
    /// (docs/user-shaders.md).
    #[arg(long)]
    pub shader: Option<PathBuf>,
    /// The method's parameter `samples` (thesis: midpoint-rule samples per particle chord);
    /// short for --param samples=N.
    #[arg(long)]
    pub samples: Option<u32>,
    /// The method's parameter `n_exact` (thesis: particles from the eye that get the lit model;
    /// a number or "all"); short for --param n_exact=N.
    #[arg(long, value_parser = parse_count)]
    pub n_exact: Option<u32>,
    /// Any parameter of the method, NAME=VALUE (repeatable; VALUE a number or "all").
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_param)]
    pub params: Vec<(String, u32)>,
    /// Use the adapter whose name contains this (case-insensitive).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Image size WIDTHxHEIGHT, overriding the scene.
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<(u32, u32)>,
    /// Render mode, overriding the scene.
    #[arg(long, value_enum)]
    pub mode: Option<RenderMode>,
    /// Optical model of the volume mode, overriding the scene (a method refuses a model it does
    /// not implement).
    #[arg(long, value_enum)]
    pub model: Option<Model>,
    /// The format of a bare particle file, whatever its extension (a scene file names the
    /// format of each include with `format = "…"`).
    #[arg(long, value_name = "NAME", value_parser = super::format_parser())]
    pub format: Option<&'static pgt::formats::Format>,
    /// PNG exposure in stops (2^exposure scales the linear image before encoding).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
}

/// A parameter value: a non-negative integer or "all" ([`N_EXACT_ALL`]).
fn parse_count(s: &str) -> Result<u32, String> {
    if s.eq_ignore_ascii_case("all") {
        return Ok(N_EXACT_ALL);
    }
    s.parse::<u32>()
        .map_err(|_| format!("expected a non-negative integer or 'all', got '{s}'"))
}

fn parse_param(s: &str) -> Result<(String, u32), String> {
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, got '{s}'"))?;
    Ok((name.trim().to_string(), parse_count(value.trim())?))
}

impl ApproxArgs {
    /// The method and parameter values the arguments choose.
    fn params(&self) -> anyhow::Result<ApproxParams> {
        let method = match (&self.shader, &self.method) {
            (Some(path), _) => Some(Method::User(path.clone())),
            (None, Some(name)) => Some(Method::named(name)?),
            (None, None) => None,
        };
        let mut values = Vec::new();
        if let Some(v) = self.samples {
            values.push(("samples".to_string(), v));
        }
        if let Some(v) = self.n_exact {
            values.push(("n_exact".to_string(), v));
        }
        values.extend(self.params.iter().cloned());
        Ok(ApproxParams {
            method,
            values,
            adapter: self.adapter.clone(),
        })
    }
}

/// "(samples 8, n_exact all)" for the summary; empty without parameters.
fn describe_params(method: &Method, values: &[(String, u32)]) -> String {
    if values.is_empty() {
        return String::new();
    }
    let specs = method.specs();
    let shown: Vec<String> = values
        .iter()
        .map(|(n, v)| match specs.iter().find(|s| s.name == n) {
            Some(s) => format!("{n} {}", s.show(*v)),
            None => format!("{n} {v}"),
        })
        .collect();
    format!(" ({})", shown.join(", "))
}

/// A spinner with the elapsed time while the GPU works (a long approximation, e.g. `thesis`
/// with many samples on lavapipe, runs for minutes in passes the CLI cannot see into); shown only
/// when stderr is a terminal (docs/design.md §7), cleared before the summary line.
fn approx_spinner(params: &ApproxParams) -> indicatif::ProgressBar {
    let method = match &params.method {
        Some(m) => m.name(),
        None => "the default method".to_string(),
    };
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {elapsed_precise} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    bar.set_message(format!("approximating with {method}"));
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

/// Where the passes stand: "pass 57, 3200 work items done" (their number is not known in
/// advance: the schedule adapts to each pass).
fn pass_text(p: approx::dispatch::PassProgress) -> String {
    let items = match p.items_done {
        // A real GPU takes every item in one pass.
        u32::MAX => "all work items done".to_string(),
        n => format!("{n} work items done"),
    };
    if p.redone {
        format!(
            "pass {} too heavy for lavapipe, redone with fewer work items ({items})",
            p.passes
        )
    } else {
        format!("pass {}, {items}", p.passes)
    }
}

/// The spinner's message after a pass: the method's words (`approximating with …`) and
/// [`pass_text`].
fn pass_message(current: &str, p: approx::dispatch::PassProgress) -> String {
    let base = current.split(": pass ").next().unwrap_or(current);
    format!("{base}: {}", pass_text(p))
}

/// How often a progress line is printed off a terminal.
const PROGRESS_EVERY: Duration = Duration::from_secs(10);

/// Off a terminal (a log, a batch job), long GPU work says where it stands: a line on stderr
/// after the first pass that ends [`PROGRESS_EVERY`] or more after the last line (or the
/// start), as a sweep prints `[k/N]` per run. Work shorter than that prints none.
#[derive(Debug, Default)]
struct ProgressLines {
    /// Time since the start at the last line.
    last: Duration,
}

impl ProgressLines {
    /// The line to print after a pass that ended `elapsed` after the start, if one is due.
    fn after_pass(
        &mut self,
        elapsed: Duration,
        p: approx::dispatch::PassProgress,
    ) -> Option<String> {
        if elapsed < self.last + PROGRESS_EVERY {
            return None;
        }
        self.last = elapsed;
        Some(format!(
            "approx: {:.0} s, {}",
            elapsed.as_secs_f64(),
            pass_text(p)
        ))
    }
}

/// `v` with three significant digits: `362`, `4.12`, `0.000412` (a fixed number of decimals
/// printed `0.000` for the figures of small or slow runs).
fn three_digits(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return format!("{v}");
    }
    let decimals = (2 - v.log10().floor() as i32).clamp(0, 12) as usize;
    format!("{v:.decimals$}")
}

/// A rate with three significant digits and an SI prefix: `181 pixels/s`, `2.41 Mpixels/s`
/// (a fixed `Mpixels/s` printed `0.000` for lavapipe's few hundred pixels a second).
fn rate(per_second: f64, unit: &str) -> String {
    let (value, prefix) = [(1e9, "G"), (1e6, "M"), (1e3, "k")]
        .into_iter()
        .find(|(scale, _)| per_second >= *scale)
        .map_or((per_second, ""), |(scale, p)| (per_second / scale, p));
    format!("{} {prefix}{unit}", three_digits(value))
}

/// Loads the scene, runs the approximation (docs/design.md §4), writes the image and prints the
/// one-line summary with the adapter and the GPU time (docs/design.md §7).
pub fn run(args: ApproxArgs) -> anyhow::Result<Outcome> {
    if args.list_methods {
        super::print_stdout(&methods::markdown_table())?;
        return Ok(Outcome::Success);
    }
    let (Some(scene_path), Some(output)) = (&args.scene, &args.output) else {
        anyhow::bail!("pgt approx needs a SCENE and -o OUTPUT (or --list-methods)");
    };
    let options = SceneLoadOptions {
        size: args.size,
        mode: args.mode,
        model: args.model,
        tol: None,
        format: args.format,
    };
    if let Some(range) = args.frames {
        return approx_frames(&args, scene_path, output, &options, range);
    }
    check_outputs(&[Output::new("--output", output, OutputKind::Image)])?;
    let scene = super::load_scene_for(scene_path, &options, args.exposure)?;
    let params = args.params()?;
    let spinner = super::stderr_is_terminal().then(|| approx_spinner(&params));
    let mut lines = ProgressLines::default();
    let start = Instant::now();
    let out = approx::render_approx_with_progress(&scene, &params, &mut |p| match &spinner {
        Some(s) => s.set_message(pass_message(&s.message(), p)),
        None => {
            if let Some(line) = lines.after_pass(start.elapsed(), p) {
                eprintln!("{line}");
            }
        }
    });
    if let Some(s) = &spinner {
        s.finish_and_clear();
    }
    let out = out?;
    write_image(output, &out.image, &[], args.exposure)?;
    for w in out.warnings() {
        eprintln!("warning: {w}");
    }
    let passes = if out.passes == 1 {
        "1 pass".to_string()
    } else {
        format!(
            "{} passes, {} s a pass",
            out.passes,
            three_digits(out.gpu_seconds / out.passes as f64)
        )
    };
    let pixels = scene.camera.width as f64 * scene.camera.height as f64;
    eprintln!(
        "approximated {} ({}x{}, {}, {} lights) with {}{} on {}: {} s GPU ({}, {passes}), {}",
        output.display(),
        scene.camera.width,
        scene.camera.height,
        scene.particles_text(),
        scene.lights.len(),
        out.method.name(),
        describe_params(&out.method, &out.params),
        out.adapter_name,
        three_digits(out.gpu_seconds),
        match out.timing {
            Timing::Timestamps => "timestamp queries",
            Timing::Wall => "wall time",
        },
        rate(pixels / out.gpu_seconds.max(1e-9), "pixels/s")
    );
    Ok(Outcome::Success)
}

/// `--frames`: every frame of the range (or of this task's part) with one device and one
/// compiled pipeline, with a progress bar over the frames and a summary line.
fn approx_frames(
    args: &ApproxArgs,
    scene_path: &std::path::Path,
    output: &std::path::Path,
    options: &SceneLoadOptions,
    range: pgt::sequence::FrameRange,
) -> anyhow::Result<Outcome> {
    let (frames, list, pattern) =
        super::frames::open_sequence(scene_path, options, args.exposure, range, args.part, output)?;
    let params = args.params()?;
    let progress = super::frames::FrameProgress::new("approx", list.len());
    let out = pgt::sequence::render::approx_frames(
        &frames,
        &list,
        &pattern,
        &params,
        args.exposure,
        &progress,
    );
    progress.finish();
    let out = out?;
    let (rendered, skipped) = out.summary.counts();
    let seconds: f64 = out
        .summary
        .frames
        .iter()
        .map(|f| match f {
            pgt::sequence::render::FrameDone::Rendered { seconds, .. } => *seconds,
            _ => 0.0,
        })
        .sum();
    eprintln!(
        "approximated {rendered} frame(s) of {} into {} with {}{} on {}{}: {} s GPU",
        scene_path.display(),
        output.display(),
        out.method.name(),
        describe_params(&out.method, &out.params),
        out.adapter_name,
        if skipped > 0 {
            format!(", skipped {skipped} already rendered")
        } else {
            String::new()
        },
        three_digits(seconds),
    );
    if out.hit_overflow_pixels > 0 {
        eprintln!(
            "warning: {} pixels over the frames crossed more than {} particles; their farthest particles were dropped",
            out.hit_overflow_pixels,
            approx::MAX_HITS
        );
    }
    if out.loop_limited_pixels > 0 {
        eprintln!(
            "warning: {} pixels over the frames reached lavapipe's limit of {} loop iterations per pixel; these pixels are wrong (use fewer samples or a real GPU)",
            out.loop_limited_pixels,
            approx::contract::LOOP_LIMIT
        );
    }
    Ok(Outcome::Success)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgt::approx::dispatch::PassProgress;

    fn pass(passes: u32) -> PassProgress {
        PassProgress {
            passes,
            items_done: 8 * passes,
            redone: false,
        }
    }

    #[test]
    fn progress_lines_come_every_ten_seconds_of_passes() {
        let mut lines = ProgressLines::default();
        let s = Duration::from_secs_f64;
        assert_eq!(lines.after_pass(s(0.7), pass(1)), None);
        assert_eq!(lines.after_pass(s(9.9), pass(14)), None);
        assert_eq!(
            lines.after_pass(s(10.4), pass(15)).as_deref(),
            Some("approx: 10 s, pass 15, 120 work items done")
        );
        assert_eq!(lines.after_pass(s(19.0), pass(27)), None);
        let line = lines.after_pass(s(31.0), pass(44)).unwrap();
        assert!(line.starts_with("approx: 31 s, pass 44"), "{line}");
    }

    #[test]
    fn rates_keep_three_digits() {
        assert_eq!(rate(181.04, "pixels/s"), "181 pixels/s");
        assert_eq!(rate(1706.7, "pixels/s"), "1.71 kpixels/s");
        assert_eq!(rate(2.414e6, "pixels/s"), "2.41 Mpixels/s");
        assert_eq!(rate(45.25e6, "pixels/s"), "45.2 Mpixels/s");
        assert_eq!(rate(0.5, "pixels/s"), "0.500 pixels/s");
        assert_eq!(three_digits(362.14), "362");
        assert_eq!(three_digits(0.000_412_3), "0.000412");
        assert_eq!(three_digits(4.0), "4.00");
    }
}

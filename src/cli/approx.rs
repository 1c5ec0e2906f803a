//! `pgt approx SCENE --method thesis --samples 100 --n-exact 5 -o OUT` (DESIGN.md §4, §7): the
//! GPU approximation, or a user's method with `--shader FILE.wgsl`.

use super::Outcome;
use crate::approx::{self, ApproxParams, Method, Timing, N_EXACT_ALL};
use crate::image_io::write_image;
use crate::scene::{OpticalModel, RenderMode, SceneLoadOptions};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

/// The built-in methods by name (`--method`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MethodName {
    /// Per-particle compositing with the emission model's closed form.
    Emission,
    /// Opaque spheres: first hit, Lambert + Blinn–Phong, hard shadows.
    Opaque,
    /// The thesis's scheme (chapter 5): lit model for the first --n-exact particles.
    Thesis,
}

/// `pgt approx` (DESIGN.md §7).
#[derive(Debug, Args)]
pub struct ApproxArgs {
    /// Scene file (.toml) or a bare particle file.
    pub scene: PathBuf,
    /// Output image; the format follows the extension (.exr or .png).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Approximation method [default: opaque for opaque scenes, thesis otherwise].
    #[arg(long, value_enum, conflicts_with = "shader")]
    pub method: Option<MethodName>,
    /// A WGSL file defining `fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32>`
    /// (docs/user-shaders.md).
    #[arg(long)]
    pub shader: Option<PathBuf>,
    /// thesis: midpoint-rule samples per particle chord.
    #[arg(long, default_value_t = 100)]
    pub samples: u32,
    /// thesis: particles from the eye that get the lit model (a number or "all").
    #[arg(long, default_value = "all", value_parser = parse_n_exact)]
    pub n_exact: u32,
    /// Use the adapter whose name contains this (case-insensitive).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Image size WIDTHxHEIGHT, overriding the scene.
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<(u32, u32)>,
    #[arg(long, value_enum)]
    pub mode: Option<RenderMode>,
    #[arg(long, value_enum)]
    pub model: Option<OpticalModel>,
    /// PNG exposure in stops (2^exposure scales the linear image before encoding).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
}

fn parse_n_exact(s: &str) -> Result<u32, String> {
    if s.eq_ignore_ascii_case("all") {
        return Ok(N_EXACT_ALL);
    }
    s.parse::<u32>()
        .map_err(|_| format!("expected a non-negative integer or 'all', got '{s}'"))
}

/// Loads the scene, runs the approximation (DESIGN.md §4), writes the image and prints the
/// one-line summary with the adapter and the GPU time (DESIGN.md §7).
pub fn run(args: ApproxArgs) -> anyhow::Result<Outcome> {
    let options = SceneLoadOptions {
        size: args.size,
        mode: args.mode,
        model: args.model,
        tol: None,
    };
    let scene = super::load_scene_for(&args.scene, &options, &args.output, args.exposure)?;
    let method = match (&args.shader, args.method) {
        (Some(path), _) => Some(Method::User(path.clone())),
        (None, Some(MethodName::Emission)) => Some(Method::Emission),
        (None, Some(MethodName::Opaque)) => Some(Method::Opaque),
        (None, Some(MethodName::Thesis)) => Some(Method::Thesis),
        (None, None) => None,
    };
    let params = ApproxParams {
        method,
        samples: args.samples,
        n_exact: args.n_exact,
        adapter: args.adapter.clone(),
    };
    let out = approx::render_approx(&scene, &params)?;
    write_image(&args.output, &out.image, &[], args.exposure)?;
    if out.hit_overflow_pixels > 0 {
        eprintln!(
            "warning: {} pixels crossed more than {} particles; their farthest particles were dropped",
            out.hit_overflow_pixels,
            approx::MAX_HITS
        );
    }
    if out.loop_limited_pixels > 0 {
        eprintln!(
            "warning: {} pixels reached lavapipe's limit of 65535 loop iterations per pixel; lavapipe cuts such loops short, so these pixels are wrong (use fewer samples or a real GPU)",
            out.loop_limited_pixels
        );
    }
    let n_exact = if args.n_exact == N_EXACT_ALL {
        "all".to_string()
    } else {
        args.n_exact.to_string()
    };
    // Only the thesis method (and user shaders, which may read them) use the parameters.
    let parameters = match out.method {
        Method::Thesis | Method::User(_) => {
            format!(" (samples {}, n_exact {n_exact})", args.samples)
        }
        Method::Emission | Method::Opaque => String::new(),
    };
    let passes = if out.passes == 1 {
        "1 pass".to_string()
    } else {
        format!("{} passes", out.passes)
    };
    let pixels = scene.camera.width as f64 * scene.camera.height as f64;
    eprintln!(
        "approximated {} ({}x{}, {} spheres, {} lights) with {}{parameters} on {}: {:.3} s GPU ({}, {passes}), {:.3} Mpixels/s",
        args.output.display(),
        scene.camera.width,
        scene.camera.height,
        scene.particles.len(),
        scene.lights.len(),
        out.method.name(),
        out.adapter_name,
        out.gpu_seconds,
        match out.timing {
            Timing::Timestamps => "timestamp queries",
            Timing::Wall => "wall time",
        },
        pixels / out.gpu_seconds.max(1e-9) / 1e6
    );
    Ok(Outcome::Success)
}

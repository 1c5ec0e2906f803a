//! The `pgt` command line (docs/design.md §7): one file per subcommand. Every subcommand returns an
//! [`Outcome`]; `main` maps it and errors to exit codes 0 / 1 / 2.

pub mod approx;
pub mod bench;
pub mod camera;
pub mod compare;
pub mod compare_frames;
pub mod export;
pub mod frames;
pub mod gen;
pub mod info;
pub mod merge;
pub mod output;
pub mod render;
pub mod sweep;

use clap::{Parser, Subcommand};
use pgt::formats::{particle_formats, Format};

/// What a subcommand ended with, when it did not fail.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Success, or a gate that passed: exit 0.
    Success,
    /// A gate that failed: exit 1.
    GateFailed,
}

#[derive(Debug, Parser)]
#[command(
    name = "pgt",
    version,
    about = "Particle ground truth: exact renderings of sphere particle scenes, GPU approximations, and their difference"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render the exact reference image of a scene (a scene TOML or a bare particle file).
    Render(render::RenderArgs),
    /// Render a scene with a GPU approximation (a built-in method or a user's WGSL shader).
    Approx(approx::ApproxArgs),
    /// Compare an approximation with the reference: metrics, maps, report, gates.
    Compare(compare::CompareArgs),
    /// Render the reference once and an approximation per parameter set; report with plots.
    Sweep(sweep::SweepArgs),
    /// Particle count, bounds, radius range and colours of a particle, trajectory or scene file,
    /// and its frames (count, atoms per frame, time step) where it has them.
    Info(info::InfoArgs),
    /// Generate synthetic data sets (`pgt gen random`).
    Gen(gen::GenArgs),
    /// The speed of the reference on standard workloads, as one table of ratios.
    Bench(bench::BenchArgs),
    /// Join the parts of a cluster render (`pgt render --part I/N`) into the whole image.
    Merge(merge::MergeArgs),
    /// The camera as view and projection matrices per graphics API (OpenGL, Vulkan, WebGPU, Direct3D).
    Camera(camera::CameraArgs),
    /// Write the resolved particles (centre, radius, colour, σ, Θmax) as CSV or PLY.
    Export(export::ExportArgs),
}

/// Parses the process's arguments ([`command`]).
pub fn try_parse() -> Result<Cli, clap::Error> {
    use clap::FromArgMatches;
    Cli::from_arg_matches(&command().try_get_matches()?)
}

/// The command line as clap sees it, with every subcommand's usage line fixed to the one its
/// `--help` shows: in an error, clap's own usage line lists the options given as if they were
/// required (`pgt render --output <OUTPUT> --size <SIZE> <SCENE>`).
pub fn command() -> clap::Command {
    let mut cmd = <Cli as clap::CommandFactory>::command();
    cmd.build();
    help_usage_in_errors(cmd)
}

fn help_usage_in_errors(mut cmd: clap::Command) -> clap::Command {
    let names: Vec<String> = cmd
        .get_subcommands()
        .map(|s| s.get_name().to_string())
        .collect();
    for name in names {
        cmd = cmd.mut_subcommand(name, |mut sub| {
            let usage = sub.render_usage().to_string();
            let usage = usage.strip_prefix("Usage: ").unwrap_or(&usage).to_string();
            help_usage_in_errors(sub.override_usage(usage))
        });
    }
    cmd
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<Outcome> {
    match cli.command {
        Command::Render(args) => render::run(args),
        Command::Approx(args) => approx::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Sweep(args) => sweep::run(args),
        Command::Info(args) => info::run(args),
        Command::Gen(args) => gen::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Merge(args) => merge::run(args),
        Command::Camera(args) => camera::run(args),
        Command::Export(args) => export::run(args),
    }
}

/// `--format NAME`: the format of a bare particle file whatever its extension, a name of the
/// table of formats that reads particles (`pgt::formats::particle_formats`; `--help` lists
/// them).
pub fn format_parser() -> impl clap::builder::TypedValueParser<Value = &'static Format> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(particle_formats().map(|f| f.name))
        .try_map(|name| Format::named(&name).ok_or_else(|| format!("unknown format '{name}'")))
}

/// The flags of a bare particle file's scene (docs/design.md §1, "A bare particle file"): what
/// a scene file says with `density` in `[defaults]`, `background` in `[render]` and an
/// include's `sh`.
#[derive(Debug, Clone, clap::Args)]
pub struct BareFileArgs {
    /// The particles' density profile: constant or gaussian [default: gaussian for a PLY of 3D
    /// Gaussian splatting, constant otherwise]. A scene file sets `density` in [defaults] or on
    /// an include.
    #[arg(long, value_parser = parse_density, value_name = "PROFILE")]
    pub density: Option<pgt::optics::Profile>,
    /// Background radiance L_bg, linear RGB: R,G,B or one value for grey [default: black for a
    /// PLY of 3D Gaussian splatting, the scene's otherwise]. Overrides a scene's [render].
    #[arg(long, value_parser = parse_background, value_name = "R,G,B")]
    pub background: Option<[f64; 3]>,
    /// The colour of a PLY of 3D Gaussian splatting: view (its SH seen from the eye) or dc
    /// (the degree-0 term) [default: view]. A scene file sets `sh` on the include.
    #[arg(long, value_parser = parse_sh, value_name = "view|dc")]
    pub sh: Option<pgt::formats::ShColor>,
}

impl BareFileArgs {
    /// The options with these flags set.
    pub fn apply(&self, options: pgt::scene::SceneLoadOptions) -> pgt::scene::SceneLoadOptions {
        pgt::scene::SceneLoadOptions {
            density: self.density,
            background: self.background,
            sh: self.sh,
            ..options
        }
    }
}

fn parse_density(s: &str) -> Result<pgt::optics::Profile, String> {
    match s {
        "constant" => Ok(pgt::optics::Profile::Constant),
        "gaussian" => Ok(pgt::optics::Profile::Gaussian),
        _ => Err(format!("expected constant or gaussian, got '{s}'")),
    }
}

fn parse_sh(s: &str) -> Result<pgt::formats::ShColor, String> {
    match s {
        "view" => Ok(pgt::formats::ShColor::View),
        "dc" => Ok(pgt::formats::ShColor::Dc),
        _ => Err(format!("expected view or dc, got '{s}'")),
    }
}

/// `R,G,B` or one value for grey, each finite and ≥ 0.
fn parse_background(s: &str) -> Result<[f64; 3], String> {
    let values: Vec<f64> = s
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected R,G,B (numbers ≥ 0) or one number, got '{s}'"))?;
    let rgb = match values[..] {
        [g] => [g, g, g],
        [r, g, b] => [r, g, b],
        _ => return Err(format!("expected R,G,B or one number, got '{s}'")),
    };
    if !rgb.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(format!("expected finite numbers ≥ 0, got '{s}'"));
    }
    Ok(rgb)
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got '{s}'"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("expected WIDTHxHEIGHT with positive integers, got '{s}'"))
    };
    let (w, h) = (parse(w)?, parse(h)?);
    pgt::scene::check_image_size(w as i64, h as i64)
}

/// What `render` and `approx` do before any work, once their outputs are checked
/// ([`output::check_outputs`]): check the exposure (so a typo fails at once, not after a long
/// render), load the scene, print its warnings.
pub fn load_scene_for(
    scene: &std::path::Path,
    options: &pgt::scene::SceneLoadOptions,
    exposure: f32,
) -> anyhow::Result<pgt::scene::Scene> {
    if !exposure.is_finite() {
        anyhow::bail!("--exposure must be a finite number");
    }
    let scene = pgt::scene::Scene::load(scene, options)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// Writes `text` to standard output. A closed pipe (`pgt info F --json | head -1`) ends the
/// output quietly, as Unix tools do, and the command's outcome stands; any other failure to
/// write is an error (exit 2).
pub fn print_stdout(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => r.map_err(|e| anyhow::anyhow!("writing to standard output: {e}")),
    }
}

/// Whether stderr is a terminal (progress bars only then).
pub fn stderr_is_terminal() -> bool {
    use std::io::IsTerminal;
    std::io::stderr().is_terminal()
}

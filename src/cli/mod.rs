//! The `pgt` command line (docs/design.md §7): one file per subcommand. Every subcommand returns an
//! [`Outcome`]; `main` maps it and errors to exit codes 0 / 1 / 2.

pub mod approx;
pub mod bench;
pub mod bench_frames;
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

use crate::formats::{particle_formats, Format};
use clap::{Parser, Subcommand};

/// What a subcommand ended with, when it did not fail.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Success, or a gate that passed: exit 0.
    Success,
    /// A gate that failed: exit 1.
    GateFailed,
}

/// The one-line message of a failed command: the error and its causes joined by ": ", leaving
/// out a cause whose text the line already ends with. pgt's own errors put their cause into
/// their message *and* report it as `source()` (so that a library user can walk the chain);
/// printing the chain naively would say "stream did not contain valid UTF-8" twice.
pub fn error_message(e: &anyhow::Error) -> String {
    let mut line = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !line.ends_with(&cause) {
            line.push_str(": ");
            line.push_str(&cause);
        }
    }
    line
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
    /// Particle count, bounds, radius range and colours of a particle or scene file.
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
/// table of formats that reads particles (`crate::formats::particle_formats`; `--help` lists
/// them).
pub fn format_parser() -> impl clap::builder::TypedValueParser<Value = &'static Format> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(particle_formats().map(|f| f.name))
        .try_map(|name| Format::named(&name).ok_or_else(|| format!("unknown format '{name}'")))
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
    crate::scene::check_image_size(w as i64, h as i64)
}

/// What `render` and `approx` do before any work, once their outputs are checked
/// ([`output::check_outputs`]): check the exposure (so a typo fails at once, not after a long
/// render), load the scene, print its warnings.
pub fn load_scene_for(
    scene: &std::path::Path,
    options: &crate::scene::SceneLoadOptions,
    exposure: f32,
) -> anyhow::Result<crate::scene::Scene> {
    if !exposure.is_finite() {
        anyhow::bail!("--exposure must be a finite number");
    }
    let scene = crate::scene::Scene::load(scene, options)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::PgtError;

    fn utf8_error() -> std::io::Error {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    }

    #[test]
    fn a_cause_already_in_the_message_is_said_once() {
        let e = anyhow::Error::from(PgtError::io("gate.toml", utf8_error()));
        assert_eq!(
            error_message(&e),
            "gate.toml: stream did not contain valid UTF-8"
        );
        let e = anyhow::Error::from(PgtError::io("a.toml", utf8_error()).context("run 3"));
        assert_eq!(
            error_message(&e),
            "run 3: a.toml: stream did not contain valid UTF-8"
        );
    }

    #[test]
    fn a_cause_not_in_the_message_is_kept() {
        let e = anyhow::Error::from(utf8_error()).context("reading the scene");
        assert_eq!(
            error_message(&e),
            "reading the scene: stream did not contain valid UTF-8"
        );
    }
}

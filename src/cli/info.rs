//! `pgt info FILE [--json]` (docs/design.md §7): particle count, bounds, radius range, colours and
//! warnings of a particle file (any format pgt reads) or of a scene file (`.toml`, loaded and
//! validated with [`pgt::scene::Scene::load`], so its includes count too). The summary is the
//! library's ([`pgt::scene::summary::info_of`]); this file parses and prints.

use super::Outcome;
use clap::Args;
use pgt::formats::summary::Info;
use pgt::formats::{particle_formats, FORMATS};
use pgt::scene::summary::info_of;
use std::path::PathBuf;

/// Options of `pgt info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// A particle file, an MD trajectory or a scene file (.toml).
    #[arg(long_help = file_help())]
    pub file: PathBuf,
    /// Print JSON on stdout instead of text.
    #[arg(long)]
    pub json: bool,
    /// The format of a bare particle file, whatever its extension (a scene file names the
    /// format of each include with `format = "…"`).
    #[arg(long, value_name = "NAME", value_parser = super::format_parser())]
    pub format: Option<&'static pgt::formats::Format>,
}

/// One line of the help's table of formats: the name, the extensions, the description.
fn format_line(name: &str, extensions: &[&str], description: &str) -> String {
    let ext: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
    format!("\n  {name:<6} {:<13} {description}", ext.join(" "))
}

/// `pgt info --help` for FILE, from the table of formats.
fn file_help() -> String {
    let mut help = String::from(
        "A particle file, an MD trajectory or a scene file (.toml). Particle formats (the name for \
         `--format` and for `format` in an [[include]], the extensions, the format):",
    );
    for f in particle_formats() {
        help.push_str(&format_line(f.name, f.extensions, f.description));
    }
    help.push_str(
        "\nMD trajectories (alone, or in a scene as `trajectory = \"…\"` beside a topology: PDB, \
         mmCIF, GRO or PSF):",
    );
    for f in FORMATS.iter().filter(|f| f.trajectory.is_some()) {
        help.push_str(&format_line(f.name, f.extensions, f.description));
    }
    help.push_str(
        "\nA file or scene with frames (PDB models, MMPLD frames, XYZ frames, a trajectory, a \
         sequence) also reports its frame count, the atoms per frame and the time step in ps \
         where the file has one; a trajectory alone is summarised as its atoms at frame 0, as \
         points.",
    );
    help
}

/// Runs `pgt info`.
pub fn run(args: InfoArgs) -> anyhow::Result<Outcome> {
    let info = info_of(&args.file, args.format)?;
    let text = if args.json {
        serde_json::to_string_pretty(&info)? + "\n"
    } else {
        text_of(&info)
    };
    super::print_stdout(&text)?;
    Ok(Outcome::Success)
}

/// The text form of `pgt info`.
fn text_of(info: &Info) -> String {
    use std::fmt::Write as _;
    let mut t = String::new();
    // Writing into a String cannot fail.
    let _ = writeln!(t, "{} ({})", info.file, info.format);
    let _ = writeln!(t, "particles: {}", info.particles);
    if let (Some(b), Some(r)) = (&info.bounds, &info.radius) {
        let v = |a: [f64; 3]| format!("[{:.4}, {:.4}, {:.4}]", a[0], a[1], a[2]);
        let _ = writeln!(t, "bounds:    {} .. {}", v(b.min), v(b.max));
        let _ = writeln!(
            t,
            "radius:    {:.4} .. {:.4} (mean {:.4})",
            r.min, r.max, r.mean
        );
    }
    let c = &info.colors;
    let _ = writeln!(
        t,
        "colours:   {} distinct, {} without a colour (scene default)",
        c.distinct, c.uncolored
    );
    for cc in &c.most_common {
        let _ = writeln!(
            t,
            "           linear RGB [{:.4}, {:.4}, {:.4}] × {}",
            cc.rgb[0], cc.rgb[1], cc.rgb[2], cc.count
        );
    }
    for (k, v) in &info.details {
        let _ = writeln!(t, "{:<10} {v}", format!("{k}:"));
    }
    if let Some(f) = &info.frames {
        let atoms = f
            .atoms_per_frame
            .map_or("atoms per frame vary or unknown".to_string(), |n| {
                format!("{n} atoms per frame")
            });
        let step = f.time_step_ps.map_or("no time step".to_string(), |dt| {
            format!("time step {dt} ps")
        });
        let _ = writeln!(t, "frames:    {} ({atoms}, {step})", f.count);
    }
    for w in &info.warnings {
        let _ = writeln!(t, "warning:   {w}");
    }
    t
}

//! `pgt info FILE [--json]` (docs/design.md §7): particle count, bounds, radius range, colours and
//! warnings of a particle file (any format pgt reads) or of a scene file (`.toml`, loaded and
//! validated with [`Scene::load`], so its includes count too).

use super::Outcome;
use crate::formats::frames::{open_frames, FrameInfo};
use crate::formats::topology::trajectory_summary;
use crate::formats::{format_of, load_bytes, particle_formats, read_input, Format, IncludeSpec};
use crate::scene::{SceneFrames, SceneLoadOptions};
use clap::Args;
use glam::DVec3;
use std::collections::HashMap;
use std::path::PathBuf;

/// Options of `pgt info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// A particle file or a scene file (.toml).
    #[arg(long_help = file_help())]
    pub file: PathBuf,
    /// Print JSON on stdout instead of text.
    #[arg(long)]
    pub json: bool,
    /// The format of a bare particle file, whatever its extension (a scene file names the
    /// format of each include with `format = "…"`).
    #[arg(long, value_name = "NAME", value_parser = super::format_parser())]
    pub format: Option<&'static crate::formats::Format>,
}

/// `pgt info --help` for FILE, from the table of formats.
fn file_help() -> String {
    let mut help = String::from(
        "A particle file or a scene file (.toml). Particle formats (the name for `--format` and \
         for `format` in an [[include]], the extensions, the format):",
    );
    for f in particle_formats() {
        let ext: Vec<String> = f.extensions.iter().map(|e| format!(".{e}")).collect();
        help.push_str(&format!(
            "\n  {:<6} {:<13} {}",
            f.name,
            ext.join(" "),
            f.description
        ));
    }
    help
}

/// How many of the most common colours the summary lists.
const TOP_COLORS: usize = 8;

/// What `pgt info` reports (also the JSON object it prints).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Info {
    /// The file as given.
    pub file: String,
    /// `scene` or the particle format.
    pub format: String,
    /// Number of particles.
    pub particles: usize,
    /// Axis-aligned bounds of the spheres (centre ± radius); absent when there are none.
    pub bounds: Option<Bounds>,
    /// Radius range and mean; absent when there are no particles.
    pub radius: Option<RadiusRange>,
    /// Colour summary.
    pub colors: ColorSummary,
    /// Warnings of the loaders.
    pub warnings: Vec<String>,
    /// Facts of the format: PDB/mmCIF `models` and `chains` (atom records per chain in the
    /// first model, before alternate locations are resolved); MMPLD `version` and `frames`.
    pub details: serde_json::Map<String, serde_json::Value>,
    /// Frames (docs/design.md §10): their count, the atoms per frame where every frame has as
    /// many and the time step in ps where the file says; absent for a file or scene of one
    /// frame. For a scene, the frames it plays; for a trajectory (`.dcd`, `.xtc`) alone, its
    /// own (the particles are then its atoms at frame 0, as points).
    pub frames: Option<FrameInfo>,
}

/// An axis-aligned box.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Bounds {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

/// Smallest, largest and mean radius.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RadiusRange {
    /// Smallest radius.
    pub min: f64,
    /// Largest radius.
    pub max: f64,
    /// Mean radius.
    pub mean: f64,
}

/// The particles' colours.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ColorSummary {
    /// Distinct colours among the particles that have one.
    pub distinct: usize,
    /// Particles without a colour of their own (they take the scene's default).
    pub uncolored: usize,
    /// The most common colours, linear RGB, with their counts.
    pub most_common: Vec<ColorCount>,
}

/// One colour and how many particles have it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ColorCount {
    /// Linear RGB.
    pub rgb: [f64; 3],
    /// Particles with this colour.
    pub count: usize,
}

/// Summarises spheres given as (centre, radius, colour).
pub fn summarize(
    file: String,
    format: String,
    spheres: impl Iterator<Item = (DVec3, f64, Option<DVec3>)>,
    warnings: Vec<String>,
) -> Info {
    let mut n = 0usize;
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut rmin, mut rmax, mut rsum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
    let mut uncolored = 0usize;
    let mut counts: HashMap<[u64; 3], usize> = HashMap::new();
    for (c, r, col) in spheres {
        n += 1;
        lo = lo.min(c - DVec3::splat(r));
        hi = hi.max(c + DVec3::splat(r));
        rmin = rmin.min(r);
        rmax = rmax.max(r);
        rsum += r;
        match col {
            Some(c) => {
                *counts
                    .entry([c.x.to_bits(), c.y.to_bits(), c.z.to_bits()])
                    .or_insert(0) += 1
            }
            None => uncolored += 1,
        }
    }
    let mut top: Vec<([u64; 3], usize)> = counts.iter().map(|(k, v)| (*k, *v)).collect();
    top.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    Info {
        file,
        format,
        particles: n,
        bounds: (n > 0).then(|| Bounds {
            min: lo.to_array(),
            max: hi.to_array(),
        }),
        radius: (n > 0).then(|| RadiusRange {
            min: rmin,
            max: rmax,
            mean: rsum / n as f64,
        }),
        colors: ColorSummary {
            distinct: counts.len(),
            uncolored,
            most_common: top
                .into_iter()
                .take(TOP_COLORS)
                .map(|(k, count)| ColorCount {
                    rgb: k.map(f64::from_bits),
                    count,
                })
                .collect(),
        },
        warnings,
        details: serde_json::Map::new(),
        frames: None,
    }
}

/// Loads a file and summarises it: a scene (`.toml`) through [`Scene::load`], a particle file
/// through the one loading path of [`crate::formats`] (so an empty file is refused here too),
/// with the format's name and [`Format::details`] from the table of formats. `format` is
/// `--format`, for a particle file whatever its extension.
pub fn info_of(path: &std::path::Path, format: Option<&'static Format>) -> crate::Result<Info> {
    let is_toml = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    let name = path.display().to_string();
    if is_toml {
        let options = SceneLoadOptions {
            format,
            ..SceneLoadOptions::default()
        };
        let frames = SceneFrames::load(path, &options)?;
        let scene = frames.first();
        let it = scene
            .particles
            .iter()
            .map(|p| (p.center, p.radius, Some(p.color)));
        let mut info = summarize(name, "scene".into(), it, scene.warnings.clone());
        info.frames = frames.frame_info();
        return Ok(info);
    }
    if let Some(format) = Format::trajectory_of(path) {
        let (frames, first, warnings) = trajectory_summary(path)?;
        let mut info = summarize(
            name,
            format.name.to_string(),
            first.iter().map(|&c| (c, 0.0, None)),
            warnings,
        );
        info.radius = None;
        info.frames = Some(frames);
        return Ok(info);
    }
    let spec = IncludeSpec {
        format,
        ..IncludeSpec::bare(path)
    };
    let format: &Format = format_of(&spec)?;
    let bytes = read_input(path)?;
    let loaded = load_bytes(&spec, format, &bytes)?;
    let it = loaded.records.iter().map(|r| (r.center, r.radius, r.color));
    let mut info = summarize(name, format.name.to_string(), it, loaded.warnings);
    if let Some(details) = format.details {
        info.details = details(path, &bytes)?;
    }
    if format.frames.is_some() {
        let frames = open_frames(&spec)?.info();
        info.frames = (frames.count > 1).then_some(frames);
    }
    Ok(info)
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
        println!("frames:    {} ({atoms}, {step})", f.count);
    }
    for w in &info.warnings {
        let _ = writeln!(t, "warning:   {w}");
    }
    t
}

//! `pgt gen random --count N --seed S [--box …] [--radius a..b] -o FILE` (docs/design.md §7): the
//! synthetic random set of [`pgt::formats::random`], written as CSV, atomically; `pgt gen
//! gaussians --count N --seed S -o FILE.ply`: Gaussians with trained-scene statistics
//! ([`pgt::formats::trained`]) as a 3DGS PLY.

use super::output::{check_outputs, Output, OutputKind};
use super::Outcome;
use clap::{Args, Subcommand};
use glam::DVec3;
use pgt::formats::random::{particles, write_csv, RandomSpec, THESIS_COUNT};
use pgt::formats::trained;
use pgt::image_io::write_atomically;
use std::io::Write as _;
use std::path::PathBuf;

/// Most particles `pgt gen random` writes (about 7.5 GB of CSV); a typo beyond it is refused
/// rather than filling the disk.
pub const MAX_COUNT: usize = 100_000_000;

/// `pgt gen …`: synthetic data sets.
#[derive(Debug, Args)]
pub struct GenArgs {
    /// Which set to generate.
    #[command(subcommand)]
    pub kind: GenKind,
}

/// The kinds of synthetic set.
#[derive(Debug, Subcommand)]
pub enum GenKind {
    /// Uniformly random spheres in a box (the thesis's random set: 73,642 particles).
    /// The random set of [`pgt::formats::random`].
    Random(RandomArgs),
    /// Gaussians with the statistics of trained 3D Gaussian splatting scenes (clustered centres,
    /// log-normal scales, flat shapes, sigmoid opacities), as a 3DGS PLY: read it with
    /// `density = "gaussian"`.
    Gaussians(GaussiansArgs),
}

/// Options of `pgt gen gaussians`.
#[derive(Debug, Args)]
pub struct GaussiansArgs {
    /// Number of Gaussians.
    #[arg(long, default_value_t = 100_000)]
    pub count: usize,
    /// Seed of the SplitMix64 generator (the same seed always gives the same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output PLY file (.ply).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Options of `pgt gen random`.
#[derive(Debug, Args)]
pub struct RandomArgs {
    /// Number of particles.
    #[arg(long, default_value_t = THESIS_COUNT)]
    pub count: usize,
    /// Seed of the SplitMix64 generator (the same seed always gives the same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Box of the centres: `S` (the cube [−S/2, S/2]³) or `x0,y0,z0,x1,y1,z1`.
    #[arg(long = "box", default_value = "200", allow_negative_numbers = true)]
    pub bbox: String,
    /// Radius range `a..b` (or one value), 0 < a ≤ b.
    #[arg(long, default_value = "0.5..2")]
    pub radius: String,
    /// Output CSV file (.csv).
    #[arg(short, long)]
    pub output: PathBuf,
}

fn parse_box(s: &str) -> anyhow::Result<(DVec3, DVec3)> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            anyhow::anyhow!("--box: expected a side length S or x0,y0,z0,x1,y1,z1, got '{s}'")
        })?;
    let (lo, hi) = match v.as_slice() {
        [side] => (DVec3::splat(-side / 2.0), DVec3::splat(side / 2.0)),
        [a, b, c, d, e, f] => (DVec3::new(*a, *b, *c), DVec3::new(*d, *e, *f)),
        _ => anyhow::bail!("--box: expected a side length S or x0,y0,z0,x1,y1,z1, got '{s}'"),
    };
    if !(lo.is_finite() && hi.is_finite() && hi.cmpgt(lo).all()) {
        anyhow::bail!("--box: the box must be finite with max > min on every axis, got '{s}'");
    }
    Ok((lo, hi))
}

fn parse_radius(s: &str) -> anyhow::Result<(f64, f64)> {
    let bad =
        || anyhow::anyhow!("--radius: expected a..b with 0 < a ≤ b (or one value > 0), got '{s}'");
    let (a, b) = match s.split_once("..") {
        Some((a, b)) => (
            a.trim().parse::<f64>().map_err(|_| bad())?,
            b.trim().parse::<f64>().map_err(|_| bad())?,
        ),
        None => {
            let r = s.trim().parse::<f64>().map_err(|_| bad())?;
            (r, r)
        }
    };
    if a.is_finite() && b.is_finite() && a > 0.0 && a <= b {
        Ok((a, b))
    } else {
        Err(bad())
    }
}

/// Runs `pgt gen`.
pub fn run(args: GenArgs) -> anyhow::Result<Outcome> {
    match args.kind {
        GenKind::Random(a) => {
            check_outputs(&[Output::new(
                "--output",
                &a.output,
                OutputKind::File(&["csv"]),
            )])?;
            let (box_min, box_max) = parse_box(&a.bbox)?;
            let spec = RandomSpec {
                count: a.count,
                seed: a.seed,
                box_min,
                box_max,
                radius: parse_radius(&a.radius)?,
            };
            if a.count > MAX_COUNT {
                anyhow::bail!("--count: at most {MAX_COUNT} particles, got {}", a.count);
            }
            write_atomically(&a.output, |w| write_csv(w, particles(&spec)))?;
            eprintln!(
                "wrote {} random particles to {}",
                a.count,
                a.output.display()
            );
            Ok(Outcome::Success)
        }
        GenKind::Gaussians(a) => {
            check_outputs(&[Output::new(
                "--output",
                &a.output,
                OutputKind::File(&["ply"]),
            )])?;
            if a.count > MAX_COUNT {
                anyhow::bail!("--count: at most {MAX_COUNT} Gaussians, got {}", a.count);
            }
            let bytes = trained::to_ply(&trained::generate(a.count, a.seed));
            write_atomically(&a.output, |w| w.write_all(&bytes))?;
            eprintln!(
                "wrote {} Gaussians with trained-scene statistics to {}",
                a.count,
                a.output.display()
            );
            Ok(Outcome::Success)
        }
    }
}

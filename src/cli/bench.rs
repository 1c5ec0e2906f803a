//! `pgt bench`: the speed of the exact reference on standard workloads, as one table of ratios
//! (docs/design.md §7). The workloads, the renders and the tables are the library's
//! ([`pgt::bench`]); this file parses the options and prints the tables.

use super::Outcome;
use clap::Args;
use pgt::bench::{BenchOptions, Workload};
use std::path::PathBuf;

/// Options of `pgt bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Image side in pixels (square images).
    #[arg(long, default_value_t = 512)]
    pub size: u32,
    /// Workloads to run, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["1uun", "random", "million"])]
    pub workloads: Vec<Workload>,
    /// Skip the Riemann-100 and emission baselines (only the adaptive renders).
    #[arg(long)]
    pub no_baselines: bool,
    /// Also render a tol 1e-9 truth and report the largest errors against it.
    #[arg(long)]
    pub accuracy: bool,
    /// Worker threads (default: rayon's, one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Renders of each renderer per workload, taken in turn (adaptive, Riemann-100, emission,
    /// then again): the table gives the fastest of each, so that the ratios compare runs that
    /// the machine's load slowed least.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeat: u32,
    /// Frames of the sequence workloads (`orbit`: 4; `xtc`: all 51).
    #[arg(long)]
    pub frames: Option<usize>,
    /// Folder with `pdb/1uun_opm_oriented.pdb` and `mmpld/cool_random.mmpld` (default `../shared/data`).
    #[arg(long, default_value = "../shared/data")]
    pub data: PathBuf,
}

pub fn run(args: BenchArgs) -> anyhow::Result<Outcome> {
    pgt::scene::check_image_size(args.size as i64, args.size as i64)
        .map_err(|e| anyhow::anyhow!("--size: {e}"))?;
    let options = BenchOptions {
        size: args.size,
        workloads: args.workloads,
        no_baselines: args.no_baselines,
        accuracy: args.accuracy,
        threads: args.threads,
        repeat: args.repeat,
        frames: args.frames,
        data: args.data,
    };
    pgt::bench::run(&options, &mut |table| super::print_stdout(table))?;
    Ok(Outcome::Success)
}

//! `pgt sweep EXPERIMENT.toml --report DIR` (DESIGN.md §5, §7): argument handling only. The
//! experiment format and the running are in [`crate::sweep`], the page, plots and JSON in
//! [`crate::report::sweep_page`].

use super::Outcome;
use crate::report::sweep_page::write_sweep_report;
use crate::sweep::{load_scene, run_sweep, Experiment, Progress, SweepOptions};
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The experiment file (TOML; the format is documented in `src/sweep/mod.rs`).
    pub experiment: PathBuf,
    /// Folder for the report, the images and the reference cache.
    #[arg(long)]
    pub report: PathBuf,
    /// Worker threads for the renders.
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Runs the experiment, printing a line for the reference and one per run on stderr, and
/// writes the report.
pub fn run(args: SweepArgs) -> anyhow::Result<Outcome> {
    let experiment = Experiment::load(&args.experiment)?;
    let scene = load_scene(&experiment)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let options = SweepOptions {
        dir: args.report.clone(),
        threads: args.threads,
        progress: super::stderr_is_terminal(),
    };
    let results = run_sweep(&experiment, &scene, &options, |p| match p {
        Progress::Reference(r) => eprintln!(
            "reference: {} ({})",
            r.cache_file.display(),
            match r.seconds {
                Some(s) => format!("rendered in {s:.2} s"),
                None => "from the cache".into(),
            }
        ),
        Progress::Run(r) => {
            let ssim = r
                .comparison
                .ssim_values()
                .map(|s| format!("{:.6}", s.mean))
                .unwrap_or("n/a".into());
            eprintln!(
                "{}: {:.2} s, SSIM {ssim}, RMSE {:.3e}",
                r.run.label(),
                r.seconds,
                r.comparison.error_values(|e| e.rmse).mean
            );
            for w in &r.warnings {
                eprintln!("warning: {}: {w}", r.run.label());
            }
        }
    })?;
    let page = write_sweep_report(&args.report, &results)?;
    println!(
        "sweep: {} runs, report {}",
        results.runs.len(),
        page.display()
    );
    Ok(Outcome::Success)
}

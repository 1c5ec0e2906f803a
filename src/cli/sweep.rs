//! `pgt sweep EXPERIMENT.toml --report DIR` (DESIGN.md §5, §7): argument handling only. The
//! experiment format and the running are in [`crate::sweep`], the page, plots and JSON in
//! [`crate::report::sweep_page`].

use super::Outcome;
use crate::image_io::write_folder_atomically;
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
    // The report is written into a temporary folder that takes the report's place at the end
    // (an interrupted sweep leaves no half-written report); the reference cache lives in the
    // report folder itself, so that it survives from one sweep to the next.
    let (runs, page) = write_folder_atomically(&args.report, |tmp| {
        let options = SweepOptions {
            dir: tmp.to_path_buf(),
            cache: args.report.join("cache"),
            threads: args.threads,
            progress: super::stderr_is_terminal(),
        };
        let results = run_sweep(&experiment, &scene, &options, print_progress)?;
        write_sweep_report(tmp, &results)?;
        Ok((results.runs.len(), args.report.join("index.html")))
    })?;
    println!("sweep: {runs} runs, report {}", page.display());
    Ok(Outcome::Success)
}

/// One line per finished render on stderr.
fn print_progress(p: Progress) {
    match p {
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
    }
}

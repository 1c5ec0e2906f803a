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

/// Runs the experiment and writes the report. On stderr: a line for the reference and one per
/// finished run, counted (`[2/6] thesis samples=4: …`); where stderr is a terminal, also a bar
/// of runs done out of the total with the run in progress (DESIGN.md §7 "Long work shows a
/// progress bar on stderr when it is a terminal").
pub fn run(args: SweepArgs) -> anyhow::Result<Outcome> {
    let experiment = Experiment::load(&args.experiment)?;
    let scene = load_scene(&experiment)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let terminal = super::stderr_is_terminal();
    let options = SweepOptions {
        dir: args.report.clone(),
        threads: args.threads,
        progress: terminal,
    };
    let mut lines = RunLines {
        bar: None,
        terminal,
        done: 0,
        total: experiment.runs.len(),
    };
    let results = run_sweep(&experiment, &scene, &options, |p| lines.show(p));
    if let Some(bar) = &lines.bar {
        bar.finish_and_clear();
    }
    let results = results?;
    let page = write_sweep_report(&args.report, &results)?;
    println!(
        "sweep: {} runs, report {}",
        results.runs.len(),
        page.display()
    );
    Ok(Outcome::Success)
}

/// The sweep's progress on stderr: the bar (a terminal only; made at the first run, after the
/// reference's own bar has finished) and the lines, printed above the bar.
struct RunLines {
    bar: Option<indicatif::ProgressBar>,
    terminal: bool,
    done: usize,
    total: usize,
}

impl RunLines {
    fn show(&mut self, p: Progress) {
        match p {
            Progress::Reference(r) => self.line(format!(
                "reference: {} ({})",
                r.cache_file.display(),
                match r.seconds {
                    Some(s) => format!("rendered in {s:.2} s"),
                    None => "from the cache".into(),
                }
            )),
            Progress::Start { index, total, run } => {
                self.total = total;
                if self.terminal {
                    let bar = self.bar.get_or_insert_with(|| run_bar(total));
                    bar.set_position(index as u64);
                    bar.set_message(run.label());
                }
            }
            Progress::Run(r) => {
                self.done += 1;
                let ssim = r
                    .comparison
                    .ssim_values()
                    .map(|s| format!("{:.6}", s.mean))
                    .unwrap_or("n/a".into());
                self.line(format!(
                    "[{}/{}] {}: {:.2} s, SSIM {ssim}, RMSE {:.3e}",
                    self.done,
                    self.total,
                    r.run.label(),
                    r.seconds,
                    r.comparison.error_values(|e| e.rmse).mean
                ));
                for w in &r.warnings {
                    self.line(format!("warning: {}: {w}", r.run.label()));
                }
                if let Some(bar) = &self.bar {
                    bar.set_position(self.done as u64);
                }
            }
        }
    }

    /// A line on stderr, above the bar where there is one.
    fn line(&self, text: String) {
        match &self.bar {
            Some(bar) => bar.println(text),
            None => eprintln!("{text}"),
        }
    }
}

/// The bar of runs: done/total, elapsed, and the run in progress.
fn run_bar(total: usize) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(total as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} runs; now: {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

//! `pgt sweep EXPERIMENT.toml --report DIR` (docs/design.md §5, §7): argument handling only. The
//! experiment format and the running are in [`pgt::sweep`], the page, plots and JSON in
//! [`pgt::report::sweep_page`].

use super::output::{check_outputs, Output, OutputKind};
use super::Outcome;
use clap::Args;
use pgt::report::sweep_page::{sweep_into_report, SweepWatch};
use pgt::sweep::{load_scene, Experiment, Progress};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The experiment file (TOML; the format is documented in `src/sweep/mod.rs`).
    pub experiment: PathBuf,
    /// Folder for the report, the images and the reference cache.
    #[arg(long)]
    pub report: PathBuf,
    /// Image size WIDTHxHEIGHT, overriding the experiment's `size` and the scene's.
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<(u32, u32)>,
    /// Worker threads for the renders.
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Runs the experiment and writes the report. On stderr: a line for the reference and one per
/// finished run, counted (`[2/6] thesis samples=4: …`); where stderr is a terminal, also a bar
/// of runs done out of the total with the run in progress (docs/design.md §7 "Long work shows a
/// progress bar on stderr when it is a terminal").
pub fn run(args: SweepArgs) -> anyhow::Result<Outcome> {
    check_outputs(&[Output::new("--report", &args.report, OutputKind::Folder)])?;
    let mut experiment = Experiment::load(&args.experiment)?;
    if let Some((w, h)) = args.size {
        experiment.size = Some([w, h]);
    }
    let scene = load_scene(&experiment)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let terminal = super::stderr_is_terminal();
    let mut lines = RunLines {
        bar: None,
        terminal,
        done: 0,
        total: experiment.runs.len(),
    };
    let outcome = sweep_into_report(
        &args.report,
        &experiment,
        &scene,
        args.threads,
        terminal,
        &mut lines,
    );
    let (runs, page) = outcome?;
    super::print_stdout(&format!("sweep: {runs} runs, report {}\n", page.display()))?;
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

impl SweepWatch for RunLines {
    fn show(&mut self, p: Progress) {
        match p {
            Progress::Reference(r) => {
                self.line(format!(
                    "reference: {} ({})",
                    r.cache_file.display(),
                    match r.seconds {
                        Some(s) => format!("rendered in {s:.2} s"),
                        None => "from the cache".into(),
                    }
                ));
                // docs/design.md §3: a pixel that does not converge is reported, not hidden.
                if let Some(u) = r.unconverged {
                    if let Some((x, y, e)) = u.worst {
                        self.line(format!(
                            "warning: {} reference pixel(s) did not reach tol; the worst is ({x}, {y}) with error estimate {e:.3e}",
                            u.count
                        ));
                    }
                }
            }
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

    fn runs_done(&mut self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl RunLines {
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

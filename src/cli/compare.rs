//! `pgt compare REF APPROX`: metrics, maps, report and gates (docs/design.md §5, §7).
//!
//! Prints a one-line verdict on stdout; `--json F` writes the summary (`-` = stdout, then the
//! verdict goes to stderr); `--report DIR` writes the HTML page and maps. Exit 0 when every gate
//! passes (or none is set), 1 when one fails (named in the verdict), 2 on any error.

use super::output::{check_outputs, Output, OutputKind};
use super::Outcome;
use anyhow::Context;
use clap::Args;
use pgt::image_io::load_pair;
use pgt::metrics::gate::Gate;
use pgt::metrics::{CompareOptions, DataRangeSource};
use pgt::report::{self, Compared, ReportOptions};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The reference image (.exr or .png), or a scene (.toml) rendered on the fly; or a
    /// sequence of frames: a folder, or a printf pattern such as ref/frame_%04d.exr.
    pub reference: PathBuf,
    /// The approximation (.exr or .png), or a sequence of frames as the reference.
    pub approximation: PathBuf,
    /// EXR layer to compare (channels LAYER.R/G/B) in both files, e.g. `err`.
    #[arg(long)]
    pub layer: Option<String>,
    /// Data range R of SSIM and PSNR (default: 1 for LDR inputs, derived from the reference for HDR).
    #[arg(long)]
    pub data_range: Option<f64>,
    /// Write the JSON summary to this file (`-` for stdout).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the HTML report, heatmaps and maps (EXR) into this folder.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Fixed top of the absolute-error heatmap scale (default: the map's maximum).
    #[arg(long)]
    pub error_scale: Option<f64>,
    /// Fixed top of the relative-error heatmap scale (default: the map's maximum).
    #[arg(long)]
    pub rel_scale: Option<f64>,
    /// Gate file (TOML; see `metrics::gate`). Command-line thresholds override it.
    #[arg(long)]
    pub gate: Option<PathBuf>,
    /// Fail unless the mean SSIM is at least this.
    #[arg(long)]
    pub min_ssim: Option<f64>,
    /// Fail unless the mean RMSE is at most this.
    #[arg(long)]
    pub max_rmse: Option<f64>,
    /// Fail unless the mean LDR-FLIP is at most this.
    #[arg(long)]
    pub max_flip: Option<f64>,
    /// Skip FLIP.
    #[arg(long)]
    pub no_flip: bool,
    /// HDR-FLIP exposure range START,STOP in stops (default: chosen from the reference).
    #[arg(long, value_parser = parse_exposures, allow_hyphen_values = true)]
    pub flip_exposures: Option<(f32, f32)>,
    /// Sequences: the temporal error above which a pixel pops (radiance units, as the images;
    /// default 0.05 × the data range).
    #[arg(long)]
    pub pop_threshold: Option<f64>,
    /// Sequences: fail unless every frame's 99th percentile of the temporal error (mean over
    /// R, G, B) is at most this.
    #[arg(long)]
    pub max_temporal_p99: Option<f64>,
    /// FLIP's viewing condition in pixels per degree.
    #[arg(long, default_value_t = pgt::metrics::flip::DEFAULT_PIXELS_PER_DEGREE)]
    pub ppd: f32,
}

pub fn run(args: CompareArgs) -> anyhow::Result<Outcome> {
    let start = Instant::now();
    let mut outputs = Vec::new();
    if let Some(json) = &args.json {
        outputs.push(Output::new("--json", json, OutputKind::Text));
    }
    if let Some(report) = &args.report {
        outputs.push(Output::new("--report", report, OutputKind::Folder));
    }
    check_outputs(&outputs)?;
    let options = CompareOptions {
        data_range: args.data_range,
        flip: !args.no_flip,
        pixels_per_degree: args.ppd,
        flip_exposures: args.flip_exposures,
    };
    let report_options = ReportOptions {
        error_scale: args.error_scale,
        rel_scale: args.rel_scale,
    };
    pgt::report::compared::check_options(&options, &report_options)?;
    let mut gate = match &args.gate {
        Some(path) => Gate::load(path)?,
        None => Gate::default(),
    };
    gate.min_ssim = args.min_ssim.or(gate.min_ssim);
    gate.max_rmse = args.max_rmse.or(gate.max_rmse);
    gate.max_flip = args.max_flip.or(gate.max_flip);
    gate.max_temporal_p99 = args.max_temporal_p99.or(gate.max_temporal_p99);
    gate.validate().map_err(anyhow::Error::msg)?;
    if let Some(outcome) = compare_sequences(&args, &gate)? {
        return Ok(outcome);
    }
    // The reference's error estimate is a second read of its EXR: done beside the pair's.
    let (pair, estimate) = rayon::join(
        || {
            load_pair(
                &args.reference,
                &args.approximation,
                args.layer.as_deref(),
                &pgt::reference::render_scene_file,
            )
        },
        || pgt::image_io::read_reference_estimate(&args.reference, args.layer.as_deref()),
    );
    let (reference, approximation) = pair?;
    let labels = (
        args.reference.display().to_string(),
        args.approximation.display().to_string(),
    );
    let compared = Compared::new(reference, approximation, estimate, labels, &options)
        .with_context(|| {
            format!(
                "comparing {} with {}",
                args.reference.display(),
                args.approximation.display()
            )
        })?;
    let cmp = &compared.comparison;
    if cmp.data_range_source == DataRangeSource::Derived {
        eprintln!(
            "note: HDR input (values above 1); data range for SSIM/PSNR derived from the reference: {} (pass --data-range to fix it)",
            cmp.data_range
        );
    }
    let summary = compared.summary(&gate, start.elapsed().as_secs_f64())?;
    if let Some(u) = &summary.reference_uncertainty {
        eprintln!(
            "reference error estimate: max {:.3e}, mean {:.3e}; the difference exceeds it at {:.3}% of pixel-channels",
            u.max_estimate,
            u.mean_estimate,
            100.0 * u.exceeding_fraction
        );
    }
    if let Some(dir) = &args.report {
        let page = compared.write_report(dir, &summary, report_options)?;
        eprintln!("report: {}", page.display());
    }
    let verdict = summary.verdict();
    match &args.json {
        Some(path) if path.as_os_str() == "-" => {
            super::print_stdout(&(serde_json::to_string_pretty(&summary)? + "\n"))?;
            eprintln!("{verdict}");
        }
        Some(path) => {
            report::text::write_text(path, &(serde_json::to_string_pretty(&summary)? + "\n"))?;
            super::print_stdout(&format!("{verdict}\n"))?;
        }
        None => super::print_stdout(&format!("{verdict}\n"))?,
    }
    Ok(match summary.passed {
        Some(false) => Outcome::GateFailed,
        _ => Outcome::Success,
    })
}

/// Two sequences of frames: their comparison ([`super::compare_frames`]), `None` for two
/// images; a sequence against an image, or a sequence's option on two images, is an error.
fn compare_sequences(args: &CompareArgs, gate: &Gate) -> anyhow::Result<Option<Outcome>> {
    if args
        .pop_threshold
        .is_some_and(|t| !(t.is_finite() && t >= 0.0))
    {
        anyhow::bail!("--pop-threshold must be a finite number ≥ 0");
    }
    let sequences =
        [&args.reference, &args.approximation].map(|p| pgt::sequence::compare::is_sequence(p));
    match sequences {
        [true, true] => {
            if args.layer.is_some() {
                anyhow::bail!(
                    "--layer compares one layer of two images; it does not apply to sequences"
                );
            }
            let seq = pgt::report::sequence_compare::SequenceArgs {
                reference: &args.reference,
                approximation: &args.approximation,
                options: CompareOptions {
                    data_range: args.data_range,
                    flip: !args.no_flip,
                    pixels_per_degree: args.ppd,
                    flip_exposures: args.flip_exposures,
                },
                pop_threshold: args.pop_threshold,
                report: args.report.as_deref(),
            };
            return super::compare_frames::run(&seq, gate, args.json.as_deref()).map(Some);
        }
        [true, false] | [false, true] => {
            let (seq, one) = if sequences[0] {
                (&args.reference, &args.approximation)
            } else {
                (&args.approximation, &args.reference)
            };
            anyhow::bail!(
                "{} is a sequence of frames (a folder or a %d pattern) but {} is one image: compare two sequences or two images",
                seq.display(),
                one.display()
            );
        }
        _ => {}
    }
    if let Some((name, _)) = gate.temporal_keys().first() {
        anyhow::bail!("{name} gates the temporal error of a sequence; {} and {} are single images (compare two folders or %d patterns of frames)", args.reference.display(), args.approximation.display());
    }
    if args.pop_threshold.is_some() {
        anyhow::bail!("--pop-threshold applies to sequences of frames, not to single images");
    }

    Ok(None)
}

/// Parses `START,STOP` (stops, finite, START <= STOP).
fn parse_exposures(s: &str) -> Result<(f32, f32), String> {
    let err = || format!("expected START,STOP in stops with START <= STOP, got '{s}'");
    let (a, b) = s.split_once(',').ok_or_else(err)?;
    let a: f32 = a.trim().parse().map_err(|_| err())?;
    let b: f32 = b.trim().parse().map_err(|_| err())?;
    if a.is_finite() && b.is_finite() && a <= b {
        Ok((a, b))
    } else {
        Err(err())
    }
}

//! The report of a sweep (docs/design.md §5): error heatmaps on one scale for all runs, SVG plots of
//! error and time against the swept parameter (the thesis's Figures 6.2/6.3), the HTML page
//! with the table (the thesis's Tables 6.1/6.2), the error attributions, `sweep.json` and
//! `summary.json` (size, reference time and threads, adapter, attributions), from a
//! [`SweepResults`](crate::sweep::SweepResults).

use super::attribution::{attribution_json, attribution_section, write_attribution_files};
use super::colorbar::colorbar_svg;
use super::html::page;
use super::plot::{line_plot_svg, PlotSpec, Series};
use super::summary::{format_db, short};
use super::text::{escape, write_text};
use super::viewer::{write_viewer, Viewer, ViewerImage};
use super::{heatmap, ColorMap, Scale};
use crate::error::{PgtError, Result};
use crate::image_io::write_folder_atomically;
use crate::metrics::Comparison;
use crate::scene::Scene;
use crate::sweep::{
    run_sweep, Experiment, ParamValue, Progress, RunResult, SweepOptions, SweepResults,
};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What follows a sweep as it runs ([`sweep_into_report`]): the reference, each run as it
/// starts and ends, and the end of the runs (before the report is written).
pub trait SweepWatch {
    /// One step of the sweep.
    fn show(&mut self, progress: Progress);
    /// Every run has ended (or one failed); the report is written next.
    fn runs_done(&mut self) {}
}

/// Runs the experiment on its scene and writes the report into the folder `report`
/// (docs/design.md §5, `pgt sweep`): the report is written into a temporary folder that takes
/// the report's place at the end (an interrupted sweep leaves no half-written report); the
/// reference cache lives in `report/cache`, so that it survives from one sweep to the next.
/// Returns the number of runs and the report's page.
pub fn sweep_into_report(
    report: &Path,
    experiment: &Experiment,
    scene: &Scene,
    threads: Option<usize>,
    progress: bool,
    watch: &mut dyn SweepWatch,
) -> Result<(usize, PathBuf)> {
    write_folder_atomically(report, |tmp| {
        let options = SweepOptions {
            dir: tmp.to_path_buf(),
            cache: report.join("cache"),
            threads,
            progress,
        };
        let results = run_sweep(experiment, scene, &options, |p| watch.show(p));
        watch.runs_done();
        let results = results?;
        write_sweep_report(tmp, &results)?;
        Ok((results.runs.len(), report.join("index.html")))
    })
}

/// Writes the heatmaps, plots, `index.html` and `sweep.json` into `dir` (where the sweep wrote
/// its images); returns the page's path.
pub fn write_sweep_report(dir: &Path, results: &SweepResults) -> Result<PathBuf> {
    // Error heatmaps on one scale for all runs, so that they can be compared by eye.
    let all: Vec<f32> = results
        .runs
        .iter()
        .map(|r| Scale::zero_to_max(&r.abs_error).hi as f32)
        .collect();
    let scale = Scale::zero_to_max(&all);
    for r in &results.runs {
        heatmap(
            &r.abs_error,
            results.width,
            results.height,
            scale,
            ColorMap::Magma,
        )
        .write_png(&dir.join(heatmap_file(r)))?;
    }
    write_plots(dir, &results.runs, results.plot_x)?;
    write_attribution_files(dir, &results.attributions, results.width, results.height)?;
    let viewer = Viewer {
        reference: &results.reference_image,
        reference_png: "reference.png".into(),
        estimate: None,
        approximations: results
            .runs
            .iter()
            .map(|r| ViewerImage {
                label: r.run.label(),
                png: r.image_file.clone(),
                heatmap: heatmap_file(r),
                image: &r.image,
            })
            .collect(),
        exposure: 0.0,
        error_caption: format!(
            "|a − r|, mean over R, G, B, magma 0 … {}, one scale for all runs",
            short(scale.hi)
        ),
    };
    let viewer_html = if results.runs.is_empty() {
        String::new()
    } else {
        write_viewer(dir, &viewer)?
    };
    let page_path = dir.join("index.html");
    write_text(&page_path, &sweep_page(results, &viewer_html, scale))?;
    write_json(dir, "sweep.json", &sweep_json(&results.runs))?;
    write_json(dir, "summary.json", &summary_json(results))?;
    Ok(page_path)
}

/// Writes `value` as pretty JSON to `dir/name`.
fn write_json(dir: &Path, name: &str, value: &serde_json::Value) -> Result<()> {
    let json = serde_json::to_string_pretty(value)
        .map_err(|e| PgtError::io(dir.join(name), std::io::Error::other(e)))?;
    write_text(&dir.join(name), &(json + "\n"))
}

/// `summary.json`: what the sweep ran on (size, reference time and threads, adapter), the
/// reference's pixels that did not reach `tol` (count, and the worst as [x, y, error estimate];
/// null where a cached reference predates them) and the error attributions; the runs are in
/// `sweep.json`.
fn summary_json(results: &SweepResults) -> serde_json::Value {
    serde_json::json!({
        "experiment": results.experiment.display().to_string(),
        "scene": results.scene.display().to_string(),
        "size": [results.width, results.height],
        "reference_seconds": results.reference.seconds,
        "reference_unconverged": results.reference.unconverged.map(|u| u.count),
        "reference_worst_unconverged": results.reference.unconverged.and_then(|u| u.worst),
        "threads": results.threads,
        "adapter": results.adapter,
        "attribution": attribution_json(&results.attributions),
    })
}

/// The run's |a − r| heatmap.
fn heatmap_file(r: &RunResult) -> String {
    format!("{}_abs_error.png", r.run.file_stem())
}

/// The plots' x axis: the experiment's `plot_x`, else the parameter with the most distinct
/// values over all runs (ties: the one named first), e.g. `samples` for the thesis's Figures
/// 6.2/6.3.
fn x_parameter(runs: &[RunResult], plot_x: Option<&'static str>) -> &'static str {
    if let Some(x) = plot_x {
        return x;
    }
    let mut names: Vec<&'static str> = Vec::new();
    let mut values: BTreeMap<&'static str, BTreeSet<ParamValue>> = BTreeMap::new();
    for r in runs {
        for (k, v) in &r.run.params {
            if !names.contains(k) {
                names.push(k);
            }
            values.entry(k).or_default().insert(*v);
        }
    }
    let mut best = names.first().copied().unwrap_or("parameter");
    for n in &names {
        if values[n].len() > values[best].len() {
            best = n;
        }
    }
    best
}

/// The x axis of the plots: numbers on a log axis, or, where a value is `"all"`, one category
/// per distinct value (sorted, `all` last) so that `all` is not drawn as 4294967295.
struct XAxis {
    name: &'static str,
    categories: Option<Vec<ParamValue>>,
}

impl XAxis {
    fn of(runs: &[RunResult], plot_x: Option<&'static str>) -> XAxis {
        let name = x_parameter(runs, plot_x);
        let values: BTreeSet<ParamValue> = runs.iter().filter_map(|r| r.run.param(name)).collect();
        let categories = values
            .contains(&ParamValue::All)
            .then(|| values.into_iter().collect());
        XAxis { name, categories }
    }

    /// Where a value sits on the axis.
    fn position(&self, v: ParamValue) -> f64 {
        match &self.categories {
            Some(c) => c.iter().position(|x| *x == v).unwrap_or(0) as f64,
            None => v.as_u32() as f64,
        }
    }

    fn labels(&self) -> Option<Vec<String>> {
        self.categories
            .as_ref()
            .map(|c| c.iter().map(|v| v.to_string()).collect())
    }
}

/// Series for a plot: x = the run's value of the x parameter, one series per method and
/// combination of the other parameters.
fn series_of(runs: &[RunResult], x: &XAxis, y: impl Fn(&RunResult) -> Option<f64>) -> Vec<Series> {
    let mut groups: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in runs {
        let Some(v) = y(r) else { continue };
        let Some(xv) = r.run.param(x.name) else {
            continue;
        };
        let mut label = r.run.method.to_string();
        for (k, v) in r.run.params.iter().filter(|(k, _)| *k != x.name) {
            let _ = write!(label, " {k}={v}");
        }
        groups.entry(label).or_default().push((x.position(xv), v));
    }
    groups
        .into_iter()
        .map(|(label, points)| Series { label, points })
        .collect()
}

/// Whether every series has a positive value (a log y axis can show it).
fn all_positive(series: &[Series]) -> bool {
    series.iter().all(|s| s.points.iter().any(|p| p.1 > 0.0))
}

/// The error-against-time plot's series: one per method and combination of the parameters
/// other than `x`, each point (time, 1 − SSIM) of one run.
fn error_time_series(runs: &[RunResult], x: &str) -> Vec<Series> {
    let mut groups: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in runs {
        let Some(s) = r.comparison.ssim_values() else {
            continue;
        };
        let mut label = r.run.method.to_string();
        for (k, v) in r.run.params.iter().filter(|(k, _)| *k != x) {
            let _ = write!(label, " {k}={v}");
        }
        groups
            .entry(label)
            .or_default()
            .push((r.seconds, 1.0 - s.mean));
    }
    groups
        .into_iter()
        .map(|(label, points)| Series { label, points })
        .collect()
}

/// `error_time.svg`: 1 − SSIM against the render time, the trade-off the thesis's Figures
/// 6.2/6.3 show only one side of.
fn write_error_time_plot(dir: &Path, runs: &[RunResult], x: &str) -> Result<()> {
    let series = error_time_series(runs, x);
    let positive = |v: f64| v > 0.0;
    let log = series
        .iter()
        .all(|s| s.points.iter().all(|p| positive(p.0) && positive(p.1)));
    let title = format!("1 − SSIM against render time (points along {x})");
    let spec = PlotSpec {
        title: &title,
        x_label: "seconds",
        y_label: "1 − SSIM",
        log_x: log,
        log_y: log,
        x_categories: None,
    };
    line_plot_svg(&dir.join("error_time.svg"), &spec, &series)
}

/// `dssim.svg`, `rmse.svg`, `time.svg`, `error_time.svg`, and `dssim_baseline.svg` where runs
/// have baselines.
fn write_plots(dir: &Path, runs: &[RunResult], plot_x: Option<&'static str>) -> Result<()> {
    let x = XAxis::of(runs, plot_x);
    write_error_time_plot(dir, runs, x.name)?;
    let categories = x.labels();
    let plot = |file: &str, title: String, y_label: &str, log_y: bool, series: &[Series]| {
        let spec = PlotSpec {
            title: &title,
            x_label: x.name,
            y_label,
            log_x: true,
            log_y,
            x_categories: categories.as_deref(),
        };
        line_plot_svg(&dir.join(file), &spec, series)
    };
    let dssim = series_of(runs, &x, |r| {
        r.comparison.ssim_values().map(|s| 1.0 - s.mean)
    });
    let title = format!("1 − SSIM (mean over R, G, B) against {}", x.name);
    plot("dssim.svg", title, "1 − SSIM", all_positive(&dssim), &dssim)?;
    let rmse = series_of(runs, &x, |r| {
        Some(r.comparison.error_values(|e| e.rmse).mean)
    });
    let title = format!("RMSE (mean over R, G, B) against {}", x.name);
    plot("rmse.svg", title, "RMSE", all_positive(&rmse), &rmse)?;
    let time = series_of(runs, &x, |r| Some(r.seconds));
    plot(
        "time.svg",
        format!("Render time against {}", x.name),
        "seconds",
        false,
        &time,
    )?;
    if runs.iter().any(|r| r.baseline.is_some()) {
        let base = series_of(runs, &x, |r| {
            let s = r.baseline.as_ref()?.comparison.ssim_values()?;
            Some(1.0 - s.mean)
        });
        let title = format!("1 − SSIM against the baseline run, against {}", x.name);
        plot(
            "dssim_baseline.svg",
            title,
            "1 − SSIM",
            all_positive(&base),
            &base,
        )?;
    }
    Ok(())
}

/// SSIM R, G, B and mean as table cells, in %.
fn ssim_cells(cmp: &Comparison) -> String {
    let pct = |v: f64| format!("{:.4}%", 100.0 * v);
    match cmp.ssim_values() {
        Some(s) => format!(
            "<td>{}</td><td>{}</td><td>{}</td><td><b>{}</b></td>",
            pct(s.r),
            pct(s.g),
            pct(s.b),
            pct(s.mean)
        ),
        None => "<td>n/a</td><td>n/a</td><td>n/a</td><td>n/a</td>".into(),
    }
}

/// The page: the header, the table against the reference, the table against the baselines (if
/// any), the viewer, the plots, the images with their heatmaps on `scale`.
fn sweep_page(results: &SweepResults, viewer: &str, scale: Scale) -> String {
    let mut b = String::new();
    let reference = &results.reference;
    let _ = writeln!(
        b,
        "<h1>pgt sweep</h1>\n<p>experiment <code>{}</code>, scene <code>{}</code>, reference <code>{}</code> ({})</p>",
        escape(&results.experiment.display().to_string()),
        escape(&results.scene.display().to_string()),
        escape(&reference.cache_file.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default()),
        match reference.seconds {
            None => "from the cache".to_string(),
            Some(s) => format!("rendered in {s:.2} s"),
        }
    );
    let _ = writeln!(
        b,
        "<p>{}×{} pixels; CPU renders on {} threads; GPU runs on {}.</p>",
        results.width,
        results.height,
        results.threads,
        escape(
            results
                .adapter
                .as_deref()
                .unwrap_or("no adapter (no GPU run)")
        )
    );
    b += "<h2>SSIM per channel (as the thesis's Tables 6.1/6.2, in %)</h2>\n<table><tr><th>run</th><th>R</th><th>G</th><th>B</th><th>mean</th><th>RMSE</th><th>PSNR</th><th>FLIP</th><th>time (s)</th></tr>\n";
    for r in &results.runs {
        let cmp = &r.comparison;
        let _ = writeln!(
            b,
            "<tr><td>{}</td>{}<td>{:.4e}</td><td>{}</td><td>{}</td><td>{:.3}</td></tr>",
            escape(&r.run.label()),
            ssim_cells(cmp),
            cmp.error_values(|e| e.rmse).mean,
            format_db(cmp.error_values(|e| e.psnr).mean),
            cmp.flip_mean().map(short).unwrap_or("n/a".into()),
            r.seconds
        );
    }
    b += "</table>\n";
    let with_baseline: Vec<&RunResult> = results
        .runs
        .iter()
        .filter(|r| r.baseline.is_some())
        .collect();
    if !with_baseline.is_empty() {
        b += "<h2>SSIM against the baseline run (as the thesis's GT column, in %)</h2>\n<table><tr><th>run</th><th>baseline</th><th>R</th><th>G</th><th>B</th><th>mean</th><th>RMSE</th></tr>\n";
        for r in with_baseline {
            let Some(base) = &r.baseline else { continue };
            let _ = writeln!(
                b,
                "<tr><td>{}</td><td>{}</td>{}<td>{:.4e}</td></tr>",
                escape(&r.run.label()),
                escape(&base.label),
                ssim_cells(&base.comparison),
                base.comparison.error_values(|e| e.rmse).mean
            );
        }
        b += "</table>\n";
    }
    b += viewer;
    b += "<h2>Plots</h2>\n<div class=\"grid\">\n";
    let mut plots = vec![
        ("dssim.svg", "1 − SSIM"),
        ("rmse.svg", "RMSE"),
        ("time.svg", "time"),
        ("error_time.svg", "1 − SSIM against time"),
    ];
    if results.runs.iter().any(|r| r.baseline.is_some()) {
        plots.push(("dssim_baseline.svg", "1 − SSIM against the baseline"));
    }
    for (f, t) in plots {
        let _ = writeln!(b, "<div class=\"plot\"><img src=\"{f}\" alt=\"{t}\"></div>");
    }
    b += "</div>\n";
    b += &attribution_section(&results.attributions);
    b += "<h2>Images</h2>\n<div class=\"grid\">\n<figure><img src=\"reference.png\" alt=\"reference\"><figcaption><b>reference</b></figcaption></figure>\n";
    for (i, r) in results.runs.iter().enumerate() {
        let label = escape(&r.run.label());
        let bar = colorbar_svg(
            scale,
            ColorMap::Magma,
            "absolute error",
            &format!("bar-{i}"),
        );
        let _ = writeln!(
            b,
            "<figure><img src=\"{}\" alt=\"{label}\"><figcaption><b>{label}</b></figcaption></figure>",
            escape(&r.image_file),
        );
        let _ = writeln!(
            b,
            "<figure><div class=\"heat\"><img src=\"{}\" alt=\"error of {label}\">{bar}</div><figcaption>|a − r|, mean over R, G, B; magma, one scale for all runs</figcaption></figure>",
            escape(&heatmap_file(r)),
        );
    }
    b += "</div>\n";
    page("pgt sweep", &b)
}

/// `sweep.json`: one object per run; `baseline` only for runs that have one.
fn sweep_json(runs: &[RunResult]) -> serde_json::Value {
    serde_json::Value::Array(
        runs.iter()
            .map(|r| {
                let params: serde_json::Map<String, serde_json::Value> = r
                    .run
                    .params
                    .iter()
                    .map(|(k, v)| (k.to_string(), serde_json::json!(v)))
                    .collect();
                let cmp = &r.comparison;
                let mut run = serde_json::json!({
                    "method": r.run.method,
                    "params": params,
                    "seconds": r.seconds,
                    "ssim": cmp.ssim_values(),
                    "rmse": cmp.error_values(|e| e.rmse),
                    "psnr": cmp.error_values(|e| e.psnr),
                    "flip": cmp.flip_mean(),
                    "image": r.image_file,
                });
                if let Some(base) = &r.baseline {
                    run["baseline"] = serde_json::json!({
                        "run": base.label,
                        "ssim": base.comparison.ssim_values(),
                        "rmse": base.comparison.error_values(|e| e.rmse),
                        "psnr": base.comparison.error_values(|e| e.psnr),
                    });
                    if !base.conventions.is_empty() {
                        let conventions: serde_json::Map<String, serde_json::Value> = base
                            .conventions
                            .iter()
                            .map(|(name, c)| {
                                let v = serde_json::json!({
                                    "ssim": c.ssim_values(),
                                    "rmse": c.error_values(|e| e.rmse),
                                });
                                (name.clone(), v)
                            })
                            .collect();
                        run["baseline"]["conventions"] = conventions.into();
                    }
                }
                run
            })
            .collect(),
    )
}

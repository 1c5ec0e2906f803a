//! `pgt sweep EXPERIMENT.toml --report DIR` (DESIGN.md §5, §7): the reference once (cached by
//! a hash of the loaded scene and the options in `DIR/cache`), an approximation for each
//! parameter combination listed in the experiment, a comparison of each, and one report with a
//! table (the thesis's Tables 6.1/6.2: SSIM per channel and mean, in %) and SVG plots of error
//! and time against the swept parameter (the thesis's Figures 6.2/6.3).
//!
//! The experiment file (TOML, unknown keys are errors):
//!
//! ```toml
//! scene = "scene.toml"        # relative to the experiment file
//! size = [256, 256]           # optional: overrides the scene's image size
//! data_range = 1.0            # optional: SSIM/PSNR data range (default as in `pgt compare`)
//!
//! [reference]                 # optional: the one reference render
//! spp = 1
//! tol = 1e-5                  # overrides the scene's quadrature tolerance
//!
//! [[approximations]]
//! method = "riemann"          # the reference with the thesis's midpoint Riemann sums
//! samples = [1, 2, 5, 10, 50, 100]
//! spp = [1]                   # optional, default [reference spp]
//!
//! [[approximations]]
//! method = "thesis"           # the GPU approximation (DESIGN.md §4)
//! samples = [100]
//! n_exact = [1, 2, 3, 5]
//! ```
//!
//! Each `[[approximations]]` entry runs the Cartesian product of its lists. Methods are
//! dispatched in [`render_approximation`]: adding one is one match arm there and one variant of
//! [`MethodSpec`]. The `thesis` runs use the GPU approximation (`crate::approx`) on the first
//! adapter wgpu finds; their time is the GPU time, the others' the wall time.

use super::Outcome;
use crate::approx::{render_approx_with, ApproxParams, GpuContext, N_EXACT_ALL};
use crate::error::PgtError;
use crate::image_io::{read_exr_layer, write_image, RgbImage};
use crate::metrics::{compare, maps, CompareOptions, Comparison};
use crate::reference::{self, Integrator, RenderOptions};
use crate::report::html::{escape, page, write_text};
use crate::report::plot::{line_plot_svg, PlotSpec, Series};
use crate::report::summary::short;
use crate::report::{heatmap, ColorMap, Scale};
use crate::scene::{Scene, SceneLoadOptions};
use anyhow::Context;
use clap::Args;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The experiment file (TOML; see `pgt sweep --help` and the module documentation).
    pub experiment: PathBuf,
    /// Folder for the report, the images and the reference cache.
    #[arg(long)]
    pub report: PathBuf,
    /// Worker threads for the renders.
    #[arg(long)]
    pub threads: Option<usize>,
}

/// The experiment file.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    pub scene: PathBuf,
    pub size: Option<[u32; 2]>,
    pub data_range: Option<f64>,
    #[serde(default)]
    pub reference: ReferenceSpec,
    pub approximations: Vec<MethodSpec>,
}

/// Options of the one reference render.
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    pub spp: Option<u32>,
    pub tol: Option<f64>,
}

/// An approximation method and the lists of its parameters.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(tag = "method", rename_all = "lowercase", deny_unknown_fields)]
pub enum MethodSpec {
    /// The reference renderer with `Integrator::Riemann { samples }` (the thesis's integrator
    /// on exact intervals), optionally at other pixel sample counts.
    Riemann {
        samples: Vec<u32>,
        spp: Option<Vec<u32>>,
    },
    /// The thesis's GPU scheme (DESIGN.md §4): `samples` midpoint samples for the first
    /// `n_exact` particles.
    Thesis {
        samples: Vec<u32>,
        n_exact: Vec<u32>,
    },
}

/// One parameter combination of one method.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    pub method: &'static str,
    /// Parameter name → value, in a fixed order (the first is the plots' x axis).
    pub params: Vec<(&'static str, u32)>,
}

impl Run {
    /// `riemann samples=10 spp=1`.
    pub fn label(&self) -> String {
        let mut s = self.method.to_string();
        for (k, v) in &self.params {
            let _ = write!(s, " {k}={v}");
        }
        s
    }

    fn file_stem(&self) -> String {
        self.label().replace([' ', '='], "_")
    }
}

impl MethodSpec {
    /// The Cartesian product of the lists, in file order.
    pub fn runs(&self, reference_spp: u32) -> Vec<Run> {
        let (method, lists): (&'static str, Vec<(&'static str, Vec<u32>)>) = match self {
            MethodSpec::Riemann { samples, spp } => (
                "riemann",
                vec![
                    ("samples", samples.clone()),
                    ("spp", spp.clone().unwrap_or(vec![reference_spp])),
                ],
            ),
            MethodSpec::Thesis { samples, n_exact } => (
                "thesis",
                vec![("samples", samples.clone()), ("n_exact", n_exact.clone())],
            ),
        };
        let mut runs = vec![Vec::new()];
        for (name, values) in &lists {
            runs = runs
                .into_iter()
                .flat_map(|prefix: Vec<(&'static str, u32)>| {
                    values.iter().map(move |&v| {
                        let mut p = prefix.clone();
                        p.push((*name, v));
                        p
                    })
                })
                .collect();
        }
        runs.into_iter()
            .map(|params| Run { method, params })
            .collect()
    }
}

/// Renders one approximation run; returns the image and, for GPU methods, the GPU time (the
/// wall time would include the shader compilation). The one place methods are dispatched. The
/// GPU context is opened on the first GPU run and kept for the rest of the sweep.
pub fn render_approximation(
    scene: &Scene,
    run: &Run,
    threads: Option<usize>,
    gpu: &mut Option<GpuContext>,
) -> anyhow::Result<(RgbImage, Option<f64>)> {
    let param = |name: &str| run.params.iter().find(|(k, _)| *k == name).map(|(_, v)| *v);
    match run.method {
        "riemann" => {
            let options = RenderOptions {
                spp: param("spp").unwrap_or(1),
                threads,
                progress: false,
                integrator: Integrator::Riemann {
                    samples: param("samples").unwrap_or(1),
                },
            };
            Ok((reference::render(scene, &options)?.image, None))
        }
        "thesis" => {
            if gpu.is_none() {
                *gpu = Some(GpuContext::new(None)?);
            }
            let ctx = gpu.as_ref().expect("opened above");
            let params = ApproxParams::for_method(
                "thesis",
                &[
                    ("samples", param("samples").unwrap_or(100)),
                    ("n_exact", param("n_exact").unwrap_or(N_EXACT_ALL)),
                ],
            )?;
            let out = render_approx_with(ctx, scene, &params)?;
            Ok((out.image, Some(out.gpu_seconds)))
        }
        other => anyhow::bail!("unknown approximation method '{other}'"),
    }
}

/// FNV-1a, 64 bit: a stable hash for the cache key (not cryptographic; a collision would need a
/// deliberately crafted scene).
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// The cache key of a reference render: everything that determines its pixels (the loaded
/// scene with its particles, which covers included particle files, the options, pgt's version).
pub fn reference_key(scene: &Scene, options: &RenderOptions) -> String {
    let text = format!(
        "pgt {} reference v1\n{:?}\n{:?}\n{:?}\n{:?}\nspp {} integrator {:?}",
        env!("CARGO_PKG_VERSION"),
        scene.camera,
        scene.render,
        scene.lights,
        scene.particles,
        options.spp,
        options.integrator
    );
    format!("{:016x}", fnv1a(text.as_bytes()))
}

/// The result of one run.
struct RunResult {
    run: Run,
    seconds: f64,
    cmp: Comparison,
    image_file: String,
    /// |a − r|, mean over channels, per pixel (for the heatmaps on a common scale).
    abs_error: Vec<f32>,
    heatmap_file: String,
}

pub fn run(args: SweepArgs) -> anyhow::Result<Outcome> {
    let text =
        std::fs::read_to_string(&args.experiment).map_err(|e| PgtError::io(&args.experiment, e))?;
    let exp: Experiment = toml::from_str(&text).map_err(|e| {
        let line = e
            .span()
            .map(|s| crate::metrics::gate::line_of(&text, s.start));
        match line {
            Some(l) => PgtError::at_line(&args.experiment, l, e.message().to_string()),
            None => PgtError::in_file(&args.experiment, e.message().to_string()),
        }
    })?;
    let ref_spp = exp.reference.spp.unwrap_or(1);
    let runs: Vec<Run> = exp
        .approximations
        .iter()
        .flat_map(|m| m.runs(ref_spp))
        .collect();
    if runs.is_empty() {
        return Err(PgtError::in_file(
            &args.experiment,
            "no approximation runs (every [[approximations]] list is empty)",
        )
        .into());
    }
    for r in &runs {
        if r.params.iter().any(|(_, v)| *v == 0) {
            return Err(PgtError::in_file(
                &args.experiment,
                format!("{}: parameters must be at least 1", r.label()),
            )
            .into());
        }
    }
    let base = args.experiment.parent().unwrap_or(Path::new("."));
    let scene_path = base.join(&exp.scene);
    let load = SceneLoadOptions {
        size: exp.size.map(|[w, h]| (w, h)),
        tol: exp.reference.tol,
        ..SceneLoadOptions::default()
    };
    let scene = Scene::load(&scene_path, &load)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let dir = &args.report;
    let cache = dir.join("cache");
    std::fs::create_dir_all(&cache).map_err(|e| PgtError::io(&cache, e))?;

    // The reference, once.
    let ref_options = RenderOptions {
        spp: ref_spp,
        threads: args.threads,
        progress: super::stderr_is_terminal(),
        integrator: Integrator::Adaptive,
    };
    let key = reference_key(&scene, &ref_options);
    let cached = cache.join(format!("reference-{key}.exr"));
    let (reference_image, ref_seconds, from_cache) = if cached.is_file() {
        (read_exr_layer(&cached, "")?, None, true)
    } else {
        let t = Instant::now();
        let out = reference::render(&scene, &ref_options)?;
        let s = t.elapsed().as_secs_f64();
        write_image(&cached, &out.image, &[], 0.0)?;
        (out.image, Some(s), false)
    };
    eprintln!(
        "reference: {} ({})",
        cached.display(),
        match ref_seconds {
            Some(s) => format!("rendered in {s:.2} s"),
            None => "from the cache".into(),
        }
    );
    let options = CompareOptions {
        data_range: exp.data_range,
        ..CompareOptions::default()
    };
    let exposure = 0.0;
    write_image(&dir.join("reference.png"), &reference_image, &[], exposure)?;

    let mut results = Vec::new();
    let mut gpu = None;
    for run in runs {
        let t = Instant::now();
        let (image, gpu_seconds) = render_approximation(&scene, &run, args.threads, &mut gpu)
            .with_context(|| run.label())?;
        let seconds = gpu_seconds.unwrap_or_else(|| t.elapsed().as_secs_f64());
        let cmp = compare(&reference_image, &image, &options).with_context(|| run.label())?;
        let image_file = format!("{}.png", run.file_stem());
        write_image(&dir.join(&image_file), &image, &[], exposure)?;
        let ssim = cmp
            .ssim_values()
            .map(|s| format!("{:.6}", s.mean))
            .unwrap_or("n/a".into());
        eprintln!(
            "{}: {seconds:.2} s, SSIM {ssim}, RMSE {:.3e}",
            run.label(),
            cmp.error_values(|e| e.rmse).mean
        );
        let abs_error = maps::channel_mean(&maps::abs_error(&reference_image, &image));
        let heatmap_file = format!("{}_abs_error.png", run.file_stem());
        results.push(RunResult {
            run,
            seconds,
            cmp,
            image_file,
            abs_error,
            heatmap_file,
        });
    }
    // Error heatmaps on one scale for all runs, so that they can be compared by eye.
    let all: Vec<f32> = results
        .iter()
        .map(|r| Scale::zero_to_max(&r.abs_error).hi as f32)
        .collect();
    let scale = Scale::zero_to_max(&all);
    for r in &results {
        let path = dir.join(&r.heatmap_file);
        heatmap(
            &r.abs_error,
            reference_image.width,
            reference_image.height,
            scale,
            ColorMap::Magma,
        )
        .write_png(&path)?;
    }
    write_plots(dir, &results)?;
    let page_path = dir.join("index.html");
    write_text(
        &page_path,
        &sweep_page(
            &args.experiment,
            &scene_path,
            &cached,
            from_cache,
            ref_seconds,
            &results,
        ),
    )?;
    write_text(
        &dir.join("sweep.json"),
        &(serde_json::to_string_pretty(&sweep_json(&results))? + "\n"),
    )?;
    println!(
        "sweep: {} runs, report {}",
        results.len(),
        page_path.display()
    );
    Ok(Outcome::Success)
}

/// The plots' x axis: the parameter with the most distinct values over all runs (ties: the one
/// named first), e.g. `samples` for the thesis's Figures 6.2/6.3.
fn x_parameter(results: &[RunResult]) -> &'static str {
    let mut names: Vec<&'static str> = Vec::new();
    let mut values: BTreeMap<&'static str, std::collections::BTreeSet<u32>> = BTreeMap::new();
    for r in results {
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

/// Series for a plot: x = the run's value of `x_name`, one series per method and combination of
/// the other parameters.
fn series_of(
    results: &[RunResult],
    x_name: &str,
    y: impl Fn(&RunResult) -> Option<f64>,
) -> Vec<Series> {
    let mut groups: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in results {
        let Some(v) = y(r) else { continue };
        let Some(x) = r.run.params.iter().find(|(k, _)| *k == x_name) else {
            continue;
        };
        let mut label = r.run.method.to_string();
        for (k, v) in r.run.params.iter().filter(|(k, _)| *k != x_name) {
            let _ = write!(label, " {k}={v}");
        }
        groups.entry(label).or_default().push((x.1 as f64, v));
    }
    groups
        .into_iter()
        .map(|(label, points)| Series { label, points })
        .collect()
}

fn write_plots(dir: &Path, results: &[RunResult]) -> anyhow::Result<()> {
    let x_label = x_parameter(results);
    let dssim = series_of(results, x_label, |r| {
        r.cmp.ssim_values().map(|s| 1.0 - s.mean)
    });
    line_plot_svg(
        &dir.join("dssim.svg"),
        &PlotSpec {
            title: &format!("1 − SSIM (mean over R, G, B) against {x_label}"),
            x_label,
            y_label: "1 − SSIM",
            log_x: true,
            log_y: dssim.iter().all(|s| s.points.iter().any(|p| p.1 > 0.0)),
        },
        &dssim,
    )?;
    let rmse = series_of(results, x_label, |r| {
        Some(r.cmp.error_values(|e| e.rmse).mean)
    });
    line_plot_svg(
        &dir.join("rmse.svg"),
        &PlotSpec {
            title: &format!("RMSE (mean over R, G, B) against {x_label}"),
            x_label,
            y_label: "RMSE",
            log_x: true,
            log_y: rmse.iter().all(|s| s.points.iter().any(|p| p.1 > 0.0)),
        },
        &rmse,
    )?;
    let time = series_of(results, x_label, |r| Some(r.seconds));
    line_plot_svg(
        &dir.join("time.svg"),
        &PlotSpec {
            title: &format!("Render time against {x_label}"),
            x_label,
            y_label: "seconds",
            log_x: true,
            log_y: false,
        },
        &time,
    )?;
    Ok(())
}

fn sweep_page(
    experiment: &Path,
    scene: &Path,
    cached: &Path,
    from_cache: bool,
    ref_seconds: Option<f64>,
    results: &[RunResult],
) -> String {
    let mut b = String::new();
    let _ = writeln!(
        b,
        "<h1>pgt sweep</h1>\n<p>experiment <code>{}</code>, scene <code>{}</code>, reference <code>{}</code> ({})</p>",
        escape(&experiment.display().to_string()),
        escape(&scene.display().to_string()),
        escape(&cached.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default()),
        if from_cache {
            "from the cache".to_string()
        } else {
            format!("rendered in {:.2} s", ref_seconds.unwrap_or(0.0))
        }
    );
    b += "<h2>SSIM per channel (as the thesis's Tables 6.1/6.2, in %)</h2>\n<table><tr><th>run</th><th>R</th><th>G</th><th>B</th><th>mean</th><th>RMSE</th><th>PSNR</th><th>FLIP</th><th>time (s)</th></tr>\n";
    for r in results {
        let pct = |v: f64| format!("{:.4}%", 100.0 * v);
        let (sr, sg, sb, sm) = match r.cmp.ssim_values() {
            Some(s) => (pct(s.r), pct(s.g), pct(s.b), pct(s.mean)),
            None => ("n/a".into(), "n/a".into(), "n/a".into(), "n/a".into()),
        };
        let _ = writeln!(
            b,
            "<tr><td>{}</td><td>{sr}</td><td>{sg}</td><td>{sb}</td><td><b>{sm}</b></td><td>{:.4e}</td><td>{}</td><td>{}</td><td>{:.3}</td></tr>",
            escape(&r.run.label()),
            r.cmp.error_values(|e| e.rmse).mean,
            crate::report::summary::format_db(r.cmp.error_values(|e| e.psnr).mean),
            r.cmp.flip_mean().map(short).unwrap_or("n/a".into()),
            r.seconds
        );
    }
    b += "</table>\n<h2>Plots</h2>\n<div class=\"grid\">\n";
    for (f, t) in [
        ("dssim.svg", "1 − SSIM"),
        ("rmse.svg", "RMSE"),
        ("time.svg", "time"),
    ] {
        let _ = writeln!(b, "<div class=\"plot\"><img src=\"{f}\" alt=\"{t}\"></div>");
    }
    b += "</div>\n<h2>Images</h2>\n<div class=\"grid\">\n<figure><img src=\"reference.png\" alt=\"reference\"><figcaption><b>reference</b></figcaption></figure>\n";
    for r in results {
        let _ = writeln!(
            b,
            "<figure><img src=\"{}\" alt=\"{}\"><figcaption><b>{}</b></figcaption></figure>",
            escape(&r.image_file),
            escape(&r.run.label()),
            escape(&r.run.label())
        );
        let _ = writeln!(
            b,
            "<figure><img src=\"{}\" alt=\"error of {}\"><figcaption>|a − r|, mean over R, G, B; magma, one scale for all runs</figcaption></figure>",
            escape(&r.heatmap_file),
            escape(&r.run.label())
        );
    }
    b += "</div>\n";
    page("pgt sweep", &b)
}

fn sweep_json(results: &[RunResult]) -> serde_json::Value {
    serde_json::Value::Array(
        results
            .iter()
            .map(|r| {
                let params: serde_json::Map<String, serde_json::Value> = r
                    .run
                    .params
                    .iter()
                    .map(|(k, v)| (k.to_string(), (*v).into()))
                    .collect();
                serde_json::json!({
                    "method": r.run.method,
                    "params": params,
                    "seconds": r.seconds,
                    "ssim": r.cmp.ssim_values(),
                    "rmse": r.cmp.error_values(|e| e.rmse),
                    "psnr": r.cmp.error_values(|e| e.psnr),
                    "flip": r.cmp.flip_mean(),
                    "image": r.image_file,
                })
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_are_the_cartesian_product() {
        let m = MethodSpec::Thesis {
            samples: vec![10, 100],
            n_exact: vec![1, 2, 3],
        };
        let runs = m.runs(1);
        assert_eq!(runs.len(), 6);
        assert_eq!(runs[0].label(), "thesis samples=10 n_exact=1");
        assert_eq!(runs[5].label(), "thesis samples=100 n_exact=3");
        let r = MethodSpec::Riemann {
            samples: vec![5],
            spp: None,
        }
        .runs(2);
        assert_eq!(r[0].params, vec![("samples", 5), ("spp", 2)]);
    }

    #[test]
    fn experiment_file_rejects_unknown_keys() {
        let ok = "scene = \"s.toml\"\n[[approximations]]\nmethod = \"riemann\"\nsamples = [1, 2]\n";
        assert!(toml::from_str::<Experiment>(ok).is_ok());
        let bad = "scene = \"s.toml\"\n[[approximations]]\nmethod = \"riemann\"\nsample = [1]\n";
        assert!(toml::from_str::<Experiment>(bad).is_err());
        let bad = "scene = \"s.toml\"\n[[approximations]]\nmethod = \"magic\"\nsamples = [1]\n";
        assert!(toml::from_str::<Experiment>(bad).is_err());
    }
}

//! Running an experiment: the reference once (cached by a hash of the loaded scene and the
//! options in `DIR/cache`), each run with its method on one [`SweepContext`], each image
//! compared with the reference and, where the run names one, with its baseline run. Writes the
//! images (`reference.png`, one PNG per run); the page, plots and JSON are `report::sweep_page`'s.

use super::attribution::{attribute, AttributionResult};
use super::experiment::{Experiment, Run};
use super::method::{SweepContext, SweepMethod};
use super::registry::find_method;
use super::run_result::{BaselineResult, RunResult};
use crate::error::{PgtError, Result};
use crate::image_io::{read_exr_layer, write_atomically, write_image, RgbImage};
use crate::metrics::{compare, maps, CompareOptions};
use crate::reference::{self, Integrator, RenderOptions};
use crate::scene::{Scene, SceneLoadOptions};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to run a sweep.
#[derive(Debug, Clone, Default)]
pub struct SweepOptions {
    /// Folder for the images (the CLI passes a temporary folder that becomes the report).
    pub dir: PathBuf,
    /// Folder of the reference cache; it outlives the sweep (`REPORT/cache` in the CLI).
    pub cache: PathBuf,
    /// Worker threads of the CPU renders; `None` uses rayon's default.
    pub threads: Option<usize>,
    /// A progress bar for the reference render (the CLI sets it when stderr is a terminal).
    pub progress: bool,
}

/// The reference render of a sweep.
#[derive(Debug, Clone)]
pub struct ReferenceInfo {
    /// The cached EXR (`DIR/cache/reference-KEY.exr`).
    pub cache_file: PathBuf,
    /// Render time in seconds; `None` when it came from the cache.
    pub seconds: Option<f64>,
    /// Pixels that did not reach `tol` (docs/design.md §3: reported, not hidden) and the worst one
    /// (x, y, its largest error estimate); `None` for a cached render from before pgt kept
    /// this beside the cached image.
    pub unconverged: Option<Unconverged>,
}

/// The pixels of a reference render that did not reach `tol`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Unconverged {
    pub count: u64,
    /// (x, y, largest channel of its error estimate).
    pub worst: Option<(u32, u32, f64)>,
}

/// Everything a sweep measured.
#[derive(Debug, Clone)]
pub struct SweepResults {
    pub experiment: PathBuf,
    pub scene: PathBuf,
    pub reference: ReferenceInfo,
    /// The reference image (linear float), for the report's pixel probe.
    pub reference_image: RgbImage,
    pub width: u32,
    pub height: u32,
    pub runs: Vec<RunResult>,
    /// The experiment's `plot_x`.
    pub plot_x: Option<&'static str>,
    /// The experiment's error attributions.
    pub attributions: Vec<AttributionResult>,
    /// The adapter of the GPU runs (`None`: no GPU run).
    pub adapter: Option<String>,
    /// Worker threads of the CPU renders (the reference's among them).
    pub threads: usize,
}

/// What [`run_sweep`] reports while it works (the CLI shows the run in progress and prints a
/// line for the reference and each finished run).
#[derive(Debug)]
pub enum Progress<'a> {
    Reference(&'a ReferenceInfo),
    /// Run `index` (0-based) of `total` is about to start.
    Start {
        index: usize,
        total: usize,
        run: &'a Run,
    },
    Run(&'a RunResult),
}

/// Loads the experiment's scene with its size and tolerance overrides.
pub fn load_scene(exp: &Experiment) -> Result<Scene> {
    let load = SceneLoadOptions {
        size: exp.size.map(|[w, h]| (w, h)),
        tol: exp.reference.tol,
        ..SceneLoadOptions::default()
    };
    Scene::load(&exp.scene, &load)
}

/// The cache key of a reference render: everything that determines its pixels (the loaded
/// scene with its particles, which covers included particle files, the options, pgt's version).
pub fn reference_key(scene: &Scene, options: &RenderOptions) -> String {
    // The same identity that ties the parts of a cluster render together.
    crate::parts::render_hash(scene, options)
}

/// The exact reference (adaptive quadrature, docs/design.md §3), from the cache or rendered and
/// cached.
fn cached_reference(
    exp: &Experiment,
    scene: &Scene,
    options: &SweepOptions,
) -> Result<(RgbImage, ReferenceInfo)> {
    let cache = &options.cache;
    std::fs::create_dir_all(cache).map_err(|e| PgtError::io(cache, e))?;
    let ref_options = RenderOptions {
        spp: exp.reference.spp.unwrap_or(1),
        threads: options.threads,
        progress: options.progress,
        integrator: Integrator::Adaptive,
    };
    let cache_file = cache.join(format!(
        "reference-{}.exr",
        reference_key(scene, &ref_options)
    ));
    // The unconverged pixels travel beside the cached image; the image is written last, so a
    // cached image always has them (unless a pgt from before wrote it).
    let status_file = cache_file.with_extension("unconverged.json");
    if cache_file.is_file() {
        let image = read_exr_layer(&cache_file, "")?;
        let unconverged = std::fs::read_to_string(&status_file)
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok());
        return Ok((
            image,
            ReferenceInfo {
                cache_file,
                seconds: None,
                unconverged,
            },
        ));
    }
    let t = Instant::now();
    let out = reference::render(scene, &ref_options)?;
    let seconds = Some(t.elapsed().as_secs_f64());
    let unconverged = Unconverged {
        count: out.stats.unconverged,
        worst: out.stats.worst_unconverged,
    };
    let json = serde_json::to_string(&unconverged).map_err(|e| PgtError::Usage(e.to_string()))?;
    write_atomically(&status_file, |w| w.write_all(json.as_bytes()))?;
    write_image(&cache_file, &out.image, &[], 0.0)?;
    Ok((
        out.image,
        ReferenceInfo {
            cache_file,
            seconds,
            unconverged: Some(unconverged),
        },
    ))
}

/// The method of a run of a validated experiment.
fn method_of(run: &Run) -> Result<&'static dyn SweepMethod> {
    find_method(run.method)
        .ok_or_else(|| PgtError::Usage(format!("unknown approximation method '{}'", run.method)))
}

/// Runs the experiment on `scene` (see [`load_scene`]): checks every method against the scene
/// first, then the reference, then each run in order; calls `progress` after each step.
pub fn run_sweep(
    exp: &Experiment,
    scene: &Scene,
    options: &SweepOptions,
    mut progress: impl FnMut(Progress),
) -> Result<SweepResults> {
    for run in &exp.runs {
        method_of(run)?
            .check_scene(scene)
            .map_err(|e| e.context(run.label()))?;
    }
    let (reference_image, reference) = cached_reference(exp, scene, options)?;
    progress(Progress::Reference(&reference));
    let compare_options = CompareOptions {
        data_range: exp.data_range,
        ..CompareOptions::default()
    };
    write_image(
        &options.dir.join("reference.png"),
        &reference_image,
        &[],
        0.0,
    )?;
    // Images of runs that are a baseline or have one, kept until every run is done.
    let mut kept: Vec<Option<RgbImage>> = vec![None; exp.runs.len()];
    let mut runs = Vec::with_capacity(exp.runs.len());
    let mut ctx = SweepContext::new(options.threads);
    for (i, run) in exp.runs.iter().enumerate() {
        progress(Progress::Start {
            index: i,
            total: exp.runs.len(),
            run,
        });
        let result = one_run(
            run,
            scene,
            &mut ctx,
            &reference_image,
            &compare_options,
            &options.dir,
        )
        .map_err(|e| e.context(run.label()))?;
        progress(Progress::Run(&result));
        let in_chain = exp
            .attributions
            .iter()
            .any(|a| a.run == i || a.steps.iter().any(|s| s.run == Some(i)));
        if in_chain || run.baseline.is_some() || exp.runs.iter().any(|r| r.baseline == Some(i)) {
            kept[i] = Some(result.image.clone());
        }
        runs.push(result);
    }
    // Each kept image as each convention stores it, prepared once.
    let prepared: Vec<Vec<Option<RgbImage>>> = exp
        .conventions
        .iter()
        .map(|c| {
            kept.iter()
                .map(|k| k.as_ref().map(|k| c.prepare(k)))
                .collect()
        })
        .collect();
    for (i, result) in runs.iter_mut().enumerate() {
        let Some(j) = result.run.baseline else {
            continue;
        };
        let (Some(image), Some(base)) = (&kept[i], &kept[j]) else {
            continue;
        };
        let label = || result.run.label();
        let comparison = compare(base, image, &compare_options).map_err(|e| e.context(label()))?;
        let mut conventions = Vec::with_capacity(exp.conventions.len());
        for (c, images) in exp.conventions.iter().zip(&prepared) {
            let (Some(image), Some(base)) = (&images[i], &images[j]) else {
                continue;
            };
            let cmp = compare(base, image, &compare_options).map_err(|e| e.context(label()))?;
            conventions.push((c.name.clone(), cmp));
        }
        result.baseline = Some(BaselineResult {
            label: exp.runs[j].label(),
            comparison,
            conventions,
        });
    }
    let attributions = exp
        .attributions
        .iter()
        .map(|a| attribute(exp, a, &kept, &runs, &reference_image, &compare_options))
        .collect::<Result<Vec<_>>>()?;
    Ok(SweepResults {
        experiment: exp.path.clone(),
        scene: exp.scene.clone(),
        reference,
        width: reference_image.width,
        height: reference_image.height,
        reference_image,
        runs,
        plot_x: exp.plot_x,
        attributions,
        adapter: ctx.adapter_name(),
        threads: options.threads.unwrap_or_else(rayon::current_num_threads),
    })
}

/// Renders one run, writes its PNG, compares it with the reference.
fn one_run(
    run: &Run,
    scene: &Scene,
    ctx: &mut SweepContext,
    reference_image: &RgbImage,
    compare_options: &CompareOptions,
    dir: &Path,
) -> Result<RunResult> {
    let t = Instant::now();
    let out = method_of(run)?.render(ctx, scene, &run.values())?;
    let seconds = out.gpu_seconds.unwrap_or_else(|| t.elapsed().as_secs_f64());
    let comparison = compare(reference_image, &out.image, compare_options)?;
    let image_file = format!("{}.png", run.file_stem());
    write_image(&dir.join(&image_file), &out.image, &[], 0.0)?;
    let abs_error = maps::channel_mean(&maps::abs_error(reference_image, &out.image));
    let result = RunResult {
        run: run.clone(),
        seconds,
        comparison,
        baseline: None,
        image_file,
        abs_error,
        image: out.image,
        warnings: out.warnings,
    };
    Ok(result)
}

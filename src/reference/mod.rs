//! The exact reference renderer (docs/design.md §3): f64 throughout, parallel over blocks of pixels with
//! rayon, bit-identical for any thread count (each pixel is a pure function of the scene).

pub mod budget;
pub mod gaussian;
pub mod gpu;
pub mod opaque;
pub mod quadrature;
pub mod riemann;
pub mod rows;
pub mod series;
pub mod shadow;
pub mod sun_lists;
pub mod volume;

use crate::error::{PgtError, Result};
use crate::geometry::{Camera, Ray};
use crate::image_io::RgbImage;
use crate::scene::{RenderMode, Scene};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// Radiance along one camera ray.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sample {
    /// Linear RGB radiance.
    pub radiance: DVec3,
    /// Absolute error estimate per channel (0 where the computation is closed-form).
    pub error: DVec3,
    /// Shadow rays traced for this sample (for the rays-per-second figure).
    pub shadow_rays: u64,
    /// The quadrature stopped before reaching `tol` (segment cap, or a segment that cannot be
    /// split in f64, e.g. a ray through a point light inside gas): `error` is what it reached.
    pub unconverged: bool,
}

/// Something that computes the radiance along camera rays: one per mode/model.
pub trait RadianceEstimator: Sync {
    fn radiance(&self, ray: &Ray) -> Sample;
    /// Whether `Sample::error` carries a quadrature error estimate worth writing out.
    fn estimates_error(&self) -> bool {
        false
    }
}

/// How the volume renderer integrates the lit and single-scatter source terms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Integrator {
    /// Adaptive Gauss–Kronrod to the scene's `tol` (docs/design.md §3).
    #[default]
    Adaptive,
    /// The thesis's midpoint Riemann sums with this many samples per interval.
    Riemann { samples: u32 },
}

/// Options of a reference render that are not part of the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Stratified k×k samples per pixel (docs/design.md §1: one by default).
    pub spp: u32,
    /// Worker threads; `None` uses rayon's default.
    pub threads: Option<usize>,
    /// Show a progress bar on stderr (the CLI sets it when stderr is a terminal).
    pub progress: bool,
    pub integrator: Integrator,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            spp: 1,
            threads: None,
            progress: false,
            integrator: Integrator::Adaptive,
        }
    }
}

/// Where a reference render is computed: on the CPU's cores, or on a GPU in f64
/// ([`gpu`], docs/design.md §12). Both give the same image within both errs, not the same bits,
/// so a render's hash (`crate::parts::render_hash_on`) names which.
#[derive(Clone, Copy)]
pub enum Device<'a> {
    Cpu,
    /// A device opened with f64 ([`crate::approx::GpuContext::with_f64`]).
    Gpu(&'a crate::approx::GpuContext),
}

/// Figures for the one-line summary (docs/design.md §7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderStats {
    pub pixels: u64,
    pub primary_rays: u64,
    pub shadow_rays: u64,
    pub seconds: f64,
    /// Largest and mean per-pixel, per-channel error estimate (`None` without estimates).
    pub max_error: Option<f64>,
    pub mean_error: Option<f64>,
    /// Pixels where a sample did not reach `tol` (docs/design.md §3: reported, not hidden).
    pub unconverged: u64,
    /// The unconverged pixel with the largest error estimate: (x, y, its largest channel).
    pub worst_unconverged: Option<(u32, u32, f64)>,
}

/// docs/design.md §3: a pixel that does not converge is reported, not hidden. The count and the pixel
/// with the largest error estimate, or `None` when every pixel reached `tol`.
pub fn unconverged_warning(stats: &RenderStats, tol: f64) -> Option<String> {
    let (x, y, e) = stats.worst_unconverged?;
    Some(format!(
        "{} pixel(s) did not reach tol {tol:e}; the worst is ({x}, {y}) with error estimate {e:.3e} (its err value says how far off it may be)",
        stats.unconverged
    ))
}

/// A finished reference render.
#[derive(Debug, Clone)]
pub struct RenderOutput {
    pub image: RgbImage,
    /// Per-pixel error estimate (the EXR's `err` layer), where the renderer has one.
    pub error: Option<RgbImage>,
    pub stats: RenderStats,
}

/// Renders the scene with the renderer its mode and model call for.
pub fn render(scene: &Scene, options: &RenderOptions) -> Result<RenderOutput> {
    render_controlled(scene, options, &RenderControl::default())
}

/// [`render`] with a [`RenderControl`] that another thread uses to follow the render and to
/// stop it (the Python package's progress and Ctrl-C).
pub fn render_controlled(
    scene: &Scene,
    options: &RenderOptions,
    control: &RenderControl,
) -> Result<RenderOutput> {
    let estimator = estimator_for(scene, options)?;
    render_with_control(&scene.camera, estimator.as_ref(), options, control)
}

/// A scene file rendered by the exact reference with its default options, as `pgt compare`
/// renders a scene given in place of an image (docs/design.md §5): its warnings, the time taken
/// and any pixel that did not reach `tol` are printed on stderr, a progress bar where stderr is
/// a terminal.
pub fn render_scene_file(path: &std::path::Path) -> anyhow::Result<RgbImage> {
    use std::io::IsTerminal;
    let scene = Scene::load(path, &crate::scene::SceneLoadOptions::default())?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let options = RenderOptions {
        progress: std::io::stderr().is_terminal(),
        ..Default::default()
    };
    let out = render(&scene, &options)?;
    eprintln!(
        "rendered the reference of {} in {:.2} s",
        path.display(),
        out.stats.seconds
    );
    if let Some(w) = unconverged_warning(&out.stats, scene.render.tol) {
        eprintln!("warning: {w}");
    }
    Ok(out.image)
}

/// Shared between a running render and the thread that waits for it: how many blocks of how
/// many are done, and a flag that stops the render. The render looks at the flag before each
/// block of 16×16 pixels, so a stop takes effect within one block per worker; the stopped
/// render returns [`PgtError::Interrupted`] and no image.
#[derive(Debug, Default)]
pub struct RenderControl {
    stop: AtomicBool,
    blocks_done: AtomicU64,
    blocks_total: AtomicU64,
}

impl RenderControl {
    /// Asks the render to stop.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }

    /// Whether [`RenderControl::stop`] was called.
    pub fn is_stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// (blocks done, blocks in the image); (0, 0) before the render has started.
    pub fn progress(&self) -> (u64, u64) {
        (
            self.blocks_done.load(Ordering::Relaxed),
            self.blocks_total.load(Ordering::Relaxed),
        )
    }
}

/// The estimator the scene's mode and model call for, after checking the options that every
/// renderer shares (`spp` range, Riemann sample count). `render` and the part renderer of
/// [`rows`] both start here, so a part is rendered exactly as the whole image is.
pub fn estimator_for<'a>(
    scene: &'a Scene,
    options: &RenderOptions,
) -> Result<Box<dyn RadianceEstimator + 'a>> {
    if !(1..=MAX_SPP).contains(&options.spp) {
        return Err(PgtError::Usage(format!(
            "--spp must be between 1 and {MAX_SPP}, got {}",
            options.spp
        )));
    }
    if scene.has_gaussians() {
        return Ok(Box::new(gaussian::GaussianRenderer::new(
            scene,
            options.integrator,
        )?));
    }
    match scene.render.mode {
        RenderMode::Opaque => Ok(Box::new(opaque::OpaqueRenderer::new(scene))),
        RenderMode::Volume => {
            if let Integrator::Riemann { samples: 0 } = options.integrator {
                return Err(PgtError::Usage(
                    "Riemann sums need at least 1 sample per interval".into(),
                ));
            }
            Ok(Box::new(volume::VolumeRenderer::new(
                scene,
                options.integrator,
            )))
        }
    }
}

/// Largest k of k×k samples per pixel.
pub const MAX_SPP: u32 = 64;

/// Side of a square block of pixels, the unit of parallel work.
const BLOCK: u32 = 16;

/// Runs `estimator` over every pixel of `camera`'s image.
pub fn render_with(
    camera: &Camera,
    estimator: &dyn RadianceEstimator,
    options: &RenderOptions,
) -> Result<RenderOutput> {
    render_with_control(camera, estimator, options, &RenderControl::default())
}

/// [`render_with`], reporting to and stopped by `control`.
pub fn render_with_control(
    camera: &Camera,
    estimator: &dyn RadianceEstimator,
    options: &RenderOptions,
    control: &RenderControl,
) -> Result<RenderOutput> {
    let start = Instant::now();
    let (w, h) = (camera.width, camera.height);
    let blocks_x = w.div_ceil(BLOCK);
    let blocks_y = h.div_ceil(BLOCK);
    let blocks: Vec<(u32, u32)> = (0..blocks_y)
        .flat_map(|ty| (0..blocks_x).map(move |tx| (tx, ty)))
        .collect();
    control
        .blocks_total
        .store(blocks.len() as u64, Ordering::Relaxed);
    let bar = if options.progress {
        let bar = indicatif::ProgressBar::new(blocks.len() as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{bar:40}] {percent}% eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(bar)
    } else {
        None
    };
    let k = options.spp;
    let run = || {
        blocks
            .par_iter()
            .map(|&(tx, ty)| {
                let mut out = Vec::with_capacity((BLOCK * BLOCK) as usize);
                let mut shadow_rays = 0u64;
                for py in ty * BLOCK..((ty + 1) * BLOCK).min(h) {
                    // A row at a time: a block of a slow scene takes seconds, a row a sixteenth
                    // of that, so a stop is seen soon (the block's partial rows are dropped).
                    if control.is_stopped() {
                        return (out, shadow_rays);
                    }
                    for px in tx * BLOCK..((tx + 1) * BLOCK).min(w) {
                        let (radiance, error, rays, unconverged) =
                            render_pixel(camera, estimator, px, py, k);
                        shadow_rays += rays;
                        out.push((px, py, radiance, error, unconverged));
                    }
                }
                if let Some(bar) = &bar {
                    bar.inc(1);
                }
                control.blocks_done.fetch_add(1, Ordering::Relaxed);
                (out, shadow_rays)
            })
            .collect::<Vec<_>>()
    };
    let results = with_threads(options.threads, run)?;
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    if control.is_stopped() {
        return Err(PgtError::Interrupted);
    }
    let mut image = RgbImage::new(w, h);
    let mut err_image = RgbImage::new(w, h);
    let mut shadow_rays = 0;
    let mut unconverged = 0;
    let mut worst_unconverged: Option<(u32, u32, f64)> = None;
    for (block, rays) in results {
        shadow_rays += rays;
        for (px, py, rad, err, not_converged) in block {
            let i = py as usize * w as usize + px as usize;
            (image.pixels[i], err_image.pixels[i]) = stored_pixel(rad, err);
            if not_converged {
                unconverged += 1;
                worst_unconverged =
                    worse_unconverged(worst_unconverged, (px, py, err.max_element()));
            }
        }
    }
    let pixels = w as u64 * h as u64;
    let (error, max_error, mean_error) = if estimator.estimates_error() {
        let values = err_image.pixels.iter().flatten().map(|&v| v as f64);
        let (max, sum) = values.fold((0.0f64, 0.0f64), |(m, s), v| (m.max(v), s + v));
        (Some(err_image), Some(max), Some(sum / (3 * pixels) as f64))
    } else {
        (None, None, None)
    };
    Ok(RenderOutput {
        image,
        error,
        stats: RenderStats {
            pixels,
            primary_rays: pixels * (k * k) as u64,
            shadow_rays,
            seconds: start.elapsed().as_secs_f64(),
            max_error,
            mean_error,
            unconverged,
            worst_unconverged,
        },
    })
}

/// One pixel: the mean of k×k stratified samples at the sub-pixel centres (docs/design.md §1 camera
/// convention, `--spp k`), as (radiance, error estimate, shadow rays, whether a sample did not
/// converge). Every renderer of whole
/// images or parts goes through this one function, so a pixel is the same bits wherever it is
/// rendered.
pub fn render_pixel(
    camera: &Camera,
    estimator: &dyn RadianceEstimator,
    px: u32,
    py: u32,
    k: u32,
) -> (DVec3, DVec3, u64, bool) {
    let inv_n = 1.0 / (k * k) as f64;
    let mut radiance = DVec3::ZERO;
    let mut error = DVec3::ZERO;
    let mut shadow_rays = 0;
    let mut unconverged = false;
    for sy in 0..k {
        for sx in 0..k {
            let x = px as f64 + (sx as f64 + 0.5) / k as f64;
            let y = py as f64 + (sy as f64 + 0.5) / k as f64;
            let s = estimator.radiance(&camera.ray_at(x, y));
            radiance += s.radiance;
            error += s.error;
            shadow_rays += s.shadow_rays;
            unconverged |= s.unconverged;
        }
    }
    (radiance * inv_n, error * inv_n, shadow_rays, unconverged)
}

/// The float32 values stored for a pixel's f64 radiance and error estimate (the image and its
/// `err` layer, which also covers the rounding to float32: [`stored_error`]), shared by
/// whole-image and part renders so both store the same bits.
#[inline]
pub fn stored_pixel(radiance: DVec3, error: DVec3) -> ([f32; 3], [f32; 3]) {
    let stored = radiance.as_vec3();
    (stored.to_array(), stored_error(radiance, stored, error))
}

/// The worse of two unconverged pixels (x, y, largest error estimate): the larger estimate,
/// ties to the first in row-major order, so the answer is the same for any thread count.
pub fn worse_unconverged(
    worst: Option<(u32, u32, f64)>,
    (px, py, e): (u32, u32, f64),
) -> Option<(u32, u32, f64)> {
    match worst {
        Some((x, y, w)) if !(e > w || (e == w && (py, px) < (y, x))) => worst,
        _ => Some((px, py, e)),
    }
}

/// docs/design.md §3 and §9: a pixel whose err exceeds `tol` beyond the float32 storage of its
/// value is reported too (err also bounds what the reference leaves out: with Gaussians, the
/// depth beyond the cut-off of k σ, so a small `gaussian_cutoff` makes err large everywhere).
/// The float32 rounding of the stored value (part 5 of err, up to one spacing of float32 at the
/// value with err's rounding up) is not counted: a tol below it is no news. The count and the
/// pixel with the largest err, or `None` when every err is within `tol` so far.
pub fn err_above_tol_warning(
    image: &RgbImage,
    err: &RgbImage,
    tol: f64,
    scene: &Scene,
) -> Option<String> {
    let mut count = 0u64;
    let mut worst: Option<(u32, u32, f64)> = None;
    for (i, (e, v)) in err.pixels.iter().zip(&image.pixels).enumerate() {
        let above = (0..3).any(|c| {
            let a = v[c].abs();
            let storage = f64::from(f32::from_bits(a.to_bits() + 1) - a);
            f64::from(e[c]) > tol + storage
        });
        if above {
            count += 1;
            let (px, py) = (
                (i % err.width as usize) as u32,
                (i / err.width as usize) as u32,
            );
            worst = worse_unconverged(worst, (px, py, f64::from(e[0].max(e[1]).max(e[2]))));
        }
    }
    let (x, y, e) = worst?;
    let gaussians = scene
        .particles
        .iter()
        .any(|p| p.profile == crate::optics::Profile::Gaussian);
    let why = match (gaussians, scene.render.gaussian_cutoff) {
        (true, Some(k)) => format!(
            ": it bounds the depth of the Gaussians the rays pass beyond the cut-off gaussian_cutoff = {k} σ; a larger cut-off (or none, to choose it from tol) makes it smaller"
        ),
        (true, None) => {
            ": it bounds what the rays leave out (Gaussian tails, and with scattering lights the shadow rays' missed depth)".to_string()
        }
        (false, _) => String::new(),
    };
    Some(format!(
        "{count} pixel(s) have err above tol {tol:e}; the largest is {e:.3e} at ({x}, {y}){why}"
    ))
}

/// Runs `work` on a pool of `threads` workers (`--threads`), or on rayon's global pool.
pub(crate) fn with_threads<T: Send>(
    threads: Option<usize>,
    work: impl FnOnce() -> T + Send,
) -> Result<T> {
    match threads {
        Some(n) => Ok(rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .map_err(|e| PgtError::Usage(format!("cannot start {n} threads: {e}")))?
            .install(work)),
        None => Ok(work()),
    }
}

/// The `err` value stored for a pixel (docs/design.md §3: err bounds |stored − true|): the estimate
/// plus the rounding of the f64 radiance to the stored f32 (|f32(L) − L|, at most half an ulp),
/// per channel, rounded up to the next f32 so that storing it cannot make it smaller.
fn stored_error(radiance: DVec3, stored: glam::Vec3, error: DVec3) -> [f32; 3] {
    let mut out = [0.0f32; 3];
    for c in 0..3 {
        let bound = error[c] + (stored[c] as f64 - radiance[c]).abs();
        out[c] = round_up_f32(bound);
    }
    out
}

/// The smallest f32 ≥ v (v ≥ 0; NaN and +∞ pass through).
fn round_up_f32(v: f64) -> f32 {
    let f = v as f32;
    if (f as f64) < v && f.is_finite() {
        // Positive and finite here (v ≥ 0): the next representable f32 above.
        f32::from_bits(f.to_bits() + 1)
    } else {
        f
    }
}

#[cfg(test)]
mod tests {
    use super::err_above_tol_warning;
    use crate::image_io::RgbImage;
    use crate::scene::{Scene, SceneLoadOptions};
    use std::path::Path;

    fn scene(text: &str) -> Scene {
        Scene::from_toml_str(text, Path::new("s.toml"), &SceneLoadOptions::default()).unwrap()
    }

    #[test]
    fn err_above_tol_is_reported_beyond_the_float32_storage_of_the_value() {
        let spheres = scene("[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n");
        let mut image = RgbImage::new(2, 1);
        let mut err = RgbImage::new(2, 1);
        image.pixels = vec![[0.5; 3], [0.5; 3]];
        // Float32's spacing at 0.5 is 5.96e-8: err 1.2e-7 at tol 1e-7 is the storage alone.
        err.pixels = vec![[1.2e-7; 3], [1.2e-7; 3]];
        assert_eq!(err_above_tol_warning(&image, &err, 1e-7, &spheres), None);
        err.pixels[1] = [0.0, 2.0e-7, 0.0];
        let w = err_above_tol_warning(&image, &err, 1e-7, &spheres).expect("a warning");
        assert!(
            w.starts_with("1 pixel(s) have err above tol 1e-7") && w.contains("at (1, 0)"),
            "{w}"
        );
        assert!(!w.contains("Gaussian"), "{w}");
        let cut = scene(
            "[render]\nmodel = \"emission\"\ngaussian_cutoff = 1.0\n[defaults]\ndensity = \"gaussian\"\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n",
        );
        let w = err_above_tol_warning(&image, &err, 1e-7, &cut).expect("a warning");
        assert!(w.contains("gaussian_cutoff = 1 σ"), "{w}");
    }
}

//! The reference over a subset of the image's rows: the unit of work of a part of a cluster
//! render (`pgt render --tile I/N`, see [`crate::parts`]). Each pixel goes through the same
//! [`render_pixel`] and [`stored_pixel`] as a whole-image render, and a pixel is a pure function
//! of the scene (docs/design.md §3: bit-identical for any thread count), so the rows of a part hold
//! exactly the bits the one-machine render holds there.

use super::{
    estimator_for, render_pixel, stored_pixel, worse_unconverged, RenderOptions, RenderStats,
};
use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use crate::scene::Scene;
use rayon::prelude::*;
use std::time::Instant;

/// Some rows of a reference render, stacked in the order asked for.
#[derive(Debug, Clone)]
pub struct RowsOutput {
    /// The rows' radiance: the full image width, one image row per requested row.
    pub image: RgbImage,
    /// The rows' error estimate, where the renderer has one.
    pub error: Option<RgbImage>,
    pub stats: RenderStats,
}

/// Renders the image rows `rows` (0 = top) of `scene` with the renderer its mode and model call
/// for, in parallel over rows.
pub fn render_rows(scene: &Scene, options: &RenderOptions, rows: &[u32]) -> Result<RowsOutput> {
    let start = Instant::now();
    let estimator = estimator_for(scene, options)?;
    let camera = &scene.camera;
    let w = camera.width;
    if let Some(&bad) = rows.iter().find(|&&y| y >= camera.height) {
        return Err(PgtError::Usage(format!(
            "row {bad} is outside the image of height {}",
            camera.height
        )));
    }
    let bar = options
        .progress
        .then(|| indicatif::ProgressBar::new(rows.len() as u64));
    let k = options.spp;
    let run = || {
        rows.par_iter()
            .map(|&py| {
                let mut radiance = Vec::with_capacity(w as usize);
                let mut error = Vec::with_capacity(w as usize);
                let mut shadow_rays = 0u64;
                let (mut unconverged, mut worst) = (0u64, None);
                for px in 0..w {
                    let (rad, err, rays, not_converged) =
                        render_pixel(camera, estimator.as_ref(), px, py, k);
                    let (r, e) = stored_pixel(rad, err);
                    radiance.push(r);
                    error.push(e);
                    shadow_rays += rays;
                    if not_converged {
                        unconverged += 1;
                        worst = worse_unconverged(worst, (px, py, err.max_element()));
                    }
                }
                if let Some(bar) = &bar {
                    bar.inc(1);
                }
                (radiance, error, shadow_rays, unconverged, worst)
            })
            .collect::<Vec<_>>()
    };
    let results = super::with_threads(options.threads, run)?;
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let height = rows.len() as u32;
    let mut image = RgbImage::new(w, height);
    let mut err_image = RgbImage::new(w, height);
    image.pixels.clear();
    err_image.pixels.clear();
    let mut shadow_rays = 0;
    let (mut unconverged, mut worst_unconverged) = (0, None);
    for (radiance, error, rays, row_unconverged, row_worst) in results {
        image.pixels.extend(radiance);
        err_image.pixels.extend(error);
        shadow_rays += rays;
        unconverged += row_unconverged;
        if let Some(p) = row_worst {
            worst_unconverged = worse_unconverged(worst_unconverged, p);
        }
    }
    let pixels = w as u64 * height as u64;
    let (error, max_error, mean_error) = if estimator.estimates_error() {
        let values = err_image.pixels.iter().flatten().map(|&v| v as f64);
        let (max, sum) = values.fold((0.0f64, 0.0f64), |(m, s), v| (m.max(v), s + v));
        let mean = sum / (3 * pixels).max(1) as f64;
        (Some(err_image), Some(max), Some(mean))
    } else {
        (None, None, None)
    };
    Ok(RowsOutput {
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

//! The exact reference on the GPU in f64 (docs/design.md §12): `pgt render --gpu`.
//!
//! Gaussian particles take their own program ([`gaussian`]). For spheres and ellipsoids:
//! the emission model, closed form per interval as on the CPU
//! (`optics::emission`), computed by `shaders/reference_emission.wgsl` one invocation per camera
//! ray, over the approximations' BVH (`approx::layout`). The CPU makes the rays
//! (`Camera::ray_at`, the sub-pixel samples of `reference::render_pixel`), so both renderers trace
//! the same f64 rays; the GPU returns per ray the radiance and the parts of its error bound, and
//! the pixels are averaged and stored as the CPU stores them (`reference::stored_pixel`).
//!
//! **err** has the CPU's meaning (docs/design.md §3 "What err guarantees"): a bound on
//! |stored − true| per pixel channel, where "true" is the emission integral along the exact ray
//! through the sample position. Its parts ([`ray_error`]):
//! * the chord ends: each end's distance from the exact one, bounded through the stable
//!   intersection step by step (the ray's direction error [`direction_error`], the
//!   subtraction o − c, every rounding), becomes optical depth σ·δt, and a sliver of depth δτ in
//!   front of radiance at most Cmax changes L by at most δτ·Cmax per channel;
//! * the composite's rounding: relative bounds carried through σ, S, τ, the opacity and the
//!   running T, with the ulp bounds of the f64 exp and expm1 ([`math::EXP_ULPS`],
//!   [`math::EXPM1_ULPS`]), doubled for the second-order terms;
//! * a ray that stops at T < [`program::T_STOP`]: the middle of what the rest could add;
//! * the float32 rounding of the stored value (`reference::stored_pixel`).
//!
//! Every ray is a pure function of the scene and its direction, and no result depends on the
//! order in which invocations finish (the only atomic counts unfinished rays), so the image is the
//! same bits on every run. The work of one ray per dispatch is bounded (lavapipe's loop limit,
//! `approx::contract::LOOP_BUDGET`): a ray stops after a batch once it has used half the budget
//! and goes on in the next pass, from the last event it took.

pub mod gaussian;
pub mod math;
mod pipeline;
pub mod program;
mod run;

pub use run::{trace, RaySample, Traced};

use super::rows::RowsOutput;
use super::{stored_pixel, RenderOptions, RenderOutput, RenderStats};
use crate::approx::GpuContext;
use crate::error::{PgtError, Result};
use crate::geometry::Camera;
use crate::image_io::RgbImage;
use crate::optics::model::LightNeed;
use crate::scene::{Profile, RenderMode, Scene};
use glam::DVec3;
use std::time::Instant;

/// Why the GPU reference cannot render `scene` with `options`, if it cannot: what it does today
/// is the emission model (a model without lights) of spheres and ellipsoids of constant density,
/// or of Gaussian particles (a scene of one kind), in the volume mode, with the adaptive
/// integrator's meaning of err.
pub fn check_supported(scene: &Scene, options: &RenderOptions) -> Result<()> {
    let refuse = |what: String| {
        Err(PgtError::Gpu(format!(
            "the GPU reference (--gpu) renders the emission model of spheres and ellipsoids of constant density or of Gaussian particles; {what}: render it on the CPU (without --gpu)"
        )))
    };
    if scene.render.mode != RenderMode::Volume {
        return refuse("this scene is in the opaque mode".into());
    }
    let model = scene.render.model;
    if model.light_need() != LightNeed::None {
        return refuse(format!("this scene's model is {}", model.name()));
    }
    let gaussians = scene
        .particles
        .iter()
        .filter(|p| p.profile == Profile::Gaussian)
        .count();
    if gaussians > 0 && gaussians < scene.particles.len() {
        return refuse(
            "this scene mixes Gaussian particles and particles of constant density".into(),
        );
    }
    if options.integrator != super::Integrator::Adaptive {
        return refuse("--integrator riemann is a CPU integrator".into());
    }
    if scene.particles.len() >= 1 << 30 {
        return refuse(format!(
            "{} particles (at most 2^30)",
            scene.particles.len()
        ));
    }
    Ok(())
}

/// Renders `scene` with the GPU reference on an adapter found by `adapter` (a substring of its
/// name, `--adapter`), refusing one without f64 by name.
pub fn render(
    scene: &Scene,
    options: &RenderOptions,
    adapter: Option<&str>,
) -> Result<RenderOutput> {
    check_supported(scene, options)?;
    let ctx = GpuContext::with_f64(adapter)?;
    render_on(&ctx, scene, options)
}

/// [`render`] on an open device (opened with [`GpuContext::with_f64`]).
pub fn render_on(ctx: &GpuContext, scene: &Scene, options: &RenderOptions) -> Result<RenderOutput> {
    let rows: Vec<u32> = (0..scene.camera.height).collect();
    let RowsOutput {
        image,
        error,
        stats,
    } = render_rows_on(ctx, scene, options, &rows)?;
    Ok(RenderOutput {
        image,
        error,
        stats,
    })
}

/// The image rows `rows` (0 = top) of [`render_on`]'s image, stacked in the order asked for: a
/// part of a cluster render (`crate::parts`). Every ray is a pure function of the scene and its
/// direction, so these rows hold the bits the whole image holds there.
pub fn render_rows_on(
    ctx: &GpuContext,
    scene: &Scene,
    options: &RenderOptions,
    rows: &[u32],
) -> Result<RowsOutput> {
    check_supported(scene, options)?;
    check_scene_size(ctx, scene)?;
    let start = Instant::now();
    let camera = &scene.camera;
    let (w, k) = (camera.width, options.spp.max(1));
    if let Some(&bad) = rows.iter().find(|&&y| y >= camera.height) {
        return Err(PgtError::Usage(format!(
            "row {bad} is outside the image of height {}",
            camera.height
        )));
    }
    let h = rows.len() as u32;
    let mut directions = Vec::with_capacity((w * h * k * k) as usize);
    for &py in rows {
        for px in 0..w {
            for sy in 0..k {
                for sx in 0..k {
                    let x = px as f64 + (sx as f64 + 0.5) / k as f64;
                    let y = py as f64 + (sy as f64 + 0.5) / k as f64;
                    directions.push(camera.ray_at(x, y).direction);
                }
            }
        }
    }
    let (samples, unconverged_rays) = if scene.has_gaussians() {
        let traced = gaussian::trace(
            ctx,
            scene,
            camera.position,
            &directions,
            direction_error(camera),
        )?;
        (traced.samples, traced.unconverged)
    } else {
        let traced = trace(
            ctx,
            scene,
            camera.position,
            &directions,
            direction_error(camera),
        )?;
        let none = vec![false; traced.samples.len()];
        (traced.samples, none)
    };
    let n = (k * k) as usize;
    let mut image = RgbImage::new(w, h);
    let mut err_image = RgbImage::new(w, h);
    let mut unconverged = 0;
    let mut worst_unconverged = None;
    for (i, pixel) in samples.chunks_exact(n).enumerate() {
        let (radiance, error) = pixel_mean(pixel);
        (image.pixels[i], err_image.pixels[i]) = stored_pixel(radiance, error);
        if unconverged_rays[i * n..(i + 1) * n].iter().any(|&u| u) {
            unconverged += 1;
            let (px, py) = (i as u32 % w, i as u32 / w);
            worst_unconverged =
                super::worse_unconverged(worst_unconverged, (px, py, error.max_element()));
        }
    }
    let pixels = w as u64 * h as u64;
    let values = err_image.pixels.iter().flatten().map(|&v| v as f64);
    let (max, sum) = values.fold((0.0f64, 0.0f64), |(m, s), v| (m.max(v), s + v));
    Ok(RowsOutput {
        image,
        error: Some(err_image),
        stats: RenderStats {
            pixels,
            primary_rays: pixels * n as u64,
            shadow_rays: 0,
            seconds: start.elapsed().as_secs_f64(),
            max_error: Some(max),
            mean_error: Some(sum / (3 * pixels).max(1) as f64),
            unconverged,
            worst_unconverged,
        },
    })
}

/// Checks the buffers whose sizes the particle count fixes against the adapter's limit before
/// the scene's data and BVH are built (docs/design.md §4 "Buffer limits", §12): the f64 particles
/// and ellipsoids of spheres and ellipsoids, the f64 Gaussians (those of σ > 0, as
/// `GaussianRenderer` keeps them) of a Gaussian scene. The traces check their buffers again
/// once their sizes are known.
pub fn check_scene_size(ctx: &GpuContext, scene: &Scene) -> Result<()> {
    let f64s = |count: usize, stride: usize| (count.max(1) * stride * 8) as u64;
    let particles = &scene.particles;
    if scene.has_gaussians() {
        let kept = particles.iter().filter(|p| p.sigma != 0.0).count();
        let gaussians = f64s(kept, gaussian::GAUSS_STRIDE);
        return ctx.check_buffers(&[("Gaussian", gaussians)], run::TOO_LARGE);
    }
    let ellipsoids = particles.iter().filter(|p| p.ellipsoid.is_some()).count();
    ctx.check_buffers(
        &[
            ("particle", f64s(particles.len(), program::PARTICLE_STRIDE)),
            ("ellipsoid", f64s(ellipsoids, program::ELLIPSOID_STRIDE)),
        ],
        run::TOO_LARGE,
    )
}

/// A bound on how far a ray of `camera` (`Camera::ray_at`, any sample position in the image)
/// lies from the exact unit vector along f + a·r + b·u with the exact a and b of its sample
/// position. With A and B the largest |a| and |b| over the image: the sample position and a
/// carry at most 5u·A + 3u·|a| (the sub-pixel offset, the cancellation in 2x/W − 1, then two
/// products; (x − cx)/fx less), b likewise; f + a·r + b·u adds 3u·(1 + |a| + |b|);
/// |f + a·r + b·u| ≥ 1 (r, u ⊥ f); the normalisation 3u. So u·(6 + 11·(A + B)), taken as
/// u·(8 + 12·(A + B)).
pub fn direction_error(camera: &Camera) -> f64 {
    let (w, h) = (camera.width as f64, camera.height as f64);
    let (a, b) = match &camera.intrinsics {
        None => ((w / h) * camera.tan_half_fov, camera.tan_half_fov),
        Some(k) => (
            k.cx.abs().max((w - k.cx).abs()) / k.fx,
            k.cy.abs().max((h - k.cy).abs()) / k.fy,
        ),
    };
    math::U * (8.0 + 12.0 * (a + b))
}

/// A bound on how far `v.normalize()` lies from the exact unit vector along v: for rays made
/// by normalising an exact (or exactly given) vector.
pub const NORMALIZED_DIRECTION_ERROR: f64 = 4.0 * math::U;

/// The mean of a pixel's samples as `reference::render_pixel` forms it, and its error bound:
/// the samples' bounds averaged, plus the rounding of the mean (k² additions and a product, of
/// non-negative values).
pub fn pixel_mean(samples: &[RaySample]) -> (DVec3, DVec3) {
    let n = samples.len();
    let inv_n = 1.0 / n as f64;
    let mut radiance = DVec3::ZERO;
    let mut error = DVec3::ZERO;
    for s in samples {
        radiance += s.radiance;
        error += s.error;
    }
    let mean = radiance * inv_n;
    if n == 1 {
        return (mean, error);
    }
    let rounding = 2.0 * (n as f64 + 1.0) * math::U;
    (
        mean,
        error * inv_n * (1.0 + rounding) + mean.abs() * rounding,
    )
}

/// A ray's err from what the GPU carried (docs/design.md §12): twice the composite's first-order
/// rounding bound, plus Cmax per unit of the events' optical-depth uncertainty, at most
/// max(L, Cmax) per channel (both L and the truth lie in [0, max(L, Cmax)]).
pub fn ray_error(rounding: DVec3, depth: f64, radiance: DVec3, cmax: DVec3) -> DVec3 {
    let channel = |r: f64, l: f64, c: f64| {
        let geometric = if c > 0.0 { c * depth } else { 0.0 };
        (2.0 * r + geometric).min(l.abs().max(c))
    };
    DVec3::new(
        channel(rounding.x, radiance.x, cmax.x),
        channel(rounding.y, radiance.y, cmax.y),
        channel(rounding.z, radiance.z, cmax.z),
    )
}

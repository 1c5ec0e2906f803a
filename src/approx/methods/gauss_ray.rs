//! # `gauss-ray` — 3D Gaussian ray tracing (3DGRT)
//!
//! The idea of 3DGRT (Moenne-Loccoz et al. 2024, "3D Gaussian Ray Tracing: Fast Tracing of
//! Particle Scenes"), docs/design.md §4: each Gaussian is traced as its 3-σ ellipsoid (the BVH
//! and the shapes the shader intersects are widened to `GAUSSIAN_TRACE_SIGMAS` = 3 standard
//! deviations before the upload); a Gaussian whose 3-σ ellipsoid the ray crosses contributes
//! α = min(0.99, o·exp(−½m*²)) at the depth t* of its maximum response along the ray (m* the
//! Mahalanobis distance at t*, t* clamped to t ≥ 0), o its splatting opacity
//! 1 − exp(−σ·s_min·√(2π)) (docs/design.md §9). The hits are blended front to back in order
//! of t*; the ray stops at the first hit that would take the transmittance below 1e-4 (not
//! added; 3DGS's rule and constant, as `splat`). They are taken a batch at a time, as `ever`
//! takes its events: each batch is one BVH traversal that keeps the `GAUSS_RAY_BATCH` = 16
//! nearest hits by (t*, particle index) beyond the last one blended (3DGRT's k nearest hits per
//! trace), so no hit list overflows (`shaders/gauss_ray.wgsl`). No α < 1/255 skip: every traced
//! hit counts. Volume mode, emission model, Gaussian particles only; spheres and ellipsoids.
//!
//! Parameters: none.
//!
//! ```sh
//! pgt approx gaussians.toml --method gauss-ray -o gauss_ray.exr
//! ```

use crate::approx::shader::{WgslModule, NEAREST_EVENTS};
use super::{ApproxMethod, Computes, Preparation};
use crate::approx::contract::GAUSSIAN_TRACE_SIGMAS;
use crate::optics::models;

/// The `gauss-ray` method (see the module docs).
pub struct GaussRay;

impl ApproxMethod for GaussRay {
    fn name(&self) -> &'static str {
        "gauss-ray"
    }
    fn summary(&self) -> &'static str {
        "3D Gaussian ray tracing: 3-σ ellipsoids in the BVH, α = min(0.99, o·e^{−½m*²}) at the peak t*, front to back by t*; Gaussians only, volume mode"
    }
    fn wgsl_path(&self) -> &'static str {
        "shaders/gauss_ray.wgsl"
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../../shaders/gauss_ray.wgsl")
    }
    fn modules(&self) -> &'static [WgslModule] {
        &[NEAREST_EVENTS]
    }
    fn computes(&self) -> Computes {
        Computes::Volume(&[models::EMISSION])
    }
    fn draws_gaussians(&self) -> bool {
        true
    }
    fn preparation(&self) -> Preparation {
        Preparation {
            traced_sigmas: Some(GAUSSIAN_TRACE_SIGMAS as f64),
            ..Preparation::default()
        }
    }
}

//! # `splat` — the forward model of 3D Gaussian splatting's rasteriser
//!
//! What the reference 3D Gaussian splatting rasteriser (graphdeco-inria
//! `diff-gaussian-rasterization`, `cuda_rasterizer/forward.cu`) draws, docs/design.md §4:
//! each Gaussian projected to a 2D Gaussian by EWA, Σ₂D = J·W·Σ·Wᵀ·Jᵀ with J the perspective
//! Jacobian at the centre (x/z, y/z clamped to 1.3·tan of the half field of view), +0.3 px² on
//! the diagonal, a footprint of radius ⌈3·√λ_max⌉ px binned into 16×16-pixel tiles, one global
//! sort by the centres' view depth, and per pixel, front to back, α = min(0.99, o·G₂D), splats
//! with α < 1/255 skipped, stopping at the first splat that would take T below 1e-4:
//! L = Σ αᵢTᵢCᵢ + T·L_bg (`shaders/splat.wgsl`). o is the Gaussian's splatting opacity,
//! 1 − exp(−σ·s_min·√(2π)) (docs/design.md §9). The constants and where they are in 3DGS:
//!
//! | constant | value | 3DGS |
//! |---|---|---|
//! | near culling | view depth ≤ 0.2 | `auxiliary.h` `in_frustum` |
//! | Jacobian clamp | 1.3·tan(fov/2) | `forward.cu` `computeCov2D` (`limx`, `limy`) |
//! | dilation | +0.3 px² | `forward.cu` `computeCov2D` |
//! | footprint | ⌈3·√max(λ₁, λ₂)⌉, discriminant ≥ 0.1 | `forward.cu` `preprocessCUDA`, `getRect` |
//! | tile | 16×16 px | `config.h` `BLOCK_X`, `BLOCK_Y` |
//! | α cap, skip | 0.99, 1/255 | `forward.cu` `renderCUDA` |
//! | stop | T·(1 − α) < 1e-4, tested before adding | `forward.cu` `renderCUDA` |
//!
//! The projection, binning and sort run **on the CPU in f32** before the dispatch
//! (`approx::splat_tiles`: pgt's dispatch has one per-pixel pass and no place for a
//! preprocessing pass); their time is counted in the method's time. The blending is on the GPU,
//! one invocation per pixel walking its tile's list. Volume mode, emission model, Gaussian
//! particles only (a scene with a constant-density particle is refused by name); spheres and
//! ellipsoids.
//!
//! Parameters: none.
//!
//! ```sh
//! pgt approx gaussians.toml --method splat -o splat.exr
//! ```

use super::{ApproxMethod, Computes, Preparation};
use crate::optics::models;

/// The `splat` method (see the module docs).
pub struct Splat;

impl ApproxMethod for Splat {
    fn name(&self) -> &'static str {
        "splat"
    }
    fn summary(&self) -> &'static str {
        "3D Gaussian splatting's rasteriser: EWA footprints in 16×16 tiles, one sort by centre depth, α = min(0.99, o·G₂D) front to back; Gaussians only, volume mode"
    }
    fn wgsl_path(&self) -> &'static str {
        "shaders/splat.wgsl"
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../../shaders/splat.wgsl")
    }
    fn computes(&self) -> Computes {
        Computes::Volume(&[models::EMISSION])
    }
    fn draws_gaussians(&self) -> bool {
        true
    }
    fn preparation(&self) -> Preparation {
        Preparation {
            splat_tiles: true,
            ..Preparation::default()
        }
    }
}

//! # `splat-pixel-sort` — `splat` with a per-pixel order by the depth of maximum response
//!
//! StopThePop's idea (Radl et al. 2024, "StopThePop: Sorted Gaussian Splatting for
//! View-Consistent Real-time Rendering"), docs/design.md §4: everything as `splat` (EWA
//! footprints, 16×16 tiles, α = min(0.99, o·G₂D), α < 1/255 skipped, stop below T = 1e-4), but
//! each pixel orders the splats of its tile by the depth t* of each Gaussian's maximum response
//! along the pixel's ray (its closest approach in the Gaussian's Mahalanobis metric), not by the
//! centres' view depth (`shaders/splat_pixel_sort.wgsl`). A pixel keeps the `MAX_HITS` nearest
//! by t* (an overflow is reported). StopThePop sorts hierarchically with small windows; this
//! sorts each pixel's list exactly. The projection and tile lists are `splat`'s, on the CPU.
//! Volume mode, emission model, Gaussian particles only.
//!
//! Parameters: none.
//!
//! ```sh
//! pgt approx gaussians.toml --method splat-pixel-sort -o sorted.exr
//! ```

use super::{ApproxMethod, Computes, Preparation};
use crate::optics::models;

/// The `splat-pixel-sort` method (see the module docs).
pub struct SplatPixelSort;

impl ApproxMethod for SplatPixelSort {
    fn name(&self) -> &'static str {
        "splat-pixel-sort"
    }
    fn summary(&self) -> &'static str {
        "splat with each pixel's splats ordered by the depth of maximum response along its ray (StopThePop); Gaussians only, volume mode"
    }
    fn wgsl_path(&self) -> &'static str {
        "shaders/splat_pixel_sort.wgsl"
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../../shaders/splat_pixel_sort.wgsl")
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

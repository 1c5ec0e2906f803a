//! # `sorted-blend` — centre-sorted whole-particle blending, as rasterisers do
//!
//! What real-time renderers do with transparent particles (3D Gaussian splatting, Mol* and
//! MegaMol transparency), docs/design.md §4: the particles hit by a ray are sorted by the view-space
//! depth of their centres, dot(centre − eye, camera forward), and each is composited whole,
//! back to front, with the emission model's closed form over its own chord,
//! L = L_behind·T + C·(1 − T) (`shaders/sorted_blend.wgsl`). It equals the exact emission model
//! where particles are disjoint and centre order is entry order (e.g. spheres in separate slabs
//! along the view axis); overlaps and large particles behind small ones show its error. It
//! implements the emission model in volume mode; a scene of another mode or model is refused
//! (`--model emission` approximates a lit scene's emission model on purpose).
//!
//! Parameters: none.
//!
//! ```sh
//! pgt approx scene.toml --method sorted-blend -o sorted.exr
//! ```

use super::{ApproxMethod, Computes};
use crate::optics::models;

/// The `sorted-blend` method (see the module docs).
pub struct SortedBlend;

impl ApproxMethod for SortedBlend {
    fn name(&self) -> &'static str {
        "sorted-blend"
    }
    fn summary(&self) -> &'static str {
        "rasteriser-style: sorted by centre depth, each particle whole with the emission closed form, back to front; volume mode"
    }
    fn wgsl_path(&self) -> &'static str {
        "shaders/sorted_blend.wgsl"
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../../shaders/sorted_blend.wgsl")
    }
    fn computes(&self) -> Computes {
        Computes::Volume(&[models::EMISSION])
    }
}

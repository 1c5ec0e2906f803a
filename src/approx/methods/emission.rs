//! # `emission` — per-particle compositing with the emission model's closed form
//!
//! The particles a camera ray crosses, sorted by entry and composited back to front with
//! docs/design.md §2's closed form L = L_behind·T + C·(1 − T) per particle (`shaders/emission.wgsl`).
//! Exact where particles do not overlap. It implements the emission model in volume mode; a
//! scene of another mode or model is refused (`--model emission` approximates a lit scene's
//! emission model on purpose).
//!
//! Parameters: none.
//!
//! ```sh
//! pgt approx scene.toml --method emission -o emission.exr
//! ```

use super::{ApproxMethod, Computes};
use crate::optics::models;

/// The `emission` method (see the module docs).
pub struct Emission;

impl ApproxMethod for Emission {
    fn name(&self) -> &'static str {
        "emission"
    }
    fn summary(&self) -> &'static str {
        "per-particle closed-form emission compositing, sorted by entry (exact without overlaps); volume mode"
    }
    fn wgsl_path(&self) -> &'static str {
        "shaders/emission.wgsl"
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../../shaders/emission.wgsl")
    }
    fn computes(&self) -> Computes {
        Computes::Volume(&[models::EMISSION])
    }
}

//! # `emission` — per-particle compositing with the emission model's closed form
//!
//! The particles a camera ray crosses, sorted by entry and composited back to front with
//! docs/design.md §2's closed form L = L_behind·T + C·(1 − T) per particle (`shaders/emission.wgsl`).
//! Exact where particles do not overlap; the scene's optical model is ignored (the emission
//! model is used). Volume mode only.
//!
//! Parameters: none.
//!
//! ```sh
//! pgt approx scene.toml --method emission -o emission.exr
//! ```

use super::ApproxMethod;
use crate::error::{PgtError, Result};
use crate::scene::{RenderMode, Scene};

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
    fn check_scene(&self, scene: &Scene) -> Result<()> {
        if scene.render.mode == RenderMode::Opaque {
            return Err(PgtError::Usage(
                "the emission method renders gas (volume mode); this scene is in opaque mode: use --method opaque or --mode volume".into(),
            ));
        }
        Ok(())
    }
}

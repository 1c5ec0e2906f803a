//! # `opaque` — opaque spheres: first hit, Lambert + Blinn–Phong, hard shadows
//!
//! docs/design.md §2 "Opaque mode" as `src/reference/opaque.rs` defines it, in f32
//! (`shaders/opaque.wgsl`): the first sphere hit, Lambertian C/π plus normalised Blinn–Phong,
//! one shadow ray per light through the BVH, plus the scene's `ambient`·C. Opaque mode; a
//! volume-mode scene is refused (`--mode opaque` draws it solid on purpose).
//!
//! Parameters: none.
//!
//! ```sh
//! pgt approx examples/shadows.toml --method opaque -o opaque.png
//! ```

use super::{ApproxMethod, Computes};

/// The `opaque` method (see the module docs).
pub struct Opaque;

impl ApproxMethod for Opaque {
    fn name(&self) -> &'static str {
        "opaque"
    }
    fn summary(&self) -> &'static str {
        "opaque spheres: first hit, Lambert + Blinn–Phong, hard shadows through the BVH; any scene"
    }
    fn wgsl_path(&self) -> &'static str {
        "shaders/opaque.wgsl"
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../../shaders/opaque.wgsl")
    }
    fn computes(&self) -> Computes {
        Computes::Opaque
    }
}

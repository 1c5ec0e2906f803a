//! # `thesis` — the thesis's scheme (chapter 5)
//!
//! The particles a camera ray crosses, sorted by entry and composited one particle at a time
//! (overlaps ignored, docs/design.md §4 and §8). The first `n_exact` particles from the eye use the
//! lit model (docs/design.md §2, thesis eq. 4.17) with `samples` midpoint-rule samples along their
//! chord and one shadow ray per sample per light; the rest, and every particle of an
//! emission-model scene, use the emission model's closed form (`shaders/thesis.wgsl`). Volume
//! mode, `emission` or `lit` model. On a Cpu adapter (lavapipe) the lit samples are spread over
//! several passes (`dispatch::PassSchedule`).
//!
//! | parameter | default | range | meaning |
//! |---|---|---|---|
//! | `samples` | 100 | 1..=16777216 | midpoint-rule samples per particle chord (thesis ch. 6 uses 100) |
//! | `n_exact` | all | 0..=all | particles from the eye that get the lit model; the rest get the emission model |
//!
//! ```sh
//! pgt approx scene.toml --method thesis --samples 100 --n-exact 5 -o thesis.exr
//! ```

use super::{ApproxMethod, Computes};
use crate::approx::param_spec::{ParamSpec, N_EXACT_ALL};
use crate::optics::models;

/// The `thesis` method (see the module docs).
pub struct Thesis;

/// The parameters. `samples` is bounded so that the work index k·samples + j of the WGSL
/// (k < `MAX_HITS` = 2⁷) stays within u32.
const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "samples",
        quiet_default: false,
        default: 100,
        min: 1,
        max: 1 << 24,
        doc: "midpoint-rule samples per particle chord (thesis ch. 6 uses 100)",
    },
    ParamSpec {
        name: "n_exact",
        quiet_default: false,
        default: N_EXACT_ALL,
        min: 0,
        max: N_EXACT_ALL,
        doc: "particles from the eye that get the lit model; the rest get the emission model",
    },
];

impl ApproxMethod for Thesis {
    fn name(&self) -> &'static str {
        "thesis"
    }
    fn summary(&self) -> &'static str {
        "the thesis's chapter 5: sorted by entry, back to front per particle, lit model by midpoint samples for the first n_exact; volume mode, emission or lit model"
    }
    fn wgsl_path(&self) -> &'static str {
        "shaders/thesis.wgsl"
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../../shaders/thesis.wgsl")
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    fn computes(&self) -> Computes {
        Computes::Volume(&[models::EMISSION, models::LIT])
    }
}

//! # `emission`: glowing gas, no lights
//!
//! | | |
//! |---|---|
//! | docs/design.md | §2, emission model (thesis 4.1, eq. 4.11) |
//! | source | Q(x) = E(x) = Σσᵢ·Cᵢ / Σσᵢ over the particles that contain x |
//! | constant part | k = 1: Q = E |
//! | per light | none: no shadow rays; L_in = L_out·e^{−σΔ} + E·(1 − e^{−σΔ}) per interval, exact |
//! | Θmax = 1 limit | E of the entry point |
//! | parameters | none |
//!
//! ```toml
//! [render]
//! model = "emission"
//! ```
//! One particle alone gives exactly L = L_bg·T + C·(1 − T).

use crate::optics::intervals::Interval;
use crate::optics::model::{LightNeed, OpticalModel};
use crate::optics::source::{LightSample, SourceParams};
use glam::DVec3;

/// The emission model (module documentation).
pub struct Emission;

impl OpticalModel for Emission {
    fn name(&self) -> &'static str {
        "emission"
    }

    fn summary(&self) -> &'static str {
        "glowing gas: Q = E, the σ-weighted particle colour (thesis eq. 4.11)"
    }

    fn light_need(&self) -> LightNeed {
        LightNeed::None
    }

    fn emission_factor(&self, _: &SourceParams) -> f64 {
        1.0
    }

    fn light_source(&self, _: &SourceParams, _: &Interval, _: &LightSample) -> DVec3 {
        DVec3::ZERO
    }

    /// docs/design.md §2, emission model: Q(x) = E(x).
    fn source(&self, _: &SourceParams, interval: &Interval, _: &[LightSample]) -> DVec3 {
        interval.emission
    }
}

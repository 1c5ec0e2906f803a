//! # `lit`: gas that glows with the light that reaches it
//!
//! | | |
//! |---|---|
//! | docs/design.md | §2, lit model (thesis 4.2, eq. 4.17; the factor σ of §8 is the renderer's) |
//! | source | Q(x) = w·Σ_l L_l(x) |
//! | constant part | k = 0 |
//! | per light | w·L_l(x): the emission model along the shadow ray from x towards l, the light's E (or I/d²) as its background, the particle containing x included |
//! | Θmax = 1 limit | L_l,∞ = L_l,rest/(1 + c) + E·c/(1 + c) (`reference::volume`) |
//! | parameters | `light_weight`: `"mean"` w = 1/m (default), `"sum"` w = 1 |
//!
//! ```toml
//! [render]
//! model = "lit"
//! light_weight = "mean"
//! ```
//! Light changes colour as it passes through coloured gas (thesis task 3).

use crate::optics::intervals::Interval;
use crate::optics::model::{LightNeed, OpticalModel};
use crate::optics::source::{LightSample, SourceParams};
use glam::DVec3;

/// The lit model (module documentation).
pub struct Lit;

impl OpticalModel for Lit {
    fn name(&self) -> &'static str {
        "lit"
    }

    fn summary(&self) -> &'static str {
        "gas lit through gas: Q = w·Σ L_l, the emission model along each shadow ray (thesis eq. 4.17)"
    }

    fn light_need(&self) -> LightNeed {
        LightNeed::Radiance
    }

    fn emission_factor(&self, _: &SourceParams) -> f64 {
        0.0
    }

    /// w·L_l(x).
    #[inline]
    fn light_source(&self, params: &SourceParams, _: &Interval, light: &LightSample) -> DVec3 {
        params.light_weight * light.radiance
    }

    /// docs/design.md §2, lit model: Q(x) = w·Σ_l L_l(x).
    fn source(&self, params: &SourceParams, _: &Interval, lights: &[LightSample]) -> DVec3 {
        let mut sum = DVec3::ZERO;
        for l in lights {
            sum += l.radiance;
        }
        params.light_weight * sum
    }
}

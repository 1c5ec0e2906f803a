//! # `single-scatter`: emission plus light scattered once, isotropically
//!
//! | | |
//! |---|---|
//! | docs/design.md | §2, single-scatter model (the physical one) |
//! | source | Q(x) = a·E(x) + α(x)·(1/4π)·Σ_l E_l(x)·T_l(x) |
//! | constant part | k = a: a·E(x), E the σ-weighted particle colour |
//! | per light | α(x)·E_l(x)·T_l(x)/4π: isotropic phase, α the σ-weighted albedo, E_l the unoccluded irradiance (I/d² for point lights), T_l the transmittance to the light through all particles |
//! | Θmax = 1 limit | T_l,∞ = T_l,rest/(1 + c) (`reference::volume`) |
//! | parameters | `emission_weight` a ∈ [0, 1] (default 1); per particle `albedo` (default its colour) |
//!
//! ```toml
//! [render]
//! model = "single-scatter"
//! emission_weight = 0.0
//! ```

use crate::optics::intervals::Interval;
use crate::optics::model::{LightNeed, OpticalModel};
use crate::optics::source::{LightSample, SourceParams};
use glam::DVec3;
use std::f64::consts::PI;

/// The single-scatter model (module documentation).
pub struct SingleScatter;

impl OpticalModel for SingleScatter {
    fn name(&self) -> &'static str {
        "single-scatter"
    }

    fn summary(&self) -> &'static str {
        "emission a·E plus single isotropic scattering α·Σ E_l·T_l/4π"
    }

    fn light_need(&self) -> LightNeed {
        LightNeed::IrradianceTransmittance
    }

    fn emission_factor(&self, params: &SourceParams) -> f64 {
        params.emission_weight
    }

    /// α(x)·E_l(x)·T_l(x)/4π.
    #[inline]
    fn light_source(&self, _: &SourceParams, interval: &Interval, light: &LightSample) -> DVec3 {
        interval.albedo * (light.irradiance * light.transmittance) / (4.0 * PI)
    }

    /// docs/design.md §2, single-scatter model: Q(x) = a·E(x) + α(x)·(1/4π)·Σ_l E_l(x)·T_l(x).
    fn source(&self, params: &SourceParams, interval: &Interval, lights: &[LightSample]) -> DVec3 {
        let mut inscatter = DVec3::ZERO;
        for l in lights {
            inscatter += l.irradiance * l.transmittance;
        }
        params.emission_weight * interval.emission + interval.albedo * inscatter / (4.0 * PI)
    }
}

//! The vocabulary the source terms Q of docs/design.md §2 share: what a shadow ray found
//! ([`LightSample`]), the scene's parameters of the models ([`SourceParams`]) and the weight of
//! the Θmax = 1 surface limit. The models themselves are in `models/`, one file each; the
//! renderer traces the shadow rays.

use super::light::LightWeight;
use glam::DVec3;

pub use super::light::light_weight;

/// What one shadow ray from a point x towards light l found.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LightSample {
    /// L_l(x): the emission model along the shadow ray with the light's arriving irradiance as
    /// its background (docs/design.md §2, lit model). Zero where the model needs only E_l and T_l
    /// (`LightNeed::IrradianceTransmittance`): the renderer does not trace it then.
    pub radiance: DVec3,
    /// E_l(x): the unoccluded irradiance (E, or I/d²).
    pub irradiance: DVec3,
    /// T_l(x): the transmittance of all particles between x and the light.
    pub transmittance: f64,
}

impl LightSample {
    /// The σ → ∞ limit of this sample at the entry point of a Θmax = 1 particle of colour
    /// `emission`, where `self` is the shadow ray without that particle and `keep` =
    /// [`surface_limit_weight`]`(c)` (see `reference::volume`, "Θmax = 1"):
    /// L_l,∞ = L_l,rest·keep + E·(1 − keep), T_l,∞ = T_l,rest·keep.
    #[inline]
    pub fn surface_limit(&self, keep: f64, emission: DVec3) -> LightSample {
        LightSample {
            radiance: self.radiance * keep + emission * (1.0 - keep),
            irradiance: self.irradiance,
            transmittance: self.transmittance * keep,
        }
    }
}

/// The scene's parameters of the source terms (docs/design.md §1 `[render]`), resolved once per
/// render so that the models' per-node work is arithmetic only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SourceParams {
    /// w of the lit model ([`light_weight`]).
    pub light_weight: f64,
    /// a of the single-scatter model, `emission_weight` ∈ [0, 1].
    pub emission_weight: f64,
}

impl SourceParams {
    /// Resolves `light_weight` for `lights` lights; `emission_weight` is taken as it is.
    pub fn new(weight: LightWeight, lights: usize, emission_weight: f64) -> Self {
        SourceParams {
            light_weight: light_weight(weight, lights),
            emission_weight,
        }
    }
}

/// The weight 1/(1 + c) with which the light that reaches the entry point of a Θmax = 1 particle
/// from outside survives, in the limit σ → ∞ (see `reference::volume`, "Θmax = 1"):
/// ∫₀^∞ e^{−u}·e^{−c·u} du = 1/(1 + c). c = +∞ (the light lies behind the surface) gives 0.
#[inline]
pub fn surface_limit_weight(c: f64) -> f64 {
    if c.is_infinite() {
        0.0
    } else {
        1.0 / (1.0 + c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_limit_blends_towards_the_particle() {
        assert_eq!(surface_limit_weight(f64::INFINITY), 0.0);
        assert_eq!(surface_limit_weight(1.0), 0.5);
        let rest = LightSample {
            radiance: DVec3::new(2.0, 0.0, 4.0),
            irradiance: DVec3::ONE,
            transmittance: 0.5,
        };
        let l = rest.surface_limit(0.5, DVec3::new(0.0, 2.0, 0.0));
        assert_eq!(l.radiance, DVec3::new(1.0, 1.0, 2.0));
        assert_eq!((l.irradiance, l.transmittance), (DVec3::ONE, 0.25));
        let p = SourceParams::new(LightWeight::Mean, 4, 0.3);
        assert_eq!((p.light_weight, p.emission_weight), (0.25, 0.3));
    }
}

//! The source terms Q of the lit and single-scatter models (DESIGN.md §2), given what the shadow
//! rays found. The renderer traces the shadow rays; this file holds only the formulas.

use crate::scene::LightWeight;
use glam::DVec3;
use std::f64::consts::PI;

/// What one shadow ray from a point x towards light l found.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LightSample {
    /// L_l(x): the emission model along the shadow ray with the light's arriving irradiance as
    /// its background (DESIGN.md §2, lit model).
    pub radiance: DVec3,
    /// E_l(x): the unoccluded irradiance (E, or I/d²).
    pub irradiance: DVec3,
    /// T_l(x): the transmittance of all particles between x and the light.
    pub transmittance: f64,
}

/// w of the lit model: 1/m for `mean` (thesis eq. 4.17), 1 for `sum`; 0 without lights.
pub fn light_weight(weight: LightWeight, lights: usize) -> f64 {
    match (weight, lights) {
        (_, 0) => 0.0,
        (LightWeight::Mean, m) => 1.0 / m as f64,
        (LightWeight::Sum, _) => 1.0,
    }
}

/// DESIGN.md §2, lit model (thesis eq. 4.17 with the λκ factor of §8 applied by the caller):
/// Q(x) = w·Σ_l L_l(x).
pub fn lit_source(w: f64, lights: &[LightSample]) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for l in lights {
        sum += l.radiance;
    }
    w * sum
}

/// DESIGN.md §2, single-scatter model: Q(x) = a·E(x) + α(x)·(1/4π)·Σ_l E_l(x)·T_l(x), with E the
/// emission colour and α the σ-weighted albedo of the particles at x.
pub fn single_scatter_source(
    a: f64,
    emission: DVec3,
    albedo: DVec3,
    lights: &[LightSample],
) -> DVec3 {
    let mut inscatter = DVec3::ZERO;
    for l in lights {
        inscatter += l.irradiance * l.transmittance;
    }
    a * emission + albedo * inscatter / (4.0 * PI)
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
    fn weights_and_sources() {
        assert_eq!(light_weight(LightWeight::Mean, 4), 0.25);
        assert_eq!(light_weight(LightWeight::Sum, 4), 1.0);
        assert_eq!(light_weight(LightWeight::Mean, 0), 0.0);
        let s = [
            LightSample {
                radiance: DVec3::X,
                irradiance: DVec3::splat(4.0 * PI),
                transmittance: 0.5,
            },
            LightSample {
                radiance: DVec3::Y,
                irradiance: DVec3::ZERO,
                transmittance: 1.0,
            },
        ];
        assert_eq!(lit_source(0.5, &s), DVec3::new(0.5, 0.5, 0.0));
        let q = single_scatter_source(1.0, DVec3::Z, DVec3::splat(0.5), &s);
        assert!((q - DVec3::new(0.25, 0.25, 1.25)).abs().max_element() < 1e-15);
        assert_eq!(surface_limit_weight(f64::INFINITY), 0.0);
        assert_eq!(surface_limit_weight(1.0), 0.5);
    }
}

//! The error budget of a pixel (docs/design.md §3): how `tol` is shared out, and the bounds
//! that let parts of the integral be bounded rather than integrated.
//!
//! Each of the m lights gets `tol`/m per channel (its *share*), spent as follows:
//!
//! | part | of the share | what it pays for |
//! |---|---|---|
//! | [`RAY_TAIL_SHARE`] | 1e-3 | the far end of the camera ray behind nearly opaque gas, bounded instead of integrated ([`VolumeRenderer::tail_cut`]); half of the bound is added to the value, half to err |
//! | [`SHADOW_STOP_SHARE`] | 1e-3 | shadow rays that stop where their transmittance has fallen to ε ([`VolumeRenderer::shadow_cut`]) |
//! | the rest ([`quadrature_tol`]) | 1 − 0.5e-3 − 1e-3 | the adaptive quadrature's error estimate |
//!
//! The shares are named in `reference::budget`, beside the Gaussian renderer's.
//!
//! Both bounded parts rest on a bound Qb of the light's source q_l along the rest of the ray
//! ([`VolumeRenderer::source_bound`]): every model's q_l is non-decreasing in the colour,
//! albedo, irradiance and shadow-ray radiance and transmittance (`OpticalModel::light_source`).
//! The shares are small so that the actual error stays far below `tol` where the quadrature's
//! estimates are pessimistic.
//!
//! Segments whose whole contribution is bounded by a few shares start at the quadrature's
//! cheapest level ([`R5_START_LIMIT`]): what that level could miss cannot exceed that bound.
//! Outside the budget, err also holds the Θmax = 1 limit's O(1/σ) remainder (`limits.rs`) and
//! the float32 rounding of the stored value (`reference::stored_pixel`).

use super::VolumeRenderer;
use crate::geometry::Ray;
use crate::optics::intervals::Interval;
use crate::optics::light::Light;
use crate::optics::source::LightSample;
use crate::reference::quadrature::Piece;
use crate::scene::Scene;
use glam::DVec3;

/// The far end of a camera ray, of each light's share of `tol` (`reference::budget`).
pub(super) use crate::reference::budget::volume::RAY_TAIL as RAY_TAIL_SHARE;
/// Shadow rays that stop where their transmittance has fallen to ε, of each light's share of
/// `tol` (`reference::budget`): ε is this part of the share over twice the bound of q_l. Dense
/// sets (many overlapping spheres) lose most of the length of their shadow rays behind that
/// point; molecules rarely get that dark.
pub(super) use crate::reference::budget::volume::SHADOW_STOP as SHADOW_STOP_SHARE;

/// A segment of a piece whose whole contribution to a light's integral is bounded by at most
/// this many times the light's share of tol (w·Δu·Qb, with Qb of
/// [`VolumeRenderer::source_bound`]) starts at the 5-node level (`quadrature::Level::R5`)
/// rather than at G7. Most segments of small weight or short extent converge there, and where
/// R5's estimate were to miss a feature, the piece cannot hold more than a few tol. Starting
/// every segment at R5 is not honest (err fell below the actual error on 1UUN), and larger
/// limits trade little speed for a weaker bound (docs/performance.md, "The R5 start").
pub(super) const R5_START_LIMIT: f64 = 10.0;

/// The tolerance of one light's quadrature, given the light's `share` of `tol`.
#[inline]
pub(super) fn quadrature_tol(share: f64) -> f64 {
    share * crate::reference::budget::volume::QUADRATURE
}

impl VolumeRenderer<'_> {
    /// Where the quadrature's shadow rays towards `light` from x(t), t ≥ `t`, may stop (docs/design.md
    /// §3: a neglected remainder is bounded and goes into err): (ε, M, Qb) with M ≥ the light's
    /// irradiance and every colour (what may lie behind the cut, per channel) and Qb the bound
    /// of q_l of [`VolumeRenderer::source_bound`]. A shadow ray stopped where its transmittance
    /// T has fallen to ε ≤ `budget`/(2·max Qb) takes the middle of what is left out
    /// (`IntervalCutter::composite`); q_l is linear in the shadow ray's radiance and
    /// transmittance and monotone (`OpticalModel::light_source`), so that changes q_l by at most
    /// T·Qb/2 ≤ ε·Qb/2 at every point. The integrand then differs from the true one by at most
    /// that, with small jumps where the cut moves from one interval to another, which the error
    /// estimate may not see: err gets 2·ε·Qb per unit of Σ weight·Δu (one ε·Qb/2 for the
    /// integral of the difference, one for the rule's sum of it, and two for what it can hide
    /// from the estimate), at most `budget`. `None` where no bound is known.
    pub(super) fn shadow_cut(
        &self,
        ray: &Ray,
        t: f64,
        light: &Light,
        budget: f64,
    ) -> Option<(f64, DVec3, DVec3)> {
        let (color, _) = self.source_bounds?;
        let q = self.source_bound(ray, t, light)?;
        let bound = light
            .max_irradiance_beyond(ray.origin, ray.direction, t)
            .max(color);
        let epsilon = budget / (2.0 * q.max_element());
        (epsilon > 0.0 && epsilon.is_finite() && bound.is_finite()).then_some((epsilon, bound, q))
    }

    /// Where the camera ray's remaining weight stops mattering for light `light`: the number
    /// of pieces (from the front) to integrate, and a per-channel bound B of the part of that
    /// light's integral ∫T·σ·q_l dt over the pieces after them (docs/design.md §3: a neglected
    /// remainder is bounded and goes into err). With q_l ≤ Qb (a bound over those points,
    /// [`VolumeRenderer::source_bound`]) the rest is at most Qb·Σ_{j≥c} T(0,t0_j)·U_j (each piece's
    /// ∫du over [0, U_j] at weight T(0,t0_j)); the first c where that is ≤ `budget` in every
    /// channel is the cut (both factors shrink along the ray). Since q_l ≥ 0 the rest lies in
    /// [0, B]. All pieces are kept (B = 0) where no bound is known.
    pub(super) fn tail_cut(
        &self,
        ray: &Ray,
        intervals: &[Interval],
        pieces: &[Piece],
        light: &Light,
        budget: f64,
    ) -> (usize, DVec3) {
        // From the back, so that the weights after c are a sum of non-negative terms (a
        // running difference from the front drifts below 0); the pieces that pass form a
        // suffix, since both factors shrink along the ray.
        let mut cut = (pieces.len(), DVec3::ZERO);
        let mut weight_after = 0.0;
        for (c, p) in pieces.iter().enumerate().rev() {
            weight_after += p.weight * p.hi;
            let Some(q) = self.source_bound(ray, intervals[c].t0, light) else {
                break;
            };
            // Rounded up against the summation's round-off (relative ~1e-16 per term).
            let bound = q * (weight_after * (1.0 + 1e-9));
            if bound.max_element() <= budget {
                cut = (c, bound);
            } else {
                break;
            }
        }
        cut
    }

    /// A per-channel bound of q_l(x), the part of Q that `light` contributes (docs/design.md §2), at
    /// every point x(t), t ≥ `t`, of `ray`: the model's q_l of the largest colour and albedo
    /// of any particle, the light's largest irradiance along the rest of the ray, a shadow
    /// ray radiance of the larger of the two (L_l is a convex combination of the light's
    /// irradiance and particle colours) and transmittance 1. Valid because every model's q_l
    /// is non-decreasing in these (`OpticalModel::light_source`). `None` without a finite bound.
    pub(super) fn source_bound(&self, ray: &Ray, t: f64, light: &Light) -> Option<DVec3> {
        let (color, albedo) = self.source_bounds?;
        let irradiance = light.max_irradiance_beyond(ray.origin, ray.direction, t);
        let sample = LightSample {
            radiance: irradiance.max(color),
            irradiance,
            transmittance: 1.0,
        };
        let bounds = Interval {
            t0: t,
            t1: t,
            sigma: 1.0,
            emission: color,
            albedo,
        };
        let q = self.model.light_source(&self.params, &bounds, &sample);
        (q.is_finite() && q.cmpge(DVec3::ZERO).all()).then_some(q)
    }
}

/// The largest colour and albedo of any particle, per channel, if no colour, albedo or light
/// of the scene is negative (`VolumeRenderer::source_bounds`).
pub(super) fn source_bounds(scene: &Scene) -> Option<(DVec3, DVec3)> {
    let mut color = DVec3::ZERO;
    let mut albedo = DVec3::ZERO;
    for p in &scene.particles {
        if !(p.color.cmpge(DVec3::ZERO).all() && p.albedo.cmpge(DVec3::ZERO).all()) {
            return None;
        }
        color = color.max(p.color);
        albedo = albedo.max(p.albedo);
    }
    let lights_ok = scene.lights.iter().all(|l| match *l {
        Light::Directional { irradiance, .. } => irradiance.cmpge(DVec3::ZERO).all(),
        Light::Point { intensity, .. } => intensity.cmpge(DVec3::ZERO).all(),
    });
    (lights_ok && color.is_finite() && albedo.is_finite()).then_some((color, albedo))
}

//! The σ → ∞ limit (docs/design.md §3): Θmax = 1 particles, and intervals so dense that f64
//! cannot resolve their skin depth.
//!
//! **Θmax = 1.** An interval with σ = ∞ is the end of the ray: T = 0 from its start t0 on. Its
//! contribution T(0,t0)·Q∞ is the σ → ∞ limit of the integral, which concentrates on x(t0⁺):
//! with s = σ·(t − t0), ∫ σe^{−σ(t−t0)}·Q dt = ∫₀^∞ e^{−s}·Q(x(t0 + s/σ)) ds. For a model
//! without a per-light part Q∞ = Q = k·E. For lit and single-scatter, Q contains the particle
//! itself along the shadow ray: if t0 is where the ray enters the particle through its surface
//! (outward normal n, cosines μ_in = −d·n > 0, μ_l = ω_l·n towards light l), the shadow ray from
//! x(t0 + s/σ) runs through the particle for a length s·c/σ with c = μ_in/μ_l when μ_l > 0
//! (optical depth s·c), and through all of it (c = ∞) when μ_l ≤ 0. Integrating gives
//!
//!   lit:            L_l,∞ = L_l,rest/(1 + c) + E·c/(1 + c)
//!   single-scatter: T_l,∞ = T_l,rest/(1 + c)
//!
//! where "rest" is the shadow ray from the entry point without the Θmax = 1 particle(s) that
//! start there (`LightSample::surface_limit`), and Q∞ is Q of those limits
//! (`OpticalModel::opaque_limit`). This is the value the renderer converges to as Θmax → 1 (a
//! test checks it); the naive "Q at the entry point" would give L_l,rest, which no finite Θmax
//! approaches. An eye inside a Θmax = 1 particle sees its colour (c = ∞). Several Θmax = 1
//! particles entered at the same point act as one (mean colour, largest c).
//!
//! **Huge σ.** Where the skin depth 1/σ falls below about 1e6 f64 spacings of positions at the
//! entry point (and the interval is optically deep), node positions and shadow chords can no
//! longer resolve it: the quadrature would collapse onto the entry point. Such an interval is
//! replaced by the same σ → ∞ limit, its particles of unresolved σ taking the place of the
//! Θmax = 1 ones, and the O(1/σ) remainder goes into err ([`VolumeRenderer::limit_remainder`]).
//! Finite σ that overflow their sum in an overlap are the limit the same way.

use super::per_light::ShadowBuffers;
use super::VolumeRenderer;
use crate::geometry::{Hit, Ray};
use crate::optics::intervals::Interval;
use crate::optics::model::LightNeed;
use crate::optics::source::{surface_limit_weight, LightSample};
use glam::DVec3;

/// Optical depth from which an interval whose skin depth the ray parameter cannot resolve is
/// replaced by its σ → ∞ limit: its transmittance e^{−τ} < 1e-30 is far below any tolerance.
const LIMIT_MIN_DEPTH: f64 = 70.0;

/// σ·δ (δ: the f64 resolution of positions near the entry point) from which the quadrature in u
/// can no longer resolve the skin depth 1/σ: node positions, shadow chords and the particle's
/// own optical depth along them carry a relative error of this order.
const RESOLUTION_LIMIT: f64 = 1e-6;

/// A particle active where a dense interval starts takes part in its σ → ∞ limit (its shadow
/// chord is replaced by the limit's) when its own σ is at least this part of the unresolved σ:
/// a thinner one adds an optical depth below 1e-3·RESOLUTION_LIMIT over the positions the
/// limit stands for.
pub(super) const LIMIT_MEMBER_SIGMA_FRACTION: f64 = 1e-3;

/// Coefficient of the first-order remainder of the σ → ∞ limit, err = F·Qmax/τ (see
/// `VolumeRenderer::limit_remainder`).
const LIMIT_REMAINDER_FACTOR: f64 = 1e3;

impl VolumeRenderer<'_> {
    /// A bound on |finite-σ integral − σ → ∞ limit| for a dense interval (per channel, before
    /// the transmittance in front of it). The limit neglects the variation of Q over a few skin
    /// depths, whose first-order term is O(1/σ) against the geometry of the entry (the interval
    /// length Δ = 2r·μ_in for a sphere entered from outside), i.e. O(1/τ) relative to the
    /// largest source: err = F·Qmax/τ with F = [`LIMIT_REMAINDER_FACTOR`], generous against the
    /// curvature and light-angle factors, and Qmax ≥ Q for every model of docs/design.md §2 (the
    /// emission colour, plus every light's unoccluded irradiance weighted by 1 + albedo, plus
    /// the limit value itself). Where the limit applies, τ ≥ 1e7 or so, and the term is tiny.
    pub(super) fn limit_remainder(&self, ray: &Ray, iv: &Interval, q: DVec3) -> DVec3 {
        let x = ray.at(iv.t0);
        let mut q_max = iv.emission + q.abs();
        for light in &self.scene.lights {
            if let Some(inc) = light.incident_at(x) {
                q_max += (DVec3::ONE + iv.albedo) * inc.irradiance;
            }
        }
        let tau = iv.sigma * iv.length();
        q_max * (LIMIT_REMAINDER_FACTOR / tau).min(1.0)
    }

    /// Q∞, the σ → ∞ limit of the source of a Θmax = 1 interval (module documentation).
    /// Particles with σ ≥ `sigma_opaque` count as Θmax = 1 here (∞ for a Θmax = 1 interval; the
    /// resolution limit of `beyond_resolution` for a huge but finite σ).
    pub(super) fn opaque_source(
        &self,
        ray: &Ray,
        iv: &Interval,
        hits: &[Hit],
        sigma_opaque: f64,
        buffers: &mut ShadowBuffers,
    ) -> DVec3 {
        if self.model.light_need() == LightNeed::None {
            return self.model.opaque_limit(&self.params, iv, &[]);
        }
        let particles = self.cutter.particles();
        let x = ray.at(iv.t0);
        // The Θmax = 1 particles active just after t0 (all start at t0: it is the first such
        // interval); whether the ray entered each through its surface there, and its normal.
        let is_opaque_here = |h: &Hit| {
            particles[h.index as usize].sigma >= sigma_opaque
                && h.chord.t_enter.max(0.0) <= iv.t0
                && h.chord.t_exit > iv.t0
        };
        let mut lights = Vec::with_capacity(self.scene.lights.len());
        for (l, light) in self.scene.lights.iter().enumerate() {
            let Some(inc) = light.incident_at(x) else {
                continue;
            };
            if !inc.irradiance.is_finite() {
                continue;
            }
            let mut c: f64 = 0.0;
            for h in hits.iter().filter(|h| is_opaque_here(h)) {
                let p = &particles[h.index as usize];
                let ci = if h.chord.t_enter == iv.t0 && h.chord.t_enter > 0.0 {
                    let n = p.shape().normal(x);
                    let mu_in = -ray.direction.dot(n);
                    let mu_l = inc.toward.dot(n);
                    if mu_l > 0.0 && mu_in > 0.0 {
                        mu_in / mu_l
                    } else {
                        f64::INFINITY
                    }
                } else {
                    // The eye is inside: the shadow ray crosses the particle for a finite length.
                    f64::INFINITY
                };
                c = c.max(ci);
            }
            let keep = surface_limit_weight(c);
            let sample = if keep > 0.0 {
                let skip = |i: u32| hits.iter().any(|h| h.index == i && is_opaque_here(h));
                let Some(rest) = self.light_sample(x, l, skip, buffers) else {
                    continue;
                };
                rest.surface_limit(keep, iv.emission)
            } else {
                // Nothing from outside survives: the shadow ray sees only the particle.
                LightSample {
                    radiance: iv.emission,
                    irradiance: inc.irradiance,
                    transmittance: 0.0,
                }
            };
            lights.push(sample);
        }
        self.model.opaque_limit(&self.params, iv, &lights)
    }
}

/// Whether interval `iv` (finite σ) is too dense for the quadrature: its skin depth 1/σ is
/// within 1/[`RESOLUTION_LIMIT`] f64 spacings of the ray parameter near its start, and it is
/// optically deep. Then the σ → ∞ limit is the better answer (docs/design.md §3: "very large σ
/// converge to the Θmax = 1 limit, never to a collapsed quadrature"). Returns the σ from which a
/// particle counts as part of that limit: the particles whose own skin depth is unresolved.
pub(super) fn beyond_resolution(ray: &Ray, iv: &Interval) -> Option<f64> {
    let sigma_unresolved = unresolved_sigma(ray, iv);
    (iv.sigma >= sigma_unresolved && iv.sigma * iv.length() >= LIMIT_MIN_DEPTH)
        .then_some(sigma_unresolved * LIMIT_MEMBER_SIGMA_FRACTION)
}

/// The σ whose skin depth is [`RESOLUTION_LIMIT`] of the f64 resolution δ of positions at the
/// start of `iv` (x = o + t·d rounds by about 8ε·(|o| + |t|)).
pub(super) fn unresolved_sigma(ray: &Ray, iv: &Interval) -> f64 {
    let delta = 8.0 * f64::EPSILON * (ray.origin.abs().max_element() + iv.t0.abs());
    RESOLUTION_LIMIT / delta.max(f64::MIN_POSITIVE)
}

//! The exact volume renderer (docs/design.md §2, §3): spheres of glowing, absorbing gas.
//!
//! Along a camera ray x(t) = o + t·d, t ≥ 0 (particles behind the eye are clipped away, an eye
//! inside a particle starts in it):
//!
//!   L = L_bg·T(0,∞) + ∫₀^∞ T(0,t)·σ(x_t)·Q(x_t) dt                       (docs/design.md §2)
//!
//! The ray is cut into intervals with a fixed set of particles (`optics::intervals`). The
//! optical model (`optics::models`, one file each) supplies Q as a constant part k·E and a part
//! per light (`optics::model::OpticalModel`); the renderer never asks which model it is.
//!
//! * A model without a per-light part (emission) has Q = k·E constant per interval, and the
//!   integral has the closed form L_in = L_out·e^{−σΔ} + Q·(1 − e^{−σΔ}) (`optics::emission`):
//!   exact, error estimate 0.
//! * The per-light parts (lit, single-scatter) are integrated one light at a time by adaptive
//!   quadrature in the variable u = 1 − e^{−σ(t−t0)}, with the shadow-ray kinks as
//!   breakpoints (`per_light.rs`), or by the thesis's midpoint sums (`reference::riemann`).
//! * A Θmax = 1 interval ends the ray, and an interval too dense for f64 to resolve its skin
//!   depth is replaced by the same σ → ∞ limit (`limits.rs`).
//! * `tol` is shared out between the quadrature and the parts that are bounded rather than
//!   integrated (`budget.rs`); every part goes into the pixel's error estimate, so err bounds
//!   |value − truth| (docs/design.md §3).
//!
//! [`VolumeRenderer::radiance_with`], below, is the per-pixel entry point.

mod budget;
mod limits;
mod per_light;
#[cfg(test)]
mod tests;

use budget::{source_bounds, R5_START_LIMIT};
use limits::{beyond_resolution, unresolved_sigma, LIMIT_MEMBER_SIGMA_FRACTION};
use per_light::ShadowBuffers;

pub use per_light::MAX_SEGMENTS;

use super::quadrature::Piece;
use super::riemann::midpoint_sum;
use super::{Integrator, RadianceEstimator, Sample};
use crate::geometry::{Bvh, Ray};
use crate::optics::cutter::{IntervalCutter, SweepScratch};
use crate::optics::emission::{composite_by, opacity};
use crate::optics::intervals::Interval;
use crate::optics::model::{LightNeed, OpticalModel};
use crate::optics::source::SourceParams;
use crate::scene::Scene;
use glam::DVec3;
use std::cell::RefCell;

/// The volume renderer of one scene (docs/design.md §2, §3).
pub struct VolumeRenderer<'a> {
    scene: &'a Scene,
    /// Over the particles with σ > 0 (`Scene::build_gas_bvh`): every query of the renderer
    /// skips the others anyway, and the occluder lists rely on it (`Occluders::gather`).
    bvh: Bvh,
    cutter: IntervalCutter<'a>,
    integrator: Integrator,
    /// The scene's optical model (docs/design.md §2).
    model: &'static dyn OpticalModel,
    /// Its parameters (w, a), resolved once.
    params: SourceParams,
    /// Whether the model reads only E_l and T_l of a shadow ray
    /// (`LightNeed::IrradianceTransmittance`): then no radiance is traced.
    transmittance_only: bool,
    /// Per channel, the largest particle colour and albedo: with the lights, a bound of the
    /// per-light sources (`VolumeRenderer::tail_cut`). `None` where a colour, albedo or light
    /// is negative (no bound, so no tail is cut).
    source_bounds: Option<(DVec3, DVec3)>,
    /// [`R5_START_LIMIT`] (a test sets 0, to start every segment at G7 or K15).
    r5_start_limit: f64,
}

impl<'a> VolumeRenderer<'a> {
    /// Builds the BVH and the canonical particle order for `scene`; `integrator` chooses how the
    /// per-light parts of Q are integrated (a model without them, emission, is closed-form).
    pub fn new(scene: &'a Scene, integrator: Integrator) -> Self {
        VolumeRenderer {
            scene,
            bvh: scene.build_gas_bvh(),
            cutter: IntervalCutter::new(&scene.particles),
            integrator,
            model: scene.render.model.model(),
            transmittance_only: scene.render.model.model().light_need()
                == LightNeed::IrradianceTransmittance,
            params: SourceParams::new(
                scene.render.light_weight,
                scene.lights.len(),
                scene.render.emission_weight,
            ),
            source_bounds: source_bounds(scene),
            r5_start_limit: R5_START_LIMIT,
        }
    }
}

impl RadianceEstimator for VolumeRenderer<'_> {
    fn radiance(&self, ray: &Ray) -> Sample {
        // One set of buffers per thread instead of new ones per camera ray: a pixel of 1UUN
        // allocated a few dozen vectors (an occluder list per interval) and grew them again.
        thread_local! {
            static SCRATCH: RefCell<ShadowBuffers> = RefCell::default();
        }
        SCRATCH.with(|cell| match cell.try_borrow_mut() {
            Ok(mut buffers) => {
                buffers.reset();
                self.radiance_with(ray, &mut buffers)
            }
            // Re-entered on this thread (not done today): fresh buffers.
            Err(_) => self.radiance_with(ray, &mut ShadowBuffers::default()),
        })
    }

    /// The adaptive integrator estimates its error (0 for the closed-form emission model); the
    /// Riemann sums have no estimate, so no `err` layer is written for them.
    fn estimates_error(&self) -> bool {
        matches!(self.integrator, Integrator::Adaptive)
    }
}

impl VolumeRenderer<'_> {
    /// The radiance along one camera ray, its error estimate and its shadow-ray count, with the
    /// caller's shadow-ray buffers (tests read what they hold afterwards): the intervals of the
    /// ray; the closed form where the model has no per-light part; otherwise the transmittance
    /// in front of each interval up to the first Θmax = 1 or unresolvably dense one (which
    /// ends the ray with its σ → ∞ limit, `limits.rs`), and the integral of Q over the
    /// intervals before it (`per_light.rs`, or the Riemann sums).
    fn radiance_with(&self, ray: &Ray, buffers: &mut ShadowBuffers) -> Sample {
        let render = &self.scene.render;
        let mut hits = Vec::new();
        self.bvh.all_hits(ray, 0.0, f64::INFINITY, &mut hits);
        let mut intervals = Vec::new();
        let mut cut_scratch = SweepScratch::default();
        self.cutter.cut(
            &hits,
            0.0,
            f64::INFINITY,
            |_| false,
            &mut cut_scratch,
            &mut intervals,
        );
        if self.model.light_need() == LightNeed::None {
            // Q = k·E is constant per interval: the closed form, exact.
            let k = self.model.emission_factor(&self.params);
            return Sample {
                radiance: composite_by(&intervals, render.background, |iv| k * iv.emission)
                    .radiance,
                error: DVec3::ZERO,
                shadow_rays: 0,
                unconverged: false,
            };
        }
        // Transmittance in front of each interval, up to the first Θmax = 1 interval.
        let mut pieces = Vec::with_capacity(intervals.len());
        let mut transmittance = 1.0;
        let mut end = DVec3::ZERO;
        let mut finite = intervals.len();
        let mut limit_error = DVec3::ZERO;
        for (k, iv) in intervals.iter().enumerate() {
            if iv.sigma.is_infinite() {
                // Θmax = 1 particles, or finite σ that overflowed their sum: both are the limit.
                let sigma_opaque = unresolved_sigma(ray, iv) * LIMIT_MEMBER_SIGMA_FRACTION;
                end = transmittance * self.opaque_source(ray, iv, &hits, sigma_opaque, buffers);
                finite = k;
                transmittance = 0.0;
                break;
            }
            if let Some(sigma_opaque) = beyond_resolution(ray, iv) {
                let q = self.opaque_source(ray, iv, &hits, sigma_opaque, buffers);
                end = transmittance * q;
                limit_error = transmittance * self.limit_remainder(ray, iv, q);
                finite = k;
                transmittance = 0.0;
                break;
            }
            let tau = iv.sigma * iv.length();
            pieces.push(Piece {
                lo: 0.0,
                hi: opacity(tau),
                weight: transmittance,
                tag: k,
            });
            transmittance *= (-tau).exp();
        }
        let background = transmittance * render.background;
        let intervals = &intervals[..finite];
        let (value, error, unconverged) = match self.integrator {
            Integrator::Riemann { samples } => {
                let mut sum = DVec3::ZERO;
                for p in &pieces {
                    let iv = &intervals[p.tag];
                    sum += p.weight
                        * midpoint_sum(iv.t0, iv.t1, iv.sigma, samples, |t| {
                            self.source(ray.at(t), iv, buffers)
                        });
                }
                (sum, DVec3::ZERO, false)
            }
            Integrator::Adaptive => self.integrate_per_light(ray, intervals, &pieces, buffers),
        };
        Sample {
            radiance: background + end + value,
            error: error + limit_error,
            shadow_rays: buffers.rays,
            unconverged: unconverged || !(value + end).is_finite(),
        }
    }

    /// Q(x) of the scene's model (docs/design.md §2) at a point inside interval `iv`.
    fn source(&self, x: DVec3, iv: &Interval, buffers: &mut ShadowBuffers) -> DVec3 {
        buffers.lights.clear();
        for l in 0..self.scene.lights.len() {
            if let Some(s) = self.light_sample(x, l, |_| false, buffers) {
                buffers.lights.push(s);
            }
        }
        self.model.source(&self.params, iv, &buffers.lights)
    }
}

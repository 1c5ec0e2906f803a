//! The exact volume renderer (docs/design.md §2, §3): spheres of glowing, absorbing gas.
//!
//! Along a camera ray x(t) = o + t·d, t ≥ 0 (particles behind the eye are clipped away, an eye
//! inside a particle starts in it):
//!
//!   L = L_bg·T(0,∞) + ∫₀^∞ T(0,t)·σ(x_t)·Q(x_t) dt                       (docs/design.md §2)
//!
//! The ray is cut into intervals with a fixed set of particles (`optics::intervals`). The
//! optical model (`optics::models`, one file each) supplies Q as a constant part k·E and a part
//! per light (`optics::model::OpticalModel`); this file never asks which model it is.
//!
//! * **no per-light part** (emission): Q = k·E is constant per interval, and the integral has
//!   the closed form L_in = L_out·e^{−σΔ} + Q·(1 − e^{−σΔ}) (`optics::emission`). Error
//!   estimate 0.
//! * **per-light parts** (lit, single-scatter): inside interval k, T(0,t) = T(0,t0)·e^{−σ(t−t0)}; with the
//!   substitution u = 1 − e^{−σ(t−t0)} (du = σ·e^{−σ(t−t0)} dt) its part of the integral is
//!
//!     T(0,t0)·∫₀^{U} Q(x(t(u))) du,   U = 1 − e^{−σΔ},   t(u) = t0 − ln(1 − u)/σ,
//!
//!   so the transmittance weight is integrated exactly and the quadrature only sees the bounded
//!   source Q (whatever σ is: a thin interval gives a short u-range, a dense one a u-range
//!   near 1 whose far end carries almost no weight). That integral is done by globally adaptive
//!   Gauss–Kronrod (G7, raised to K15 where needed, and pieces of small weight from a
//!   5-node rule: `reference::quadrature`, [`R5_SHARE`]) to `tol` per pixel and channel, or by
//!   the thesis's midpoint sums in t (`reference::riemann`). Q is linear in the lights, so the adaptive path
//!   integrates each light's part on its own (one shadow ray per node, only that light's kinks,
//!   tol/m each; the estimates add up to ≤ tol), and the constant part k·E (single-scatter's
//!   a·E) exactly.
//!
//! **Kinks.** Q is smooth inside an interval except where a shadow ray grazes a sphere. Those
//! camera-ray parameters are computed in closed form (`optics::kinks`: ray–cylinder for
//! directional lights, ray–cone for point lights) and every one is a breakpoint from the start
//! (a shadow that falls between the nodes of a segment would otherwise be missed by both rules,
//! and by the error estimate with them). The square root of a kink lies on one side of it, the
//! side where the shadow rays cross the grazed sphere (`kinks::push_sided_tangencies`); the
//! segment on that side is integrated with an endpoint substitution that flattens that end and
//! turns the square root into a smooth integrand, and its error estimate carries a safety
//! factor, while the segment on the other side sees a smooth integrand there and is integrated
//! as it is (`quadrature::integrate_adaptive_with_ends`). Kinks the closed form might miss
//! (round-off in the roots) are left to the adaptivity.
//!
//! **Θmax = 1.** An interval with σ = ∞ is the end of the ray: T = 0 from its start t0 on. Its
//! contribution T(0,t0)·Q∞ is the σ → ∞ limit of the integral, which concentrates on x(t0⁺):
//! with s = σ·(t − t0), ∫ σe^{−σ(t−t0)}·Q dt = ∫₀^∞ e^{−s}·Q(x(t0 + s/σ)) ds. For a model
//! without a per-light part Q∞ = Q = k·E. For lit and single-scatter, Q contains the particle itself along the shadow ray:
//! if t0 is where the ray enters the particle through its surface (outward normal n, cosines
//! μ_in = −d·n > 0, μ_l = ω_l·n towards light l), the shadow ray from x(t0 + s/σ) runs through
//! the particle for a length s·c/σ with c = μ_in/μ_l when μ_l > 0 (optical depth s·c), and
//! through all of it (c = ∞) when μ_l ≤ 0. Integrating gives
//!
//!   lit:            L_l,∞ = L_l,rest/(1 + c) + E·c/(1 + c)
//!   single-scatter: T_l,∞ = T_l,rest/(1 + c)
//!
//! where "rest" is the shadow ray from the entry point without the Θmax = 1 particle(s) that
//! start there (`LightSample::surface_limit`), and Q∞ is Q of those limits
//! (`OpticalModel::opaque_limit`). This is the value the renderer converges to as Θmax → 1 (a test checks it); the
//! naive "Q at the entry point" would give L_l,rest, which no finite Θmax approaches. An eye
//! inside a Θmax = 1 particle sees its colour (c = ∞). Several Θmax = 1 particles entered at the
//! same point act as one (mean colour, largest c).
//!
//! **Huge σ.** Where the skin depth 1/σ falls below about 1e6 f64 spacings of positions at the
//! entry point (and the interval is optically deep), node positions and shadow chords can no
//! longer resolve it: the quadrature would collapse onto the entry point. Such an interval is
//! replaced by the same σ → ∞ limit, its particles of unresolved σ taking the place of the
//! Θmax = 1 ones, and the O(1/σ) remainder goes into err (`VolumeRenderer::limit_remainder`).
//! Finite σ that overflow their sum in an overlap are the limit the same way.
//!
//! **The far end of a ray.** Behind gas that has made the ray nearly opaque, the rest of each
//! light's integral is bounded rather than integrated: with q_l ≤ Qb (the model's q_l of the
//! largest colour, albedo and irradiance, `VolumeRenderer::source_bound`) the part after
//! interval c is at most Qb·(T(0,t0_c) − T(0,end)), and the first c where that is below
//! [`TAIL_SHARE`] of the light's share of tol is the cut (`VolumeRenderer::tail_cut`). Half the
//! bound is added to the value and half to err (the rest lies in [0, bound]), and the quadrature
//! gets the remaining tol. On 1UUN this rarely applies; on dense sets (a million spheres) it
//! cuts most of each ray.
//!
//! **The far end of a shadow ray.** The quadrature's shadow rays stop where their
//! transmittance T has fallen to ε and take the middle of what the rest could add (between 0 and
//! T times the largest irradiance or colour): q_l is linear in the shadow ray's radiance and
//! transmittance, so that moves it by at most ε·Qb/2. ε is [`CUT_SHARE`] of the light's share of
//! tol over 2·Qb, and where any shadow ray of a light was cut, err gets 2·ε·Qb per unit of the
//! camera ray's weight (`VolumeRenderer::shadow_cut`). On 1UUN no shadow ray gets that dark; in a
//! million random spheres half of the shadow rays' intervals lay behind the cut.
//!
//! **Point lights.** Where the camera ray passes closest to a point light, the irradiance I/d²
//! peaks, as sharply as the ray passes close; that point is a breakpoint of the light's
//! integral like a kink, so that the peak is an end of two segments rather than a feature
//! between the nodes of one.
//!
//! **Shadow rays** test only the candidate occluders of their camera-ray interval
//! (`reference::shadow`), with the same hits as a traversal of the whole BVH: one BVH query per
//! camera ray and light, from which each interval's list is narrowed. The quadrature asks for
//! the nodes of a segment's level together (`quadrature::integrate_adaptive_batched`), and
//! their shadow rays read that list once, each candidate tested against all of them in SIMD
//! lanes (`Occluders::hits_batch`); the composites follow one by one, in node order.
//!
//! **Where the time goes** (1UUN chains A+B lit, the thesis's two lights, tol 1e-4, 128²;
//! counted with a throwaway instrumented build, issue 10). About 1,970 of the 16,384 camera
//! rays reach gas. Each light's integral over such a ray has 16 pieces (camera-ray
//! intervals), which the 53 kinks inside them (of 87 in the ray's range) split into 69
//! segments: the kinks make three quarters of the segments. 86 % of the 2.04 M shadow rays are
//! the segments' first levels (6.4 nodes each), 9 % raise a segment to K15 and 5 % start the
//! halves of a split. So the error estimate's pessimism costs little now: doubling each
//! light's tol takes 4.7 % of the shadow rays off, quadrupling it 8.1 %. Nor are the kinks
//! negligible ones: the transmittance from the kink's point to the sphere it grazes is above
//! 0.1 at 60 % of them and above 0.01 at 85 %, and that times the camera ray's own
//! transmittance is below 1e-5 at 9 %. With every segment at five nodes and none refined the
//! count would fall by a third at most (starting every segment at R5 was measured and is not
//! honest, [`R5_SHARE`]). So the cost is the number of kinks times about six shadow rays,
//! times what one shadow ray costs: about 4,000 instructions. Of the render's instructions
//! (callgrind, 64²), the ray–sphere tests take 15 %, keeping the layouts of chord ends 22 %
//! (17 % since only the intervals about changed ends are formed anew, `optics::intervals`)
//! and the exponentials 9 %; the rest is spread thin.
//!
//! Two more counts (64², the sixteenth session's instrumented build) say that neither factor has
//! slack left. The occluder lists are tight: 9.1 hits per shadow ray, and 97 % of the sphere tests
//! that pass the reach-range check are hits, so narrower lists cannot pay. And no segment is
//! negligible: of the 71,099 segments started, the bound on a segment's whole contribution
//! (w·Δu·Qb, as `first_level` sees it) is below 1e-4 of the light's share of tol at 0.3 % and below
//! 1e-2 at 4.3 %; 47 % are within R5's limit ([`R5_SHARE`]), 53 % above it. Bounding small segments
//! instead of integrating them would save almost nothing. Riemann-100's shadow rays go through the
//! same composite (`VolumeRenderer::light_sample`, with a whole-BVH traversal instead of the
//! occluder lists), so a cheaper composite lowers both render times and moves their ratio little;
//! fewer shadow rays per segment, fewer segments or cheaper hit tests are what change it.

use super::quadrature::{
    integrate_adaptive_batched, Level, Piece, BOTH_ENDS, HIGH_END, LOW_END, MAX_NODES,
};
use super::riemann::midpoint_sum;
use super::shadow::{KeptEndOrders, Occluders, ShadowCompositor, ShadowRay};
use super::{Integrator, RadianceEstimator, Sample};
use crate::geometry::{Bvh, Hit, Ray};
use crate::optics::emission::{composite_by, opacity};
use crate::optics::cutter::{IntervalCutter, SweepScratch};
use crate::optics::intervals::Interval;
use crate::optics::kinks::{CROSSES_ABOVE, CROSSES_BELOW};
use crate::optics::light::Light;
use crate::optics::model::{LightNeed, OpticalModel};
use crate::optics::source::{surface_limit_weight, LightSample, SourceParams};
use crate::optics::transmittance::transmittance;
use crate::scene::Scene;
use glam::DVec3;
use std::cell::RefCell;

/// Optical depth σ·Δt of a segment above which it starts at K15 rather than G7
/// (the `first_level` of `quadrature::integrate_adaptive_batched`). In u = 1 − e^{−σ(t−t0)}
/// the map t(u) has its singularity at u = 1, which lies 1/(e^τ − 1) segment widths beyond the end of a segment
/// of depth τ: close enough for deep segments (near Θmax = 1) that the 7-node estimate missed
/// errors on the honesty scenes, while at τ ≤ 0.25 it is ≥ 3.5 widths away.
pub const COARSE_DEPTH: f64 = 0.25;

/// A segment of a piece whose whole contribution to a light's integral is bounded by at most
/// this many times the light's share of tol (w·Δu·Qb, with Qb of
/// [`VolumeRenderer::source_bound`]) starts at the 5-node level (`quadrature::Level::R5`)
/// rather than at G7. Most segments of small weight or short extent converge there (96 % on
/// 1UUN lit), and where R5's estimate were to miss a feature, the piece cannot hold more than
/// a few tol. A start at R5 for every segment was measured and rejected: on 1UUN lit 128²
/// the actual error exceeded err at one pixel channel (4.3e-6 against 1.1e-6; taking the
/// largest of three estimates against the three degree-3 rules on R5's nodes, instead of one,
/// still left a pixel channel above its err, and the largest error at 1.1e-5). With the
/// present code, 1UUN 128² lit (and with two point lights, one inside the gas), limits of
/// 30, 100, 300 and 1000 take 2.4, 4.4, 5.3 and 5.5 % (2.1, 4.1, 5.3, 5.8 %) of the shadow
/// rays off against 10, and give largest errors against a tol 1e-9 render of 5.2e-7,
/// 5.1e-7, 9.1e-7 and 2.2e-6 (4.8e-7, 5.4e-7, 1.8e-6, 1.8e-6; at 10: 5.2e-7 and 4.8e-7), all
/// covered by err; from 300 on the first is above the 7.7e-7 that keeps adaptive ≥ 100× more
/// accurate than Riemann-100 (issue 10). 100 would save 4 % for a ten times weaker bound on
/// what a missed feature could cost; 10 is kept.
pub const R5_SHARE: f64 = 10.0;

/// The interval tag of the whole camera ray's occluder list (`ShadowScratch::wide`): no
/// interval has it.
const WHOLE_RAY: usize = usize::MAX;

/// Ratio of the distances from a point light's closest approach of successive breakpoints of
/// its graded mesh (`VolumeRenderer::breakpoints`).
const GRADE: f64 = 3.0;

/// Segments per pixel and light at most; beyond it the remaining error estimate is reported as
/// it stands (the pixel then may miss `tol`, and says so in its `err` value).
pub const MAX_SEGMENTS: usize = 4000;

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
    /// [`R5_SHARE`] (a test sets 0, to start every segment at G7 or K15).
    r5_share: f64,
}

/// Per-camera-ray buffers for shadow rays (reused, so shadow rays do not allocate; and kept
/// per thread from one camera ray to the next, [`ShadowScratch::reset`] between them).
#[derive(Default)]
struct ShadowScratch {
    hits: Vec<Hit>,
    compositor: KeptEndOrders,
    /// `optics::transmittance`'s buffer.
    depths: Vec<(u32, f64)>,
    lights: Vec<LightSample>,
    rays: u64,
    /// Candidate occluders per interval of the camera ray, for the light being integrated.
    occluders: Vec<Occluders>,
    /// The candidates of the whole camera ray for the light being integrated, which the
    /// intervals' lists are narrowed from (one BVH query per light instead of one per interval).
    wide: Occluders,
    /// Where the quadrature's shadow rays for the light being integrated may stop: (ε, M) of
    /// `IntervalCutter::composite` (`VolumeRenderer::shadow_cut`); `None` for exact ones.
    shadow_cut: Option<(f64, DVec3)>,
    /// Whether a shadow ray was cut since this was last cleared.
    was_cut: bool,
    /// The hits of each shadow ray of a batch (`VolumeRenderer::light_sources`).
    batch: Vec<Vec<Hit>>,
}

impl ShadowScratch {
    /// Makes a buffer used for one camera ray ready for the next: counters and flags to their
    /// start, and every occluder list keyed to nothing, since the next ray's intervals have
    /// the same tags (a list left keyed would be taken for the new ray's and give it another
    /// ray's occluders).
    fn reset(&mut self) {
        self.rays = 0;
        self.was_cut = false;
        self.shadow_cut = None;
        self.wide.invalidate();
        for o in &mut self.occluders {
            o.invalidate();
        }
        // The kept layout of the shadow composite names particles by index: this may be
        // another scene's camera ray.
        self.compositor.forget();
    }
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
            r5_share: R5_SHARE,
        }
    }

    /// The shadow ray from `x` towards light `l`: L_l(x) (emission model with the light's
    /// irradiance as background), E_l(x) and T_l(x). `None` where the light sends nothing
    /// usable: x exactly at a point light (or so close that I/d² overflows), a measure-zero set.
    fn light_sample(
        &self,
        x: DVec3,
        l: usize,
        skip: impl Fn(u32) -> bool,
        sh: &mut ShadowScratch,
    ) -> Option<LightSample> {
        let inc = self.scene.lights[l].incident_at(x)?;
        if !inc.irradiance.is_finite() {
            return None;
        }
        let ray = Ray {
            origin: x,
            direction: inc.toward,
        };
        sh.rays += 1;
        self.bvh.all_hits(&ray, 0.0, inc.distance, &mut sh.hits);
        Some(if self.transmittance_only {
            self.shadow_transmittance(inc.distance, inc.irradiance, skip, sh)
        } else {
            self.shadow_composite(inc.distance, inc.irradiance, skip, None, sh)
        })
    }

    /// What a model that reads only E_l and T_l (`LightNeed::IrradianceTransmittance`) needs
    /// of the shadow ray of length `distance` whose hits are in `sh.hits`: the transmittance
    /// alone, one sum and one exponential (`optics::transmittance`), with no sweep and
    /// no cut, and the radiance left at zero (such a model must not read it; tested for every
    /// model).
    fn shadow_transmittance(
        &self,
        distance: f64,
        irradiance: DVec3,
        skip: impl Fn(u32) -> bool,
        sh: &mut ShadowScratch,
    ) -> LightSample {
        let transmittance = transmittance(
            &self.cutter,
            &sh.hits,
            (0.0, distance),
            skip,
            &mut sh.depths,
        );
        LightSample {
            radiance: DVec3::ZERO,
            irradiance,
            transmittance,
        }
    }

    /// The emission model along a shadow ray of length `distance` whose hits are in `sh.hits`,
    /// with the light's `irradiance` as background (docs/design.md §2, lit model); with `cut`, it
    /// may stop where the transmittance falls to ε (`IntervalCutter::composite`), and then
    /// sets `sh.was_cut`.
    fn shadow_composite(
        &self,
        distance: f64,
        irradiance: DVec3,
        skip: impl Fn(u32) -> bool,
        cut: Option<(f64, DVec3)>,
        sh: &mut ShadowScratch,
    ) -> LightSample {
        let (c, was_cut) = sh.compositor.composite(
            &self.cutter,
            &sh.hits,
            (0.0, distance),
            skip,
            (irradiance, cut),
        );
        sh.was_cut |= was_cut;
        LightSample {
            radiance: c.radiance,
            irradiance,
            transmittance: c.transmittance,
        }
    }

    /// Q(x) of the scene's model (docs/design.md §2) at a point inside interval `iv`.
    fn source(&self, x: DVec3, iv: &Interval, sh: &mut ShadowScratch) -> DVec3 {
        sh.lights.clear();
        for l in 0..self.scene.lights.len() {
            if let Some(s) = self.light_sample(x, l, |_| false, sh) {
                sh.lights.push(s);
            }
        }
        self.model.source(&self.params, iv, &sh.lights)
    }

    /// The part of Q(x) that light `l` contributes at x = ray.at(t) in interval `k` (Q is
    /// linear in the lights, docs/design.md §2): lit w·L_l(x); single-scatter α(x)·E_l(x)·T_l(x)/4π,
    /// into `out[i]` for each t = `ts[i]`, the nodes of one quadrature segment. The shadow rays
    /// test only the candidate occluders of interval `k` (`reference::shadow`), narrowed on
    /// first use from the list of the whole camera ray (`ShadowScratch::wide`), and read that
    /// list once for all of them (`Occluders::hits_batch`); they are then composited one by
    /// one, in node order, as the kept layouts of `optics::intervals` expect.
    fn light_sources(
        &self,
        ray: &Ray,
        ts: &[f64],
        (k, iv): (usize, &Interval),
        l: usize,
        sh: &mut ShadowScratch,
        out: &mut [DVec3],
    ) {
        let light = &self.scene.lights[l];
        if sh.occluders.len() <= k {
            sh.occluders.resize_with(k + 1, Occluders::default);
        }
        let mut shadow = [ShadowRay {
            t: 0.0,
            ray: *ray,
            t_max: 0.0,
        }; MAX_NODES];
        let mut lit = [(0, DVec3::ZERO); MAX_NODES];
        let mut n = 0;
        for (i, &t) in ts.iter().enumerate() {
            out[i] = DVec3::ZERO;
            let x = ray.at(t);
            let Some(inc) = light.incident_at(x) else {
                continue;
            };
            if !inc.irradiance.is_finite() {
                continue;
            }
            if !sh.occluders[k].covers(k, l, t) {
                // `integrate_per_light` gathers the whole ray's list for light l before its
                // quadrature, and every node lies in one of the ray's intervals.
                debug_assert!(sh.wide.covers(WHOLE_RAY, l, t));
                sh.occluders[k].narrow(&sh.wide, ray, (k, l), light, (iv.t0, iv.t1));
            }
            shadow[n] = ShadowRay {
                t,
                ray: Ray {
                    origin: x,
                    direction: inc.toward,
                },
                t_max: inc.distance,
            };
            lit[n] = (i, inc.irradiance);
            n += 1;
        }
        sh.rays += n as u64;
        let mut batch = std::mem::take(&mut sh.batch);
        batch.resize_with(MAX_NODES, Vec::new);
        sh.occluders[k].hits_batch(&shadow[..n], &mut batch[..n]);
        let cut = sh.shadow_cut;
        for ((s, &(i, irradiance)), hits) in shadow[..n].iter().zip(&lit[..n]).zip(&mut batch) {
            std::mem::swap(&mut sh.hits, hits);
            let sample = if self.transmittance_only {
                self.shadow_transmittance(s.t_max, irradiance, |_| false, sh)
            } else {
                self.shadow_composite(s.t_max, irradiance, |_| false, cut, sh)
            };
            std::mem::swap(&mut sh.hits, hits);
            out[i] = self.model.light_source(&self.params, iv, &sample);
        }
        sh.batch = batch;
    }

    /// Σ_k T(0,t0_k)·∫₀^{U_k} Q du over the finite intervals, adaptively. Q is linear in the
    /// lights, so each light is integrated on its own, with only its own kinks as breakpoints
    /// and one shadow ray per node (integrating the sum would put every light's kinks into
    /// every light's integral), each to tol/m; the summed estimates are ≤ tol. The constant
    /// part k·E of Q (single-scatter's a·E) is exact: k·E·U.
    fn integrate_per_light(
        &self,
        ray: &Ray,
        intervals: &[Interval],
        pieces: &[Piece],
        sh: &mut ShadowScratch,
    ) -> (DVec3, DVec3, bool) {
        let render = &self.scene.render;
        let mut value = DVec3::ZERO;
        let mut error = DVec3::ZERO;
        let mut unconverged = false;
        let k = self.model.emission_factor(&self.params);
        if k != 0.0 {
            for p in pieces {
                value += (p.weight * (p.hi - p.lo) * k) * intervals[p.tag].emission;
            }
        }
        let Some(first) = intervals.first() else {
            return (value, error, unconverged);
        };
        let m = self.scene.lights.len();
        // pieces[k] spans the whole of interval k in u: [0, U_k] (built so by the caller).
        let t_of = |k: usize, u: f64| t_at(&intervals[k], pieces[k].hi, u);
        let (mut marks, mut kinks, mut sides) = (Vec::new(), Vec::new(), Vec::new());
        let mut split = Vec::with_capacity(pieces.len());
        let mut bounds = Vec::with_capacity(pieces.len());
        let share = render.tol / m as f64;
        for (l, light) in self.scene.lights.iter().enumerate() {
            // The far end of the ray, whose weight cannot matter, is bounded instead of
            // integrated: half its bound goes into the value, half into the error.
            let (kept, tail) = self.tail_cut(ray, intervals, pieces, light, TAIL_SHARE * share);
            value += 0.5 * tail;
            error += 0.5 * tail;
            let pieces = &pieces[..kept];
            let Some(last) = intervals[..kept].last() else {
                continue;
            };
            sh.wide
                .gather(&self.bvh, ray, (WHOLE_RAY, l), light, (first.t0, last.t1));
            self.breakpoints(ray, (first.t0, last.t1), light, &sh.wide, &mut marks);
            kinks.clear();
            sides.clear();
            kinks.extend(marks.iter().map(|&(t, _)| t));
            sides.extend(marks.iter().map(|&(_, side)| side));
            split_at_kinks(pieces, intervals, &kinks, &mut split);
            let kink_in = |k: usize, lo: f64, hi: f64| {
                let (a, b) = (t_of(k, lo), t_of(k, hi));
                let from = kinks.partition_point(|&t| t <= a);
                let to = kinks.partition_point(|&t| t < b);
                if from >= to {
                    // Also where clamping t(u) to the interval collapses (a, b) to a point.
                    return None;
                }
                let mid = t_of(k, 0.5 * (lo + hi));
                let t = kinks[from..to]
                    .iter()
                    .copied()
                    .min_by(|x, y| (x - mid).abs().total_cmp(&(y - mid).abs()))?;
                let iv = &intervals[k];
                let u = opacity(iv.sigma * (t - iv.t0));
                (u > lo && u < hi).then_some(u)
            };
            // Shadow rays through dense gas stop where their transmittance falls to ε; what
            // that can change is bounded below, if it happened.
            // (Single-scatter's shadow rays trace the transmittance alone and are never cut.)
            let cut = if self.transmittance_only {
                None
            } else {
                self.shadow_cut(ray, first.t0, light, CUT_SHARE * share)
            };
            sh.shadow_cut = cut.map(|(epsilon, bound, _)| (epsilon, bound));
            sh.was_cut = false;
            let tol = share * (1.0 - 0.5 * TAIL_SHARE - CUT_SHARE);
            // The largest channel of q_l's bound over each interval (∞ where none is known).
            bounds.clear();
            bounds.extend(intervals[..kept].iter().map(|iv| {
                let q = self.source_bound(ray, iv.t0, light);
                q.map_or(f64::INFINITY, |q| q.max_element())
            }));
            let singular_ends = |k: usize, lo: f64, hi: f64, hair: f64| {
                let near = (t_of(k, lo - hair), t_of(k, hi + hair));
                singular_ends(&kinks, &sides, &intervals[k], near, (lo, hi, hair))
            };
            let nodes = |k: usize, us: &[f64], out: &mut [DVec3]| {
                let mut ts = [0.0; MAX_NODES];
                for (t, &u) in ts.iter_mut().zip(us) {
                    *t = t_of(k, u);
                }
                self.light_sources(ray, &ts[..us.len()], (k, &intervals[k]), l, sh, out);
            };
            let r = integrate_adaptive_batched(
                &split,
                tol,
                MAX_SEGMENTS,
                nodes,
                (
                    &kink_in,
                    |k, lo, hi| {
                        let bound = pieces[k].weight * bounds[k];
                        first_level((lo, hi), bound, self.r5_share * share)
                    },
                    singular_ends,
                ),
            );
            value += r.value;
            error += r.error;
            unconverged |= !r.converged;
            if let (true, Some((epsilon, _, q))) = (sh.was_cut, cut) {
                let weight: f64 = pieces.iter().map(|p| p.weight * (p.hi - p.lo)).sum();
                error += (2.0 * epsilon * weight) * q;
            }
            sh.shadow_cut = None;
        }
        (value, error, unconverged)
    }

    /// The breakpoints of light `light`'s integral along `ray` in (t_lo, t_hi), sorted, into
    /// `out` (cleared first), each with the sides on which it is a square-root point
    /// (`kinks::CROSSES_ABOVE`, `CROSSES_BELOW`): its kinks (`optics::kinks`, found among `occluders`, a list
    /// gathered towards that light for a stretch of `ray` that holds (t_lo, t_hi):
    /// [`Occluders::sided_tangencies`]), and for a point light the point
    /// where the ray passes closest to it, t*, with a graded mesh around it. There the
    /// irradiance I/d² = I/(h² + (t − t*)²) peaks, as sharply as the ray passes close (h); as a
    /// breakpoint the peak is an end of two segments (where the rules put nodes densely) rather
    /// than a feature between the nodes of one. A peak much narrower than its segments was
    /// still under-resolved there, by both rules alike (err 1.3–1.7× below the actual error at
    /// a pixel of the dark-roof honesty scene), so t* ± h·3ᵏ, k = 0, 1, …, are breakpoints
    /// too: each segment then spans at most a factor 3 in distance from t*, where the Lorentzian
    /// is smooth on the segment's scale. That costs 2·log₃(L/h) segments on a ray that passes
    /// the light at h across a stretch L, and nothing where h is not below L.
    fn breakpoints(
        &self,
        ray: &Ray,
        (t_lo, t_hi): (f64, f64),
        light: &Light,
        occluders: &Occluders,
        out: &mut Vec<(f64, u8)>,
    ) {
        out.clear();
        occluders.sided_tangencies(ray, (t_lo, t_hi), light, out);
        if let Light::Point { position, .. } = *light {
            let t = (position - ray.origin).dot(ray.direction);
            let h = (position - ray.at(t)).length();
            let inside = |x: f64| x > t_lo && x < t_hi;
            let before = out.len();
            // The peak is smooth, but its marks keep the substitution at both ends and the
            // kinks' safety factor, with which the dark-roof scene's err was found honest.
            let both = CROSSES_ABOVE | CROSSES_BELOW;
            if inside(t) {
                out.push((t, both));
            }
            // Written so that h = 0 or NaN adds nothing more (and cannot loop).
            let mut d = h;
            while d > 0.0 && (inside(t - d) || inside(t + d)) {
                out.extend(
                    [t - d, t + d]
                        .into_iter()
                        .filter(|&x| inside(x))
                        .map(|x| (x, both)),
                );
                d *= GRADE;
            }
            if out.len() > before {
                out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            }
        }
    }

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
    fn shadow_cut(
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
    fn tail_cut(
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
    fn source_bound(&self, ray: &Ray, t: f64, light: &Light) -> Option<DVec3> {
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

    /// A bound on |finite-σ integral − σ → ∞ limit| for a dense interval (per channel, before
    /// the transmittance in front of it). The limit neglects the variation of Q over a few skin
    /// depths, whose first-order term is O(1/σ) against the geometry of the entry (the interval
    /// length Δ = 2r·μ_in for a sphere entered from outside), i.e. O(1/τ) relative to the
    /// largest source: err = F·Qmax/τ with F = [`LIMIT_REMAINDER_FACTOR`], generous against the
    /// curvature and light-angle factors, and Qmax ≥ Q for every model of docs/design.md §2 (the
    /// emission colour, plus every light's unoccluded irradiance weighted by 1 + albedo, plus
    /// the limit value itself). Where the limit applies, τ ≥ 1e7 or so, and the term is tiny.
    fn limit_remainder(&self, ray: &Ray, iv: &Interval, q: DVec3) -> DVec3 {
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
    fn opaque_source(
        &self,
        ray: &Ray,
        iv: &Interval,
        hits: &[Hit],
        sigma_opaque: f64,
        sh: &mut ShadowScratch,
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
                    let n = (x - p.center).normalize_or_zero();
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
                let Some(rest) = self.light_sample(x, l, skip, sh) else {
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

/// Part of each light's share of `tol` that the far end of a camera ray may take as a bound
/// instead of being integrated (`VolumeRenderer::tail_cut`); the quadrature keeps the rest. Small,
/// so that the actual error stays far below tol where the estimates are pessimistic (issue 10
/// asks adaptive tol 1e-4 to be ≥ 100× more accurate than Riemann-100, about 8e-7).
pub const TAIL_SHARE: f64 = 1e-3;

/// Part of each light's share of `tol` that the quadrature's shadow rays may spend by stopping
/// where their transmittance has fallen to ε (`VolumeRenderer::shadow_cut`): ε is this part
/// of the share over twice the bound of q_l, a few times 1e-8 on the 1UUN benchmark, where no shadow
/// ray gets that dark. In a million random spheres half of the shadow rays' intervals lie
/// behind that point.
pub const CUT_SHARE: f64 = 1e-3;

/// The largest colour and albedo of any particle, per channel, if no colour, albedo or light
/// of the scene is negative (`VolumeRenderer::source_bounds`).
fn source_bounds(scene: &Scene) -> Option<(DVec3, DVec3)> {
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
const LIMIT_MEMBER_FRACTION: f64 = 1e-3;
/// Which ends of the segment [lo, hi] (in u) of interval `iv` are square-root points of a
/// light's integrand ([`integrate_adaptive_with_ends`]), from its `kinks` (sorted) and their
/// `sides`: a kink at the low end whose shadow rays cross its sphere above it, one at the high
/// end crossed below it; a kink inside (one that could not be a breakpoint) counts as both.
/// `(a, b)` is the segment in t, widened by `hair` in u, within which a kink is at an end.
fn singular_ends(
    kinks: &[f64],
    sides: &[u8],
    iv: &Interval,
    (a, b): (f64, f64),
    (lo, hi, hair): (f64, f64, f64),
) -> u8 {
    let from = kinks.partition_point(|&t| t <= a);
    // Also where clamping t(u) to the interval collapses (a, b) to a point, or reverses it
    // (a ray through a point light): no kink, as in `kink_in`.
    let to = kinks.partition_point(|&t| t < b).max(from);
    let mut ends = 0;
    for (&t, &side) in kinks[from..to].iter().zip(&sides[from..to]) {
        let u = opacity(iv.sigma * (t - iv.t0));
        ends |= if (u - lo).abs() <= hair {
            if side & CROSSES_ABOVE != 0 {
                LOW_END
            } else {
                0
            }
        } else if (u - hi).abs() <= hair {
            if side & CROSSES_BELOW != 0 {
                HIGH_END
            } else {
                0
            }
        } else {
            BOTH_ENDS
        };
    }
    ends
}

/// The level at which the quadrature starts a segment [lo, hi] (in u) of a piece whose
/// integrand is bounded by `bound` per unit of u (its weight times Qb): K15 for an optically
/// deep segment ([`COARSE_DEPTH`]; σ·Δt of [lo, hi] is ln(1 − lo) − ln(1 − hi)), R5 where
/// the segment's whole contribution is at most `r5_limit` ([`R5_SHARE`] of the light's share
/// of tol), G7 otherwise.
fn first_level((lo, hi): (f64, f64), bound: f64, r5_limit: f64) -> Level {
    // Also K15 where the depth is NaN.
    let shallow = (-lo).ln_1p() - (-hi).ln_1p() <= COARSE_DEPTH;
    if !shallow {
        Level::K15
    } else if bound * (hi - lo) <= r5_limit {
        Level::R5
    } else {
        Level::G7
    }
}

/// `pieces` (of `intervals`, in u) cut at every one of the sorted `kinks` (in t) inside them,
/// into `split` (cleared first). Every kink is a breakpoint from the start: a shadow that falls
/// between the nodes of a segment would otherwise go unseen by both rules, and by the error
/// estimate.
fn split_at_kinks(pieces: &[Piece], intervals: &[Interval], kinks: &[f64], split: &mut Vec<Piece>) {
    split.clear();
    for p in pieces {
        let iv = &intervals[p.tag];
        let from = kinks.partition_point(|&t| t <= iv.t0);
        let to = kinks.partition_point(|&t| t < iv.t1);
        let mut lo = p.lo;
        for &t in &kinks[from..to] {
            let u = opacity(iv.sigma * (t - iv.t0));
            if u > lo && u < p.hi {
                split.push(Piece { lo, hi: u, ..*p });
                lo = u;
            }
        }
        split.push(Piece { lo, ..*p });
    }
}

/// Coefficient of the first-order remainder of the σ → ∞ limit, err = F·Qmax/τ (see
/// `VolumeRenderer::limit_remainder`).
const LIMIT_REMAINDER_FACTOR: f64 = 1e3;

/// Whether interval `iv` (finite σ) is too dense for the quadrature: its skin depth 1/σ is
/// within 1/[`RESOLUTION_LIMIT`] f64 spacings of the ray parameter near its start, and it is
/// optically deep. Then the σ → ∞ limit is the better answer (docs/design.md §3: "very large σ
/// converge to the Θmax = 1 limit, never to a collapsed quadrature"). Returns the σ from which a
/// particle counts as part of that limit: the particles whose own skin depth is unresolved.
fn beyond_resolution(ray: &Ray, iv: &Interval) -> Option<f64> {
    let sigma_unresolved = unresolved_sigma(ray, iv);
    (iv.sigma >= sigma_unresolved && iv.sigma * iv.length() >= LIMIT_MIN_DEPTH)
        .then_some(sigma_unresolved * LIMIT_MEMBER_FRACTION)
}

/// The σ whose skin depth is [`RESOLUTION_LIMIT`] of the f64 resolution δ of positions at the
/// start of `iv` (x = o + t·d rounds by about 8ε·(|o| + |t|)).
fn unresolved_sigma(ray: &Ray, iv: &Interval) -> f64 {
    let delta = 8.0 * f64::EPSILON * (ray.origin.abs().max_element() + iv.t0.abs());
    RESOLUTION_LIMIT / delta.max(f64::MIN_POSITIVE)
}

/// The ray parameter t(u) = t0 − ln(1 − u)/σ of interval `iv` (module documentation), with u
/// clamped to [0, U], U = 1 − e^{−σΔ} the interval's end. Callers widen segments by a hair to
/// see kinks at their ends; for an optical depth above ~37, U rounds to 1 and u a hair above it
/// would make ln_1p(−u) NaN.
fn t_at(iv: &Interval, u_max: f64, u: f64) -> f64 {
    // max/min rather than clamp: never a panic, whatever u_max is.
    let u = u.max(0.0).min(u_max);
    (iv.t0 - (-u).ln_1p() / iv.sigma).clamp(iv.t0, iv.t1)
}

impl RadianceEstimator for VolumeRenderer<'_> {
    fn radiance(&self, ray: &Ray) -> Sample {
        // One set of buffers per thread instead of new ones per camera ray: a pixel of 1UUN
        // allocated a few dozen vectors (an occluder list per interval) and grew them again.
        thread_local! {
            static SCRATCH: RefCell<ShadowScratch> = RefCell::default();
        }
        SCRATCH.with(|cell| match cell.try_borrow_mut() {
            Ok(mut sh) => {
                sh.reset();
                self.radiance_with(ray, &mut sh)
            }
            // Re-entered on this thread (not done today): fresh buffers.
            Err(_) => self.radiance_with(ray, &mut ShadowScratch::default()),
        })
    }

    /// The adaptive integrator estimates its error (0 for the closed-form emission model); the
    /// Riemann sums have no estimate, so no `err` layer is written for them.
    fn estimates_error(&self) -> bool {
        matches!(self.integrator, Integrator::Adaptive)
    }
}

impl VolumeRenderer<'_> {
    /// [`RadianceEstimator::radiance`] with the caller's shadow-ray buffers (tests read what
    /// they hold afterwards).
    fn radiance_with(&self, ray: &Ray, sh: &mut ShadowScratch) -> Sample {
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
                let sigma_opaque = unresolved_sigma(ray, iv) * LIMIT_MEMBER_FRACTION;
                end = transmittance * self.opaque_source(ray, iv, &hits, sigma_opaque, sh);
                finite = k;
                transmittance = 0.0;
                break;
            }
            if let Some(sigma_opaque) = beyond_resolution(ray, iv) {
                let q = self.opaque_source(ray, iv, &hits, sigma_opaque, sh);
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
                            self.source(ray.at(t), iv, sh)
                        });
                }
                (sum, DVec3::ZERO, false)
            }
            Integrator::Adaptive => self.integrate_per_light(ray, intervals, &pieces, sh),
        };
        Sample {
            radiance: background + end + value,
            error: error + limit_error,
            shadow_rays: sh.rays,
            unconverged: unconverged || !(value + end).is_finite(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Camera;
    use crate::optics::{models, Model, Particle};
    use crate::scene::{LightWeight, RenderMode, RenderSettings};

    /// A gas sphere of the given opacity Θmax, its albedo its colour.
    fn sphere(center: DVec3, radius: f64, color: DVec3, opacity: f64) -> Particle {
        Particle {
            center,
            radius,
            color,
            sigma: crate::optics::extinction::sigma_from_opacity(opacity, radius),
            albedo: color,
            ks: 0.0,
            shininess: 32.0,
        }
    }

    /// One sphere under a roof of 3×3×3 overlapping spheres of opacity 0.999 (optical depth 6.9
    /// through a centre), lit from straight above: every shadow ray from the sphere crosses
    /// three layers of the roof, most of them near a centre, and its transmittance falls far
    /// below the cut's ε at tol 1e-4 (about 2.5e-8); near the gaps between the columns it
    /// does not, so the cut comes and goes along each camera ray.
    fn roof_scene(model: Model, tol: f64) -> Scene {
        let mut particles = vec![sphere(DVec3::ZERO, 1.0, DVec3::new(0.9, 0.6, 0.3), 0.5)];
        for i in 0..27 {
            let c = DVec3::new((i % 3) as f64, 3.0 + (i / 9) as f64, ((i / 3) % 3) as f64);
            let color = DVec3::new(0.2, 0.5, 0.9) * (0.5 + 0.05 * i as f64 % 0.5);
            particles.push(sphere(
                1.4 * (c - DVec3::new(1.0, 0.0, 1.0)),
                1.0,
                color,
                0.999,
            ));
        }
        Scene {
            source: "test".into(),
            camera: Camera::new(
                DVec3::new(0.0, 0.0, -8.0),
                DVec3::ZERO,
                DVec3::Y,
                30.0,
                8,
                8,
            ),
            render: RenderSettings {
                mode: RenderMode::Volume,
                model,
                light_weight: LightWeight::Mean,
                tol,
                ..RenderSettings::default()
            },
            lights: vec![Light::Directional {
                direction: -DVec3::Y,
                irradiance: DVec3::new(1.0, 2.0, 0.5),
            }],
            particles,
            warnings: vec![],
        }
    }

    /// A camera ray's sample at tol 1e-4 against its truth (a much tighter render): both
    /// converged, err covers the difference (with the truth's own err), and err meets tol.
    fn assert_honest(model: Model, (x, y): (f64, f64), got: &Sample, want: &Sample) {
        assert!(!got.unconverged && !want.unconverged);
        let actual = (got.radiance - want.radiance).abs();
        assert!(
            actual.cmple(got.error + want.error).all(),
            "{model} ({x}, {y}): off by {actual}, err {}",
            got.error
        );
        assert!(got.error.max_element() <= 1e-4 * (1.0 + 1e-9));
    }

    /// The lit model's shadow rays under a dark roof are cut, and err covers the cut;
    /// single-scatter's are not (it traces the transmittance alone, exactly,
    /// `VolumeRenderer::shadow_transmittance`), and its err covers the rest.
    #[test]
    fn shadow_rays_under_a_dark_roof_are_cut_and_err_covers_the_cut() {
        for model in [models::LIT, models::SINGLE_SCATTER] {
            let scene = roof_scene(model, 1e-4);
            let truth_scene = roof_scene(model, 1e-11);
            let (r, truth) = (
                VolumeRenderer::new(&scene, Integrator::Adaptive),
                VolumeRenderer::new(&truth_scene, Integrator::Adaptive),
            );
            for (x, y) in [(0.0, 0.0), (0.3, -0.2), (-0.5, 0.6), (0.8, 0.1)] {
                let ray = Ray::new(DVec3::new(x, y, -8.0), DVec3::Z);
                let mut sh = ShadowScratch::default();
                let got = r.radiance_with(&ray, &mut sh);
                assert_eq!(
                    sh.was_cut,
                    model == models::LIT,
                    "{model} ({x}, {y}): whether a shadow ray was cut"
                );
                let want = truth.radiance(&ray);
                assert_honest(model, (x, y), &got, &want);
            }
        }
    }

    /// Segments of small weight start at R5 ([`R5_SHARE`]): fewer shadow rays in all than with
    /// every segment at G7 or above, and err still covers |value − tol 1e-11 render|, on rays
    /// through the sphere, its shadow and the roof, for both models with a per-light part.
    #[test]
    fn segments_of_small_weight_start_at_five_nodes_and_stay_honest() {
        for model in [models::LIT, models::SINGLE_SCATTER] {
            let scene = roof_scene(model, 1e-4);
            let truth_scene = roof_scene(model, 1e-11);
            let r = VolumeRenderer::new(&scene, Integrator::Adaptive);
            let mut no_r5 = VolumeRenderer::new(&scene, Integrator::Adaptive);
            no_r5.r5_share = 0.0;
            let truth = VolumeRenderer::new(&truth_scene, Integrator::Adaptive);
            let (mut rays, mut rays_no_r5) = (0, 0);
            for i in 0..36 {
                let (x, y) = (-1.2 + 0.4 * (i % 6) as f64, -1.1 + 0.9 * (i / 6) as f64);
                let ray = Ray::new(DVec3::new(x, y, -8.0), DVec3::Z);
                let (got, want) = (r.radiance(&ray), truth.radiance(&ray));
                rays += got.shadow_rays;
                rays_no_r5 += no_r5.radiance(&ray).shadow_rays;
                assert_honest(model, (x, y), &got, &want);
            }
            assert!(rays < rays_no_r5, "{model}: {rays} against {rays_no_r5}");
            eprintln!("{model}: {rays} shadow rays, {rays_no_r5} with every segment at G7");
        }
    }

    /// The shadow-ray buffers are kept per thread from one camera ray to the next
    /// (`RadianceEstimator::radiance`): a camera ray gives the same bits whatever ray came
    /// before it on the thread, as with fresh buffers. The occluder lists are keyed by interval
    /// and light, which the next ray reuses; a list left keyed would give it the wrong
    /// occluders.
    #[test]
    fn reused_shadow_buffers_change_no_bit() {
        for model in [models::LIT, models::SINGLE_SCATTER] {
            let scene = roof_scene(model, 1e-4);
            let r = VolumeRenderer::new(&scene, Integrator::Adaptive);
            let rays: Vec<Ray> = (0..24)
                .map(|i| {
                    let (x, y) = (-1.2 + 0.1 * i as f64, 0.9 - 0.07 * i as f64);
                    Ray::new(DVec3::new(x, y, -8.0), DVec3::Z)
                })
                .collect();
            let bits = |s: Sample| {
                (
                    s.radiance.to_array().map(f64::to_bits),
                    s.error.to_array().map(f64::to_bits),
                    s.shadow_rays,
                )
            };
            let fresh: Vec<_> = rays
                .iter()
                .map(|ray| bits(r.radiance_with(ray, &mut ShadowScratch::default())))
                .collect();
            assert!(fresh.iter().filter(|f| f.2 > 0).count() > 12, "{model}");
            // Forwards, backwards and forwards again on this thread's buffers.
            for pass in 0..3 {
                let order: Vec<usize> = if pass == 1 {
                    (0..rays.len()).rev().collect()
                } else {
                    (0..rays.len()).collect()
                };
                for i in order {
                    assert_eq!(bits(r.radiance(&rays[i])), fresh[i], "{model} ray {i}");
                }
            }
        }
    }

    /// Camera rays that pass a point light inside a gas sphere at distances h from 1e-4 to 0.3
    /// of its radius: the peak of I/d² is as narrow as h. err covers |value − tol 1e-7
    /// render| in every channel, for both models with a per-light part, and the breakpoints
    /// hold the light's closest approach t* with the graded mesh t* ± h·3ᵏ around it.
    #[test]
    fn rays_passing_close_to_a_point_light_inside_gas_are_honest() {
        let gas = |center: DVec3, color: DVec3| sphere(center, 1.0, color, 0.9);
        for model in [models::LIT, models::SINGLE_SCATTER] {
            let scene = |tol: f64| {
                let mut s = roof_scene(model, tol);
                s.particles = vec![
                    gas(DVec3::ZERO, DVec3::new(0.9, 0.6, 0.3)),
                    gas(DVec3::new(0.4, 0.3, 0.5), DVec3::new(0.2, 0.5, 0.9)),
                ];
                s.lights = vec![Light::Point {
                    position: DVec3::new(0.1, 0.05, 0.2),
                    intensity: DVec3::new(1.0, 0.5, 0.25),
                    falloff: crate::optics::Falloff::InverseSquare,
                }];
                s
            };
            // At h = 1e-4 the pixel is about 1e4 (I/d² peaks at 1e8): a truth at tol 1e-7 is
            // already 1e-11 relative.
            let (coarse, fine) = (scene(1e-4), scene(1e-7));
            let (r, truth) = (
                VolumeRenderer::new(&coarse, Integrator::Adaptive),
                VolumeRenderer::new(&fine, Integrator::Adaptive),
            );
            let light = coarse.lights[0];
            for h in [1e-4, 1e-3, 1e-2, 0.1, 0.3] {
                // Along z, passing the light at distance h in x.
                let origin = DVec3::new(0.1 + h, 0.05, -8.0);
                let ray = Ray::new(origin, DVec3::Z);
                let mut marks = Vec::new();
                let mut wide = Occluders::default();
                wide.gather(&r.bvh, &ray, (0, 0), &light, (6.0, 10.0));
                r.breakpoints(&ray, (6.0, 10.0), &light, &wide, &mut marks);
                let t_star = 8.2;
                let near = |x: f64| {
                    marks
                        .iter()
                        .any(|&(m, _)| (m - x).abs() <= 1e-9 * (1.0 + x))
                };
                assert!(near(t_star), "{model} h {h}: {marks:?}");
                let mut graded = 0;
                let mut d = h;
                while d < 1.5 {
                    assert!(
                        near(t_star - d) && near(t_star + d),
                        "{model} h {h}: {marks:?}"
                    );
                    graded += 2;
                    d *= GRADE;
                }
                assert!(graded >= 2, "{model} h {h}");
                let got = r.radiance(&ray);
                let want = truth.radiance(&ray);
                assert!(
                    !got.unconverged && !want.unconverged,
                    "{model} h {h}: {} {}",
                    got.unconverged,
                    want.unconverged
                );
                let actual = (got.radiance - want.radiance).abs();
                assert!(
                    actual.cmple(got.error + want.error).all(),
                    "{model} h {h}: off by {actual}, err {}",
                    got.error
                );
                assert!(
                    got.error.max_element() <= 1e-4 * (1.0 + 1e-9),
                    "{model} h {h}"
                );
            }
        }
    }

    #[test]
    fn t_of_u_stays_in_the_interval_for_deep_intervals() {
        // Optical depth 50: U = 1 − e^{−50} rounds to 1; a segment end widened by a hair lies
        // above it and must give the interval's end, not NaN.
        let iv = Interval {
            t0: 2.0,
            t1: 3.0,
            sigma: 50.0,
            emission: DVec3::ONE,
            albedo: DVec3::ONE,
        };
        let u_max = crate::optics::emission::opacity(iv.sigma * iv.length());
        assert_eq!(u_max, 1.0);
        for u in [u_max, u_max + 1e-9, 1.5, f64::INFINITY] {
            assert_eq!(t_at(&iv, u_max, u), iv.t1, "u = {u}");
        }
        assert_eq!(t_at(&iv, u_max, -1e-9), iv.t0);
        let mid = t_at(&iv, u_max, 0.5);
        assert!((mid - (2.0 + std::f64::consts::LN_2 / 50.0)).abs() < 1e-15);
    }
}

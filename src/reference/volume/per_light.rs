//! The per-light parts of Q, integrated adaptively along a camera ray, and the shadow rays
//! they need (docs/design.md §2 lit and single-scatter models, §3).
//!
//! Inside interval k of the ray, T(0,t) = T(0,t0)·e^{−σ(t−t0)}; with the substitution
//! u = 1 − e^{−σ(t−t0)} (du = σ·e^{−σ(t−t0)} dt) its part of the integral is
//!
//!   T(0,t0)·∫₀^{U} Q(x(t(u))) du,   U = 1 − e^{−σΔ},   t(u) = t0 − ln(1 − u)/σ,
//!
//! so the transmittance weight is integrated exactly and the quadrature only sees the bounded
//! source Q, whatever σ is (a thin interval gives a short u-range, a dense one a u-range near 1
//! whose far end carries almost no weight). Q is linear in the lights, so each light's part is
//! integrated on its own (one shadow ray per node, only that light's kinks as breakpoints, its
//! share tol/m of the tolerance: the estimates add up to ≤ tol), by globally adaptive
//! Gauss–Kronrod (`reference::quadrature`); the constant part k·E (single-scatter's a·E) is
//! exact, k·E·U.
//!
//! **Kinks.** Q is smooth inside an interval except where a shadow ray grazes a sphere. Those
//! camera-ray parameters are computed in closed form (`optics::kinks`: ray–cylinder for
//! directional lights, ray–cone for point lights) and every one is a breakpoint from the start
//! (a shadow that falls between the nodes of a segment would otherwise be missed by both rules,
//! and by the error estimate with them). The square root of a kink lies on one side of it, the
//! side where the shadow rays cross the grazed sphere (`kinks::push_sided_tangencies`); the
//! segment on that side is integrated with an endpoint substitution that flattens that end and
//! turns the square root into a smooth integrand, and its error estimate carries a safety
//! factor, while the segment on the other side is integrated as it is
//! (`quadrature::integrate_adaptive_with_ends`). Kinks the closed form might miss (round-off in
//! the roots) are left to the adaptivity.
//!
//! **Point lights.** Where the camera ray passes closest to a point light, the irradiance I/d²
//! peaks, as sharply as the ray passes close; that point and a graded mesh about it are
//! breakpoints ([`VolumeRenderer::breakpoints`]).
//!
//! **Shadow rays** test only the candidate occluders of their camera-ray interval
//! (`reference::shadow::Occluders`), with the same hits as a traversal of the whole BVH: one BVH
//! query per camera ray and light, from which each interval's list is narrowed. The quadrature
//! asks for the nodes of a segment's level together (`quadrature::integrate_adaptive_batched`),
//! and their shadow rays read that list once, each candidate tested against all of them in SIMD
//! lanes (`Occluders::hits_batch`); the composites follow one by one, in node order, as the
//! kept end orders of `reference::shadow` expect.

use super::budget::{quadrature_tol, RAY_TAIL_SHARE, SHADOW_STOP_SHARE};
use super::VolumeRenderer;
use crate::geometry::{Hit, Ray};
use crate::optics::emission::opacity;
use crate::optics::intervals::Interval;
use crate::optics::kinks::{CROSSES_ABOVE, CROSSES_BELOW};
use crate::optics::light::Light;
use crate::optics::source::LightSample;
use crate::optics::transmittance::transmittance;
use crate::reference::quadrature::{
    integrate_adaptive_batched, Level, Piece, BOTH_ENDS, HIGH_END, LOW_END, MAX_NODES,
};
use crate::reference::shadow::{KeptEndOrders, Occluders, ShadowCompositor, ShadowRay};
use glam::DVec3;

/// Optical depth σ·Δt of a segment above which it starts at K15 rather than G7
/// ([`first_level`]). In u = 1 − e^{−σ(t−t0)} the map t(u) has its singularity at u = 1, which
/// lies 1/(e^τ − 1) segment widths beyond the end of a segment of depth τ: close enough for
/// deep segments (near Θmax = 1) to fool the 7-node estimate, while at τ ≤ 0.25 it is ≥ 3.5
/// widths away.
const K15_START_DEPTH: f64 = 0.25;

/// The interval tag of the whole camera ray's occluder list ([`ShadowBuffers::wide`]): no
/// interval has it.
const WHOLE_RAY_TAG: usize = usize::MAX;

/// Ratio of the distances from a point light's closest approach of successive breakpoints of
/// its graded mesh (`VolumeRenderer::breakpoints`).
pub(super) const POINT_LIGHT_GRADING: f64 = 3.0;

/// Segments per pixel and light at most; beyond it the remaining error estimate is reported as
/// it stands (the pixel then may miss `tol`, and says so in its `err` value).
pub const MAX_SEGMENTS: usize = 4000;

/// Per-camera-ray buffers for shadow rays (reused, so shadow rays do not allocate; and kept
/// per thread from one camera ray to the next, [`ShadowBuffers::reset`] between them).
#[derive(Default)]
pub(super) struct ShadowBuffers {
    pub(super) hits: Vec<Hit>,
    pub(super) compositor: KeptEndOrders,
    /// `optics::transmittance`'s buffer.
    pub(super) depths: Vec<(u32, f64)>,
    pub(super) lights: Vec<LightSample>,
    pub(super) rays: u64,
    /// Candidate occluders per interval of the camera ray, for the light being integrated.
    pub(super) occluders: Vec<Occluders>,
    /// The candidates of the whole camera ray for the light being integrated, which the
    /// intervals' lists are narrowed from (one BVH query per light instead of one per interval).
    pub(super) wide: Occluders,
    /// Where the quadrature's shadow rays for the light being integrated may stop: (ε, M) of
    /// `IntervalCutter::composite` (`VolumeRenderer::shadow_cut`); `None` for exact ones.
    pub(super) shadow_cut: Option<(f64, DVec3)>,
    /// Whether a shadow ray was cut since this was last cleared.
    pub(super) was_cut: bool,
    /// The hits of each shadow ray of a batch (`VolumeRenderer::light_sources`).
    pub(super) batch: Vec<Vec<Hit>>,
}

impl ShadowBuffers {
    /// Makes a buffer used for one camera ray ready for the next: counters and flags to their
    /// start, and every occluder list keyed to nothing, since the next ray's intervals have
    /// the same tags (a list left keyed would be taken for the new ray's and give it another
    /// ray's occluders).
    pub(super) fn reset(&mut self) {
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

impl VolumeRenderer<'_> {
    /// The shadow ray from `x` towards light `l`: L_l(x) (emission model with the light's
    /// irradiance as background), E_l(x) and T_l(x). `None` where the light sends nothing
    /// usable: x exactly at a point light (or so close that I/d² overflows), a measure-zero set.
    pub(super) fn light_sample(
        &self,
        x: DVec3,
        l: usize,
        skip: impl Fn(u32) -> bool,
        buffers: &mut ShadowBuffers,
    ) -> Option<LightSample> {
        let inc = self.scene.lights[l].incident_at(x)?;
        if !inc.irradiance.is_finite() {
            return None;
        }
        let ray = Ray {
            origin: x,
            direction: inc.toward,
        };
        buffers.rays += 1;
        self.bvh
            .all_hits(&ray, 0.0, inc.distance, &mut buffers.hits);
        Some(if self.transmittance_only {
            self.shadow_transmittance(inc.distance, inc.irradiance, skip, buffers)
        } else {
            self.shadow_composite(inc.distance, inc.irradiance, skip, None, buffers)
        })
    }

    /// What a model that reads only E_l and T_l (`LightNeed::IrradianceTransmittance`) needs
    /// of the shadow ray of length `distance` whose hits are in `buffers.hits`: the transmittance
    /// alone, one sum and one exponential (`optics::transmittance`), with no sweep and
    /// no cut, and the radiance left at zero (such a model must not read it; tested for every
    /// model).
    fn shadow_transmittance(
        &self,
        distance: f64,
        irradiance: DVec3,
        skip: impl Fn(u32) -> bool,
        buffers: &mut ShadowBuffers,
    ) -> LightSample {
        let transmittance = transmittance(
            &self.cutter,
            &buffers.hits,
            (0.0, distance),
            skip,
            &mut buffers.depths,
        );
        LightSample {
            radiance: DVec3::ZERO,
            irradiance,
            transmittance,
        }
    }

    /// The emission model along a shadow ray of length `distance` whose hits are in `buffers.hits`,
    /// with the light's `irradiance` as background (docs/design.md §2, lit model); with `cut`, it
    /// may stop where the transmittance falls to ε (`IntervalCutter::composite`), and then
    /// sets `buffers.was_cut`.
    fn shadow_composite(
        &self,
        distance: f64,
        irradiance: DVec3,
        skip: impl Fn(u32) -> bool,
        cut: Option<(f64, DVec3)>,
        buffers: &mut ShadowBuffers,
    ) -> LightSample {
        let (c, was_cut) = buffers.compositor.composite(
            &self.cutter,
            &buffers.hits,
            (0.0, distance),
            skip,
            (irradiance, cut),
        );
        buffers.was_cut |= was_cut;
        LightSample {
            radiance: c.radiance,
            irradiance,
            transmittance: c.transmittance,
        }
    }

    /// The part of Q(x) that light `l` contributes at x = ray.at(t) in interval `k` (Q is
    /// linear in the lights, docs/design.md §2): lit w·L_l(x); single-scatter α(x)·E_l(x)·T_l(x)/4π,
    /// into `out[i]` for each t = `ts[i]`, the nodes of one quadrature segment. The shadow rays
    /// test only the candidate occluders of interval `k` (`reference::shadow`), narrowed on
    /// first use from the list of the whole camera ray (`ShadowBuffers::wide`), and read that
    /// list once for all of them (`Occluders::hits_batch`); they are then composited one by
    /// one, in node order, as the kept layouts of `optics::intervals` expect.
    fn light_sources(
        &self,
        ray: &Ray,
        ts: &[f64],
        (k, iv): (usize, &Interval),
        l: usize,
        buffers: &mut ShadowBuffers,
        out: &mut [DVec3],
    ) {
        let light = &self.scene.lights[l];
        if buffers.occluders.len() <= k {
            buffers.occluders.resize_with(k + 1, Occluders::default);
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
            if !buffers.occluders[k].covers(k, l, t) {
                // `integrate_per_light` gathers the whole ray's list for light l before its
                // quadrature, and every node lies in one of the ray's intervals.
                debug_assert!(buffers.wide.covers(WHOLE_RAY_TAG, l, t));
                buffers.occluders[k].narrow(&buffers.wide, ray, (k, l), light, (iv.t0, iv.t1));
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
        buffers.rays += n as u64;
        let mut batch = std::mem::take(&mut buffers.batch);
        batch.resize_with(MAX_NODES, Vec::new);
        buffers.occluders[k].hits_batch(&shadow[..n], &mut batch[..n]);
        let cut = buffers.shadow_cut;
        for ((s, &(i, irradiance)), hits) in shadow[..n].iter().zip(&lit[..n]).zip(&mut batch) {
            std::mem::swap(&mut buffers.hits, hits);
            let sample = if self.transmittance_only {
                self.shadow_transmittance(s.t_max, irradiance, |_| false, buffers)
            } else {
                self.shadow_composite(s.t_max, irradiance, |_| false, cut, buffers)
            };
            std::mem::swap(&mut buffers.hits, hits);
            out[i] = self.model.light_source(&self.params, iv, &sample);
        }
        buffers.batch = batch;
    }

    /// Σ_k T(0,t0_k)·∫₀^{U_k} Q du over the finite intervals, adaptively. Q is linear in the
    /// lights, so each light is integrated on its own, with only its own kinks as breakpoints
    /// and one shadow ray per node (integrating the sum would put every light's kinks into
    /// every light's integral), each to tol/m; the summed estimates are ≤ tol. The constant
    /// part k·E of Q (single-scatter's a·E) is exact: k·E·U.
    pub(super) fn integrate_per_light(
        &self,
        ray: &Ray,
        intervals: &[Interval],
        pieces: &[Piece],
        buffers: &mut ShadowBuffers,
    ) -> (DVec3, DVec3, bool) {
        let render = &self.scene.render;
        let mut value = self.constant_part(intervals, pieces);
        let mut error = DVec3::ZERO;
        let mut unconverged = false;
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
            let (kept, tail) = self.tail_cut(ray, intervals, pieces, light, RAY_TAIL_SHARE * share);
            value += 0.5 * tail;
            error += 0.5 * tail;
            let pieces = &pieces[..kept];
            let Some(last) = intervals[..kept].last() else {
                continue;
            };
            self.light_breakpoints(
                ray,
                (first.t0, last.t1),
                (l, light),
                buffers,
                (&mut marks, &mut kinks, &mut sides),
            );
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
                self.shadow_cut(ray, first.t0, light, SHADOW_STOP_SHARE * share)
            };
            buffers.shadow_cut = cut.map(|(epsilon, bound, _)| (epsilon, bound));
            buffers.was_cut = false;
            let tol = quadrature_tol(share);
            self.interval_bounds(ray, &intervals[..kept], light, &mut bounds);
            let singular_ends = |k: usize, lo: f64, hi: f64, hair: f64| {
                let near = (t_of(k, lo - hair), t_of(k, hi + hair));
                singular_ends(&kinks, &sides, &intervals[k], near, (lo, hi, hair))
            };
            let nodes = |k: usize, us: &[f64], out: &mut [DVec3]| {
                let mut ts = [0.0; MAX_NODES];
                for (t, &u) in ts.iter_mut().zip(us) {
                    *t = t_of(k, u);
                }
                self.light_sources(ray, &ts[..us.len()], (k, &intervals[k]), l, buffers, out);
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
                        first_level((lo, hi), bound, self.r5_start_limit * share)
                    },
                    singular_ends,
                ),
            );
            value += r.value;
            error += r.error;
            unconverged |= !r.converged;
            if let (true, Some((epsilon, _, q))) = (buffers.was_cut, cut) {
                let weight: f64 = pieces.iter().map(|p| p.weight * (p.hi - p.lo)).sum();
                error += (2.0 * epsilon * weight) * q;
            }
            buffers.shadow_cut = None;
        }
        (value, error, unconverged)
    }

    /// The part of Q that does not depend on the lights (k·E, single-scatter's a·E), exact on
    /// every piece: the weight times the piece's u-range times k·E.
    fn constant_part(&self, intervals: &[Interval], pieces: &[Piece]) -> DVec3 {
        let mut value = DVec3::ZERO;
        let k = self.model.emission_factor(&self.params);
        if k != 0.0 {
            for p in pieces {
                value += (p.weight * (p.hi - p.lo) * k) * intervals[p.tag].emission;
            }
        }
        value
    }

    /// Light `l`'s breakpoints on `ray` in `span` ([`Self::breakpoints`], among the occluders
    /// gathered towards it for the whole span into `buffers.wide`): the marks with their sides,
    /// and the same as two lists of parameters and sides.
    fn light_breakpoints(
        &self,
        ray: &Ray,
        span: (f64, f64),
        (l, light): (usize, &Light),
        buffers: &mut ShadowBuffers,
        (marks, kinks, sides): (&mut Vec<(f64, u8)>, &mut Vec<f64>, &mut Vec<u8>),
    ) {
        buffers
            .wide
            .gather(&self.bvh, ray, (WHOLE_RAY_TAG, l), light, span);
        self.breakpoints(ray, span, light, &buffers.wide, marks);
        kinks.clear();
        sides.clear();
        kinks.extend(marks.iter().map(|&(t, _)| t));
        sides.extend(marks.iter().map(|&(_, side)| side));
    }

    /// The largest channel of light `light`'s source bound q_l over each interval, into `out`
    /// (cleared first; ∞ where none is known).
    fn interval_bounds(
        &self,
        ray: &Ray,
        intervals: &[Interval],
        light: &Light,
        out: &mut Vec<f64>,
    ) {
        out.clear();
        out.extend(intervals.iter().map(|iv| {
            let q = self.source_bound(ray, iv.t0, light);
            q.map_or(f64::INFINITY, |q| q.max_element())
        }));
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
    pub(super) fn breakpoints(
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
                d *= POINT_LIGHT_GRADING;
            }
            if out.len() > before {
                out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            }
        }
    }
}

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
/// deep segment ([`K15_START_DEPTH`]; σ·Δt of [lo, hi] is ln(1 − lo) − ln(1 − hi)), R5 where
/// the segment's whole contribution is at most `r5_limit` ([`R5_START_LIMIT`] of the light's share
/// of tol), G7 otherwise.
fn first_level((lo, hi): (f64, f64), bound: f64, r5_limit: f64) -> Level {
    // Also K15 where the depth is NaN.
    let shallow = (-lo).ln_1p() - (-hi).ln_1p() <= K15_START_DEPTH;
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

/// The ray parameter t(u) = t0 − ln(1 − u)/σ of interval `iv` (module documentation), with u
/// clamped to [0, U], U = 1 − e^{−σΔ} the interval's end. Callers widen segments by a hair to
/// see kinks at their ends; for an optical depth above ~37, U rounds to 1 and u a hair above it
/// would make ln_1p(−u) NaN.
pub(super) fn t_at(iv: &Interval, u_max: f64, u: f64) -> f64 {
    // max/min rather than clamp: never a panic, whatever u_max is.
    let u = u.max(0.0).min(u_max);
    (iv.t0 - (-u).ln_1p() / iv.sigma).clamp(iv.t0, iv.t1)
}

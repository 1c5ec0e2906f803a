//! The exact renderer of particles of Gaussian density (docs/design.md §9 "Gaussian density"),
//! emission and single-scatter models.
//!
//! Along a camera ray each Gaussian's density is a 1D Gaussian in t (`optics::gaussian`), so
//! the optical depth through any number of them is a sum of closed forms (erf differences) and
//!
//!   L = L_bg·T(0,∞) + ∫₀^∞ T(0,t)·Σᵢ σᵢ(t)·Cᵢ dt
//!
//! is computed a segment at a time. The ray is cut at each Gaussian's window ends and at its
//! centre t*; on a segment [a, b] with the Gaussians A whose windows cover it, for any colour
//! C_ref,
//!
//!   ∫_a^b T(0,t)·Σ_A σᵢCᵢ dt = T(0,a)·[C_ref·(1 − e^{−τ(a,b)}) + ∫_a^b e^{−τ(a,t)}·Σ_A σᵢ(Cᵢ − C_ref) dt]
//!
//! because ∫ e^{−τ(a,t)}σ(t) dt = 1 − e^{−τ(a,b)} exactly. C_ref is the colour of the Gaussian
//! with the most depth on the segment, so a segment where all have one colour is closed form.
//! Where no light scatters, the rest is bounded in closed form where the bound is tight
//! ([`deviation_bounds`]: one Gaussian dominates, or the piece is thin) while the bounds fit
//! their share; otherwise it is a small, smooth integrand for adaptive Gauss–Kronrod
//! (`quadrature`), with its share of the pixel's budget (`reference::budget::gaussian` names
//! every share of tol; the parts of err are [`ErrorParts`]). In that integrand the windows wide
//! on a piece are one polynomial per piece (`reference::series`, their bound a part of err).
//! The candidates are gathered front to back, and the gather stops where the ray surely stops
//! (`GaussianRenderer::gather`).
//!
//! **What is left out, and bounded into err.** The rendered medium is the true one less some
//! density δσ ≥ 0: (1) every Gaussian whose k-σ ellipsoid the ray does not meet in front of
//! the eye (k = `gaussian_cutoff`), (2) Gaussians the ray meets whose depth in front of the
//! eye is so small that together they fit a budget, (3) each remaining Gaussian's tails outside
//! its window |t − t*| ≤ wᵢ·s. With Δ the optical depth of δσ along the ray, per channel
//!
//!   |L_true − L_rendered| ≤ M·(1 − e^{−Δ}),   M = max(maxᵢ Cᵢ, L_bg),
//!
//! because the radiance of an emission–absorption medium is the expected colour where light is
//! first emitted along the ray (or L_bg), and adding the independent medium δσ changes that
//! only where δσ comes first, with probability ≤ 1 − e^{−Δ}, and then by at most M. (2) and
//! (3) are summed exactly in closed form; for (1) each Gaussian i missed adds at most
//! σᵢ·s_max,i·√(2π)·e^{−k²/2} (its line depth at Mahalanobis distance ≥ k, or the tail beyond
//! its chord when the chord lies behind the eye), summed over the scene once. k defaults to
//! the smallest value ≥ 3 that puts M times that sum within its share of tol. A ray whose
//! transmittance has fallen to T with T·M ≤ twice the ray-stop share of tol stops: what lies
//! beyond is in [0, T·M], taken as its midpoint with half of it in err.
//!
//! **Single-scatter.** The source is Q = a·E + α·(1/4π)·Σ_l E_l·T_l (docs/design.md §2), so σ·Q =
//! a·Σσᵢ(t)Cᵢ + (1/4π)·Σᵢσᵢ(t)αᵢ·Σ_l E_l(x_t)·T_l(x_t): the first term is the emission model's with
//! colours a·Cᵢ, the second is added to the quadrature's integrand of every piece, with T_l in
//! closed form: the sum of the erf depths, over [0, d_l], of the Gaussians whose k-σ ellipsoid the
//! shadow ray meets (a point light's by a BVH traversal per shadow ray, a directional light's from
//! one list per piece, `reference::sun_lists`). The model is asked for its per-light part
//! (`OpticalModel::light_source`, at the σ-weighted albedo of the point), never by name; a model
//! that needs the shadow ray's radiance (lit) is refused. A point light's nearest point on the
//! camera ray is a cut, where its 1/d² peaks. Two more things go into err: M above bounds Q on this
//! ray, a·max Cᵢ + the model's part at max αᵢ and each light's largest irradiance on the ray
//! (`Light::max_irradiance_beyond`, +∞ for a ray through a point light, which is then reported as
//! not converged); and each shadow ray leaves out at most the same missed depth Δ_far as a camera
//! ray, so the rendered T_l is at most e^{Δ_far} times the true one and the scattered radiance is
//! high by at most (L + err)·(1 − e^{−Δ_far}). A shadow ray stops once its depth reaches D with
//! e^{−D}·Σ_l q̂_l within the shadow-stop share of tol (q̂_l the bound of light l's part on this
//! ray): its T_l is then high by at most e^{−D}, the pixel by at most e^{−D}·Σ_l q̂_l, which goes
//! into err where a shadow ray stopped; where no shadow ray can stop, that share is the
//! quadrature's.

use super::budget::gaussian as share;
use super::quadrature::{integrate_adaptive, Piece};
use super::series::{WideSum, MAX_HALF_WIDTH};
use super::sun_lists::{SunGaussian, SunLists};
use super::volume::MAX_SEGMENTS;
use super::{Integrator, RadianceEstimator, Sample};
use crate::error::{PgtError, Result};
use crate::geometry::{Bvh, Ellipsoid, Ray};
use crate::optics::gaussian::{DepthFrom, GaussianAlongRay};
use crate::optics::intervals::Interval;
use crate::optics::light::Light;
use crate::optics::model::{LightNeed, OpticalModel};
use crate::optics::source::{LightSample, SourceParams};
use crate::optics::Profile;
use crate::scene::{RenderMode, Scene, Setting};
use glam::{DQuat, DVec3};
use std::cell::RefCell;

/// The shortest piece of a ray, in mean standard deviations along the ray of its Gaussians:
/// shorter pieces cost each Gaussian more evaluations (every piece its window meets starts with
/// seven nodes), longer ones more splits (docs/performance.md, "Gaussian particles in the reference").
const PIECE_WIDTH: f64 = 4.0;

/// The smallest cut-off k chosen automatically: the reference 3DGS rasteriser's footprint.
const MIN_AUTO_CUTOFF: f64 = 3.0;

/// One Gaussian as the renderer keeps it: the shape holds its standard deviations.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Gaussian {
    pub(crate) center: DVec3,
    pub(crate) shape: Ellipsoid,
    pub(crate) sigma: f64,
    /// k·Cᵢ, the colour of the model's constant part k·E (k = 1 in the emission model, a in
    /// single-scatter).
    pub(crate) emitted: DVec3,
    color: DVec3,
    albedo: DVec3,
}

/// The renderer of a scene whose particles all have Gaussian density.
pub struct GaussianRenderer {
    pub(crate) gaussians: Vec<Gaussian>,
    /// Over the k-σ ellipsoids of `gaussians` (indices into it).
    pub(crate) bvh: Bvh,
    pub(crate) background: DVec3,
    /// Per channel, max(maxᵢ k·Cᵢ, L_bg): M where no light scatters.
    pub(crate) bound: DVec3,
    pub(crate) tol: f64,
    /// The cut-off k: the BVH holds the k-σ ellipsoids.
    pub(crate) cutoff: f64,
    /// The bound on the depth of the Gaussians a ray does not meet within k σ.
    pub(crate) far_depth: f64,
    model: &'static dyn OpticalModel,
    params: SourceParams,
    /// The lights whose part of Q is integrated: empty where the model has none.
    lights: Vec<Light>,
    /// The unit direction toward each directional light of `lights`, in their order: their
    /// shadow rays take a candidate list per piece (`reference::sun_lists`).
    suns: Vec<DVec3>,
    /// Per channel, the largest k·Cᵢ, colour and albedo of any Gaussian.
    max_emitted: DVec3,
    max_color: DVec3,
    max_albedo: DVec3,
}

/// One candidate Gaussian of a ray: its profile and depth in front of the eye.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    index: u32,
    profile: GaussianAlongRay,
    /// The optical depth over [0, ∞).
    front: f64,
}

/// An included Gaussian's window [lo, hi] along the ray, and the last point where erfc of its
/// profile was taken, with that value.
#[derive(Debug, Clone, Copy)]
struct Window {
    index: u32,
    profile: GaussianAlongRay,
    lo: f64,
    hi: f64,
    tail_at: Option<(f64, f64)>,
}

/// A window's part of one piece: [x0, x1] = window ∩ piece, its depth there, and the depth
/// from x0 to later points.
#[derive(Debug, Clone, Copy)]
struct Member {
    window: usize,
    x0: f64,
    x1: f64,
    from: DepthFrom,
    depth: f64,
}

/// A piece that needs quadrature: its reference colour, the windows evaluated one by one
/// (`members[first..first + count]`) and the wide ones summed as polynomials
/// (`series[i]`, [`WideSum`]).
#[derive(Debug, Clone, Copy)]
struct Deviation {
    reference: DVec3,
    first: usize,
    count: usize,
    series: Option<usize>,
}

/// The parts of one pixel's err per channel (docs/design.md §3, §9), each paid from its share
/// of `tol` (`reference::budget::gaussian`); `Sample::error` is their [`ErrorParts::total`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ErrorParts {
    /// Half the bound of what lies behind a ray stopped behind nearly opaque gas
    /// ([`share::RAY_STOP`]).
    pub ray_stop: DVec3,
    /// The half-widths of the colour deviations bounded in closed form instead of integrated
    /// ([`share::BOUNDED`]).
    pub bounded: DVec3,
    /// The quadrature's error estimate ([`share::QUADRATURE`]).
    pub quadrature: DVec3,
    /// What summing the wide windows of a piece as polynomials may change in its integral
    /// ([`share::SERIES`], `reference::series`).
    pub series: DVec3,
    /// Shadow rays stopped at depth D: e^{−D}·Σ_l q̂_l ([`share::SHADOW_STOP`]).
    pub shadow_stop: DVec3,
    /// The shadow rays' missed depth, (L + err)·(1 − e^{−Δ_far}): unbudgeted.
    pub shadow_missed: DVec3,
    /// M·(1 − e^{−Δ}) for the depth Δ left out of the camera ray: faint Gaussians, tails and the
    /// Gaussians not met within k σ ([`share::FAINT`] + [`share::TAILS`] + [`share::FAR`]).
    pub left_out: DVec3,
}

impl ErrorParts {
    /// err: the parts summed in a fixed order.
    pub fn total(&self) -> DVec3 {
        self.ray_stop
            + self.bounded
            + self.quadrature
            + self.series
            + self.shadow_stop
            + self.shadow_missed
            + self.left_out
    }
}

#[derive(Default)]
struct Scratch {
    candidates: Vec<Candidate>,
    windows: Vec<Window>,
    cuts: Vec<(f64, bool)>,
    points: Vec<f64>,
    members: Vec<Member>,
    deviations: Vec<Deviation>,
    series: Vec<WideSum>,
    pieces: Vec<Piece>,
    /// The windows the sweep's current piece may meet, by index in `windows`, in order.
    open: Vec<usize>,
    /// The (end, depth) pairs of a front-to-back gather ([`narrow_reach`]).
    reach: Vec<(f64, f64)>,
    /// The long pieces tried by [`choose_long_pieces`], the narrow windows' cuts and the
    /// windows' standard deviations, sorted.
    long: Vec<f64>,
    fixed: Vec<f64>,
    sizes: Vec<f64>,
    ends: Vec<f64>,
    /// `points` are long pieces, on which every open window counts whole.
    long_pieces: bool,
    /// Where the last gather stopped (+∞: it gathered the whole ray).
    reach_end: f64,
    /// The last sweep ran out of gathered windows before the ray could stop.
    incomplete: bool,
    /// The directional lights' candidate lists of the queued pieces.
    suns: SunLists,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

impl GaussianRenderer {
    /// The renderer of `scene`, or the reason it cannot render it (a name for each: a mixed
    /// scene, the opaque mode, a model that needs the shadow rays' radiance (lit), an infinite
    /// peak density, a negative colour, albedo or light).
    pub fn new(scene: &Scene, integrator: Integrator) -> Result<GaussianRenderer> {
        check(scene, integrator)?;
        let refuse = |why: String| Err(PgtError::Usage(why));
        let model = scene.render.model.model();
        let mut gaussians = Vec::with_capacity(scene.particles.len());
        for (i, p) in scene.particles.iter().enumerate() {
            if !p.sigma.is_finite() {
                return refuse(format!(
                    "particle {i} is a Gaussian of infinite peak density (opacity 1); a Gaussian's opacity must be < 1"
                ));
            }
            if !(p.color.cmpge(DVec3::ZERO).all() && p.albedo.cmpge(DVec3::ZERO).all()) {
                return refuse(format!(
                    "particle {i} has a negative colour or albedo; the reference's bound on what it leaves out of a Gaussian scene needs them ≥ 0"
                ));
            }
            if p.sigma == 0.0 {
                continue;
            }
            let shape = p
                .ellipsoid
                .unwrap_or_else(|| Ellipsoid::new(DVec3::splat(p.radius), DQuat::IDENTITY));
            gaussians.push(Gaussian {
                center: p.center,
                shape,
                sigma: p.sigma,
                emitted: DVec3::ZERO,
                color: p.color,
                albedo: p.albedo,
            });
        }
        let params = SourceParams::new(
            scene.render.light_weight,
            scene.lights.len(),
            scene.render.emission_weight,
        );
        let k = model.emission_factor(&params);
        for g in &mut gaussians {
            g.emitted = k * g.color;
        }
        let lights = if model.light_need() == LightNeed::None {
            Vec::new()
        } else {
            scene.lights.clone()
        };
        let suns = lights
            .iter()
            .filter_map(|l| match *l {
                Light::Directional { direction, .. } => Some(-direction),
                Light::Point { .. } => None,
            })
            .collect();
        let background = scene.render.background;
        let bound = gaussians.iter().fold(background, |m, g| m.max(g.emitted));
        let max_emitted = gaussians.iter().fold(DVec3::ZERO, |m, g| m.max(g.emitted));
        let max_color = gaussians.iter().fold(DVec3::ZERO, |m, g| m.max(g.color));
        let max_albedo = gaussians.iter().fold(DVec3::ZERO, |m, g| m.max(g.albedo));
        let tol = scene.render.tol;
        // Σᵢ σᵢ·s_max,i·√(2π): the line depth of every Gaussian through its centre along its
        // longest axis, the factor of e^{−k²/2} in the bound on what is missed.
        let line_depth: f64 = gaussians
            .iter()
            .map(|g| Profile::Gaussian.centre_depth(g.shape.semi_axes().max_element(), g.sigma))
            .sum();
        let mut renderer = GaussianRenderer {
            gaussians,
            bvh: Bvh::build_shapes(Vec::new(), Vec::new(), Vec::new(), |_| true),
            background,
            bound,
            tol,
            cutoff: 0.0,
            far_depth: 0.0,
            model,
            params,
            lights,
            suns,
            max_emitted,
            max_color,
            max_albedo,
        };
        let cutoff = scene.render.gaussian_cutoff.unwrap_or_else(|| {
            auto_cutoff(line_depth, renderer.typical_bound().max_element(), tol)
        });
        renderer.cutoff = cutoff;
        let gaussians = &renderer.gaussians;
        renderer.far_depth = line_depth * (-0.5 * cutoff * cutoff).exp();
        renderer.bvh = Bvh::build_shapes(
            gaussians.iter().map(|g| g.center).collect(),
            gaussians
                .iter()
                .map(|g| cutoff * g.shape.bounding_radius())
                .collect(),
            gaussians
                .iter()
                .map(|g| {
                    Some(Ellipsoid::new(
                        cutoff * g.shape.semi_axes(),
                        g.shape.rotation(),
                    ))
                })
                .collect(),
            |_| true,
        );
        Ok(renderer)
    }

    /// M of this ray per channel: a bound of Q at every point of the ray, and of L_bg; and
    /// Σ_l q̂_l, the bound of the lights' part of Q alone.
    fn source_bound(&self, ray: &Ray) -> (DVec3, DVec3) {
        let mut q = self.bound;
        let mut scattered = DVec3::ZERO;
        for light in &self.lights {
            scattered +=
                self.light_part_bound(light.max_irradiance_beyond(ray.origin, ray.direction, 0.0));
        }
        if scattered != DVec3::ZERO {
            q = q.max(self.max_emitted + scattered);
        }
        (q, scattered)
    }

    /// M for choosing the cut-off: as [`GaussianRenderer::source_bound`], with each point
    /// light's irradiance at the distance of the nearest Gaussian's centre (no ray's bound: a
    /// ray may pass through the light).
    fn typical_bound(&self) -> DVec3 {
        let mut scattered = DVec3::ZERO;
        for light in &self.lights {
            let nearest = self
                .gaussians
                .iter()
                .filter_map(|g| light.incident_at(g.center))
                .fold(DVec3::ZERO, |m, inc| m.max(inc.irradiance));
            scattered += self.light_part_bound(nearest);
        }
        let q = self.bound.max(self.max_emitted + scattered);
        if q.is_finite() {
            q
        } else {
            self.bound
        }
    }

    /// The model's part of Q for one light at the largest colour and albedo and `irradiance`,
    /// unshadowed: a bound of that part wherever the irradiance is at most `irradiance`
    /// (`OpticalModel::light_source` is non-decreasing in each).
    fn light_part_bound(&self, irradiance: DVec3) -> DVec3 {
        let bounds = Interval {
            t0: 0.0,
            t1: 0.0,
            sigma: 1.0,
            emission: self.max_color,
            albedo: self.max_albedo,
        };
        let sample = LightSample {
            radiance: DVec3::ZERO,
            irradiance,
            transmittance: 1.0,
        };
        self.model.light_source(&self.params, &bounds, &sample)
    }

    /// The sample of `ray` and the parts of its err, which sum to `Sample::error` in the
    /// order [`ErrorParts::total`] adds them.
    fn radiance_with(&self, ray: &Ray, s: &mut Scratch) -> (Sample, ErrorParts) {
        let (bound, scattered) = self.source_bound(ray);
        let m_max = bound.max_element();
        if m_max == 0.0 {
            // Every colour, light and the background are black: L = 0 whatever the densities.
            return (Sample::default(), ErrorParts::default());
        }
        // Optical depth left out, as radiance M·Δ: the faint Gaussians and the tails outside
        // the windows, each within its share of tol. A ray through a point light has no finite
        // M; its windows are those of the scene's M.
        let m_budget = if m_max.is_finite() {
            m_max
        } else {
            self.typical_bound().max_element().max(f64::MIN_POSITIVE)
        };
        let depth_per_tol = self.tol / m_budget;
        // The depth after which the sweep surely stops: T·max M ≤ 2·RAY_STOP·tol even with the
        // faint Gaussians and the tails left out.
        let reach_depth = if m_max.is_finite() {
            (m_max / (2.0 * share::RAY_STOP * self.tol)).ln().max(0.0)
                + (share::FAINT + share::TAILS) * depth_per_tol
                + 1e-6
        } else {
            f64::INFINITY
        };
        let mut parts = ErrorParts::default();
        let mut delta = self.far_depth + self.gather(ray, s, depth_per_tol, reach_depth);
        cut_pieces(s, &self.lights, ray);
        let mut radiance = self.sweep(s, bound, &mut parts);
        if s.incomplete {
            // The gathered part of the ray did not stop the sweep: the whole ray instead.
            parts = ErrorParts::default();
            delta = self.far_depth + self.gather(ray, s, depth_per_tol, f64::INFINITY);
            cut_pieces(s, &self.lights, ray);
            radiance = self.sweep(s, bound, &mut parts);
        }
        let q = scattered.max_element();
        let stop_depth = if q > 0.0 && q.is_finite() {
            (q / (share::SHADOW_STOP * self.tol)).ln().max(0.0)
        } else {
            f64::INFINITY
        };
        let (converged, shadow_rays, stopped) =
            self.deviations(ray, s, stop_depth, &mut radiance, &mut parts.quadrature);
        if stopped {
            parts.shadow_stop = scattered * (-stop_depth).exp();
        }
        if !self.lights.is_empty() {
            // The scattered part is at most the whole radiance; the shadow rays' missed depth
            // makes it high by at most that part's 1 − e^{−Δ_far}.
            let so_far = parts.ray_stop + parts.bounded + parts.quadrature + parts.shadow_stop;
            parts.shadow_missed = (radiance + so_far) * -(-self.far_depth).exp_m1();
        }
        parts.left_out = bound * -(-delta).exp_m1();
        let error = parts.total();
        let sample = Sample {
            radiance,
            error,
            shadow_rays,
            unconverged: !converged || !error.is_finite(),
        };
        (sample, parts)
    }

    /// The sample of `ray` and the parts of its err (docs/design.md §3 "What err guarantees"),
    /// each spent from its share of `tol` (`reference::budget::gaussian`).
    pub fn radiance_and_parts(&self, ray: &Ray) -> (Sample, ErrorParts) {
        SCRATCH.with(|s| self.radiance_with(ray, &mut s.borrow_mut()))
    }

    /// Fills `s.windows` with the Gaussians the ray keeps (sorted by window start) and
    /// returns the optical depth left out of them: the faint ones left out whole, within
    /// [`share::FAINT`] of `depth_per_tol` (the depth whose M·Δ is tol), and the tails outside
    /// the windows, within [`share::TAILS`] of it. With a finite `reach_depth`, the gather goes
    /// front to back and stops at a `s.reach_end` by which the Gaussians met so far hold that
    /// much depth ([`GaussianRenderer::narrow_reach`]); the Gaussians whose k-σ ellipsoid starts
    /// beyond it are not gathered (their depth before it is in the far depth).
    fn gather(&self, ray: &Ray, s: &mut Scratch, depth_per_tol: f64, reach_depth: f64) -> f64 {
        let mut delta = 0.0;
        s.candidates.clear();
        s.reach.clear();
        let (mut pending, mut next_check) = (0.0, reach_depth);
        let mut reach_end = f64::INFINITY;
        let (candidates, reach) = (&mut s.candidates, &mut s.reach);
        self.bvh
            .visit_hits_narrowing(ray, 0.0, f64::INFINITY, |index, _, limit| {
                let g = &self.gaussians[index as usize];
                let profile = GaussianAlongRay::new(ray, g.center, &g.shape, g.sigma);
                // Wholly in front of the eye (beyond 9 s the part behind is below 1e-18 of it)
                // the depth in front is the whole line's, an upper bound, without an erfc.
                let front = if profile.t_star >= 9.0 * profile.s {
                    profile.total_depth()
                } else {
                    profile.optical_depth(0.0, f64::INFINITY)
                };
                candidates.push(Candidate {
                    index,
                    profile,
                    front,
                });
                // A lower bound of its depth over [0, t* + 3s]: what is in front less the
                // tail beyond 3 s (≤ 0.00135 of the whole) and the 9 s shortcut's excess.
                let end = profile.t_star + 3.0 * profile.s;
                let within = front - profile.total_depth() * (TAIL_BEYOND_3S + 1e-15);
                if reach_depth.is_finite() && end < *limit && end > 0.0 && within > 0.0 {
                    reach.push((end, within));
                    pending += within;
                    if pending >= next_check {
                        (*limit, pending) = narrow_reach(reach, reach_depth);
                        reach_end = *limit;
                        next_check = pending + REACH_RECHECK * reach_depth;
                    }
                }
                false
            });
        s.reach_end = reach_end;
        // The smallest first, left out while they fit half the budget.
        s.candidates
            .sort_unstable_by(|a, b| a.front.total_cmp(&b.front).then(a.index.cmp(&b.index)));
        let mut left_out = 0.0;
        let mut first_kept = s.candidates.len();
        for (k, c) in s.candidates.iter().enumerate() {
            if left_out + c.front > share::FAINT * depth_per_tol {
                first_kept = k;
                break;
            }
            left_out += c.front;
        }
        delta += left_out;
        let kept = &s.candidates[first_kept..];
        let tail_budget = share::TAILS * depth_per_tol / kept.len().max(1) as f64;
        s.windows.clear();
        for c in kept {
            let total = c.profile.total_depth();
            // The depth outside the window is total·erfc(w/√2) ≤ total·e^{−w²/2}, which this w
            // makes tail_budget; the bound goes into Δ.
            let w = if total > tail_budget {
                (2.0 * (total / tail_budget).ln()).sqrt()
            } else {
                0.0
            };
            delta += total * (-0.5 * w * w).exp();
            let p = c.profile;
            let (lo, hi) = ((p.t_star - w * p.s).max(0.0), p.t_star + w * p.s);
            if hi > lo {
                s.windows.push(Window {
                    index: c.index,
                    profile: p,
                    lo,
                    hi,
                    tail_at: None,
                });
            }
        }
        s.windows
            .sort_unstable_by(|a, b| a.lo.total_cmp(&b.lo).then(a.index.cmp(&b.index)));

        delta
    }

    /// The closed-form part of every piece, front to back: T(a)·C_ref·(1 − e^{−τ(a,b)}); the
    /// pieces whose colours differ bounded in closed form ([`deviation_bounds`], half-widths
    /// into `parts.bounded`) while that fits [`share::BOUNDED`] and no light scatters, else
    /// queued for quadrature (`s.pieces`), as is every piece where lights scatter; then
    /// L_bg·T(0,∞), or the bounded rest of a ray stopped at T·max M ≤ 2·[`share::RAY_STOP`]·tol
    /// (`bound` is M), half of which goes into `parts.ray_stop`. Returns the radiance so far.
    fn sweep(&self, s: &mut Scratch, bound: DVec3, parts: &mut ErrorParts) -> DVec3 {
        let m_max = bound.max_element();
        let bounded_budget = share::BOUNDED * self.tol;
        let mut radiance = DVec3::ZERO;
        let mut transmittance = 1.0;
        let mut stopped = false;
        s.members.clear();
        s.deviations.clear();
        s.series.clear();
        s.pieces.clear();
        s.open.clear();
        let mut next = 0;
        for i in 1..s.points.len() {
            let (a, b) = (s.points[i - 1], s.points[i]);
            let first = s.members.len();
            // Windows are sorted by their start: those that start before b join the open ones,
            // in their order; an open one that ends by a is done.
            while next < s.windows.len() && s.windows[next].lo < b {
                s.open.push(next);
                next += 1;
            }
            let (windows, members, long) = (&mut s.windows, &mut s.members, s.long_pieces);
            s.open.retain(|&k| {
                let w = &mut windows[k];
                if w.hi <= a {
                    return false;
                }
                let (x0, x1) = member_span(w, a, b, long);
                // The erfc at x0 is the one the last piece computed at its end, where the
                // window goes on.
                let from = match w.tail_at {
                    Some((x, tail)) if x == x0 => w.profile.depth_from_tail(x0, tail),
                    _ => w.profile.depth_from(x0),
                };
                let (depth, tail) = from.to_with_tail(x1);
                w.tail_at = Some((x1, tail));
                members.push(Member {
                    window: k,
                    x0,
                    x1,
                    from,
                    depth,
                });
                true
            });
            let count = s.members.len() - first;
            if count == 0 {
                continue;
            }
            if transmittance * m_max <= 2.0 * share::RAY_STOP * self.tol {
                let rest = 0.5 * transmittance * bound;
                radiance += rest;
                parts.ray_stop += rest;
                stopped = true;
                s.members.truncate(first);
                break;
            }
            let members = &s.members[first..];
            let tau: f64 = members.iter().map(|m| m.depth).sum();
            let heaviest = members
                .iter()
                .fold(&members[0], |h, m| if m.depth > h.depth { m } else { h });
            let reference = self.color_of(&s.windows[heaviest.window]);
            radiance += transmittance * reference * -(-tau).exp_m1();
            let deviates = members
                .iter()
                .any(|m| self.color_of(&s.windows[m.window]) != reference);
            // Where no light scatters, a deviation that fits what is left of its share is
            // bounded in closed form instead of integrated.
            let closed = (deviates && self.lights.is_empty())
                .then(|| deviation_bounds(members, &s.windows, self, reference, tau))
                .filter(|&(_, half)| {
                    (parts.bounded + transmittance * half).max_element() <= bounded_budget
                });
            if let Some((middle, half)) = closed {
                radiance += transmittance * middle;
                parts.bounded += transmittance * half;
                s.members.truncate(first);
            } else if !self.lights.is_empty() || deviates {
                s.pieces.push(Piece {
                    lo: a,
                    hi: b,
                    weight: transmittance,
                    tag: s.deviations.len(),
                });
                let series = if self.lights.is_empty() {
                    self.sum_wide(s, (first, a, b), reference, transmittance, parts)
                } else {
                    None
                };
                s.deviations.push(Deviation {
                    reference,
                    first,
                    count: s.members.len() - first,
                    series,
                });
            } else {
                s.members.truncate(first);
            }
            transmittance *= (-tau).exp();
        }
        s.incomplete = false;
        if !stopped && s.reach_end.is_finite() {
            // The gather stopped at reach_end: what lies beyond the last window is in
            // [0, T·M], bounded as a stopped ray's rest where it fits, else gathered whole.
            if transmittance * m_max <= 2.0 * share::RAY_STOP * self.tol {
                let rest = 0.5 * transmittance * bound;
                radiance += rest;
                parts.ray_stop += rest;
            } else {
                s.incomplete = true;
            }
        } else if !stopped {
            radiance += transmittance * self.background;
        }
        radiance
    }

    /// Sums the windows of the piece [a, b] (`s.members[first..]`) that cover it and are wide
    /// on it (r = h/(2s) ≤ [`MAX_HALF_WIDTH`]) into one [`WideSum`] and takes them out of the
    /// members, when at least two are and the bound on what the polynomials change, times the
    /// piece's `weight` (its transmittance), fits what is left of [`share::SERIES`] (the bound
    /// goes into `parts.series`); returns the sum's index in `s.series`.
    fn sum_wide(
        &self,
        s: &mut Scratch,
        (first, a, b): (usize, f64, f64),
        reference: DVec3,
        weight: f64,
        parts: &mut ErrorParts,
    ) -> Option<usize> {
        let half = 0.5 * (b - a);
        let wide =
            |m: &Member, w: &Window| m.x0 == a && m.x1 == b && half <= MAX_HALF_WIDTH * w.profile.s;
        let members = &s.members[first..];
        let count = members
            .iter()
            .filter(|m| wide(m, &s.windows[m.window]))
            .count();
        if count < 2 {
            return None;
        }
        let mut sum = WideSum::new(a, b);
        let mut deviation_depth = DVec3::ZERO;
        for m in members {
            let w = &s.windows[m.window];
            let deviation = self.color_of(w) - reference;
            deviation_depth += m.depth * deviation.abs();
            if wide(m, w) {
                let p = w.profile;
                sum.add(p.peak, p.t_star, p.s, deviation);
            }
        }
        let error = weight * sum.integral_error(deviation_depth);
        let fits = (parts.series + error).max_element() <= share::SERIES * self.tol;
        if !fits {
            return None;
        }
        parts.series += error;
        sum.finish();
        let mut kept = first;
        for k in first..s.members.len() {
            let m = s.members[k];
            if !wide(&m, &s.windows[m.window]) {
                s.members[kept] = m;
                kept += 1;
            }
        }
        s.members.truncate(kept);
        s.series.push(sum);
        Some(s.series.len() - 1)
    }

    /// The colour deviations of the queued pieces, and the lights' part where they scatter, by
    /// adaptive Gauss–Kronrod with [`share::QUADRATURE`] of tol (and [`share::SHADOW_STOP`] where
    /// no shadow ray may stop, [`share::BOUNDED`] where lights scatter), added to `radiance` and
    /// their estimate to `error`; whether the quadrature converged, the number of shadow rays
    /// traced and whether one stopped at `stop_depth`.
    fn deviations(
        &self,
        ray: &Ray,
        s: &mut Scratch,
        stop_depth: f64,
        radiance: &mut DVec3,
        error: &mut DVec3,
    ) -> (bool, u64, bool) {
        let mut converged = true;
        let mut shadow_rays = 0;
        let mut stopped = false;
        if !s.pieces.is_empty() {
            if !self.suns.is_empty() {
                self.gather_suns(ray, s);
            }
            let (windows, members, deviations) = (&s.windows, &s.members, &s.deviations);
            let (series, suns) = (&s.series, &s.suns);
            let scatters = !self.lights.is_empty();
            let integrand = |tag: usize, t: f64| {
                let d = &deviations[tag];
                let (mut tau, mut sum) = match d.series {
                    Some(i) => series[i].at(t),
                    None => (0.0, DVec3::ZERO),
                };
                let (mut sigma, mut color, mut albedo) = (0.0, DVec3::ZERO, DVec3::ZERO);
                for m in &members[d.first..d.first + d.count] {
                    if t <= m.x0 {
                        continue;
                    }
                    if t >= m.x1 {
                        tau += m.depth;
                        continue;
                    }
                    let w = &windows[m.window];
                    tau += m.from.to(t);
                    let density = w.profile.density(t);
                    let g = &self.gaussians[w.index as usize];
                    sum += density * (g.emitted - d.reference);
                    if scatters {
                        sigma += density;
                        color += density * g.color;
                        albedo += density * g.albedo;
                    }
                }
                if sigma > 0.0 {
                    let x = ray.at(t);
                    let here = Interval {
                        t0: t,
                        t1: t,
                        sigma,
                        emission: color / sigma,
                        albedo: albedo / sigma,
                    };
                    let mut sun = 0;
                    for light in &self.lights {
                        let Some(incident) = light.incident_at(x) else {
                            continue;
                        };
                        shadow_rays += 1;
                        let (transmittance, cut) = if let Light::Directional { .. } = light {
                            sun += 1;
                            suns.transmittance(tag, sun - 1, t, stop_depth)
                        } else {
                            self.transmittance(x, incident.toward, incident.distance, stop_depth)
                        };
                        stopped |= cut;
                        let sample = LightSample {
                            radiance: DVec3::ZERO,
                            irradiance: incident.irradiance,
                            transmittance,
                        };
                        sum += sigma * self.model.light_source(&self.params, &here, &sample);
                    }
                }
                (-tau).exp() * sum
            };
            // The shares no part of this ray can spend are the quadrature's: the shadow stop's
            // where no shadow ray can stop, the bounded deviations' where lights scatter.
            let mut quadrature = share::QUADRATURE;
            if !stop_depth.is_finite() {
                quadrature += share::SHADOW_STOP;
            }
            if scatters {
                quadrature += share::BOUNDED;
            }
            let quadrature_tol = quadrature * self.tol;
            let result = integrate_adaptive(
                &s.pieces,
                quadrature_tol,
                MAX_SEGMENTS,
                integrand,
                |_, _, _| None,
                |_, _, _| true,
            );
            *radiance += result.value;
            *error = result.error;
            converged = result.converged;
        }
        (converged, shadow_rays, stopped)
    }

    /// The directional lights' candidate lists of the queued pieces (`s.suns`, by the pieces'
    /// tags, which are their positions in `s.pieces`).
    fn gather_suns(&self, ray: &Ray, s: &mut Scratch) {
        debug_assert!(s.pieces.iter().enumerate().all(|(k, p)| p.tag == k));
        let gaussian = |index: u32| {
            let g = &self.gaussians[index as usize];
            SunGaussian {
                center: g.center,
                to_unit: g.shape.to_unit_matrix(),
                sigma: g.sigma,
            }
        };
        let pieces = s.pieces.iter().map(|p| (p.lo, p.hi));
        s.suns
            .gather(&self.bvh, gaussian, self.cutoff, ray, pieces, &self.suns);
    }

    /// T_l of a point light: the transmittance from `x` over `distance` along `toward` (unit)
    /// through the Gaussians whose k-σ ellipsoid that stretch meets, in closed form, in the
    /// BVH's order; stopped once the depth reaches `stop_depth` (then true).
    fn transmittance(
        &self,
        x: DVec3,
        toward: DVec3,
        distance: f64,
        stop_depth: f64,
    ) -> (f64, bool) {
        let shadow = Ray {
            origin: x,
            direction: toward,
        };
        let mut depth = 0.0;
        let mut stopped = false;
        self.bvh.visit_hits(&shadow, 0.0, distance, |index, _| {
            let g = &self.gaussians[index as usize];
            depth += GaussianAlongRay::new(&shadow, g.center, &g.shape, g.sigma)
                .optical_depth(0.0, distance);
            stopped = depth >= stop_depth;
            stopped
        });
        ((-depth).exp(), stopped)
    }

    /// The colour of a window's Gaussian in the model's constant part, k·Cᵢ.
    #[inline]
    fn color_of(&self, w: &Window) -> DVec3 {
        self.gaussians[w.index as usize].emitted
    }
}

impl RadianceEstimator for GaussianRenderer {
    fn radiance(&self, ray: &Ray) -> Sample {
        self.radiance_and_parts(ray).0
    }

    fn estimates_error(&self) -> bool {
        true
    }
}

/// The scene-wide reasons the renderer refuses `scene` (each by name): a mixed scene, the
/// opaque mode, a model that needs the shadow rays' radiance (lit), the Riemann sums, a
/// negative light.
fn check(scene: &Scene, integrator: Integrator) -> Result<()> {
    let refuse = |why: String| Err(PgtError::Usage(why));
    if scene
        .particles
        .iter()
        .any(|p| p.profile != Profile::Gaussian)
    {
        return Err(scene.mixed_density_refused(
            "the reference renders a scene of one kind (docs/design.md §9)",
        ));
    }
    if scene.render.mode != RenderMode::Volume {
        return Err(scene.gaussians_refused(
            Setting::Mode,
            "Gaussian particles have no surface: the opaque mode does not draw them (render them in the volume mode)",
        ));
    }
    let model = scene.render.model.model();
    if model.light_need() == LightNeed::Radiance {
        return Err(scene.gaussians_refused(Setting::Model, &format!(
            "the {} model's shadow rays composite coloured emission, which the reference does not integrate through Gaussian particles (docs/design.md §9): choose model = \"emission\" or \"single-scatter\" ([render], or --model)",
            model.name()
        )));
    }
    if let Integrator::Riemann { .. } = integrator {
        return Err(scene.gaussians_refused(
            Setting::Flag("--integrator riemann"),
            "the Riemann sums apply to particles of constant density; Gaussian particles are integrated adaptively",
        ));
    }
    if model.light_need() != LightNeed::None
        && scene.lights.iter().any(|l| match *l {
            Light::Directional { irradiance, .. } => !irradiance.cmpge(DVec3::ZERO).all(),
            Light::Point { intensity, .. } => !intensity.cmpge(DVec3::ZERO).all(),
        })
    {
        return refuse(
            "a light has a negative irradiance or intensity; the reference's bound on what it leaves out of a Gaussian scene needs them ≥ 0".into(),
        );
    }
    Ok(())
}

/// The deviation ∫_a^b e^{−τ(a,t)}·Σ σᵢ(Cᵢ − C_ref) dt of one piece in closed form, as a
/// middle and a half-width per channel: with dᵢ window i's depth on the piece and τ all of
/// theirs, τᵢ(a,t) ≤ τ(a,t) ≤ τᵢ(a,t) + τ − dᵢ, so ∫ e^{−τ(a,t)}σᵢ dt lies in
/// [e^{−(τ − dᵢ)}·(1 − e^{−dᵢ}), 1 − e^{−dᵢ}] (∫ e^{−τᵢ(a,t)}σᵢ dt = 1 − e^{−dᵢ} exactly). The
/// half-width is O(dᵢ·(τ − dᵢ)): small where one Gaussian dominates or the piece is thin.
fn deviation_bounds(
    members: &[Member],
    windows: &[Window],
    renderer: &GaussianRenderer,
    reference: DVec3,
    tau: f64,
) -> (DVec3, DVec3) {
    let (mut middle, mut half) = (DVec3::ZERO, DVec3::ZERO);
    for m in members {
        let delta = renderer.color_of(&windows[m.window]) - reference;
        if delta == DVec3::ZERO {
            continue;
        }
        let own = -(-m.depth).exp_m1();
        let others = (-(tau - m.depth).max(0.0)).exp();
        middle += delta * (0.5 * own * (1.0 + others));
        half += delta.abs() * (0.5 * own * (1.0 - others));
    }
    (middle, half)
}

/// Cuts the ray into `s.points`: the windows' ends and centres, thinned so that neighbouring
/// cuts are at least [`PIECE_WIDTH`] mean standard deviations apart (the quadrature splits where
/// a piece needs it; an evaluation costs the windows that hold the node, not the piece's), and
/// the point of the ray nearest to each point light, where its irradiance peaks.
fn cut_pieces(s: &mut Scratch, lights: &[Light], ray: &Ray) {
    s.cuts.clear();
    let mut mean_s = 0.0;
    for w in &s.windows {
        mean_s += w.profile.s;
    }
    let gap = PIECE_WIDTH * mean_s / s.windows.len().max(1) as f64;
    for w in &s.windows {
        // A window narrower than the gap keeps its own cuts: thinned away, it would lie inside
        // a piece whose nodes step over it (a flat splat's window can be 10⁻¹⁰ of the others').
        let own = w.hi - w.lo < gap;
        s.cuts.push((w.lo, own));
        s.cuts.push((w.hi, own));
        if w.profile.t_star > w.lo && w.profile.t_star < w.hi {
            s.cuts.push((w.profile.t_star, own));
        }
    }
    if let (Some(first), Some(last)) = (
        s.windows.iter().map(|w| w.lo).reduce(f64::min),
        s.windows.iter().map(|w| w.hi).reduce(f64::max),
    ) {
        for light in lights {
            if let Light::Point { position, .. } = *light {
                let nearest = (position - ray.origin).dot(ray.direction);
                if nearest > first && nearest < last {
                    s.cuts.push((nearest, true));
                }
            }
        }
    }
    s.cuts
        .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
    s.points.clear();
    let Some(&(end, _)) = s.cuts.last() else {
        return;
    };
    for &(t, own) in &s.cuts {
        match s.points.last() {
            Some(&last) if t == last || (!own && t - last < gap) => {}
            _ => s.points.push(t),
        }
    }
    if s.points.last().is_some_and(|&last| last < end) {
        s.points.push(end);
    }
    s.long_pieces = false;
    if lights.is_empty() {
        choose_long_pieces(s);
    }
}

/// The part [x0, x1] of the piece [a, b] on which the window `w` open on it counts: all of it
/// on long pieces (the Gaussian's tail beyond the window only brings the rendered medium nearer
/// the true one; what is left out stays within Δ), else where the two overlap.
fn member_span(w: &Window, a: f64, b: f64, long: bool) -> (f64, f64) {
    if long {
        (a, b)
    } else {
        (w.lo.max(a), w.hi.min(b))
    }
}

/// The longest piece, in standard deviations of each window open on it wider than the narrow
/// ones: there the window is wide (r = h/(2s) ≤ 1/2) and its polynomial of degree 16 leaves
/// at most ~10⁻¹³ of its peak out.
const LONG_PIECE: f64 = 0.5;

/// Long pieces are tried where the thinned cuts' pieces have at least this many windows open
/// on them on average: with fewer, the windows rarely overlap enough to pay for the trial.
const MIN_OPEN_FOR_LONG: usize = 48;

/// The quantiles of the windows' standard deviations below which a window is narrow, tried by
/// [`choose_long_pieces`].
const NARROW_QUANTILES: [f64; 2] = [0.05, 0.2];

/// Where no light scatters, replaces the thinned cuts by long pieces when that costs less:
/// pieces as long as [`LONG_PIECE`] standard deviations of every window open on them, cut also
/// at the ends and centres of the narrow windows (those below a quantile of the ray's standard
/// deviations, [`NARROW_QUANTILES`]), which keep their own pieces. Flat Gaussians seen edge-on
/// and face-on in one ray cut it at every window's ends though nearly every window is wide on
/// the pieces between (docs/performance.md "Long pieces"); the cost compared is the sweep's,
/// a pair of a window and a piece it is open on, eight where it is not wide there.
fn choose_long_pieces(s: &mut Scratch) {
    if s.windows.len() < 2 {
        return;
    }
    s.ends.clear();
    s.ends.extend(s.windows.iter().map(|w| w.hi));
    s.ends.sort_unstable_by(f64::total_cmp);
    let mut best = sweep_cost(&s.windows, &s.ends, &s.points);
    let pieces = s.points.len().saturating_sub(1);
    if best < (MIN_OPEN_FOR_LONG + PIECE_COST) * pieces {
        return;
    }
    s.sizes.clear();
    s.sizes.extend(s.windows.iter().map(|w| w.profile.s));
    s.sizes.sort_unstable_by(f64::total_cmp);
    let limit = 4 * s.points.len();
    for q in NARROW_QUANTILES {
        let narrow = s.sizes[(q * s.sizes.len() as f64) as usize];
        let long = (&s.windows[..], &mut s.long, &mut s.fixed, &mut s.open);
        if !cut_long_pieces(long, narrow, limit) {
            continue;
        }
        let cost = sweep_cost(&s.windows, &s.ends, &s.long);
        if cost < best {
            best = cost;
            std::mem::swap(&mut s.points, &mut s.long);
            s.long_pieces = true;
        }
    }
}

/// Fills `points` with pieces no longer than 2·[`LONG_PIECE`] standard deviations of any window
/// of s ≥ `narrow` open on them, cut at the ends and centres of the windows of s < `narrow`;
/// false where that takes more than `limit` points or a piece would be empty in f64.
fn cut_long_pieces(
    (windows, points, fixed, open): (&[Window], &mut Vec<f64>, &mut Vec<f64>, &mut Vec<usize>),
    narrow: f64,
    limit: usize,
) -> bool {
    points.clear();
    fixed.clear();
    open.clear();
    for w in windows.iter().filter(|w| w.profile.s < narrow) {
        fixed.extend([w.lo, w.hi]);
        if w.profile.t_star > w.lo && w.profile.t_star < w.hi {
            fixed.push(w.profile.t_star);
        }
    }
    fixed.sort_unstable_by(f64::total_cmp);
    let end = windows.iter().fold(f64::NEG_INFINITY, |e, w| e.max(w.hi));
    // Windows are sorted by their start.
    let mut t = windows[0].lo;
    points.push(t);
    let (mut next, mut f) = (0, 0);
    while t < end {
        while next < windows.len() && windows[next].lo <= t {
            if windows[next].profile.s >= narrow {
                open.push(next);
            }
            next += 1;
        }
        open.retain(|&k| windows[k].hi > t);
        while f < fixed.len() && fixed[f] <= t {
            f += 1;
        }
        let mut b = fixed.get(f).map_or(end, |&x| x.min(end));
        for &k in open.iter() {
            b = b.min(t + 2.0 * LONG_PIECE * windows[k].profile.s);
        }
        // A window that starts on the piece shortens it to its own length, or ends it where
        // it starts.
        for w in &windows[next..] {
            if w.lo >= b {
                break;
            }
            if w.profile.s >= narrow {
                b = b.min(w.lo.max(t + 2.0 * LONG_PIECE * w.profile.s));
            }
        }
        if b <= t || points.len() >= limit {
            return false;
        }
        points.push(b);
        t = b;
    }
    true
}

/// What sweeping the pieces between `points` costs: one for each window open on a piece
/// (an erfc and a polynomial term) and [`PIECE_COST`] a piece (its quadrature's nodes), from
/// the windows' starts (sorted, as `windows` is) and `ends` (sorted).
fn sweep_cost(windows: &[Window], ends: &[f64], points: &[f64]) -> usize {
    let (mut started, mut ended, mut cost) = (0, 0, 0);
    for piece in points.windows(2) {
        let (a, b) = (piece[0], piece[1]);
        while started < windows.len() && windows[started].lo < b {
            started += 1;
        }
        while ended < ends.len() && ends[ended] <= a {
            ended += 1;
        }
        cost += started - ended + PIECE_COST;
    }
    cost
}

/// What a piece costs beyond its windows in [`sweep_cost`]'s units: the quadrature's seven
/// nodes or more, each two polynomials.
const PIECE_COST: usize = 8;

/// The depth of a 1D Gaussian beyond 3 standard deviations on one side, rounded up:
/// erfc(3/√2)/2 = 0.0013499.
const TAIL_BEYOND_3S: f64 = 0.00135;

/// A front-to-back gather looks for a nearer end again each time the depth it has met grows
/// by this fraction of the depth it needs (each look sorts what it holds).
const REACH_RECHECK: f64 = 0.25;

/// The smallest end t of the `(end, depth)` pairs by which the depths of the pairs ending no
/// later reach `depth`, with their sum; the pairs beyond it are dropped.
fn narrow_reach(reach: &mut Vec<(f64, f64)>, depth: f64) -> (f64, f64) {
    reach.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let mut sum = 0.0;
    for k in 0..reach.len() {
        sum += reach[k].1;
        if sum >= depth {
            let end = reach[k].0;
            reach.truncate(k + 1);
            return (end, sum);
        }
    }
    (f64::INFINITY, sum)
}

/// The smallest k ≥ 3 with M·Σᵢ σᵢ·s_max,i·√(2π)·e^{−k²/2} ≤ [`share::FAR`]·tol.
fn auto_cutoff(line_depth: f64, m_max: f64, tol: f64) -> f64 {
    let ratio = m_max * line_depth / (share::FAR * tol);
    if ratio > 1.0 {
        (2.0 * ratio.ln()).sqrt().max(MIN_AUTO_CUTOFF)
    } else {
        MIN_AUTO_CUTOFF
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A window of standard deviation `s` along the ray about `t_star`, six of them each side.
    fn window(index: u32, t_star: f64, s: f64) -> Window {
        Window {
            index,
            profile: GaussianAlongRay {
                t_star,
                s,
                peak: 0.1,
            },
            lo: t_star - 6.0 * s,
            hi: t_star + 6.0 * s,
            tail_at: None,
        }
    }

    fn cut(windows: Vec<Window>, lights: &[Light]) -> Scratch {
        let mut s = Scratch {
            windows,
            ..Scratch::default()
        };
        s.windows.sort_unstable_by(|a, b| a.lo.total_cmp(&b.lo));
        let ray = Ray {
            origin: DVec3::ZERO,
            direction: DVec3::Z,
        };
        cut_pieces(&mut s, lights, &ray);
        s.ends.clear();
        s.ends.extend(s.windows.iter().map(|w| w.hi));
        s.ends.sort_unstable_by(f64::total_cmp);
        s
    }

    /// Many wide windows overlapping and a few flat ones among them (a ray along hair-like
    /// splats): long pieces, each short enough for every wide window open on it to be wide,
    /// the flat windows' ends and centres kept, and fewer pieces than the thinned cuts give.
    #[test]
    fn overlapping_wide_windows_take_long_pieces_and_narrow_ones_keep_their_cuts() {
        // Standard deviations from 0.5 to 2.2, and three grazing windows far wider, which make
        // the thinned cuts' gap wider than most windows: those keep their own cuts.
        let mut windows: Vec<Window> = (0..120)
            .map(|i| {
                let s = 0.5 * (1.5 * f64::from(i % 11) / 10.0).exp();
                window(i, 10.0 + 0.05 * f64::from(i), s)
            })
            .collect();
        for k in 0..3 {
            windows.push(window(300 + k, 12.0 + f64::from(k), 60.0));
        }
        let flat: Vec<(f64, f64)> = (0..12)
            .map(|i| (8.0 + 0.61 * f64::from(i), 0.002 + 0.0001 * f64::from(i)))
            .collect();
        for (k, &(t, s)) in flat.iter().enumerate() {
            windows.push(window(200 + k as u32, t, s));
        }
        // A sun keeps the thinned cuts (its shadow rays need no cut of their own).
        let sun = Light::Directional {
            direction: DVec3::NEG_Y,
            irradiance: DVec3::ONE,
        };
        let thinned = cut(windows.clone(), &[sun]);
        let s = cut(windows, &[]);
        assert!(s.long_pieces, "{} points", s.points.len());
        let narrow = s.sizes[(NARROW_QUANTILES[1] * s.sizes.len() as f64) as usize];
        for piece in s.points.windows(2) {
            let (a, b) = (piece[0], piece[1]);
            assert!(b > a);
            for w in s.windows.iter().filter(|w| w.lo < b && w.hi > a) {
                if w.profile.s >= narrow {
                    assert!(
                        0.5 * (b - a) <= LONG_PIECE * w.profile.s * (1.0 + 1e-12),
                        "[{a}, {b}] is too long for s = {}",
                        w.profile.s
                    );
                }
            }
        }
        for &(t, sd) in &flat {
            for x in [t - 6.0 * sd, t, t + 6.0 * sd] {
                assert!(s.points.contains(&x), "{x} is not a cut");
            }
        }
        let cost = sweep_cost(&s.windows, &s.ends, &s.points);
        let before = sweep_cost(&thinned.windows, &thinned.ends, &thinned.points);
        assert!(cost < before, "{cost} against {before}");
    }

    /// Where few windows overlap, the thinned cuts stay (and with them the images of sparse
    /// scenes).
    #[test]
    fn sparse_windows_keep_the_thinned_cuts() {
        let windows = (0..30)
            .map(|i| window(i, 2.0 + 1.5 * f64::from(i), 0.3 + 0.01 * f64::from(i)))
            .collect();
        assert!(!cut(windows, &[]).long_pieces);
    }
}

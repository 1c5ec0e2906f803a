//! Globally adaptive Gauss–Kronrod quadrature (G7–K15) of RGB-valued integrands, with an error
//! estimate (DESIGN.md §3: "adaptive Gauss–Kronrod quadrature with an error estimate, to an
//! absolute radiance tolerance `tol` per pixel and channel").
//!
//! **Error estimate.** Per segment and channel the estimate is the larger of |K15 − G7| and
//! QUADPACK's heuristic resasc·min(1, (200·|K15 − G7|/resasc)^{3/2}) (Piessens et al. 1983,
//! `qk15`), with QUADPACK's round-off floor 50·ε·∫|f|. The plain |K15 − G7| is the error of the
//! *Gauss* rule; the value returned is the Kronrod one, which for smooth integrands is far
//! better, so the estimate is pessimistic there. QUADPACK's heuristic alone can fall below
//! |K15 − G7| (when the difference is tiny against resasc), which is the optimistic direction;
//! taking the maximum keeps the estimate an overestimate in practice. The three channels are
//! integrated at the same nodes, and a difference that cancels by chance in one of them is no
//! evidence that it is resolved: each channel's estimate is raised to the worst channel's error
//! relative to the integrand's variation (QUADPACK's resasc), scaled to its own variation.
//! Segments that contain or touch a kink the caller knows of (a square-root point where a shadow
//! ray grazes a sphere, see `optics::kinks`) are integrated with an endpoint-smoothing
//! substitution ([`gauss_kronrod_15_smoothed`]) and their estimate is multiplied by
//! [`KINK_SAFETY`]: near a kink both rules err alike and their difference can understate the
//! error. (The volume renderer also makes every kink a breakpoint before the first pass, so that
//! no shadow falls unseen between the nodes of a segment.)
//!
//! **Global adaptivity.** All segments of one pixel (every interval of the camera ray) share
//! one error budget: the segment with the largest estimate is split until the summed estimate is
//! ≤ `tol` in every channel. A segment with a kink inside is split at the kink nearest to its
//! middle (so the pieces are smooth), others are bisected. After `max_segments` segments, or
//! when no segment can be split any more in f64, it stops and reports the remaining summed
//! estimate honestly (`converged = false`).

// `!(a > b)` is deliberate throughout: unlike `a <= b` it is also true when a value is NaN, so
// degenerate input takes the safe branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::DVec3;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Kronrod abscissae on [−1, 1] (the positive half, then 0) and weights (QUADPACK `qk15`).
#[allow(clippy::excessive_precision)] // the digits as QUADPACK publishes them
const XGK: [f64; 8] = [
    0.991_455_371_120_812_639_206_854_697_526_329,
    0.949_107_912_342_758_524_526_189_684_047_851,
    0.864_864_423_359_769_072_789_712_788_640_926,
    0.741_531_185_599_394_439_863_864_773_280_788,
    0.586_087_235_467_691_130_294_144_845_693_013,
    0.405_845_151_377_397_166_906_606_412_076_961,
    0.207_784_955_007_898_467_600_689_403_773_245,
    0.0,
];
#[allow(clippy::excessive_precision)] // the digits as QUADPACK publishes them
const WGK: [f64; 8] = [
    0.022_935_322_010_529_224_963_732_008_058_970,
    0.063_092_092_629_978_553_290_700_663_189_204,
    0.104_790_010_322_250_183_839_876_322_541_518,
    0.140_653_259_715_525_918_745_189_590_510_238,
    0.169_004_726_639_267_902_826_583_426_598_550,
    0.190_350_578_064_785_409_913_256_402_421_014,
    0.204_432_940_075_298_892_414_161_999_234_649,
    0.209_482_141_084_727_828_012_999_174_891_714,
];
/// Gauss weights of the 7-point rule, for the Kronrod nodes XGK[1], XGK[3], XGK[5], XGK[7].
#[allow(clippy::excessive_precision)] // the digits as QUADPACK publishes them
const WG: [f64; 4] = [
    0.129_484_966_168_869_693_270_611_432_679_082,
    0.279_705_391_489_276_667_901_467_771_423_780,
    0.381_830_050_505_118_944_950_369_775_488_975,
    0.417_959_183_673_469_387_755_102_040_816_327,
];

/// Kronrod abscissae of G3–K7 on [−1, 1] (positive half, then 0) and their weights.
#[allow(clippy::excessive_precision)] // the digits as published (Kronrod 1965, Piessens 1983)
const XGK7: [f64; 4] = [
    0.960_491_268_708_020_283_423_507_092_629_080,
    0.774_596_669_241_483_377_035_853_079_956_480,
    0.434_243_749_346_802_558_002_071_502_844_628,
    0.0,
];
#[allow(clippy::excessive_precision)] // the digits as published (Kronrod 1965, Piessens 1983)
const WGK7: [f64; 4] = [
    0.104_656_226_026_467_265_193_823_857_192_073,
    0.268_488_089_868_333_440_728_569_280_666_710,
    0.401_397_414_775_962_222_905_051_818_618_432,
    0.450_916_538_658_474_142_345_110_087_045_571,
];
/// Gauss weights of the 3-point rule, for XGK7[1] and the centre.
const WG3: [f64; 2] = [5.0 / 9.0, 8.0 / 9.0];

/// Multiplier of the error estimate of a segment that contains a known kink.
pub const KINK_SAFETY: f64 = 2.0;

/// Integrand evaluations per segment.
pub const NODES_PER_SEGMENT: usize = 15;

/// K15 value and error estimate of one segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RuleResult {
    pub value: DVec3,
    pub error: DVec3,
}

/// A Gauss–Kronrod pair on [−1, 1]: the Kronrod abscissae (positive half, then 0), their
/// weights, and the Gauss weights of the nodes at odd positions of `xgk` and of the centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rule {
    xgk: &'static [f64],
    wgk: &'static [f64],
    wg: &'static [f64],
}

impl Rule {
    /// G7–K15 (QUADPACK `qk15`).
    pub const K15: Rule = Rule {
        xgk: &XGK,
        wgk: &WGK,
        wg: &WG,
    };
    /// G3–K7: Kronrod's extension of the 3-point Gauss rule (exact to degree 9 at the Kronrod
    /// nodes, 5 at the Gauss nodes).
    pub const K7: Rule = Rule {
        xgk: &XGK7,
        wgk: &WGK7,
        wg: &WG3,
    };

    /// Integrand evaluations per segment.
    pub const fn nodes(&self) -> usize {
        2 * self.xgk.len() - 1
    }
}

/// G7–K15 on [lo, hi] with the error estimate described in the module documentation.
pub fn gauss_kronrod_15(f: &mut impl FnMut(f64) -> DVec3, lo: f64, hi: f64) -> RuleResult {
    gauss_kronrod(Rule::K15, f, lo, hi)
}

/// A Gauss–Kronrod pair on [lo, hi]: the Kronrod value and the error estimate described in the
/// module documentation (the same formula for both pairs; for G3–K7 QUADPACK's heuristic only
/// ever raises the plain |K − G| further, it never lowers it).
pub fn gauss_kronrod(rule: Rule, f: &mut impl FnMut(f64) -> DVec3, lo: f64, hi: f64) -> RuleResult {
    let centre = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo);
    let n = rule.xgk.len() - 1;
    let mut fv = [DVec3::ZERO; 15];
    for j in 0..n {
        let dx = half * rule.xgk[j];
        fv[2 * j] = f(centre - dx);
        fv[2 * j + 1] = f(centre + dx);
    }
    let fc = f(centre);
    let fv = &fv[..2 * n];
    let mut resk = rule.wgk[n] * fc;
    let mut resg = rule.wg[rule.wg.len() - 1] * fc;
    for j in 0..n {
        let pair = fv[2 * j] + fv[2 * j + 1];
        resk += rule.wgk[j] * pair;
        if j % 2 == 1 {
            resg += rule.wg[j / 2] * pair;
        }
    }
    let mean = 0.5 * resk;
    let mut resabs = rule.wgk[n] * fc.abs();
    let mut resasc = rule.wgk[n] * (fc - mean).abs();
    for j in 0..n {
        resabs += rule.wgk[j] * (fv[2 * j].abs() + fv[2 * j + 1].abs());
        resasc += rule.wgk[j] * ((fv[2 * j] - mean).abs() + (fv[2 * j + 1] - mean).abs());
    }
    let h = half.abs();
    let diff = ((resk - resg) * h).abs();
    let (resabs, resasc) = (resabs * h, resasc * h);
    let mut error = diff;
    let mut relative = 0.0f64;
    for c in 0..3 {
        if resasc[c] > 0.0 && diff[c] > 0.0 {
            error[c] = diff[c].max(resasc[c] * (200.0 * diff[c] / resasc[c]).powf(1.5).min(1.0));
            relative = relative.max(error[c] / resasc[c]);
        }
    }
    for c in 0..3 {
        // The channels share their nodes: a Gauss–Kronrod difference that cancels by luck in
        // one channel does not mean that channel is resolved. Each channel's estimate is at
        // least the worst channel's error relative to its variation (resasc), scaled to its own.
        error[c] = error[c].max(relative * resasc[c]);
        error[c] = error[c].max(50.0 * f64::EPSILON * resabs[c]);
    }
    RuleResult {
        value: resk * half,
        error,
    }
}

/// G7–K15 after the substitution u = lo + (hi − lo)·g(s), g(s) = s²(3 − 2s), s ∈ [0, 1]. Since
/// g′(0) = g′(1) = 0, a square-root singularity at either end (a shadow ray grazing a sphere, see
/// `optics::kinks`) becomes f(g(s))·g′(s) ~ s·√s·…, smooth enough for the rule to converge
/// fast, and a smooth integrand stays smooth (a cubic change of variable).
pub fn gauss_kronrod_15_smoothed(f: &mut impl FnMut(f64) -> DVec3, lo: f64, hi: f64) -> RuleResult {
    gauss_kronrod_smoothed(Rule::K15, f, lo, hi)
}

/// [`gauss_kronrod`] after the endpoint-smoothing substitution of [`gauss_kronrod_15_smoothed`].
pub fn gauss_kronrod_smoothed(
    rule: Rule,
    f: &mut impl FnMut(f64) -> DVec3,
    lo: f64,
    hi: f64,
) -> RuleResult {
    let w = hi - lo;
    gauss_kronrod(
        rule,
        &mut |s| {
            let g = s * s * (3.0 - 2.0 * s);
            let dg = 6.0 * s * (1.0 - s);
            f(lo + w * g) * (w * dg)
        },
        0.0,
        1.0,
    )
}

/// One piece of the integration domain: ∫_lo^hi f(tag, u) du, weighted by `weight` ≥ 0 (the
/// transmittance in front of the interval).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piece {
    pub lo: f64,
    pub hi: f64,
    pub weight: f64,
    pub tag: usize,
}

/// What the adaptive integration returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveResult {
    /// Σ weight·∫ f.
    pub value: DVec3,
    /// Summed error estimate per channel.
    pub error: DVec3,
    /// Segments at the end.
    pub segments: usize,
    /// Integrand evaluations.
    pub evaluations: usize,
    /// Whether the summed estimate reached `tol` in every channel.
    pub converged: bool,
}

#[derive(Debug, Clone, Copy)]
struct Segment {
    lo: f64,
    hi: f64,
    weight: f64,
    tag: usize,
    value: DVec3,
    error: DVec3,
    alive: bool,
}

/// Heap entry: the largest channel error of a segment, then its index (a total order, so the
/// refinement sequence is deterministic).
#[derive(PartialEq)]
struct Priority(f64, usize);
impl Eq for Priority {}
impl PartialOrd for Priority {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Priority {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0).then(other.1.cmp(&self.1))
    }
}

/// Globally adaptive integration of Σ_pieces weight·∫ f (module documentation). `kink_in(tag,
/// lo, hi)` returns a known non-smooth point strictly inside (lo, hi) (the one nearest to the
/// middle), or `None`.
pub fn integrate_adaptive(
    pieces: &[Piece],
    tol: f64,
    max_segments: usize,
    f: impl FnMut(usize, f64) -> DVec3,
    kink_in: impl Fn(usize, f64, f64) -> Option<f64>,
) -> AdaptiveResult {
    integrate_adaptive_with(Rule::K15, pieces, tol, max_segments, f, kink_in)
}

/// [`integrate_adaptive`] with the Gauss–Kronrod pair `rule` on every segment.
pub fn integrate_adaptive_with(
    rule: Rule,
    pieces: &[Piece],
    tol: f64,
    max_segments: usize,
    mut f: impl FnMut(usize, f64) -> DVec3,
    kink_in: impl Fn(usize, f64, f64) -> Option<f64>,
) -> AdaptiveResult {
    let mut segments: Vec<Segment> = Vec::with_capacity(pieces.len() * 2);
    let mut heap = BinaryHeap::new();
    let mut evaluations = 0;
    let evaluate =
        |lo: f64, hi: f64, weight: f64, tag: usize, f: &mut dyn FnMut(usize, f64) -> DVec3| {
            // A kink inside, or at an end (a segment split at a kink keeps a square-root endpoint
            // singularity), makes the estimate less reliable: widen the test by a hair to see ends.
            let hair = (hi - lo) * 1e-9;
            let near_kink = kink_in(tag, lo - hair, hi + hair).is_some();
            let r = if near_kink {
                gauss_kronrod_smoothed(rule, &mut |u| f(tag, u), lo, hi)
            } else {
                gauss_kronrod(rule, &mut |u| f(tag, u), lo, hi)
            };
            let safety = if near_kink { KINK_SAFETY } else { 1.0 };
            Segment {
                lo,
                hi,
                weight,
                tag,
                value: weight * r.value,
                error: (weight * safety) * r.error,
                alive: true,
            }
        };
    let mut total_error = DVec3::ZERO;
    for p in pieces {
        if !(p.hi > p.lo) || !(p.weight > 0.0) {
            continue;
        }
        let s = evaluate(p.lo, p.hi, p.weight, p.tag, &mut f);
        evaluations += rule.nodes();
        total_error += s.error;
        heap.push(Priority(s.error.max_element(), segments.len()));
        segments.push(s);
    }
    let mut live = segments.len();
    let mut converged;
    loop {
        converged = total_error.max_element() <= tol;
        if converged {
            // The running sum drifts by round-off; confirm with an exact one before stopping.
            total_error = segments.iter().filter(|s| s.alive).map(|s| s.error).sum();
            converged = total_error.max_element() <= tol;
            if converged {
                break;
            }
        }
        if live >= max_segments {
            break;
        }
        let Some(Priority(_, i)) = heap.pop() else {
            break;
        };
        let s = segments[i];
        let mid = kink_in(s.tag, s.lo, s.hi).unwrap_or(0.5 * (s.lo + s.hi));
        if !(mid > s.lo && mid < s.hi) {
            // Too narrow to split in f64: its estimate stays in the total, it leaves the heap.
            continue;
        }
        segments[i].alive = false;
        total_error -= s.error;
        for (lo, hi) in [(s.lo, mid), (mid, s.hi)] {
            let child = evaluate(lo, hi, s.weight, s.tag, &mut f);
            evaluations += rule.nodes();
            total_error += child.error;
            heap.push(Priority(child.error.max_element(), segments.len()));
            segments.push(child);
        }
        live += 1;
    }
    let alive = segments.iter().filter(|s| s.alive);
    let value = alive.clone().map(|s| s.value).sum();
    let error = alive.map(|s| s.error).sum();
    AdaptiveResult {
        value,
        error,
        segments: live,
        evaluations,
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn k15_integrates_polynomials_of_degree_22_exactly() {
        let r = gauss_kronrod_15(&mut |x| DVec3::new(x.powi(22), x.powi(3), 1.0), -1.0, 2.0);
        let exact = DVec3::new((2f64.powi(23) + 1.0) / 23.0, (16.0 - 1.0) / 4.0, 3.0);
        assert!(
            ((r.value - exact) / exact).abs().max_element() < 1e-13,
            "{:?}",
            r.value
        );
    }

    #[test]
    fn adaptive_reaches_tol_on_a_sqrt_kink_and_the_estimate_covers_the_error() {
        // ∫_0^2 sqrt|x − 0.7| dx, kink not announced: adaptivity alone.
        let exact = (2.0 / 3.0) * (0.7f64.powf(1.5) + 1.3f64.powf(1.5));
        for tol in [1e-4, 1e-7, 1e-10] {
            let pieces = [Piece {
                lo: 0.0,
                hi: 2.0,
                weight: 1.0,
                tag: 0,
            }];
            let r = integrate_adaptive(
                &pieces,
                tol,
                10_000,
                |_, x| DVec3::splat((x - 0.7f64).abs().sqrt()),
                |_, _, _| None,
            );
            assert!(r.converged);
            let actual = (r.value.x - exact).abs();
            assert!(
                actual <= r.error.x,
                "tol {tol}: actual {actual} > estimate {}",
                r.error.x
            );
            assert!(r.error.x <= tol);
        }
    }

    #[test]
    fn announced_kinks_and_max_segments() {
        let f = |_: usize, x: f64| DVec3::splat((x - 0.7f64).abs().sqrt());
        let pieces = [Piece {
            lo: 0.0,
            hi: 2.0,
            weight: 0.5,
            tag: 0,
        }];
        let kink = |_: usize, lo: f64, hi: f64| (lo < 0.7 && 0.7 < hi).then_some(0.7);
        let with = integrate_adaptive(&pieces, 1e-9, 10_000, f, kink);
        let without = integrate_adaptive(&pieces, 1e-9, 10_000, f, |_, _, _| None);
        assert!(with.converged && without.converged);
        let exact = 0.5 * (2.0 / 3.0) * (0.7f64.powf(1.5) + 1.3f64.powf(1.5));
        assert!((with.value.x - exact).abs() <= with.error.x);
        assert!((without.value.x - exact).abs() <= without.error.x);
        // A square-root kink stays an endpoint singularity after the exact split, so both runs
        // bisect towards it; knowing it must not cost more than a little.
        assert!(with.evaluations <= without.evaluations + 4 * NODES_PER_SEGMENT);
        let capped = integrate_adaptive(&pieces, 1e-14, 3, f, |_, _, _| None);
        assert!(!capped.converged && capped.segments == 3);
        assert!((capped.value.x - exact).abs() <= capped.error.x);
    }
}

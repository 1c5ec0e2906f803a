//! Globally adaptive Gauss–Kronrod quadrature (G7–K15) of RGB-valued integrands, with an error
//! estimate (docs/design.md §3: "adaptive Gauss–Kronrod quadrature with an error estimate, to an
//! absolute radiance tolerance `tol` per pixel and channel").
//!
//! **Error estimate.** Per segment and channel the estimate is the larger of |K15 − G7| and
//! QUADPACK's heuristic resasc·min(1, (200·|K15 − G7|/resasc)^{3/2}) (Piessens et al. 1983,
//! `qk15`), with QUADPACK's round-off floor 50·ε·∫|f| (the lower levels below use the factor
//! 100 for 200: [`LOWER_AMPLIFICATION`]). The plain |K15 − G7| is the error of the
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
//! error. Where the caller knows on which side of a kink the square root lies (the volume
//! renderer does, for tangency kinks), only the singular ends are flattened
//! ([`integrate_adaptive_with_ends`]), and a segment with none is integrated as it is. (The
//! volume renderer also makes every kink a breakpoint before the first pass, so that no shadow
//! falls unseen between the nodes of a segment.)
//!
//! **Two levels per segment** (and a third below them, see below). The 7 Gauss nodes are a
//! subset of the 15 Kronrod nodes, so a segment is first integrated by G7 alone, whose estimate is its difference from the
//! interpolatory 5-node rule on five of its nodes (degree 5 against G7's 13, so for smooth
//! integrands the estimate is far above G7's error), and raised to K15 by eight more nodes only
//! where that does not meet the budget.
//! Cheaper schemes (fewer nodes at the first level, no amplification of the estimate, nested
//! rules that share more nodes) were measured and rejected: each was honest or nearly so, but
//! either missed features of lit integrands that K15 against G7 catches, or let the actual
//! error at tol 1e-4 rise towards Riemann-100's, and the pessimism of this estimate is what
//! keeps it far below (docs/performance.md, "The quadrature's levels").
//!
//! **A third, lower level where the caller allows it.** A 5-node first level is kept for
//! segments the caller chooses ([`Level::R5`], [`integrate_adaptive_batched`]'s
//! `first_level`): R5 on G7's nodes 0, ±XGK[1], ±XGK[3] ([`WG7_SUB5`]), estimated against the
//! 3-node rule on 0, ±XGK[3] ([`R3`]), raised to G7 by the two nodes ±XGK[5] and then to K15.
//! The volume renderer starts a piece there only where its whole contribution is bounded by a
//! few tol (`R5_START_LIMIT` of `reference::volume`'s error budget).
//!
//! **Global adaptivity.** All segments of one pixel (every interval of the camera ray) share
//! one error budget: the segment with the largest estimate is raised or split until the summed
//! estimate is ≤ `tol` in every channel. A segment with a kink inside is split at the kink
//! nearest to its middle (so the pieces are smooth), others are bisected. After `max_segments` segments, or
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

/// Multiplier of the error estimate of a segment that contains a known kink.
pub const KINK_SAFETY: f64 = 2.0;

/// K15 value and error estimate of one segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RuleResult {
    pub value: DVec3,
    pub error: DVec3,
}

/// G7–K15 on [lo, hi] with the error estimate described in the module documentation.
pub fn gauss_kronrod_15(f: &mut impl FnMut(f64) -> DVec3, lo: f64, hi: f64) -> RuleResult {
    single_segment(f, lo, hi, false)
}

/// G7–K15 after the substitution u = lo + (hi − lo)·g(s), g(s) = s²(3 − 2s), s ∈ [0, 1]. Since
/// g′(0) = g′(1) = 0, a square-root singularity at either end (a shadow ray grazing a sphere, see
/// `optics::kinks`) becomes f(g(s))·g′(s) ~ s·√s·…, smooth enough for the rule to converge
/// fast, and a smooth integrand stays smooth (a cubic change of variable).
pub fn gauss_kronrod_15_smoothed(f: &mut impl FnMut(f64) -> DVec3, lo: f64, hi: f64) -> RuleResult {
    single_segment(f, lo, hi, true)
}

fn single_segment(
    f: &mut impl FnMut(f64) -> DVec3,
    lo: f64,
    hi: f64,
    smoothed: bool,
) -> RuleResult {
    let ends = if smoothed { BOTH_ENDS } else { 0 };
    let mut s = NestedSegment::new(lo, hi, 1.0, 0, ends);
    let f: &mut Nodes = &mut each_node(|_, u| f(u));
    s.raise_to(Level::K15, f);
    RuleResult {
        value: s.value,
        error: s.error,
    }
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

/// Weights of the 5-node interpolatory rule on the G7 nodes 0, ±XGK[1], ±XGK[3] (exact to
/// degree 5; the only 5-node subset of G7 whose interpolatory weights are all positive): the
/// coarse rule that G7 is compared with on a segment's first level (order: centre, ±XGK[1],
/// ±XGK[3]). The solution of w0 + 2w1 + 2w3 = 2, 2w1·x1² + 2w3·x3² = 2/3, 2w1·x1⁴ + 2w3·x3⁴ = 2/5
/// (a unit test checks it).
#[allow(clippy::excessive_precision)]
const WG7_SUB5: [f64; 3] = [
    0.855_061_816_216_368_475_12,
    0.052_860_187_099_682_856_771,
    0.519_608_904_792_132_905_67,
];

/// The integrand of a batch of nodes of one segment: `f(tag, us, values)` sets `values[i]`
/// to the integrand at `us[i]` of piece `tag` (the nodes a segment's level adds, in the order
/// of [`NestedSegment::raise_to`], so that the caller may share work between them).
pub type Nodes<'a> = dyn FnMut(usize, &[f64], &mut [DVec3]) + 'a;

/// The most nodes one call of [`Nodes`] asks for (the eight that K15 adds to G7).
pub const MAX_NODES: usize = 8;

/// Integrand evaluations of a segment at its first level (G7) and at its second (K15, reusing
/// the first level's seven).
pub const NESTED_NODES: [usize; 2] = [7, 15];

/// The rule a segment is at. Each level's nodes hold the last one's, so raising a segment
/// costs only the nodes it adds: R5 (5 nodes) → G7 (2 more) → K15 (8 more).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// The interpolatory rule on G7's nodes 0, ±XGK[1], ±XGK[3] ([`WG7_SUB5`]), estimated
    /// against the interpolatory rule on 0, ±XGK[3] ([`R3`]): for pieces whose whole
    /// contribution is small (the caller's judgement, `first_level`).
    R5,
    /// G7, estimated against R5.
    G7,
    /// K15, estimated against G7 (QUADPACK's `qk15`).
    K15,
}

impl Level {
    /// The level above, if any.
    fn next(self) -> Option<Level> {
        match self {
            Level::R5 => Some(Level::G7),
            Level::G7 => Some(Level::K15),
            Level::K15 => None,
        }
    }
}

/// Weights of the 3-node interpolatory rule on 0, ±XGK[3] (exact to degree 3; both positive):
/// w₃ = 1/(3·x₃²) from 2w₃·x₃² = 2/3, and w₀ = 2 − 2w₃ (order: centre, ±XGK[3]; a unit test
/// checks them). The coarse rule that R5 is compared with.
const R3: [f64; 2] = [
    2.0 - 2.0 / (3.0 * XGK[3] * XGK[3]),
    1.0 / (3.0 * XGK[3] * XGK[3]),
];

/// The factor a of QUADPACK's heuristic resasc·min(1, (a·|K15 − G7|/resasc)^{3/2}) for K15
/// against G7, as `qk15` has it.
const QUADPACK_AMPLIFICATION: f64 = 200.0;

/// The factor a of the same heuristic for the lower levels, G7 against R5 and R5 against R3.
/// There the difference of the pair is the coarse rule's error (R5's: degree 5 against G7's
/// 13), far above that of the value returned, so the estimate is pessimistic before any
/// amplification, and half of QUADPACK's factor keeps every honesty scene honest (a = 50 did
/// not; docs/performance.md, "The quadrature's levels").
const LOWER_AMPLIFICATION: f64 = 100.0;

/// The error estimate of a pair of rules on one segment (module documentation): `resk` the
/// better rule, `resg` the coarser, `resabs` = ∫|f| and `resasc` = ∫|f − mean| by the better
/// rule's weights, all on [−1, 1]; `h` the half-width; `amplification` the factor of QUADPACK's
/// heuristic ([`QUADPACK_AMPLIFICATION`], [`LOWER_AMPLIFICATION`]).
fn pair_estimate(
    resk: DVec3,
    resg: DVec3,
    resabs: DVec3,
    resasc: DVec3,
    h: f64,
    amplification: f64,
) -> DVec3 {
    let diff = ((resk - resg) * h).abs();
    let (resabs, resasc) = (resabs * h, resasc * h);
    let mut error = diff;
    let mut relative = 0.0f64;
    for c in 0..3 {
        if resasc[c] > 0.0 && diff[c] > 0.0 {
            // q^{3/2} as q·√q: one square root instead of `powf`.
            let q = amplification * diff[c] / resasc[c];
            error[c] = diff[c].max(resasc[c] * (q * q.sqrt()).min(1.0));
            relative = relative.max(error[c] / resasc[c]);
        }
    }
    for c in 0..3 {
        error[c] = error[c].max(relative * resasc[c]);
        error[c] = error[c].max(50.0 * f64::EPSILON * resabs[c]);
    }
    error
}

/// One segment of [`integrate_adaptive`]: the integrand at the Kronrod nodes evaluated so
/// far (`fv[2j]` at centre − half·XGK[j], `fv[2j+1]` at centre + half·XGK[j], `fv[14]` at the
/// centre), and its level (`None` before the first).
#[derive(Debug, Clone, Copy)]
struct NestedSegment {
    lo: f64,
    hi: f64,
    weight: f64,
    tag: usize,
    /// Which ends are square-root points ([`LOW_END`], [`HIGH_END`]): those the substitution
    /// flattens; 0 for none (no substitution).
    ends: u8,
    level: Option<Level>,
    fv: [DVec3; 15],
    value: DVec3,
    error: DVec3,
    alive: bool,
}

impl NestedSegment {
    /// A segment with no node evaluated yet.
    fn new(lo: f64, hi: f64, weight: f64, tag: usize, ends: u8) -> Self {
        NestedSegment {
            lo,
            hi,
            weight,
            tag,
            ends,
            level: None,
            fv: [DVec3::ZERO; 15],
            value: DVec3::ZERO,
            error: DVec3::ZERO,
            alive: true,
        }
    }

    /// Where the integrand is taken for abscissa x ∈ [−1, 1] of the segment, and the factor
    /// its value is multiplied by: after the endpoint-smoothing substitution of
    /// [`integrate_adaptive_with_ends`] that flattens its singular `ends`, the map's
    /// derivative; `None` without one.
    fn node(&self, x: f64) -> (f64, Option<f64>) {
        if self.ends != 0 {
            // s ∈ [0, 1], the variable of `gauss_kronrod_15_smoothed` (half-width 1/2), and a
            // map g with g′ = 0 at the singular ends only.
            let w = self.hi - self.lo;
            let s = 0.5 + 0.5 * x;
            let (g, dg) = match self.ends {
                LOW_END => (s * s, 2.0 * s),
                HIGH_END => {
                    let r = 1.0 - s;
                    (1.0 - r * r, 2.0 * r)
                }
                _ => (s * s * (3.0 - 2.0 * s), 6.0 * s * (1.0 - s)),
            };
            (self.lo + w * g, Some(w * dg))
        } else {
            let centre = 0.5 * (self.lo + self.hi);
            let half = 0.5 * (self.hi - self.lo);
            (centre + half * x, None)
        }
    }

    /// Evaluates the nodes that `level` adds to the segment's present level (all of its own
    /// on a new segment; a new segment is raised to K15 through G7), and the segment's value
    /// and error estimate at that level: R5 against R3 ([`R3`]), G7 against R5 ([`WG7_SUB5`]),
    /// or K15 against G7 (QUADPACK's `qk15`). Returns the number of nodes evaluated.
    fn raise_to(&mut self, level: Level, f: &mut Nodes) -> usize {
        // The nodes the level adds, as (abscissa, slot in `fv`), from one end of the segment to
        // the other: consecutive shadow rays then differ least, and the most recent end order
        // of the shadow compositor (`reference::shadow`) is the one that holds. The values do
        // not depend on the order.
        let nodes: &[(f64, usize)] = match (self.level, level) {
            (None, Level::R5) => &[
                (-XGK[1], 2),
                (-XGK[3], 6),
                (0.0, 14),
                (XGK[3], 7),
                (XGK[1], 3),
            ],
            (Some(Level::R5), Level::G7) => &[(-XGK[5], 10), (XGK[5], 11)],
            (None, Level::G7) => &[
                (-XGK[1], 2),
                (-XGK[3], 6),
                (-XGK[5], 10),
                (0.0, 14),
                (XGK[5], 11),
                (XGK[3], 7),
                (XGK[1], 3),
            ],
            (Some(Level::G7), Level::K15) => &[
                (-XGK[0], 0),
                (-XGK[2], 4),
                (-XGK[4], 8),
                (-XGK[6], 12),
                (XGK[6], 13),
                (XGK[4], 9),
                (XGK[2], 5),
                (XGK[0], 1),
            ],
            (None, Level::K15) => {
                return self.raise_to(Level::G7, f) + self.raise_to(Level::K15, f);
            }
            (from, to) => unreachable!("a segment at {from:?} is not raised to {to:?}"),
        };
        self.level = Some(level);
        let mut us = [0.0; MAX_NODES];
        let mut factors = [None; MAX_NODES];
        for (i, &(x, _)) in nodes.iter().enumerate() {
            (us[i], factors[i]) = self.node(x);
        }
        let n = nodes.len();
        let mut values = [DVec3::ZERO; MAX_NODES];
        f(self.tag, &us[..n], &mut values[..n]);
        for ((&(_, slot), v), factor) in nodes.iter().zip(values).zip(factors) {
            self.fv[slot] = match factor {
                Some(factor) => v * factor,
                None => v,
            };
        }
        let fc = self.fv[14];
        let pair = |j: usize| self.fv[2 * j] + self.fv[2 * j + 1];
        // Each rule only where its nodes have been evaluated.
        let g7 = || WG[3] * fc + WG[0] * pair(1) + WG[1] * pair(3) + WG[2] * pair(5);
        let r5 = || WG7_SUB5[0] * fc + WG7_SUB5[1] * pair(1) + WG7_SUB5[2] * pair(3);
        let (resk, resg, wc, used): (DVec3, DVec3, f64, &[(usize, f64)]) = match level {
            Level::R5 => {
                let r3 = R3[0] * fc + R3[1] * pair(3);
                (r5(), r3, WG7_SUB5[0], &[(1, WG7_SUB5[1]), (3, WG7_SUB5[2])])
            }
            Level::G7 => (g7(), r5(), WG[3], &[(1, WG[0]), (3, WG[1]), (5, WG[2])]),
            Level::K15 => {
                let mut k15 = WGK[7] * fc;
                for (j, w) in WGK[..7].iter().enumerate() {
                    k15 += *w * pair(j);
                }
                let used = &[
                    (0, WGK[0]),
                    (1, WGK[1]),
                    (2, WGK[2]),
                    (3, WGK[3]),
                    (4, WGK[4]),
                    (5, WGK[5]),
                    (6, WGK[6]),
                ];
                (k15, g7(), WGK[7], used)
            }
        };
        let mean = 0.5 * resk;
        let mut resabs = wc * fc.abs();
        let mut resasc = wc * (fc - mean).abs();
        for &(j, w) in used {
            let (a, b) = (self.fv[2 * j], self.fv[2 * j + 1]);
            resabs += w * (a.abs() + b.abs());
            resasc += w * ((a - mean).abs() + (b - mean).abs());
        }
        let h = if self.ends != 0 {
            0.5
        } else {
            0.5 * (self.hi - self.lo).abs()
        };
        self.value = self.weight * (resk * h);
        let amplification = match level {
            Level::K15 => QUADPACK_AMPLIFICATION,
            Level::R5 | Level::G7 => LOWER_AMPLIFICATION,
        };
        self.error = self.weight * pair_estimate(resk, resg, resabs, resasc, h, amplification);
        n
    }
}

/// Globally adaptive integration of Σ_pieces weight·∫ f (module documentation), with the
/// Kronrod extension as a second level. A segment starts with the 7 Gauss nodes: value G7,
/// estimate against the 5-node rule on five of them ([`WG7_SUB5`]). The segment with the
/// largest estimate is first raised to K15 by the 8 other Kronrod nodes (value K15, estimate
/// against G7, as QUADPACK's `qk15`), and only a segment already at K15 is split, at a known kink
/// or else in the middle, into two new G7 segments. A segment for which `coarse_ok(tag, lo, hi)`
/// is false starts at K15: the caller's judgement of where the coarse estimate cannot be
/// trusted. `kink_in(tag, lo, hi)` returns a known non-smooth point strictly inside (lo, hi)
/// (the one nearest to the middle), or `None`; segments that contain or touch one use the
/// endpoint-smoothing substitution at both ends and [`KINK_SAFETY`] at both levels
/// ([`integrate_adaptive_with_ends`] with both ends singular wherever a kink is near).
pub fn integrate_adaptive(
    pieces: &[Piece],
    tol: f64,
    max_segments: usize,
    f: impl FnMut(usize, f64) -> DVec3,
    kink_in: impl Fn(usize, f64, f64) -> Option<f64>,
    coarse_ok: impl Fn(usize, f64, f64) -> bool,
) -> AdaptiveResult {
    let ends = |tag: usize, lo: f64, hi: f64, hair: f64| {
        if kink_in(tag, lo - hair, hi + hair).is_some() {
            BOTH_ENDS
        } else {
            0
        }
    };
    integrate_adaptive_with_ends(pieces, tol, max_segments, f, &kink_in, coarse_ok, ends)
}

/// A segment's low end is a square-root point of the integrand (a bit of [`NestedSegment`]'s
/// `ends`, as `singular_ends` of [`integrate_adaptive_with_ends`] returns them).
pub const LOW_END: u8 = 1;
/// Its high end is one.
pub const HIGH_END: u8 = 2;
/// Both ends are, or a kink lies inside.
pub const BOTH_ENDS: u8 = LOW_END | HIGH_END;

/// [`integrate_adaptive`], where `singular_ends(tag, lo, hi, hair)` says which ends of a new
/// segment [lo, hi] are square-root points ([`LOW_END`], [`HIGH_END`]; [`BOTH_ENDS`] also for a
/// kink inside; `hair` is how far from an end a kink still counts as at it). A segment with a
/// singular end takes the substitution that flattens that end only: u = lo + w·s² (low),
/// u = hi − w·(1 − s)² (high), or the cubic s²(3 − 2s) of [`gauss_kronrod_15_smoothed`] (both),
/// and [`KINK_SAFETY`]; a segment with none is integrated as it is. The substitution is needed
/// only where the singularity is: at a tangency kink the integrand has its square root on the
/// side where the shadow ray crosses the sphere and is smooth on the other
/// (`optics::kinks::push_sided_tangencies`), and flattening a smooth end only crowds the nodes
/// there.
pub fn integrate_adaptive_with_ends(
    pieces: &[Piece],
    tol: f64,
    max_segments: usize,
    f: impl FnMut(usize, f64) -> DVec3,
    kink_in: &impl Fn(usize, f64, f64) -> Option<f64>,
    coarse_ok: impl Fn(usize, f64, f64) -> bool,
    singular_ends: impl Fn(usize, f64, f64, f64) -> u8,
) -> AdaptiveResult {
    let first_level = |tag, lo, hi| {
        if coarse_ok(tag, lo, hi) {
            Level::G7
        } else {
            Level::K15
        }
    };
    let tests = (kink_in, first_level, singular_ends);
    integrate_adaptive_batched(pieces, tol, max_segments, each_node(f), tests)
}

/// A per-node integrand `f(tag, u)` as a [`Nodes`] one: each node of a batch in turn.
fn each_node(mut f: impl FnMut(usize, f64) -> DVec3) -> impl FnMut(usize, &[f64], &mut [DVec3]) {
    move |tag, us, values| {
        for (u, v) in us.iter().zip(values) {
            *v = f(tag, *u);
        }
    }
}

/// [`integrate_adaptive_with_ends`] with the integrand taken a segment's level at a time
/// ([`Nodes`]): the same nodes in the same order, and the same result, bit for bit, where
/// `first_level(tag, lo, hi)` is G7 where `coarse_ok` is true and K15 where it is false. The
/// volume renderer's shadow rays from one segment share their occluder list, which is then read
/// once for all of them. `first_level` may also start a piece at [`Level::R5`], whose
/// estimate then raises it to G7 where needed, before K15 and any split (the halves of a split
/// start at G7 or K15 as `first_level` says, never at R5: they are what a coarse start did
/// not resolve).
pub fn integrate_adaptive_batched(
    pieces: &[Piece],
    tol: f64,
    max_segments: usize,
    mut f: impl FnMut(usize, &[f64], &mut [DVec3]),
    (kink_in, first_level, singular_ends): (
        &impl Fn(usize, f64, f64) -> Option<f64>,
        impl Fn(usize, f64, f64) -> Level,
        impl Fn(usize, f64, f64, f64) -> u8,
    ),
) -> AdaptiveResult {
    let f: &mut Nodes = &mut f;
    // Near a kink both rules of a pair err alike and their difference can understate the error.
    let safety = |s: &NestedSegment| if s.ends != 0 { KINK_SAFETY } else { 1.0 };
    let mut segments: Vec<NestedSegment> = Vec::with_capacity(pieces.len() * 2);
    let mut heap = BinaryHeap::new();
    let mut evaluations = 0;
    let mut total_error = DVec3::ZERO;
    let new_segment = |lo: f64, hi: f64, weight: f64, tag: usize, lowest: Level, f: &mut Nodes| {
        // A kink inside, or at an end (a segment split at a kink keeps a square-root endpoint
        // singularity), calls for the substitution: widen the test by a hair to see ends.
        let hair = (hi - lo) * 1e-9;
        let ends = singular_ends(tag, lo, hi, hair);
        let mut s = NestedSegment::new(lo, hi, weight, tag, ends);
        let nodes = s.raise_to(first_level(tag, lo, hi).max(lowest), f);
        s.error *= safety(&s);
        (s, nodes)
    };
    for p in pieces {
        if !(p.hi > p.lo) || !(p.weight > 0.0) {
            continue;
        }
        let (s, n) = new_segment(p.lo, p.hi, p.weight, p.tag, Level::R5, f);
        total_error += s.error;
        evaluations += n;
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
        let Some(Priority(_, i)) = heap.pop() else {
            break;
        };
        if let Some(next) = segments[i].level.and_then(Level::next) {
            let s = &mut segments[i];
            total_error -= s.error;
            evaluations += s.raise_to(next, f);
            s.error *= safety(s);
            total_error += s.error;
            heap.push(Priority(s.error.max_element(), i));
            continue;
        }
        if live >= max_segments {
            break;
        }
        let s = segments[i];
        let mid = kink_in(s.tag, s.lo, s.hi).unwrap_or(0.5 * (s.lo + s.hi));
        if !(mid > s.lo && mid < s.hi) {
            // Too narrow to split in f64: its estimate stays in the total, it leaves the heap.
            continue;
        }
        segments[i].alive = false;
        total_error -= s.error;
        for (lo, hi) in [(s.lo, mid), (mid, s.hi)] {
            let (child, n) = new_segment(lo, hi, s.weight, s.tag, Level::G7, f);
            total_error += child.error;
            evaluations += n;
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

    /// The single piece [lo, hi] with weight `weight`.
    fn one_piece(lo: f64, hi: f64, weight: f64) -> [Piece; 1] {
        [Piece {
            lo,
            hi,
            weight,
            tag: 0,
        }]
    }

    /// ∫_lo^hi g to `tol` with no kinks announced and every segment free to start at G7.
    fn integrate_plain(lo: f64, hi: f64, tol: f64, g: impl Fn(f64) -> f64) -> AdaptiveResult {
        integrate_adaptive(
            &one_piece(lo, hi, 1.0),
            tol,
            10_000,
            |_, x| DVec3::splat(g(x)),
            |_, _, _| None,
            |_, _, _| true,
        )
    }

    /// The batched integrand gets each segment's level as one batch: G7's seven nodes or the
    /// eight K15 adds, from one end of the segment to the other, all in the piece, as many in
    /// all as `evaluations`; and the result is the per-node one's, bit for bit.
    #[test]
    fn nodes_come_a_level_at_a_time_in_order() {
        let pieces = [
            Piece {
                lo: 0.0,
                hi: 0.6,
                weight: 0.8,
                tag: 0,
            },
            Piece {
                lo: 0.2,
                hi: 0.9,
                weight: 0.5,
                tag: 1,
            },
        ];
        let g =
            |tag: usize, u: f64| DVec3::new((u - 0.3).abs().sqrt(), (9.0 * u).sin(), tag as f64);
        let kink_in =
            |tag: usize, lo: f64, hi: f64| (tag == 0 && lo < 0.3 && hi > 0.3).then_some(0.3);
        let ends = |tag: usize, lo: f64, hi: f64, hair: f64| {
            if kink_in(tag, lo - hair, hi + hair).is_some() {
                BOTH_ENDS
            } else {
                0
            }
        };
        let coarse_ok = |tag: usize, _: f64, _: f64| tag == 0;
        let first_level = |tag: usize, lo: f64, hi: f64| {
            if coarse_ok(tag, lo, hi) {
                Level::G7
            } else {
                Level::K15
            }
        };
        let mut batches = Vec::new();
        let batched = integrate_adaptive_batched(
            &pieces,
            1e-10,
            1000,
            |tag, us: &[f64], out: &mut [DVec3]| {
                batches.push((tag, us.to_vec()));
                for (u, v) in us.iter().zip(out) {
                    *v = g(tag, *u);
                }
            },
            (&kink_in, first_level, ends),
        );
        let one_by_one =
            integrate_adaptive_with_ends(&pieces, 1e-10, 1000, g, &kink_in, coarse_ok, ends);
        assert_eq!(batched, one_by_one);
        assert!(batched.converged && batched.segments > 10);
        let mut count = 0;
        for (tag, us) in &batches {
            let p = &pieces[*tag];
            assert!(us.len() == 7 || us.len() == 8, "{us:?}");
            assert!(us.windows(2).all(|w| w[0] < w[1]), "{us:?}");
            assert!(us.iter().all(|&u| u > p.lo && u < p.hi), "{us:?}");
            count += us.len();
        }
        assert_eq!(count, batched.evaluations);
        assert!(batches.iter().any(|(tag, us)| *tag == 1 && us.len() == 8));
    }

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
            let r = integrate_plain(0.0, 2.0, tol, |x| (x - 0.7f64).abs().sqrt());
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

    /// A square root at one end, announced as that end: the one-sided substitution reaches tol
    /// with an honest estimate, and with fewer evaluations than flattening both ends.
    #[test]
    fn a_singular_end_alone_is_flattened_and_the_estimate_covers_the_error() {
        // ∫_0.3^1 √(u − 0.3)·(1 + u) du and its mirror image ∫_0^0.7 √(0.7 − u)·(1 + u) du.
        let v = 0.7f64;
        let exact_low = (2.0 / 3.0) * v.powf(1.5) * 1.3 + (2.0 / 5.0) * v.powf(2.5);
        let exact_high = (2.0 / 3.0) * v.powf(1.5) * 1.7 - (2.0 / 5.0) * v.powf(2.5);
        let cases: [(f64, f64, u8, f64); 2] = [
            (0.3, 1.0, LOW_END, exact_low),
            (0.0, 0.7, HIGH_END, exact_high),
        ];
        for (lo, hi, end, exact) in cases {
            let f = |_: usize, u: f64| {
                let d = if end == LOW_END { u - 0.3 } else { 0.7 - u };
                DVec3::splat(d.max(0.0).sqrt() * (1.0 + u))
            };
            let pieces = one_piece(lo, hi, 1.0);
            let mut evaluations = [0; 2];
            for (k, ends) in [end, BOTH_ENDS].into_iter().enumerate() {
                let r = integrate_adaptive_with_ends(
                    &pieces,
                    1e-10,
                    100,
                    f,
                    &|_, _, _| None,
                    |_, _, _| true,
                    |_, _, _, _| ends,
                );
                let actual = (r.value.x - exact).abs();
                assert!(r.converged && r.error.x <= 1e-10, "ends {ends}: {r:?}");
                assert!(actual <= r.error.x, "ends {ends}: {actual} > {}", r.error.x);
                evaluations[k] = r.evaluations;
            }
            assert!(evaluations[0] < evaluations[1], "{evaluations:?}");
        }
    }

    #[test]
    fn announced_kinks_and_max_segments() {
        let f = |_: usize, x: f64| DVec3::splat((x - 0.7f64).abs().sqrt());
        let pieces = one_piece(0.0, 2.0, 0.5);
        let kink = |_: usize, lo: f64, hi: f64| (lo < 0.7 && 0.7 < hi).then_some(0.7);
        let coarse = |_: usize, _: f64, _: f64| true;
        let with = integrate_adaptive(&pieces, 1e-9, 10_000, f, kink, coarse);
        let without = integrate_adaptive(&pieces, 1e-9, 10_000, f, |_, _, _| None, coarse);
        assert!(with.converged && without.converged);
        let exact = 0.5 * (2.0 / 3.0) * (0.7f64.powf(1.5) + 1.3f64.powf(1.5));
        assert!((with.value.x - exact).abs() <= with.error.x);
        assert!((without.value.x - exact).abs() <= without.error.x);
        // A square-root kink stays an endpoint singularity after the exact split, so both runs
        // bisect towards it; knowing it must not cost more than a little.
        assert!(with.evaluations <= without.evaluations + 4 * NESTED_NODES[1]);
        let capped = integrate_adaptive(&pieces, 1e-14, 3, f, |_, _, _| None, coarse);
        assert!(!capped.converged && capped.segments == 3);
        assert!((capped.value.x - exact).abs() <= capped.error.x);
    }

    #[test]
    fn the_g7_subrule_is_exact_to_degree_5_and_not_6() {
        let (x1, x3) = (XGK[1], XGK[3]);
        let rule = |p: i32| {
            WG7_SUB5[0] * 0f64.powi(p) + 2.0 * (WG7_SUB5[1] * x1.powi(p) + WG7_SUB5[2] * x3.powi(p))
        };
        for p in [0, 2, 4] {
            let exact = 2.0 / (p + 1) as f64;
            assert!((rule(p) - exact).abs() < 1e-15, "x^{p}: {}", rule(p));
        }
        assert!((rule(6) - 2.0 / 7.0).abs() > 1e-3);
        assert!(WG7_SUB5.iter().all(|&w| w > 0.0));
        // G7's weights, for comparison: exact to degree 13.
        let g7 = 2.0 * (WG[0] * x1.powi(12) + WG[1] * x3.powi(12) + WG[2] * XGK[5].powi(12));
        assert!((g7 - 2.0 / 13.0).abs() < 1e-15 * 13.0);
    }

    #[test]
    fn the_three_node_rule_is_exact_to_degree_3_and_not_4() {
        let x3 = XGK[3];
        let rule = |p: i32| R3[0] * 0f64.powi(p) + 2.0 * R3[1] * x3.powi(p);
        for p in [0, 2] {
            let exact = 2.0 / (p + 1) as f64;
            assert!((rule(p) - exact).abs() < 1e-15, "x^{p}: {}", rule(p));
        }
        assert!((rule(4) - 2.0 / 5.0).abs() > 1e-2);
        assert!(R3.iter().all(|&w| w > 0.0));
    }

    /// [`integrate_adaptive_batched`] with every piece started at `first`, one piece [lo, hi]
    /// of weight 1; the sizes of the batches asked for, in order.
    fn integrate_from(
        first: Level,
        (lo, hi): (f64, f64),
        tol: f64,
        g: impl Fn(f64) -> f64,
    ) -> (AdaptiveResult, Vec<usize>) {
        let mut batches = Vec::new();
        let r = integrate_adaptive_batched(
            &one_piece(lo, hi, 1.0),
            tol,
            10_000,
            |_, us: &[f64], out: &mut [DVec3]| {
                batches.push(us.len());
                for (u, v) in us.iter().zip(out) {
                    *v = DVec3::splat(g(*u));
                }
            },
            (&|_, _, _| None, |_, _, _| first, |_, _, _, _| 0),
        );
        (r, batches)
    }

    #[test]
    fn an_r5_start_stops_at_five_nodes_or_is_raised_to_g7_by_two_and_to_k15_by_eight() {
        // e^x on [0, 0.5]: R5 is off by ~1e-9, its estimate against R3 is ~1e-4; G7's against
        // R5 ~1e-8.
        let exact = 0.5f64.exp() - 1.0;
        let (loose, batches) = integrate_from(Level::R5, (0.0, 0.5), 1e-3, f64::exp);
        assert_eq!((loose.evaluations, batches), (5, vec![5]));
        assert!((loose.value.x - exact).abs() <= loose.error.x && loose.error.x <= 1e-3);
        // Where R5's estimate does not meet tol, two more nodes make it G7: the same value and
        // estimate, bit for bit, as a start at G7.
        let (raised, batches) = integrate_from(Level::R5, (0.0, 0.5), 1e-6, f64::exp);
        let (g7, g7_batches) = integrate_from(Level::G7, (0.0, 0.5), 1e-6, f64::exp);
        assert_eq!((raised.evaluations, batches), (7, vec![5, 2]));
        assert_eq!(g7_batches, vec![7]);
        assert_eq!((raised.value, raised.error), (g7.value, g7.error));
        // And eight more make it K15, before any split.
        let (fine, batches) = integrate_from(Level::R5, (0.0, 0.5), 1e-13, f64::exp);
        assert_eq!((fine.evaluations, fine.segments), (15, 1));
        assert_eq!(batches, vec![5, 2, 8]);
        assert!((fine.value.x - exact).abs() <= fine.error.x.max(1e-16));
        // The halves of a split start at G7, not at R5.
        let (split, batches) =
            integrate_from(Level::R5, (0.0, 1.0), 1e-9, |x| (x - 0.37).abs().powf(1.5));
        assert!(split.segments > 1);
        assert_eq!(batches[..3], [5, 2, 8]);
        assert!(
            batches[3..].iter().all(|&n| n == 7 || n == 8),
            "{batches:?}"
        );
    }

    #[test]
    fn smooth_segments_stop_at_seven_nodes_and_a_coarse_refusal_starts_at_fifteen() {
        // e^x on [0, 0.5]: G7 is exact to ~1e-20, its estimate against the 5-node rule ~1e-8.
        let pieces = one_piece(0.0, 0.5, 1.0);
        let f = |_: usize, x: f64| DVec3::splat(x.exp());
        let exact = 0.5f64.exp() - 1.0;
        let coarse = integrate_adaptive(&pieces, 1e-6, 100, f, |_, _, _| None, |_, _, _| true);
        assert_eq!(coarse.evaluations, NESTED_NODES[0]);
        assert!((coarse.value.x - exact).abs() <= coarse.error.x && coarse.error.x <= 1e-6);
        // The same at a tolerance the 7-node estimate cannot meet: raised to K15, not split.
        let fine = integrate_adaptive(&pieces, 1e-13, 100, f, |_, _, _| None, |_, _, _| true);
        assert_eq!(fine.evaluations, NESTED_NODES[1]);
        assert_eq!(fine.segments, 1);
        assert!((fine.value.x - exact).abs() <= fine.error.x.max(1e-16));
        let refused = integrate_adaptive(&pieces, 1e-6, 100, f, |_, _, _| None, |_, _, _| false);
        assert_eq!(refused.evaluations, NESTED_NODES[1]);
        // At K15 the value and estimate are the single K15 rule's.
        let k15 = gauss_kronrod_15(&mut |x| DVec3::splat(x.exp()), 0.0, 0.5);
        assert_eq!(refused.value, k15.value);
        assert_eq!(refused.error, k15.error);
    }

    #[test]
    fn the_estimate_covers_the_error_on_peaks_and_kinks_at_every_tolerance() {
        // Integrands with a sharp peak, an unannounced kink and an oscillation, against closed
        // forms: the summed estimate must cover the actual error whenever it claims convergence.
        let cases: [(&dyn Fn(f64) -> f64, f64); 3] = [
            (&|x: f64| 1.0 / (1e-3 + (x - 0.31).powi(2)), {
                let a = 1e-3f64.sqrt();
                ((1.0 - 0.31) / a).atan() / a - ((0.0 - 0.31) / a).atan() / a
            }),
            (
                &|x: f64| (x - 0.37).abs().powf(1.5),
                (0.37f64.powf(2.5) + 0.63f64.powf(2.5)) / 2.5,
            ),
            (&|x: f64| (40.0 * x).sin(), (1.0 - 40f64.cos()) / 40.0),
        ];
        for (i, (g, exact)) in cases.iter().enumerate() {
            for tol in [1e-3, 1e-6, 1e-9] {
                let plain = integrate_plain(0.0, 1.0, tol, g);
                // Started at R5 (as the volume renderer starts pieces of small weight).
                let (from_r5, _) = integrate_from(Level::R5, (0.0, 1.0), tol, g);
                for (r, start) in [(plain, "G7"), (from_r5, "R5")] {
                    assert!(r.converged, "case {i} tol {tol} from {start}");
                    let actual = (r.value.x - exact).abs();
                    assert!(
                        actual <= r.error.x,
                        "case {i} tol {tol} from {start}: actual {actual:e} > estimate {:e}",
                        r.error.x
                    );
                }
            }
        }
    }
}

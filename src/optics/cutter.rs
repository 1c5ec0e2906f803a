//! The interval cut of `optics::intervals` with less work: what the renderers call.
//!
//! [`IntervalCutter::cut`] gives the intervals of the plain event sweep
//! ([`cut_by_events`](super::intervals::cut_by_events)) bit for bit (a test below compares
//! them), in two ways:
//!
//! * chords that do not overlap (most shadow rays) give one interval each, with the same
//!   operations [`medium_of`] does on a one-particle set ([`disjoint_interval`]);
//! * otherwise a sweep over the chord ends that needs no sorted list of events: the next event
//!   is the earlier of the next start and the earliest end among the open chords, and the open
//!   set stays in canonical rank order by insertion ([`sweep_open`]).
//!
//! [`IntervalCutter::composite`] composites the emission model along the chords while they
//! are swept ([`FrontToBack`]), without building the intervals: a shadow ray needs only its
//! radiance and transmittance.

// `!(a > b)` is deliberate throughout: unlike `a <= b` it is also true when a value is NaN, so
// degenerate input takes the safe branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::emission::FrontToBack;
use super::intervals::{canonical_ranks, clipped_chords, medium_of, Interval};
use super::particle::Particle;
use crate::geometry::Hit;
use glam::DVec3;

/// The particles of a scene with their canonical ranks: cuts rays into intervals.
#[derive(Debug, Clone)]
pub struct IntervalCutter<'a> {
    particles: &'a [Particle],
    ranks: Vec<u32>,
}

/// Reusable buffers of [`IntervalCutter::cut`] and [`IntervalCutter::composite`], so that
/// shadow rays do not allocate.
#[derive(Debug, Default, Clone)]
pub struct SweepScratch {
    /// The clipped chords of the ray, sorted by start.
    chords: Vec<Hit>,
    /// The chords of the sweep, in start order, with what their sums need.
    swept: Vec<SweptChord>,
    /// The open chords of the sweep: positions in `swept`, in canonical rank order.
    open: Vec<u32>,
}

/// One chord of [`sweep_open`], with what the sums of its interval need.
#[derive(Debug, Clone, Copy)]
struct SweptChord {
    exit: f64,
    rank: u32,
    index: u32,
    sigma: f64,
    /// σᵢ·Cᵢ.
    weighted: DVec3,
}

impl<'a> IntervalCutter<'a> {
    /// Ranks the particles once (O(n log n)); cutting a ray is then O(k log k) in the k spheres
    /// it crosses.
    pub fn new(particles: &'a [Particle]) -> Self {
        IntervalCutter {
            particles,
            ranks: canonical_ranks(particles),
        }
    }

    /// The particles, in input order.
    pub fn particles(&self) -> &'a [Particle] {
        self.particles
    }

    /// The canonical rank of every particle, by index ([`canonical_ranks`]).
    pub fn ranks(&self) -> &[u32] {
        &self.ranks
    }

    /// Cuts the part (t_min, t_max) of a ray into intervals (docs/design.md §3), given every
    /// sphere the ray crosses (`hits`, in any order). Particles with σ = 0 and those for which
    /// `skip` returns true are left out. `out` is cleared first and receives the intervals in
    /// ray order; gaps without particles produce no interval.
    pub fn cut(
        &self,
        hits: &[Hit],
        t_min: f64,
        t_max: f64,
        skip: impl Fn(u32) -> bool,
        scratch: &mut SweepScratch,
        out: &mut Vec<Interval>,
    ) {
        out.clear();
        let particles = self.particles;
        if self.sorted_chords(hits, (t_min, t_max), skip, scratch) {
            for h in &scratch.chords {
                out.push(disjoint_interval(h, &particles[h.index as usize]));
            }
        } else {
            sweep_open(scratch, particles, &self.ranks, |swept, set, t0, t1| {
                let set = set.iter().map(|&j| swept[j as usize].index);
                out.push(medium_of(set, particles, t0, t1));
                true
            });
        }
    }

    /// The emission model (docs/design.md §2) along the part (t_min, t_max) of a ray crossing
    /// the spheres `hits` (any order), added to `acc` front to back as the chords are swept,
    /// without building the intervals: per interval only σ = Σσᵢ and S = Σσᵢ·Cᵢ (summed in
    /// canonical order, as [`medium_of`]) are formed, and `acc` adds T·(1 − e^{−σΔ})·S/σ. It
    /// stops where `acc` says nothing more is to be added. Intervals with σ = ∞ or an
    /// overflowing Σσᵢ go in whole ([`FrontToBack::add_interval`]).
    pub fn composite(
        &self,
        hits: &[Hit],
        range: (f64, f64),
        skip: impl Fn(u32) -> bool,
        scratch: &mut SweepScratch,
        mut acc: FrontToBack,
    ) -> FrontToBack {
        let particles = self.particles;
        if self.sorted_chords(hits, range, skip, scratch) {
            for h in &scratch.chords {
                let p = &particles[h.index as usize];
                let more = if p.sigma.is_infinite() {
                    acc.add_interval(disjoint_interval(h, p))
                } else {
                    acc.add(p.sigma, p.sigma * p.color, h.chord.t_exit - h.chord.t_enter)
                };
                if !more {
                    break;
                }
            }
        } else {
            sweep_open(scratch, particles, &self.ranks, |swept, set, t0, t1| {
                let mut sigma = 0.0;
                let mut weighted = DVec3::ZERO;
                for &j in set {
                    let c = &swept[j as usize];
                    sigma += c.sigma;
                    weighted += c.weighted;
                }
                if sigma.is_finite() {
                    acc.add(sigma, weighted, t1 - t0)
                } else {
                    // A Θmax = 1 particle (σ = ∞, and then `weighted` is NaN or ∞) or Σσᵢ
                    // overflowing: the general medium.
                    let set = set.iter().map(|&j| swept[j as usize].index);
                    acc.add_interval(medium_of(set, particles, t0, t1))
                }
            });
        }
        acc
    }

    /// The chords of `hits` clipped to `range` ([`clipped_chords`]), sorted by start into
    /// `scratch.chords`; whether no two of them overlap.
    fn sorted_chords(
        &self,
        hits: &[Hit],
        range: (f64, f64),
        skip: impl Fn(u32) -> bool,
        scratch: &mut SweepScratch,
    ) -> bool {
        let chords = &mut scratch.chords;
        chords.clear();
        chords.extend(clipped_chords(hits, range, self.particles, skip));
        chords.sort_unstable_by(|a, b| a.chord.t_enter.total_cmp(&b.chord.t_enter));
        chords
            .windows(2)
            .all(|w| w[0].chord.t_exit <= w[1].chord.t_enter)
    }
}

/// The sweep over the ends of `scratch.chords` (sorted by start), taking the next event as the
/// earlier of the next start and the earliest end among the open chords. All ends and starts at
/// one t are applied before the interval from t is formed and handed to `emit` (which returns
/// false to stop) with the table of chords and the open ones, as positions in it, in canonical
/// rank order: a chord is inserted at its place when it opens, and leaving keeps the order, so
/// no interval sorts. So the intervals are those of the plain event sweep bit for bit, and
/// shuffling the particles changes none of them.
///
/// The chords' data are written to the table once, before the sweep, and the open set moves
/// only their positions, so the sums read data stored long before (moving whole records
/// through a sorted open list made the shadow rays' speed depend on how the compiler laid out
/// those moves).
fn sweep_open(
    scratch: &mut SweepScratch,
    particles: &[Particle],
    ranks: &[u32],
    mut emit: impl FnMut(&[SweptChord], &[u32], f64, f64) -> bool,
) {
    let SweepScratch {
        chords,
        swept,
        open,
    } = scratch;
    let chords = &chords[..];
    swept.clear();
    open.clear();
    for h in chords {
        let p = &particles[h.index as usize];
        swept.push(SweptChord {
            exit: h.chord.t_exit,
            rank: ranks[h.index as usize],
            index: h.index,
            sigma: p.sigma,
            weighted: p.sigma * p.color,
        });
    }
    let swept = &swept[..];
    let Some(first) = chords.first() else {
        return;
    };
    let key = |j: u32| {
        let c = &swept[j as usize];
        (c.rank, c.index)
    };
    let mut t = first.chord.t_enter;
    let mut next = 0;
    loop {
        open.retain(|&j| swept[j as usize].exit != t);
        while next < chords.len() && chords[next].chord.t_enter == t {
            let j = next as u32;
            let index = swept[next].index;
            // A particle entered twice cannot happen on a ray; ignoring it keeps the sweep total.
            if !open.iter().any(|&o| swept[o as usize].index == index) {
                // Insertion at its place in rank order.
                open.push(j);
                let mut k = open.len() - 1;
                while k > 0 && key(open[k - 1]) > key(j) {
                    open[k] = open[k - 1];
                    k -= 1;
                }
                open[k] = j;
            }
            next += 1;
        }
        // The earliest remaining event, by the same total order as the sorted starts.
        let mut t_next = chords.get(next).map_or(f64::INFINITY, |h| h.chord.t_enter);
        for &j in open.iter() {
            let exit = swept[j as usize].exit;
            if exit.total_cmp(&t_next).is_lt() {
                t_next = exit;
            }
        }
        if open.is_empty() {
            if next >= chords.len() {
                return;
            }
        } else if !emit(swept, open, t, t_next) {
            return;
        }
        t = t_next;
    }
}

/// The interval of one clipped chord crossed by particle `p` alone. The event sweep would give
/// exactly this where no chords overlap (where one chord ends as the next starts, both events
/// share one t and the interval that follows holds the next particle alone), and σ, E and α are
/// computed with the same operations as [`medium_of`] on a one-particle set (0 + σᵢ,
/// (0 + σᵢ·Cᵢ)/σ, a colour divided by 1 for σ = ∞), so it is bit-identical to the sweep's.
fn disjoint_interval(h: &Hit, p: &Particle) -> Interval {
    let (t0, t1) = (h.chord.t_enter, h.chord.t_exit);
    if p.sigma.is_infinite() {
        Interval {
            t0,
            t1,
            sigma: f64::INFINITY,
            emission: (DVec3::ZERO + p.color) / 1.0,
            albedo: (DVec3::ZERO + p.albedo) / 1.0,
        }
    } else {
        let sigma = 0.0 + p.sigma;
        Interval {
            t0,
            t1,
            sigma,
            emission: (DVec3::ZERO + p.sigma * p.color) / sigma,
            albedo: (DVec3::ZERO + p.sigma * p.albedo) / sigma,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::geometry::Chord;
    use crate::optics::intervals::cut_by_events;

    pub(crate) fn particle(sigma: f64, color: DVec3) -> Particle {
        Particle {
            ellipsoid: None,
            profile: crate::optics::Profile::Constant,
            center: DVec3::ZERO,
            radius: 1.0,
            color,
            sigma,
            albedo: color,
            ks: 0.0,
            shininess: 0.0,
        }
    }

    /// `n` particles with colours in [0, `scale`)³ and σ in [lo, lo + span).
    pub(crate) fn random_particles(
        rng: &mut crate::formats::random::SplitMix64,
        n: usize,
        scale: f64,
        (lo, span): (f64, f64),
    ) -> Vec<Particle> {
        (0..n)
            .map(|_| {
                let c = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * scale;
                particle(lo + span * rng.next_f64(), c)
            })
            .collect()
    }

    pub(crate) fn hit(index: u32, t_enter: f64, t_exit: f64) -> Hit {
        Hit {
            index,
            chord: Chord { t_enter, t_exit },
        }
    }

    /// Both paths of the cut give the plain event sweep's intervals bit for bit: the disjoint one
    /// (chords that touch end to start, σ = ∞, colours that σ·C/σ does not reproduce exactly)
    /// and the sweep (chords that overlap by a hair or heavily, with coinciding ends). The
    /// composite along the same chords is `emission::composite` of those intervals to the last
    /// bits, and within its bound where it stops at ε.
    #[test]
    fn the_cut_gives_the_event_sweeps_intervals_bit_for_bit() {
        let mut rng = crate::formats::random::SplitMix64::new(11);
        let mut ps = random_particles(&mut rng, 50, 3.0, (0.1, 7.0));
        ps[3].sigma = f64::INFINITY;
        let cutter = IntervalCutter::new(&ps);
        let bits = |v: &[Interval]| -> Vec<[u64; 9]> {
            v.iter()
                .map(|iv| {
                    let (e, a) = (iv.emission, iv.albedo);
                    [iv.t0, iv.t1, iv.sigma, e.x, e.y, e.z, a.x, a.y, a.z].map(f64::to_bits)
                })
                .collect()
        };
        let mut fast = Vec::new();
        let mut s = SweepScratch::default();
        let mut depths = Vec::new();
        let (mut fallbacks, mut opaque, mut cuts) = (0, 0, 0);
        for trial in 0..1000 {
            let n = 1 + trial % 7;
            let mut t = -1.0 + rng.next_f64();
            let mut hits = Vec::new();
            for k in 0..n {
                let index = ((trial * 7 + k * 13) % ps.len()) as u32;
                if trial % 2 == 1 {
                    // Heavy overlap, with starts and ends that coincide (a grid of quarters,
                    // clipped at 0 and 4) and ones that do not.
                    let end = |rng: &mut crate::formats::random::SplitMix64| {
                        let x = -0.5 + 5.0 * rng.next_f64();
                        if rng.next_f64() < 0.5 {
                            (x * 4.0).round() / 4.0
                        } else {
                            x
                        }
                    };
                    let (a, b) = (end(&mut rng), end(&mut rng));
                    hits.push(hit(index, a.min(b), a.max(b) + 0.01));
                    continue;
                }
                let t1 = t + 0.01 + rng.next_f64();
                hits.push(hit(index, t, t1));
                // Touching (next starts where this ends), a gap, or (rarely) an overlap.
                t = match rng.next_f64() {
                    x if x < 0.3 => t1,
                    x if x < 0.95 => t1 + rng.next_f64(),
                    _ => t1 - 1e-12,
                };
            }
            hits.reverse();
            let mut seen: Vec<u32> = hits.iter().map(|h| h.index).collect();
            seen.sort_unstable();
            seen.dedup();
            if seen.len() < hits.len() {
                continue; // one particle crossed twice cannot happen on a ray
            }
            cutter.cut(&hits, 0.0, 4.0, |_| false, &mut s, &mut fast);
            let chords: Vec<Hit> = clipped_chords(&hits, (0.0, 4.0), &ps, |_| false).collect();
            let swept = cut_by_events(&chords, &ps, cutter.ranks());
            assert_eq!(bits(&fast), bits(&swept), "trial {trial}: {hits:?}");
            if !s
                .chords
                .windows(2)
                .all(|w| w[0].chord.t_exit <= w[1].chord.t_enter)
            {
                fallbacks += 1;
            }
            // The composite along the chords is `composite` of these intervals, to the last
            // bits (it divides by σ once instead of forming E = S/σ, and takes e^{−τ} = 1 − a).
            let background = DVec3::new(0.3, 2.0, 7.0);
            let want = crate::optics::emission::composite(&swept, background);
            let composite = |cut: Option<(f64, DVec3)>, s: &mut SweepScratch| {
                cutter
                    .composite(&hits, (0.0, 4.0), |_| false, s, FrontToBack::new(cut))
                    .finish(background, cut)
            };
            let (got, was_cut) = composite(None, &mut s);
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-13 * (1.0 + a.abs());
            // The transmittance alone, summed per particle (single-scatter's shadow rays), is
            // the composite's up to rounding, and exactly 0 where it is.
            let alone = crate::optics::transmittance::transmittance(
                &cutter,
                &hits,
                (0.0, 4.0),
                |_| false,
                &mut depths,
            );
            assert!(
                close(alone, want.transmittance) && (alone == 0.0) == (want.transmittance == 0.0),
                "trial {trial}: {alone} against {want:?}"
            );
            assert!(
                !was_cut
                    && close(got.transmittance, want.transmittance)
                    && (0..3).all(|c| close(got.radiance[c], want.radiance[c])),
                "trial {trial}: {got:?} against {want:?}"
            );
            // Cut where T falls to ε: within half the range of what was left out, T·M/2 for
            // the radiance (M bounds the background and every colour) and T/2 for the
            // transmittance, T the transmittance where it stopped.
            let bound = ps.iter().fold(background, |m, p| m.max(p.color));
            for epsilon in [0.5, 0.05, 1e-3] {
                let (c, was_cut) = composite(Some((epsilon, bound)), &mut s);
                if !was_cut {
                    // Never fell to ε, or fell straight to an exact 0: nothing was left out.
                    assert_eq!(c, got, "trial {trial}");
                    continue;
                }
                cuts += 1;
                let t_stop = 2.0 * c.transmittance;
                assert!(
                    t_stop > 0.0 && t_stop <= epsilon,
                    "trial {trial}: T {t_stop}"
                );
                let slack = 1e-12 * (1.0 + want.radiance.max_element());
                assert!(
                    (c.transmittance - want.transmittance).abs() <= 0.5 * t_stop + 1e-15,
                    "trial {trial}: {c:?} against {want:?}"
                );
                for ch in 0..3 {
                    assert!(
                        (c.radiance[ch] - want.radiance[ch]).abs()
                            <= 0.5 * t_stop * bound[ch] + slack,
                        "trial {trial}, ε {epsilon}: {c:?} against {want:?}"
                    );
                }
            }
            opaque += usize::from(want.transmittance == 0.0);
        }
        assert!(fallbacks > 150, "many trials must overlap: {fallbacks}");
        assert!(cuts > 300, "many trials must be cut: {cuts}");
        assert!(
            opaque > 50,
            "many trials must cross the σ = ∞ particle: {opaque}"
        );
    }
}

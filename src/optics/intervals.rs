//! Cutting a ray into intervals with a constant set of particles (docs/design.md §3 "intervals").
//!
//! Every sphere entry and exit on the ray is a cut. Inside one interval the set of particles is
//! fixed, so σ = Σσᵢ and the emission colour E = Σσᵢ·Cᵢ / Σσᵢ (docs/design.md §2, emission model) and
//! the σ-weighted albedo α = Σσᵢ·αᵢ / Σσᵢ (single-scatter) are constants.
//!
//! **Order independence.** Floating-point sums depend on their order, and the renderer promises
//! that shuffling the particle list changes no pixel. The sums therefore run over the active set
//! sorted by a *canonical rank*: the position of the particle in a total order of its content
//! (σ, radius, centre, colour, albedo), which does not depend on where it sits in the input.
//! Particles with equal content are interchangeable, so ties cannot change a sum either.
//!
//! **Θmax = 0 and Θmax = 1.** Particles with σ = 0 are invisible and skipped. Where a particle
//! with σ = +∞ is active the interval has σ = +∞; its colour and albedo are the plain mean over
//! the infinite particles present (the limit of equal, growing σ), never ∞/∞.

// `!(a > b)` is deliberate throughout: unlike `a <= b` it is also true when a value is NaN, so
// degenerate input takes the safe branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::emission::{opacity_and_transmittance, Composite};
use super::particle::Particle;
use crate::geometry::Hit;
use glam::DVec3;
use std::cmp::Ordering;

/// A piece [t0, t1] of a ray with a fixed set of particles: what the models of docs/design.md §2 need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Ray parameter where the interval starts (m).
    pub t0: f64,
    /// Ray parameter where the interval ends (m), > t0.
    pub t1: f64,
    /// Extinction σ = Σσᵢ (1/m), > 0; +∞ where a Θmax = 1 particle is active.
    pub sigma: f64,
    /// Emission colour E = Σσᵢ·Cᵢ / Σσᵢ (linear RGB).
    pub emission: DVec3,
    /// Single-scatter albedo α = Σσᵢ·αᵢ / Σσᵢ.
    pub albedo: DVec3,
}

impl Interval {
    /// Length Δ = t1 − t0 (m).
    #[inline]
    pub fn length(&self) -> f64 {
        self.t1 - self.t0
    }
}

/// The canonical rank of every particle (index → rank): the position of the particle in a total
/// order of its content, so that sums over a set of particles can run in an order that the input
/// order does not influence.
pub fn canonical_ranks(particles: &[Particle]) -> Vec<u32> {
    let key = |p: &Particle| {
        [
            p.sigma, p.radius, p.center.x, p.center.y, p.center.z, p.color.x, p.color.y, p.color.z,
            p.albedo.x, p.albedo.y, p.albedo.z,
        ]
    };
    let mut order: Vec<u32> = (0..particles.len() as u32).collect();
    // Sequential: rayon's parallel merge sort was slower than this on two busy cores (it makes
    // more calls of the heavy comparison).
    order.sort_by(|&a, &b| {
        let (ka, kb) = (key(&particles[a as usize]), key(&particles[b as usize]));
        ka.iter()
            .zip(&kb)
            .map(|(x, y)| x.total_cmp(y))
            .find(|o| *o != Ordering::Equal)
            .unwrap_or(Ordering::Equal)
    });
    let mut rank = vec![0u32; particles.len()];
    for (r, &i) in order.iter().enumerate() {
        rank[i as usize] = r as u32;
    }
    rank
}

/// A chord end on the ray: where particle `index` (of canonical rank `rank`) enters or leaves.
#[cfg(test)]
#[derive(Debug, Clone, Copy)]
struct Event {
    t: f64,
    rank: u32,
    index: u32,
    enter: bool,
}

/// A chord clipped to the cut's range: particle `index` is present on (t0, t1), t0 < t1.
#[derive(Debug, Clone, Copy)]
struct Span {
    t0: f64,
    t1: f64,
    index: u32,
}

/// Reusable buffers of [`IntervalCutter::cut`] and [`IntervalCutter::composite`], so that
/// shadow rays do not allocate; they also keep the [`Layout`] of the last composite.
#[derive(Debug, Default, Clone)]
pub struct IntervalScratch {
    spans: Vec<Span>,
    /// The chords of the sweep, in start order, with what their sums need.
    chords: Vec<Open>,
    /// The open chords of the sweep: positions in `chords`, in canonical rank order.
    open: Vec<u32>,
    /// The particles of the current composite's clipped chords, in the order of its hits.
    members: Vec<u32>,
    /// Their clipped ends: `ends[2m]` where member m starts, `ends[2m + 1]` where it ends.
    ends: Vec<f64>,
    /// The layouts of recent composites, the most recently used first ([`LAYOUTS`] at most).
    layouts: Vec<Layout>,
    layout_work: LayoutWork,
}

/// How many [`Layout`]s an [`IntervalScratch`] keeps. The quadrature evaluates a segment's
/// nodes in order along it, so the most recent layout is the one that holds for 70 % of the
/// shadow rays on 1UUN lit 128², and an older one for about 1 % (mostly the Kronrod nodes of a
/// segment raised later, between the nodes that made its layouts; counted before layouts were
/// reordered in place).
const LAYOUTS: usize = 4;

/// The most chords a [`Layout`] holds: its open set is a 64-bit mask.
const LAYOUT_CHORDS: usize = 64;

/// How far from an interval's own place [`Layout::form_intervals`] looks for its open set
/// among the intervals before a reorder (two ends that cross shift the intervals behind them
/// by at most one).
const BEFORE_REACH: usize = 2;

impl IntervalScratch {
    /// Forgets the kept [`Layout`]: for buffers that move on to another scene (the layout is
    /// keyed by particle indices, which mean other particles there).
    pub fn forget(&mut self) {
        for layout in &mut self.layouts {
            layout.valid = false;
        }
    }
}

/// The particles of a scene with their canonical ranks: cuts rays into intervals.
#[derive(Debug, Clone)]
pub struct IntervalCutter<'a> {
    particles: &'a [Particle],
    ranks: Vec<u32>,
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

    /// Cuts the part (t_min, t_max) of a ray into intervals (docs/design.md §3), given every sphere
    /// the ray crosses (`hits`, in any order). Particles with σ = 0 and those for which `skip`
    /// returns true are left out. `out` is cleared first and receives the intervals in ray
    /// order; gaps without particles produce no interval.
    pub fn cut(
        &self,
        hits: &[Hit],
        t_min: f64,
        t_max: f64,
        skip: impl Fn(u32) -> bool,
        scratch: &mut IntervalScratch,
        out: &mut Vec<Interval>,
    ) {
        cut_into_intervals(
            hits,
            (t_min, t_max),
            self.particles,
            &self.ranks,
            skip,
            scratch,
            out,
        )
    }

    /// The emission model (docs/design.md §2) along the part (t_min, t_max) of a ray crossing the
    /// spheres `hits` (any order), towards `background`: what [`composite`] gives on the
    /// intervals of [`IntervalCutter::cut`], without building them (shadow rays only need the
    /// result). Same sums in the same canonical order; the last bits may differ from
    /// [`composite`], which divides E = S/σ first.
    ///
    /// With `cut = Some((ε, M))` the sweep stops once the transmittance T has fallen to ε or
    /// below (after the interval that took it there) and the rest of the ray is replaced by the
    /// middle of its range: what lies behind contributes T·L_rest with 0 ≤ L_rest ≤ M per
    /// channel (M ≥ `background` and every colour behind, a caller's bound), so the radiance
    /// becomes F + T·M/2 and the transmittance T/2, each off by at most half its range
    /// (T·M/2 and T/2, both ≤ ε·(M, 1)/2). The flag says whether that happened; an exactly
    /// opaque stop (T = 0) is exact and is not a cut.
    ///
    /// [`composite`]: super::emission::composite
    pub fn composite(
        &self,
        hits: &[Hit],
        (t_min, t_max): (f64, f64),
        skip: impl Fn(u32) -> bool,
        background: DVec3,
        cut: Option<(f64, DVec3)>,
        scratch: &mut IntervalScratch,
    ) -> (Composite, bool) {
        composite_spans(
            hits,
            (t_min, t_max),
            self.particles,
            &self.ranks,
            skip,
            (background, cut),
            scratch,
        )
    }
}

/// `IntervalCutter::cut`: the chords clipped to (t_min, t_max), then the general sweep over
/// their ends ([`sweep_open`]). Most shadow rays cross a few spheres whose chords do not
/// overlap; those take [`disjoint_intervals`] instead, which gives the same intervals, bit for
/// bit, without the sweep (a test compares the two).
fn cut_into_intervals(
    hits: &[Hit],
    range: (f64, f64),
    particles: &[Particle],
    ranks: &[u32],
    skip: impl Fn(u32) -> bool,
    scratch: &mut IntervalScratch,
    out: &mut Vec<Interval>,
) {
    out.clear();
    if clipped_spans(hits, range, particles, skip, &mut scratch.spans) {
        disjoint_intervals(&scratch.spans, particles, out);
    } else {
        sweep_open(scratch, particles, ranks, |chords, set, t0, t1| {
            let set = set.iter().map(|&j| chords[j as usize].index);
            out.push(medium_of(set, particles, t0, t1));
            true
        });
    }
}

/// The chords of `hits` clipped to (t_min, t_max), of particles with σ > 0 not skipped, as
/// (index, t0, t1) with t0 < t1, in the order of `hits`.
fn clipped_chords<'a>(
    hits: &'a [Hit],
    (t_min, t_max): (f64, f64),
    particles: &'a [Particle],
    skip: impl Fn(u32) -> bool + 'a,
) -> impl Iterator<Item = (u32, f64, f64)> + 'a {
    hits.iter().filter_map(move |h| {
        let p = &particles[h.index as usize];
        if !(p.sigma > 0.0) || skip(h.index) {
            return None;
        }
        let t0 = h.chord.t_enter.max(t_min);
        let t1 = h.chord.t_exit.min(t_max);
        (t1 > t0).then_some((h.index, t0, t1))
    })
}

/// The chords of `hits` clipped to (t_min, t_max), of particles with σ > 0 not skipped, sorted
/// by start into `spans`; whether no two of them overlap.
fn clipped_spans(
    hits: &[Hit],
    (t_min, t_max): (f64, f64),
    particles: &[Particle],
    skip: impl Fn(u32) -> bool,
    spans: &mut Vec<Span>,
) -> bool {
    spans.clear();
    spans.extend(
        clipped_chords(hits, (t_min, t_max), particles, skip).map(|(index, t0, t1)| Span {
            t0,
            t1,
            index,
        }),
    );
    spans.sort_unstable_by(|a, b| a.t0.total_cmp(&b.t0));
    spans.windows(2).all(|w| w[0].t1 <= w[1].t0)
}

/// `IntervalCutter::composite`: the emission model (docs/design.md §2) along the chords of `hits`
/// in (t_min, t_max), with no intervals built. Per interval it needs only σ = Σσᵢ and
/// E = S·(1/σ), S = Σσᵢ·Cᵢ (summed in canonical order, as [`medium_of`]), and adds
/// T·(1 − e^{−σΔ})·E as [`composite`](super::emission::composite) does without forming the
/// albedo (consecutive intervals of the same E as one, `Accumulator::add_emission`). The
/// order of the chord ends, and with it every interval's particles, σ and E, is kept between
/// calls as a [`Layout`]; a shadow ray whose ends come in the same order (mostly the next node
/// of the same quadrature segment: 71 % of the shadow rays on 1UUN lit) only checks that order
/// and takes each interval's length from its own ends. More than 64 chords,
/// or a set with a Θmax = 1 particle or an overflowing Σσᵢ, take [`composite_by_sweep`].
fn composite_spans(
    hits: &[Hit],
    (t_min, t_max): (f64, f64),
    particles: &[Particle],
    ranks: &[u32],
    skip: impl Fn(u32) -> bool,
    (background, cut): (DVec3, Option<(f64, DVec3)>),
    scratch: &mut IntervalScratch,
) -> (Composite, bool) {
    let mut acc = Accumulator::new(cut);
    let IntervalScratch {
        members,
        ends,
        layouts,
        layout_work,
        ..
    } = &mut *scratch;
    members.clear();
    ends.clear();
    for (index, t0, t1) in clipped_chords(hits, (t_min, t_max), particles, &skip) {
        members.push(index);
        ends.extend([t0, t1]);
    }
    if members.len() > LAYOUT_CHORDS {
        // More chords than a layout's mask holds (77 % of the shadow rays in a million random
        // spheres): the sweep, with no layout to compare or keep.
        let acc = composite_by_sweep(hits, (t_min, t_max), particles, ranks, &skip, scratch, acc);
        return finish(acc, background, cut);
    }
    match layouts
        .iter()
        .position(|l| l.fits(particles, members, ends))
    {
        Some(0) => {}
        Some(i) => layouts[..=i].rotate_right(1),
        None => match layouts
            .iter()
            .position(|l| l.same_members(particles, members))
        {
            // The same chords in another order: its order is nearly this one.
            Some(i) => {
                layouts[..=i].rotate_right(1);
                layouts[0].reorder(ends, layout_work);
            }
            None => {
                if layouts.len() < LAYOUTS {
                    layouts.push(Layout::default());
                }
                layouts.rotate_right(1);
                let (new, kept) = layouts.split_at_mut(1);
                let near = kept.first().is_some_and(|neighbour| {
                    new[0].build_near(neighbour, particles, ranks, (members, ends))
                });
                if !near {
                    new[0].build(particles, ranks, (members, ends), layout_work);
                }
                #[cfg(test)]
                {
                    layout_work.nears += usize::from(near);
                }
            }
        },
    }
    let layout = &layouts[0];
    if layout.general {
        acc = composite_by_sweep(hits, (t_min, t_max), particles, ranks, &skip, scratch, acc);
    } else {
        for iv in &layout.intervals {
            let length = ends[iv.to as usize] - ends[iv.from as usize];
            if !acc.add_emission(iv.sigma, iv.emission, length) {
                break;
            }
        }
    }
    finish(acc, background, cut)
}

/// The end of [`composite_spans`]: the background behind what was composited, or, where the
/// composite stopped with something still visible behind, the middle of what the rest could
/// add (also where the stop came at the last interval: conservative, and within the same
/// bound); whether it stopped so.
fn finish(mut acc: Accumulator, background: DVec3, cut: Option<(f64, DVec3)>) -> (Composite, bool) {
    acc.flush();
    let t = acc.transmittance;
    match cut {
        Some((epsilon, bound)) if t > 0.0 && t <= epsilon => (
            Composite {
                radiance: acc.radiance + t * (0.5 * bound),
                transmittance: 0.5 * t,
            },
            true,
        ),
        _ => (
            Composite {
                radiance: acc.radiance + t * background,
                transmittance: t,
            },
            false,
        ),
    }
}

/// The composite of [`composite_spans`] by the sweep over the chord ends itself
/// ([`sweep_open`], or in order where no two chords overlap), for any σ: the general path, and
/// the oracle of [`Layout`] in the tests.
fn composite_by_sweep(
    hits: &[Hit],
    range: (f64, f64),
    particles: &[Particle],
    ranks: &[u32],
    skip: impl Fn(u32) -> bool,
    scratch: &mut IntervalScratch,
    mut acc: Accumulator,
) -> Accumulator {
    if clipped_spans(hits, range, particles, skip, &mut scratch.spans) {
        for s in &scratch.spans {
            let p = &particles[s.index as usize];
            let more = if p.sigma.is_infinite() {
                acc.add_interval(disjoint_interval(s, p))
            } else {
                acc.add(p.sigma, p.sigma * p.color, s.t1 - s.t0)
            };
            if !more {
                break;
            }
        }
        acc
    } else {
        composite_overlapping(particles, ranks, scratch, acc)
    }
}

/// The order of the chord ends of a shadow ray and the intervals it makes, kept by
/// [`composite_spans`] for the next shadow ray.
///
/// Shadow rays from the nodes of one quadrature segment cross the same spheres (segments end
/// where a shadow ray grazes one, `optics::kinks`), and their chord ends mostly come in the
/// same order. The sweep over those ends ([`sweep_open`]: the open set, its canonical order,
/// the sums σ = Σσᵢ and S = Σσᵢ·Cᵢ) depends on nothing but that order, so it is done once and
/// the next ray only checks that its ends are in it. On 1UUN lit (128², issue 10) the sweep
/// took about 45 % of the render's time; 71 % of the shadow rays now find a kept layout, 17 %
/// find one of the same chords in another order (two ends crossed between nodes), and 12 %
/// start a new one (mostly the first node of a segment). A layout of the same chords is
/// reordered in place ([`Layout::reorder`]); where just two neighbouring ends crossed (three
/// in four such rays) only the intervals about them change ([`Layout::swap_neighbours`]). A
/// new layout whose chords are the last one's with one more or one fewer (three in four) is
/// made from it without sorting ([`Layout::build_near`]). A new layout costs more than one
/// sweep, so the render takes about a quarter fewer instructions (callgrind), not 45 %.
///
/// Most of what a new or reordered layout cost was forming all its intervals again, where
/// only those about a few ends change. So a layout from a neighbour whose ends keep their
/// order puts the new chord's ends in (or takes the old one's out) and forms only the
/// intervals about them ([`Layout::splice`]: 86 % of the layouts from a neighbour on 1UUN lit
/// 64²), and a reorder whose ends moved within one stretch of the order forms only the
/// intervals about that stretch ([`Layout::reform_between`]: 85 % of the reorders that are
/// not one swap). The other intervals keep their sums. Together: 7.4 % fewer instructions
/// for the whole render (callgrind, 64², one thread: 2.459 G → 2.276 G, the same bytes).
///
/// **Same bits.** A layout holds for a ray with the same members (particle indices, in the
/// order of its hits) whose ends, taken in the layout's `order`, are equal (`==`) within each
/// group and strictly increasing from group to group: then the sweep would open and close the
/// same chords at the same events and form the same intervals with the same sums, and each
/// interval's length is the difference of the same two end values (the sweep's t is the
/// first of its group in `f64::total_cmp` order, as here). A test compares the bits with
/// [`composite_by_sweep`] on reused and fresh layouts.
#[derive(Debug, Default, Clone)]
struct Layout {
    /// Whether the layout was built (and not forgotten).
    valid: bool,
    /// The particle slice it was built for (address and length): a guard against reuse with
    /// another scene's particles that `IntervalScratch::forget` did not catch.
    scene: (usize, usize),
    members: Vec<u32>,
    /// Positions in the ends (2m: start of member m, 2m + 1: its end), sorted by value.
    order: Vec<u32>,
    /// `new_group[k]`: whether `order[k]` starts a new group (a larger value than `order[k − 1]`).
    new_group: Vec<bool>,
    intervals: Vec<LayoutInterval>,
    /// The mask bit of each member, and σᵢ, σᵢ·Cᵢ of the members in canonical order.
    bit: Vec<u64>,
    terms: Vec<(f64, DVec3)>,
    /// Some interval's Σσᵢ is not finite (a Θmax = 1 particle, or an overflow): the general
    /// sweep instead of the intervals.
    general: bool,
}

#[cfg(test)]
thread_local! {
    /// Layouts made by [`Layout::splice`] on this thread (read by a test).
    static SPLICES: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Buffers of [`Layout::build`] and [`Layout::reorder`].
#[derive(Debug, Default, Clone)]
struct LayoutWork {
    /// (canonical key: rank, then index; member position), sorted.
    by_key: Vec<(u64, u32)>,
    /// (end value, end position), sorted.
    sorted: Vec<(f64, u32)>,
    /// The intervals of a layout before [`Layout::reorder`].
    before: Vec<LayoutInterval>,
    /// Reorders done by [`Layout::swap_neighbours`], and layouts made by
    /// [`Layout::build_near`] (read by a test).
    #[cfg(test)]
    swaps: usize,
    #[cfg(test)]
    nears: usize,
    #[cfg(test)]
    reforms: usize,
}

/// Sorts the end positions `order` by value in `ends` (`total_cmp`), then position (a total
/// order, so that every way of making a layout of the same ends agrees with
/// [`Layout::build`]'s sort), by insertion: for an order that nearly holds already.
fn sort_nearly_sorted(order: &mut [u32], ends: &[f64]) -> Sorted {
    let before = |a: u32, b: u32| {
        let (x, y) = (ends[a as usize], ends[b as usize]);
        x.total_cmp(&y).then(a.cmp(&b)).is_lt()
    };
    let mut sorted = Sorted {
        moves: 0,
        swapped: None,
        touched: None,
    };
    for i in 1..order.len() {
        let x = order[i];
        let mut j = i;
        while j > 0 && before(x, order[j - 1]) {
            order[j] = order[j - 1];
            j -= 1;
        }
        order[j] = x;
        if j < i {
            sorted.moves += 1;
            sorted.swapped = (i == j + 1).then_some(j);
            let first = sorted.touched.map_or(j, |(first, _)| first.min(j));
            sorted.touched = Some((first, i));
        }
    }
    sorted
}

/// What [`sort_nearly_sorted`] did.
struct Sorted {
    /// How many ends moved back.
    moves: usize,
    /// Where the last one that moved landed, if it moved by one place.
    swapped: Option<usize>,
    /// The first and last places whose end changed, if any did.
    touched: Option<(usize, usize)>,
}

/// The key of the canonical order of a layout's members: rank, then index.
fn canonical_key(ranks: &[u32], index: u32) -> u64 {
    (u64::from(ranks[index as usize]) << 32) | u64::from(index)
}

/// One interval of a [`Layout`]: from the end at `from` to the end at `to` (positions in the
/// ends), with σ = Σσᵢ and E = S·(1/σ) of its particles.
#[derive(Debug, Clone, Copy)]
struct LayoutInterval {
    from: u32,
    to: u32,
    sigma: f64,
    emission: DVec3,
    /// The open set: the bits of its particles (members in canonical order).
    mask: u64,
    /// The place of `from` in the layout's order.
    at: u32,
}

impl Layout {
    /// Whether the layout holds for a ray with these `members` and `ends` (type docs).
    fn fits(&self, particles: &[Particle], members: &[u32], ends: &[f64]) -> bool {
        if !self.same_members(particles, members) {
            return false;
        }
        // No ends (no chords): nothing to check.
        let Some(&first) = self.order.first() else {
            return true;
        };
        let mut previous = ends[first as usize];
        for (&j, &new_group) in self.order[1..].iter().zip(&self.new_group[1..]) {
            let t = ends[j as usize];
            let in_order = if new_group {
                previous < t
            } else {
                previous == t
            };
            if !in_order {
                return false;
            }
            previous = t;
        }
        true
    }

    /// Whether the layout was built for these particles and members (in any order of ends).
    fn same_members(&self, particles: &[Particle], members: &[u32]) -> bool {
        self.same_scene(particles) && self.members == members
    }

    /// Whether the layout was built (and not forgotten) for these particles.
    fn same_scene(&self, particles: &[Particle]) -> bool {
        self.valid && self.scene == (particles.as_ptr() as usize, particles.len())
    }

    /// A new layout of a ray with these `members` and `ends`: the members' bits and terms in
    /// canonical order (rank, then index; bit b of the mask is the b-th), the ends sorted,
    /// and [`Layout::form_intervals`]. At most [`LAYOUT_CHORDS`] members.
    fn build(
        &mut self,
        particles: &[Particle],
        ranks: &[u32],
        (members, ends): (&[u32], &[f64]),
        work: &mut LayoutWork,
    ) {
        self.valid = true;
        self.scene = (particles.as_ptr() as usize, particles.len());
        self.members.clear();
        self.members.extend_from_slice(members);
        work.by_key.clear();
        work.by_key.extend(
            members
                .iter()
                .enumerate()
                .map(|(m, &index)| (canonical_key(ranks, index), m as u32)),
        );
        work.by_key.sort_unstable();
        self.bit.clear();
        self.bit.resize(members.len(), 0);
        self.terms.clear();
        for &(_, m) in &work.by_key {
            self.push_term(m as usize, &particles[members[m as usize] as usize]);
        }
        work.sorted.clear();
        work.sorted
            .extend(ends.iter().enumerate().map(|(e, &t)| (t, e as u32)));
        work.sorted
            .sort_unstable_by(|&a, &b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        self.order.clear();
        self.order.extend(work.sorted.iter().map(|&(_, e)| e));
        self.intervals.clear();
        self.form_intervals(ends, &[]);
    }

    /// [`Layout::build`] from the layout of the shadow ray before, `neighbour`, where the
    /// members are its members with one more or one fewer (a segment that starts at a kink,
    /// where one sphere begins or ceases to shade: three in four new layouts on 1UUN lit
    /// 128²), without sorting anew. The canonical order and the terms are the neighbour's with
    /// that member put in at its key or taken out; the order of the ends is the neighbour's
    /// (positions renumbered), with the new member's ends appended, re-sorted by insertion;
    /// then [`Layout::form_intervals`]. The same layout as [`Layout::build`] makes (a test
    /// compares them). False, with nothing built, where the members are another case.
    fn build_near(
        &mut self,
        neighbour: &Layout,
        particles: &[Particle],
        ranks: &[u32],
        (members, ends): (&[u32], &[f64]),
    ) -> bool {
        let old = &neighbour.members;
        if !neighbour.same_scene(particles) || neighbour.general {
            return false;
        }
        // The place where the member lists part, and whether one was put in there.
        let part = old.iter().zip(members).position(|(a, b)| a != b);
        let (at, inserted) = if members.len() == old.len() + 1 {
            let at = part.unwrap_or(old.len());
            if old[at..] != members[at + 1..] {
                return false;
            }
            (at, true)
        } else if members.len() + 1 == old.len() {
            let at = part.unwrap_or(members.len());
            if old[at + 1..] != members[at..] {
                return false;
            }
            (at, false)
        } else {
            return false;
        };
        // Old member position → new one (`None`: the one taken out).
        let renumber = |m: usize| match (inserted, m.cmp(&at)) {
            (_, Ordering::Less) => Some(m),
            (true, _) => Some(m + 1),
            (false, Ordering::Equal) => None,
            (false, Ordering::Greater) => Some(m - 1),
        };
        self.valid = true;
        self.scene = neighbour.scene;
        self.members.clear();
        self.members.extend_from_slice(members);
        // Canonical order: the neighbour's, as member positions by bit.
        let mut by_bit = [0u32; LAYOUT_CHORDS];
        for (m, &bit) in neighbour.bit.iter().enumerate() {
            by_bit[bit.trailing_zeros() as usize] = m as u32;
        }
        self.bit.clear();
        self.bit.resize(members.len(), 0);
        self.terms.clear();
        // The member put in goes before the first of the neighbour's with a larger key.
        let new_key = inserted.then(|| canonical_key(ranks, members[at]));
        let mut to_place = inserted;
        for (b, &m) in by_bit[..old.len()].iter().enumerate() {
            if to_place && new_key < Some(canonical_key(ranks, old[m as usize])) {
                self.push_term(at, &particles[members[at] as usize]);
                to_place = false;
            }
            if let Some(n) = renumber(m as usize) {
                self.bit[n] = 1 << self.terms.len();
                self.terms.push(neighbour.terms[b]);
            }
        }
        if to_place {
            self.push_term(at, &particles[members[at] as usize]);
        }
        // The ends in the neighbour's order, renumbered, the new member's last. An end
        // position e is member e / 2's, so `renumber` moves e by two from the changed
        // member's ends on (written on e itself: no division in this loop).
        let ends_from = 2 * at as u32;
        let renumber_end = |e: u32| match (inserted, e.cmp(&ends_from)) {
            (_, Ordering::Less) => Some(e),
            (true, _) => Some(e + 2),
            (false, _) if e <= ends_from + 1 => None,
            (false, _) => Some(e - 2),
        };
        self.order.clear();
        self.order
            .extend(neighbour.order.iter().filter_map(|&e| renumber_end(e)));
        // The changed member's bit: in this layout's canonical order where it was put in,
        // in the neighbour's where it was taken out.
        let changed = if inserted {
            self.bit[at]
        } else {
            neighbour.bit[at]
        };
        if self.splice(neighbour, ends, (at, inserted, changed), renumber_end) {
            #[cfg(test)]
            {
                SPLICES.with(|n| n.set(n.get() + 1));
            }
            return true;
        }
        if inserted {
            self.order.extend([2 * at as u32, 2 * at as u32 + 1]);
        }
        sort_nearly_sorted(&mut self.order, ends);
        self.intervals.clear();
        self.form_intervals(ends, &[]);
        true
    }

    /// The first part of [`Layout::splice`]: puts the changed member's ends into `order` at
    /// their places (put in), or finds where they were in the neighbour's (taken out, both
    /// alone in their groups), and makes `new_group` the neighbour's with the same change.
    /// Returns those places (the final ones where put in: the second end is one further),
    /// or `None`, with `order` as it was, where the case is another one.
    fn place_changed_ends(
        &mut self,
        neighbour: &Layout,
        ends: &[f64],
        (at, inserted): (usize, bool),
    ) -> Option<(usize, usize)> {
        let old_n = neighbour.order.len();
        let alone = |k: usize| {
            (k == 0 || neighbour.new_group[k]) && (k + 1 >= old_n || neighbour.new_group[k + 1])
        };
        self.new_group.clear();
        self.new_group.extend_from_slice(&neighbour.new_group);
        let places = if inserted {
            let (va, vb) = (ends[2 * at], ends[2 * at + 1]);
            if !(va < vb) {
                return None;
            }
            let value = |k: usize| ends[self.order[k] as usize];
            // Strictly between groups: the old ends about them are checked below.
            let pa = self.order.partition_point(|&e| ends[e as usize] < va);
            let pb = self.order.partition_point(|&e| ends[e as usize] < vb);
            if (pa < old_n && !(value(pa) > va)) || (pb < old_n && !(value(pb) > vb)) {
                return None;
            }
            // The old ends after the new ones must have started a group in the neighbour too
            // (not have been equal to the one before them there), or the neighbour's intervals
            // about them are another grouping's.
            let started = |k: usize| k == 0 || k >= old_n || neighbour.new_group[k];
            if !(started(pa) && started(pb)) {
                return None;
            }
            self.order.insert(pb, 2 * at as u32 + 1);
            self.order.insert(pa, 2 * at as u32);
            self.new_group.insert(pb, true);
            self.new_group.insert(pa, true);
            let n = self.order.len();
            for k in [pa + 1, pb + 2] {
                if k < n {
                    self.new_group[k] = true;
                }
            }
            (pa, pb)
        } else {
            let find = |e: u32| neighbour.order.iter().position(|&o| o == e);
            let (Some(ra), Some(rb)) = (find(2 * at as u32), find(2 * at as u32 + 1)) else {
                return None;
            };
            if !(ra < rb && alone(ra) && alone(rb)) {
                return None;
            }
            self.new_group.remove(rb);
            self.new_group.remove(ra);
            (ra, rb)
        };
        if let Some(g) = self.new_group.first_mut() {
            *g = false;
        }
        Some(places)
    }

    /// [`Layout::build_near`] where the neighbour's ends keep their order and groups and the
    /// member put in or taken out has both its ends alone in their groups (and the ends after
    /// a member put in started groups in the neighbour too): only the intervals about those
    /// ends change. `self` holds the members, bits and terms, and in `order` the
    /// neighbour's ends renumbered (without the member put in). Puts the member's ends in at
    /// their places (or finds where they were), checks every group against the new ends as
    /// [`Layout::fits`] does (with the sort's order within a group), and forms the intervals
    /// anew only from the group before the first changed end to the end after the last one;
    /// the intervals before and after are the neighbour's, their masks moved to the new bits
    /// and their sums kept: a mask without the changed member's bit sums the same terms in the
    /// same order, so the same bits. The same layout as [`Layout::build`] makes (tested). False,
    /// with `order` as it was given, where the case is another one; `new_group` and
    /// `intervals` are then left to [`Layout::form_intervals`].
    fn splice(
        &mut self,
        neighbour: &Layout,
        ends: &[f64],
        (at, inserted, changed): (usize, bool, u64),
        renumber_end: impl Fn(u32) -> Option<u32>,
    ) -> bool {
        let Some((first, last)) = self.place_changed_ends(neighbour, ends, (at, inserted)) else {
            return false;
        };
        let n = self.order.len();
        // Every group as the sort would make it for these ends: strictly increasing from group
        // to group, equal and in (total order, then position) order within one.
        for k in 1..n {
            let (a, b) = (self.order[k - 1], self.order[k]);
            let (x, y) = (ends[a as usize], ends[b as usize]);
            let holds = if self.new_group[k] {
                x < y
            } else {
                x == y && x.total_cmp(&y).then(a.cmp(&b)).is_lt()
            };
            if !holds {
                // Give `order` back as it came (the slow path appends and sorts).
                if inserted {
                    self.order.remove(last + 1);
                    self.order.remove(first);
                }
                return false;
            }
        }
        // The walk: from the group before the first changed end (old and new places agree
        // before it) to the place, in the final order, of the old end after the last changed
        // one; old intervals from that end on move by two places.
        let mut lo = first.saturating_sub(1);
        while lo > 0 && !self.new_group[lo] {
            lo -= 1;
        }
        let (tail_old, walk_end, shift) = if inserted {
            (last, last + 2, 2i64)
        } else {
            (last + 1, last - 1, -2i64)
        };
        let low = changed - 1;
        let remap = |m: u64| {
            if inserted {
                (m & low) | ((m & !low) << 1)
            } else {
                (m & low) | ((m >> 1) & !low)
            }
        };
        let moved = |iv: &LayoutInterval, by: i64| {
            let (from, to) = (renumber_end(iv.from), renumber_end(iv.to));
            debug_assert!((iv.mask & if inserted { 0 } else { changed }) == 0);
            LayoutInterval {
                from: from.expect("an interval about the changed member is formed anew"),
                to: to.expect("an interval about the changed member is formed anew"),
                mask: remap(iv.mask),
                at: (iv.at as i64 + by) as u32,
                ..*iv
            }
        };
        self.intervals.clear();
        self.general = false;
        let old = &neighbour.intervals;
        let before = old.partition_point(|iv| (iv.at as usize) < lo);
        self.intervals
            .extend(old[..before].iter().map(|iv| moved(iv, 0)));
        let open = self.open_before(lo);
        self.form_groups((lo, walk_end), open, &[]);
        let after = old.partition_point(|iv| (iv.at as usize) < tail_old);
        self.intervals
            .extend(old[after..].iter().map(|iv| moved(iv, shift)));
        true
    }

    /// The layout of the same members for ends that came in another order (two ends crossed
    /// between the nodes of a quadrature segment: 17 % of the shadow rays on 1UUN lit 128²),
    /// in place: the order re-sorted by insertion from the old one, which it nearly is, and
    /// the intervals formed again, where an interval with the same open set as one of the
    /// old intervals about its place takes its sums (the same terms added in the same order:
    /// the same bits). The same layout as [`Layout::build`] would make.
    fn reorder(&mut self, ends: &[f64], work: &mut LayoutWork) {
        let sorted = sort_nearly_sorted(&mut self.order, ends);
        // Where a single end moved back by one place: two neighbours crossed.
        if let (1, Some(p)) = (sorted.moves, sorted.swapped) {
            if self.swap_neighbours(ends, p) {
                #[cfg(test)]
                {
                    work.swaps += 1;
                }
                return;
            }
        }
        std::mem::swap(&mut self.intervals, &mut work.before);
        if let Some(touched) = sorted.touched {
            if self.reform_between(ends, touched, &work.before) {
                #[cfg(test)]
                {
                    work.reforms += 1;
                }
                return;
            }
        }
        self.intervals.clear();
        self.form_intervals(ends, &work.before);
    }

    /// [`Layout::reorder`] where the ends changed places only between places `p0` and `p1`
    /// of `order` (re-sorted) and no group changed outside them: the intervals `before` (the
    /// layout's until now) from the groups before and after stay as they are (the same ends
    /// in the same places, and the same ends before each, so the same open sets), and the
    /// intervals from the group before `p0` up to the first group after `p1` that also
    /// started a group before (a group of equal ends may have come apart just after `p1`)
    /// are formed anew ([`Layout::form_groups`]). The same layout as
    /// [`Layout::form_intervals`] would make (tested). False, with `intervals` empty and
    /// `new_group` to be formed again, where a group changed elsewhere or a sum was not
    /// finite before.
    fn reform_between(
        &mut self,
        ends: &[f64],
        (p0, p1): (usize, usize),
        before: &[LayoutInterval],
    ) -> bool {
        self.intervals.clear();
        let n = self.order.len();
        if self.general || self.new_group.len() != n {
            return false;
        }
        // Whether the place after the last change started a group before.
        let started = p1 + 1 >= n || self.new_group[p1 + 1];
        let value = |k: usize| ends[self.order[k] as usize];
        // As `form_intervals` groups: each end that is not equal to the one before starts one.
        for k in 1..n {
            let starts = value(k) != value(k - 1);
            if k >= p0 && k <= p1 + 1 {
                self.new_group[k] = starts;
            } else if starts != self.new_group[k] {
                return false;
            }
        }
        let mut lo = p0.saturating_sub(1);
        while lo > 0 && !self.new_group[lo] {
            lo -= 1;
        }
        // The walk ends where a group starts both before and now: where one starts only now
        // (a group of equal ends that came apart), the intervals from it are formed too.
        let mut end = p1 + 1;
        if end < n && !(started && self.new_group[end]) {
            end += 1;
            while end < n && !self.new_group[end] {
                end += 1;
            }
        }
        let head = before.partition_point(|iv| (iv.at as usize) < lo);
        self.intervals.extend_from_slice(&before[..head]);
        let open = self.open_before(lo);
        self.form_groups((lo, end), open, &[]);
        let tail = before.partition_point(|iv| (iv.at as usize) < end);
        self.intervals.extend_from_slice(&before[tail..]);
        true
    }

    /// The open set just before place `lo` of `order` (a group's start), from the intervals
    /// formed so far (those before `lo`): the last one's, where it ends at `lo`, else none.
    fn open_before(&self, lo: usize) -> u64 {
        match self.intervals.last() {
            Some(iv) if lo < self.order.len() && iv.to == self.order[lo] => iv.mask,
            _ => 0,
        }
    }

    /// The intervals from the groups that start at places `lo` (a group's start) up to `end`
    /// (the next group's start after them, or the order's length) of `order`, grouped by
    /// `new_group`, where the open set before `lo` is `open`: pushed onto `intervals`, with
    /// their sums, each taken from one of `before` with the same open set within
    /// [`BEFORE_REACH`] of its place where there is one (the same terms in the same order).
    fn form_groups(&mut self, (lo, end): (usize, usize), mut open: u64, before: &[LayoutInterval]) {
        let n = self.order.len();
        let mut k = lo;
        while k < end.min(n) {
            let from = self.order[k];
            let mut next = k;
            loop {
                let e = self.order[next];
                let bit = self.bit[(e / 2) as usize];
                if e % 2 == 1 {
                    open &= !bit;
                } else {
                    open |= bit;
                }
                next += 1;
                if next >= n || self.new_group[next] {
                    break;
                }
            }
            if next < n && open != 0 {
                let j = self.intervals.len();
                let near = j.saturating_sub(BEFORE_REACH)..before.len().min(j + BEFORE_REACH + 1);
                let kept = before
                    .get(near)
                    .and_then(|near| near.iter().find(|iv| iv.mask == open));
                let (sigma, emission) = match kept {
                    Some(iv) => (iv.sigma, iv.emission),
                    None => self.sums(open),
                };
                if !sigma.is_finite() {
                    self.general = true;
                }
                self.intervals.push(LayoutInterval {
                    from,
                    to: self.order[next],
                    sigma,
                    emission,
                    mask: open,
                    at: k as u32,
                });
            }
            k = next;
        }
    }

    /// [`Layout::reorder`] where the ends at places p and p + 1 of `order` have just been
    /// swapped, both alone in their groups, and no group changed elsewhere: three intervals
    /// change at most. The one that ended at p now ends at the other end; the one from p
    /// (open set m₀ with the end now at p toggled, m₀ the open set before p) is formed anew,
    /// or appears or goes; the one from p + 1 keeps its open set and sums and starts at the
    /// other end. The same intervals as [`Layout::form_intervals`] would form (a test
    /// compares them). False, with the intervals untouched, where the case is another one.
    fn swap_neighbours(&mut self, ends: &[f64], p: usize) -> bool {
        let (q, n) = (p + 1, self.order.len());
        if self.general {
            return false;
        }
        let value = |k: usize| ends[self.order[k] as usize];
        for k in 1..n {
            if (value(k) != value(k - 1)) != self.new_group[k] {
                return false;
            }
        }
        let alone = |k: usize| k == 0 || k >= n || self.new_group[k];
        if !(alone(p) && alone(q) && alone(q + 1)) {
            return false;
        }
        let (now_p, now_q) = (self.order[p], self.order[q]);
        let toggle = |e: u32| self.bit[(e / 2) as usize];
        // The interval that ended at p, and the open set before p.
        let i = self.intervals.partition_point(|iv| (iv.at as usize) < p);
        let before = match i.checked_sub(1).map(|h| &mut self.intervals[h]) {
            Some(iv) if iv.to == now_q => {
                iv.to = now_p;
                iv.mask
            }
            _ => 0,
        };
        let had_middle = self.intervals.get(i).is_some_and(|iv| iv.at as usize == p);
        if let Some(iv) = self.intervals.get_mut(i + usize::from(had_middle)) {
            if iv.at as usize == q {
                iv.from = now_q;
            }
        }
        let open = before ^ toggle(now_p);
        if open == 0 {
            if had_middle {
                self.intervals.remove(i);
            }
            return true;
        }
        let (sigma, emission) = self.sums(open);
        self.general = !sigma.is_finite();
        let middle = LayoutInterval {
            from: now_p,
            to: now_q,
            sigma,
            emission,
            mask: open,
            at: p as u32,
        };
        if had_middle {
            self.intervals[i] = middle;
        } else {
            self.intervals.insert(i, middle);
        }
        true
    }

    /// Gives member `m` (particle `p`) the next bit of the canonical order, and its terms σᵢ and
    /// σᵢ·Cᵢ.
    fn push_term(&mut self, m: usize, p: &Particle) {
        self.bit[m] = 1 << self.terms.len();
        self.terms.push((p.sigma, p.sigma * p.color));
    }

    /// σ = Σσᵢ and E = S·(1/σ), S = Σσᵢ·Cᵢ, of the open set `open`, added in the order of its
    /// bits (canonical order).
    fn sums(&self, open: u64) -> (f64, DVec3) {
        let mut sigma = 0.0;
        let mut weighted = DVec3::ZERO;
        let mut rest = open;
        while rest != 0 {
            let (s, w) = self.terms[rest.trailing_zeros() as usize];
            sigma += s;
            weighted += w;
            rest &= rest - 1;
        }
        (sigma, weighted * (1.0 / sigma))
    }

    /// The intervals of `order` (empty before): the sweep of [`sweep_open`] over groups of
    /// equal ends (a chord cannot start and end in one group, since t1 > t0), with the open
    /// set as a bit mask whose bits are the members in canonical order, so that its sums run
    /// in that order; the sums of an interval are taken from one of `before` with the same
    /// open set within [`BEFORE_REACH`] of its place, where there is one. A sum that is not
    /// finite: the general sweep.
    fn form_intervals(&mut self, ends: &[f64], before: &[LayoutInterval]) {
        self.general = false;
        let order = &self.order;
        self.new_group.clear();
        self.new_group.extend(
            (0..order.len())
                .map(|k| k > 0 && ends[order[k] as usize] != ends[order[k - 1] as usize]),
        );
        self.form_groups((0, order.len()), 0, before);
    }
}

/// One chord of [`sweep_open`], with what the sums of its interval need.
#[derive(Debug, Clone, Copy)]
struct Open {
    exit: f64,
    rank: u32,
    index: u32,
    sigma: f64,
    /// σᵢ·Cᵢ.
    weighted: DVec3,
}

/// The general cut of `scratch.spans` (sorted by start): a sweep over the chord ends, taking
/// the next event as the earlier of the next start and the earliest end among the open chords
/// (no list of events to sort). All ends and starts at one t are applied before the interval
/// from t is formed and handed to `emit` (which returns false to stop) with the table of chords
/// and the open ones, as positions in it, in canonical rank order: a chord is inserted at its
/// place when it opens, and leaving keeps the order, so no interval sorts. So the intervals are
/// those of the plain event sweep in rank order bit for bit (`sweep_intervals` in the tests),
/// and shuffling the particles changes none of them.
///
/// The chords' data are written to the table once, before the sweep, and the open set moves
/// only their positions, so the sums read data stored long before. The sweep used to move
/// whole records through a sorted open list; with that code, changes elsewhere in the crate
/// that the lit model never runs (the single-scatter path of issue 10) made its shadow rays on
/// 1UUN about 25 % slower, through how the compiler happened to lay out the moves and the
/// loads after them. With the table, those builds come within 3–14 % of the old one
/// (same-run comparisons on a noisy machine, issue 10). Shadow rays now sweep only where no
/// [`Layout`] can be kept (more than [`LAYOUT_CHORDS`] chords) or a sum is not finite.
fn sweep_open(
    scratch: &mut IntervalScratch,
    particles: &[Particle],
    ranks: &[u32],
    mut emit: impl FnMut(&[Open], &[u32], f64, f64) -> bool,
) {
    let IntervalScratch {
        spans,
        chords,
        open,
        ..
    } = scratch;
    let spans = &spans[..];
    chords.clear();
    open.clear();
    for s in spans {
        let p = &particles[s.index as usize];
        chords.push(Open {
            exit: s.t1,
            rank: ranks[s.index as usize],
            index: s.index,
            sigma: p.sigma,
            weighted: p.sigma * p.color,
        });
    }
    let chords = &chords[..];
    let Some(first) = spans.first() else {
        return;
    };
    let key = |j: u32| {
        let c = &chords[j as usize];
        (c.rank, c.index)
    };
    let mut t = first.t0;
    let mut next = 0;
    loop {
        open.retain(|&j| chords[j as usize].exit != t);
        while next < spans.len() && spans[next].t0 == t {
            let j = next as u32;
            let index = chords[next].index;
            // A particle entered twice cannot happen on a ray; ignoring it keeps the sweep total.
            if !open.iter().any(|&o| chords[o as usize].index == index) {
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
        let mut t_next = spans.get(next).map_or(f64::INFINITY, |s| s.t0);
        for &j in open.iter() {
            let exit = chords[j as usize].exit;
            if exit.total_cmp(&t_next).is_lt() {
                t_next = exit;
            }
        }
        if open.is_empty() {
            if next >= spans.len() {
                return;
            }
        } else if !emit(chords, open, t, t_next) {
            return;
        }
        t = t_next;
    }
}

/// [`sweep_open`] over overlapping spans (`scratch.spans`), compositing each interval into
/// `acc` as it is formed from σ = Σσᵢ and S = Σσᵢ·Cᵢ alone. The accumulator is passed and
/// returned by value.
fn composite_overlapping(
    particles: &[Particle],
    ranks: &[u32],
    scratch: &mut IntervalScratch,
    mut acc: Accumulator,
) -> Accumulator {
    sweep_open(scratch, particles, ranks, |chords, set, t0, t1| {
        let mut sigma = 0.0;
        let mut weighted = DVec3::ZERO;
        for &j in set {
            let c = &chords[j as usize];
            sigma += c.sigma;
            weighted += c.weighted;
        }
        if sigma.is_finite() {
            acc.add(sigma, weighted, t1 - t0)
        } else {
            // A Θmax = 1 particle (σ = ∞, and then `weighted` is NaN or ∞) or Σσᵢ
            // overflowing: the general medium.
            let set = set.iter().map(|&j| chords[j as usize].index);
            acc.add_interval(medium_of(set, particles, t0, t1))
        }
    });
    acc
}

/// The running front-to-back composite of [`composite_spans`].
struct Accumulator {
    radiance: DVec3,
    transmittance: f64,
    /// Transmittance at or below which nothing more is added (0: only an opaque stop).
    stop_at: f64,
    /// The run of intervals added since the last flush, all of this emission E, and their
    /// summed optical depth Σσ·Δ (0 and NaN emission: none).
    run_emission: DVec3,
    run_depth: f64,
}

impl Accumulator {
    /// Nothing composited yet; stopping where T falls to the cut's ε, if any.
    fn new(cut: Option<(f64, DVec3)>) -> Self {
        Accumulator {
            radiance: DVec3::ZERO,
            transmittance: 1.0,
            stop_at: cut.map_or(0.0, |(epsilon, _)| epsilon),
            run_emission: DVec3::NAN,
            run_depth: 0.0,
        }
    }

    /// Adds a homogeneous piece of finite extinction σ, σ-weighted colour S = Σσᵢ·Cᵢ and the
    /// given length; false once nothing more is to be added (T ≤ `stop_at`). E = S·(1/σ) is
    /// formed before the exponential, which it does not depend on: dividing after it (T·a/σ)
    /// put the division's latency on the path from each exponential to the running sums.
    #[inline]
    fn add(&mut self, sigma: f64, weighted: DVec3, length: f64) -> bool {
        self.add_emission(sigma, weighted * (1.0 / sigma), length)
    }

    /// [`Accumulator::add`] with E = S·(1/σ) formed by the caller. Consecutive pieces of the
    /// same E (bit for bit) are one homogeneous source behind each other: their composite is
    /// T·(1 − e^{−Σσ·Δ})·E, so their depths are summed and composited as one, with one
    /// exponential (about a third of the intervals of a shadow ray through 1UUN continue the
    /// previous one's colour). T is checked against `stop_at` where a run ends.
    #[inline]
    fn add_emission(&mut self, sigma: f64, emission: DVec3, length: f64) -> bool {
        if emission == self.run_emission {
            self.run_depth += sigma * length;
            return true;
        }
        if !self.flush() {
            return false;
        }
        self.run_emission = emission;
        self.run_depth = sigma * length;
        true
    }

    /// Composites the pending run; false once nothing more is to be added.
    #[inline]
    fn flush(&mut self) -> bool {
        if self.run_depth != 0.0 {
            let (a, e) = opacity_and_transmittance(self.run_depth);
            self.radiance += (self.transmittance * a) * self.run_emission;
            self.transmittance *= e;
        }
        self.run_emission = DVec3::NAN;
        self.run_depth = 0.0;
        self.transmittance > self.stop_at
    }

    /// Adds an interval as [`composite`](super::emission::composite) does (σ may be ∞).
    fn add_interval(&mut self, iv: Interval) -> bool {
        if !self.flush() {
            return false;
        }
        if iv.sigma.is_infinite() {
            self.radiance += self.transmittance * iv.emission;
            self.transmittance = 0.0;
        } else {
            let (a, e) = opacity_and_transmittance(iv.sigma * iv.length());
            self.radiance += (self.transmittance * a) * iv.emission;
            self.transmittance *= e;
        }
        self.transmittance > self.stop_at
    }
}

/// The plain event sweep over the chord ends of `spans` (in any order), keeping the active set
/// sorted by canonical rank: the oracle of [`sweep_open`] and [`disjoint_intervals`].
#[cfg(test)]
fn sweep_intervals(
    spans: &[Span],
    particles: &[Particle],
    ranks: &[u32],
    events: &mut Vec<Event>,
    active: &mut Vec<(u32, u32)>,
    out: &mut Vec<Interval>,
) {
    events.clear();
    for s in spans {
        let rank = ranks[s.index as usize];
        events.push(Event {
            t: s.t0,
            rank,
            index: s.index,
            enter: true,
        });
        events.push(Event {
            t: s.t1,
            rank,
            index: s.index,
            enter: false,
        });
    }
    // Only t matters for the order: all events at one t are applied before the next interval.
    events.sort_unstable_by(|a, b| a.t.total_cmp(&b.t));
    active.clear();
    let mut i = 0;
    while i < events.len() {
        let t = events[i].t;
        while i < events.len() && events[i].t == t {
            let e = events[i];
            let key = (e.rank, e.index);
            match active.binary_search(&key) {
                Ok(pos) if !e.enter => {
                    active.remove(pos);
                }
                Err(pos) if e.enter => active.insert(pos, key),
                // An exit without entry (or a double entry) cannot happen for chords with
                // t_enter < t_exit; ignoring it keeps the sweep total rather than panicking.
                _ => {}
            }
            i += 1;
        }
        if active.is_empty() || i >= events.len() {
            continue;
        }
        let t_next = events[i].t;
        out.push(medium_of(
            active.iter().map(|&(_, i)| i),
            particles,
            t,
            t_next,
        ));
    }
}

/// The intervals of chords that do not overlap (`spans` sorted by start, each ending at or before
/// the next one starts): one interval per chord, holding that particle alone. The event sweep
/// would give exactly these (where one chord ends as the next starts, both events share one t and
/// the interval that follows holds the next particle alone), and σ, E and α are computed with the
/// same operations as [`medium_of`] on a one-particle set (0 + σᵢ, (0 + σᵢ·Cᵢ)/σ, a colour
/// divided by 1 for σ = ∞), so every interval is bit-identical to the sweep's.
fn disjoint_intervals(spans: &[Span], particles: &[Particle], out: &mut Vec<Interval>) {
    for s in spans {
        out.push(disjoint_interval(s, &particles[s.index as usize]));
    }
}

/// The interval of one span crossed by particle `p` alone ([`disjoint_intervals`]).
fn disjoint_interval(s: &Span, p: &Particle) -> Interval {
    let (t0, t1) = (s.t0, s.t1);
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

/// σ, E and α of a fixed set of particles, given by index (in canonical rank order, or at most
/// two of them, so the sums do not depend on the input order).
fn medium_of(
    set: impl Iterator<Item = u32> + Clone,
    particles: &[Particle],
    t0: f64,
    t1: f64,
) -> Interval {
    let mut sigma = 0.0;
    let mut weighted_color = DVec3::ZERO;
    let mut weighted_albedo = DVec3::ZERO;
    let mut n_inf = 0u32;
    let mut inf_color = DVec3::ZERO;
    let mut inf_albedo = DVec3::ZERO;
    for index in set.clone() {
        let p = &particles[index as usize];
        if p.sigma.is_infinite() {
            n_inf += 1;
            inf_color += p.color;
            inf_albedo += p.albedo;
        } else {
            sigma += p.sigma;
            weighted_color += p.sigma * p.color;
            weighted_albedo += p.sigma * p.albedo;
        }
    }
    if n_inf > 0 {
        let n = n_inf as f64;
        Interval {
            t0,
            t1,
            sigma: f64::INFINITY,
            emission: inf_color / n,
            albedo: inf_albedo / n,
        }
    } else if sigma.is_finite() {
        Interval {
            t0,
            t1,
            sigma,
            emission: weighted_color / sigma,
            albedo: weighted_albedo / sigma,
        }
    } else {
        // Σσᵢ overflowed (σ near f64::MAX from a huge κ): weigh by σᵢ/σ_max instead, so the
        // colour stays a convex combination rather than ∞/∞.
        let scale = set
            .clone()
            .map(|i| particles[i as usize].sigma)
            .fold(0.0, f64::max);
        let (mut w, mut c, mut a) = (0.0, DVec3::ZERO, DVec3::ZERO);
        for index in set {
            let p = &particles[index as usize];
            let s = p.sigma / scale;
            w += s;
            c += s * p.color;
            a += s * p.albedo;
        }
        Interval {
            t0,
            t1,
            sigma,
            emission: c / w,
            albedo: a / w,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Chord;

    fn particle(sigma: f64, color: DVec3) -> Particle {
        Particle {
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
    fn random_particles(
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

    fn hit(index: u32, t_enter: f64, t_exit: f64) -> Hit {
        Hit {
            index,
            chord: Chord { t_enter, t_exit },
        }
    }

    #[test]
    fn overlapping_chords_give_three_intervals_with_summed_sigma() {
        let ps = vec![particle(1.0, DVec3::X), particle(3.0, DVec3::Y)];
        let cutter = IntervalCutter::new(&ps);
        let mut out = Vec::new();
        let mut s = IntervalScratch::default();
        let hits = [hit(0, 1.0, 3.0), hit(1, 2.0, 5.0)];
        cutter.cut(&hits, 0.0, f64::INFINITY, |_| false, &mut s, &mut out);
        assert_eq!(out.len(), 3);
        assert_eq!((out[0].t0, out[0].t1, out[0].sigma), (1.0, 2.0, 1.0));
        assert_eq!((out[1].t0, out[1].t1, out[1].sigma), (2.0, 3.0, 4.0));
        assert_eq!(out[1].emission, DVec3::new(0.25, 0.75, 0.0));
        assert_eq!((out[2].t0, out[2].t1, out[2].sigma), (3.0, 5.0, 3.0));
    }

    /// Both paths of the cut give the plain event sweep's intervals bit for bit: the disjoint one
    /// (chords that touch end to start, σ = ∞, colours that σ·C/σ does not reproduce exactly)
    /// and the merge (chords that overlap by a hair or heavily, with coinciding ends).
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
        let (mut fast, mut swept) = (Vec::new(), Vec::new());
        let mut s = IntervalScratch::default();
        let (mut events, mut active, mut depths) = (Vec::new(), Vec::new(), Vec::new());
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
            let mut spans = s.spans.clone();
            spans.reverse();
            swept.clear();
            sweep_intervals(
                &spans,
                &ps,
                &cutter.ranks,
                &mut events,
                &mut active,
                &mut swept,
            );
            assert_eq!(bits(&fast), bits(&swept), "trial {trial}: {hits:?}");
            if !s.spans.windows(2).all(|w| w[0].t1 <= w[1].t0) {
                fallbacks += 1;
            }
            // The fused composite of shadow rays is `composite` of these intervals, to the last
            // bits (it divides by σ once instead of forming E = S/σ, and takes e^{−τ} = 1 − a).
            let background = DVec3::new(0.3, 2.0, 7.0);
            let want = crate::optics::emission::composite(&swept, background);
            let (got, was_cut) =
                cutter.composite(&hits, (0.0, 4.0), |_| false, background, None, &mut s);
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
                let (c, was_cut) = cutter.composite(
                    &hits,
                    (0.0, 4.0),
                    |_| false,
                    background,
                    Some((epsilon, bound)),
                    &mut s,
                );
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

    /// The composite through kept layouts is the sweep's, bit for bit: on shadow rays that
    /// follow one another as the nodes of a quadrature segment do (the same chords, ends that
    /// move a little, so that their order sometimes changes), with ends that coincide (chords
    /// clipped at 0, and a grid of values), a σ = ∞ particle, more than 64 chords, the stop at
    /// ε, and hit lists that change between rays (other members, other order).
    #[test]
    fn kept_layouts_give_the_sweeps_composite_bit_for_bit() {
        let mut rng = crate::formats::random::SplitMix64::new(5);
        let mut ps = random_particles(&mut rng, 120, 2.0, (0.05, 3.0));
        ps[7].sigma = f64::INFINITY;
        ps[8].sigma = 0.0;
        let cutter = IntervalCutter::new(&ps);
        let background = DVec3::new(0.5, 1.5, 3.0);
        let bound = ps.iter().fold(background, |m, p| m.max(p.color));
        let bits = |(c, cut): (Composite, bool)| {
            let r = c.radiance;
            ([r.x, r.y, r.z, c.transmittance].map(f64::to_bits), cut)
        };
        let mut kept = IntervalScratch::default();
        let (mut reused, mut seeded, mut built, mut general) = (0, 0, 0, 0);
        let splices_before = SPLICES.with(|n| n.get());
        for trial in 0..400 {
            let n = match trial % 10 {
                9 => 70, // more than a mask holds
                k => 1 + k,
            };
            let first = (trial * 11) % (ps.len() - n);
            let base: Vec<(f64, f64)> = (0..n)
                .map(|_| {
                    let a = -1.0 + 5.0 * rng.next_f64();
                    let a = if rng.next_f64() < 0.3 {
                        (a * 4.0).round() / 4.0
                    } else {
                        a
                    };
                    (a, a + 0.05 + 2.0 * rng.next_f64())
                })
                .collect();
            let range = (0.0, if trial % 3 == 0 { 3.0 } else { f64::INFINITY });
            let cut = match trial % 4 {
                0 => Some((0.05, bound)),
                _ => None,
            };
            for node in 0..8 {
                // Small moves (nearby nodes); every ninth trial, moves large enough to reorder.
                let scale = if trial % 9 == 0 { 0.3 } else { 0.02 };
                let mut hits: Vec<Hit> = base
                    .iter()
                    .enumerate()
                    .map(|(k, &(a, b))| {
                        let da = scale * (rng.next_f64() - 0.5);
                        let db = scale * (rng.next_f64() - 0.5);
                        // Ends on the grid stay there (as a chord clipped at 0 does).
                        let a = if a == (a * 4.0).round() / 4.0 {
                            a
                        } else {
                            a + da
                        };
                        hit((first + k) as u32, a, b + db)
                    })
                    .collect();
                if node == 5 {
                    hits.reverse(); // the same chords as other members' order
                }
                // Node 6 leaves out one chord (a new layout next to node 5's if that one
                // was in the same order), node 7 has it again.
                let skip = |i: u32| node == 6 && i as usize == first + trial % n;
                let members: Vec<u32> = {
                    let mut m = Vec::new();
                    for h in &hits {
                        let p = &ps[h.index as usize];
                        let (t0, t1) = (h.chord.t_enter.max(range.0), h.chord.t_exit.min(range.1));
                        if p.sigma > 0.0 && !skip(h.index) && t1 > t0 {
                            m.push(h.index);
                        }
                    }
                    m
                };
                let ends: Vec<f64> = hits
                    .iter()
                    .filter(|h| members.contains(&h.index))
                    .flat_map(|h| [h.chord.t_enter.max(range.0), h.chord.t_exit.min(range.1)])
                    .collect();
                if members.len() > LAYOUT_CHORDS {
                    general += 1;
                } else if kept.layouts.iter().any(|l| l.fits(&ps, &members, &ends)) {
                    reused += 1;
                } else if kept.layouts.iter().any(|l| l.same_members(&ps, &members)) {
                    seeded += 1;
                } else {
                    built += 1;
                }
                let got = cutter.composite(&hits, range, skip, background, cut, &mut kept);
                if members.len() <= LAYOUT_CHORDS {
                    general += usize::from(kept.layouts[0].general);
                    // A kept, reordered or patched layout is the one a new build makes.
                    let mut fresh = Layout::default();
                    let mut work = LayoutWork::default();
                    fresh.build(&ps, &cutter.ranks, (&members, &ends), &mut work);
                    assert_eq!(
                        layout_bits(&kept.layouts[0]),
                        layout_bits(&fresh),
                        "trial {trial}, node {node}"
                    );
                }
                let mut fresh = IntervalScratch::default();
                let acc = composite_by_sweep(
                    &hits,
                    range,
                    &ps,
                    &cutter.ranks,
                    skip,
                    &mut fresh,
                    Accumulator::new(cut),
                );
                let want = finish(acc, background, cut);
                assert_eq!(
                    bits(got),
                    bits(want),
                    "trial {trial}, node {node}: {hits:?}"
                );
            }
        }
        // Every path was taken, many times.
        assert!(
            reused > 1000 && seeded > 100 && built > 300 && general > 200,
            "reused {reused}, seeded {seeded}, built {built}, general {general}"
        );
        let swaps = kept.layout_work.swaps;
        assert!(
            swaps > 50 && swaps < seeded,
            "{swaps} of {seeded} reorders were one swap"
        );
        let nears = kept.layout_work.nears;
        assert!(
            nears > 50 && nears < built,
            "{nears} of {built} new layouts from a neighbour"
        );
        let reforms = kept.layout_work.reforms;
        assert!(
            reforms > 20 && reforms + swaps < seeded,
            "{reforms} of {seeded} reorders formed only the groups about the changes"
        );
        let splices = SPLICES.with(|n| n.get()) - splices_before;
        assert!(
            splices > 20 && splices < nears,
            "{splices} of {nears} layouts from a neighbour spliced"
        );
    }

    /// Runs `steps` random changes to a hit list (a chord put in or taken out at the front,
    /// in the middle or at the back; ends moved a little or a lot, ends on a grid and
    /// clipped at 0 that coincide), composites each through one scratch, and compares its
    /// layout with a fresh build of the same ray. Returns the first difference, and how many
    /// layouts were spliced and reformed.
    fn layouts_through_changes(seed: u64, steps: usize) -> Result<(usize, usize), String> {
        type Rng = crate::formats::random::SplitMix64;
        let mut rng = Rng::new(seed);
        let ps = random_particles(&mut rng, 24, 2.0, (0.05, 3.0));
        let cutter = IntervalCutter::new(&ps);
        let mut kept = IntervalScratch::default();
        let pick = |rng: &mut Rng, n: usize| ((rng.next_f64() * n as f64) as usize).min(n - 1);
        // On the grid of quarters: `+ 0.0` makes a −0 of the rounding +0. (Where two ends are
        // −0 and +0, a kept layout may hold them in either order, since `==` cannot tell them
        // apart; the composite is the same, but not the layout's bits this test compares.)
        let grid = |t: f64| (t * 4.0).round() / 4.0 + 0.0;
        let end = |rng: &mut Rng, lo: f64, span: f64| {
            let t = lo + span * rng.next_f64();
            if rng.next_f64() < 0.3 {
                grid(t)
            } else {
                t
            }
        };
        let mut chords: Vec<(u32, f64, f64)> = (0..10)
            .map(|i| {
                let a = end(&mut rng, -1.0, 5.0);
                (2 * i, a, a + 0.25 * (1 + pick(&mut rng, 8)) as f64)
            })
            .collect();
        let splices = SPLICES.with(|n| n.get());
        for step in 0..steps {
            // A chord put in or taken out (with the other ends moved as well, half the time),
            // or the ends moved.
            let kind = pick(&mut rng, 6);
            match kind {
                0 if chords.len() < ps.len() => {
                    let from = pick(&mut rng, ps.len()) as u32;
                    let index = (from..from + ps.len() as u32)
                        .map(|i| i % ps.len() as u32)
                        .find(|i| chords.iter().all(|c| c.0 != *i))
                        .expect("a particle not on the ray");
                    let a = end(&mut rng, -1.0, 5.0);
                    let b = a + 0.25 * (1 + pick(&mut rng, 8)) as f64;
                    let at = pick(&mut rng, chords.len() + 1);
                    chords.insert(at, (index, a, b));
                }
                1 if chords.len() > 1 => {
                    let at = pick(&mut rng, chords.len());
                    chords.remove(at);
                }
                _ => {}
            }
            if kind >= 2 || rng.next_f64() < 0.5 {
                let scale = [0.02, 0.02, 0.1, 0.1, 0.5][pick(&mut rng, 5)];
                for c in &mut chords {
                    for t in [&mut c.1, &mut c.2] {
                        // Ends on the grid mostly stay there (as ends clipped at 0 do), and
                        // sometimes leave it; ends off it sometimes land on it: groups of
                        // equal ends form and come apart.
                        let on_grid = *t == grid(*t);
                        let u = rng.next_f64();
                        if on_grid && u < 0.7 {
                            continue;
                        }
                        *t = if !on_grid && u < 0.1 {
                            grid(*t)
                        } else {
                            *t + scale * (rng.next_f64() - 0.5)
                        };
                    }
                    if c.2 <= c.1 {
                        c.2 = c.1 + 0.01;
                    }
                }
            }
            let hits: Vec<Hit> = chords.iter().map(|&(i, a, b)| hit(i, a, b)).collect();
            let range = (0.0, f64::INFINITY);
            let before = kept.layouts.first().map(layout_bits);
            cutter.composite(&hits, range, |_| false, DVec3::ONE, None, &mut kept);
            // The composite's own ends: `t.max(0.0)` of a chord that starts at −0 may give
            // either zero, depending on how the compiler ordered the operands where it was
            // inlined (a group of equal ends sorts −0 first, and the composite is the same).
            let (members, ends) = (&kept.members, &kept.ends);
            let mut fresh = Layout::default();
            fresh.build(
                &ps,
                &cutter.ranks,
                (members, ends),
                &mut LayoutWork::default(),
            );
            let (got, want) = (layout_bits(&kept.layouts[0]), layout_bits(&fresh));
            if got != want {
                return Err(format!(
                    "step {step}: members {members:?}, ends {ends:?}\n got {got:?}\nwant {want:?}\nlayout before {before:?}"
                ));
            }
        }
        Ok((
            SPLICES.with(|n| n.get()) - splices,
            kept.layout_work.reforms,
        ))
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

        /// Layouts changed in place ([`Layout::splice`] where a chord is put in or taken out,
        /// [`Layout::reform_between`] where ends moved within a stretch, the other reorders)
        /// are the layouts a fresh build makes, bit for bit, through a sequence of changes.
        #[test]
        fn layouts_changed_in_place_are_the_fresh_builds(seed in 0u64..u64::MAX, steps in 20usize..80) {
            let paths = layouts_through_changes(seed, steps);
            proptest::prop_assert!(paths.is_ok(), "{}", paths.unwrap_err());
        }
    }

    /// [`layouts_through_changes`] on fixed seeds: no difference, and both in-place paths
    /// taken many times (so that the property test above tests them).
    #[test]
    fn fixed_change_sequences_splice_and_reform_layouts() {
        let (mut splices, mut reforms) = (0, 0);
        for seed in 0..60 {
            let (s, r) = layouts_through_changes(seed, 60).unwrap_or_else(|e| panic!("{e}"));
            splices += s;
            reforms += r;
        }
        assert!(
            splices > 200 && reforms > 100,
            "{splices} spliced, {reforms} reformed"
        );
    }

    /// The two ways a group of equal ends (chords clipped at 0) that comes apart could leave
    /// an interval out of a layout changed in place: a reorder whose last change is just
    /// before an end that was in such a group (1UUN's dark roof found it), and a chord put in
    /// between two ends that were one group. Each layout is the fresh build's.
    #[test]
    fn groups_that_come_apart_are_formed_anew() {
        let ps: Vec<Particle> = (0..4)
            .map(|i| particle(0.5 + i as f64, DVec3::new(0.1, 0.2 * i as f64, 0.3)))
            .collect();
        let cutter = IntervalCutter::new(&ps);
        let ranks = &cutter.ranks;
        let fresh = |members: &[u32], ends: &[f64]| {
            let mut l = Layout::default();
            l.build(&ps, ranks, (members, ends), &mut LayoutWork::default());
            layout_bits(&l)
        };
        // Three chords from 0; then the first two starts swap and the third comes apart.
        let members = [0, 1, 2];
        let mut l = Layout::default();
        let mut work = LayoutWork::default();
        l.build(
            &ps,
            ranks,
            (&members, &[0.0, 1.0, 0.0, 2.0, 0.0, 3.0]),
            &mut work,
        );
        let ends = [0.3, 1.0, 0.0, 2.0, 0.4, 3.0];
        l.reorder(&ends, &mut work);
        assert_eq!(layout_bits(&l), fresh(&members, &ends));
        assert_eq!((work.swaps, work.reforms), (0, 1), "the reform path");
        // Two chords from 0; then the second starts later and a third lies between.
        let mut neighbour = Layout::default();
        neighbour.build(&ps, ranks, (&[0, 1], &[0.0, 1.0, 0.0, 2.0]), &mut work);
        let (members, ends) = ([0, 3, 1], [0.0, 1.0, 0.25, 0.3, 0.5, 2.0]);
        let mut near = Layout::default();
        assert!(near.build_near(&neighbour, &ps, ranks, (&members, &ends)));
        assert_eq!(layout_bits(&near), fresh(&members, &ends));
    }

    /// Everything of a layout that its composites read, as bits.
    #[allow(clippy::type_complexity)]
    fn layout_bits(
        l: &Layout,
    ) -> (
        Vec<u32>,
        Vec<bool>,
        bool,
        Vec<(u32, u32, u32, u64, [u64; 4])>,
    ) {
        let intervals = l
            .intervals
            .iter()
            .map(|iv| {
                let e = iv.emission;
                let bits = [iv.sigma, e.x, e.y, e.z].map(f64::to_bits);
                (iv.from, iv.to, iv.at, iv.mask, bits)
            })
            .collect();
        (l.order.clone(), l.new_group.clone(), l.general, intervals)
    }

    #[test]
    fn clipping_skipping_and_infinite_sigma() {
        let ps = vec![
            particle(f64::INFINITY, DVec3::X),
            particle(0.0, DVec3::Y),
            particle(2.0, DVec3::Z),
        ];
        let cutter = IntervalCutter::new(&ps);
        let mut out = Vec::new();
        let mut s = IntervalScratch::default();
        let hits = [hit(0, -1.0, 1.0), hit(1, 0.0, 4.0), hit(2, 0.5, 2.0)];
        cutter.cut(&hits, 0.0, 1.5, |_| false, &mut s, &mut out);
        assert_eq!(out.len(), 3);
        assert_eq!((out[0].t0, out[0].t1), (0.0, 0.5));
        assert!(out[0].sigma.is_infinite());
        assert_eq!(out[0].emission, DVec3::X);
        assert!(out[1].sigma.is_infinite());
        assert_eq!((out[2].t0, out[2].t1, out[2].sigma), (1.0, 1.5, 2.0));
        cutter.cut(&hits, 0.0, 1.5, |i| i == 0, &mut s, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!((out[0].t0, out[0].t1, out[0].sigma), (0.5, 1.5, 2.0));
    }
}

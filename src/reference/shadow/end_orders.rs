//! The end orders of recent shadow rays, kept so that the next shadow ray through the same
//! spheres skips most of the interval sweep: the fast implementation of
//! [`ShadowCompositor`](super::ShadowCompositor), with [`PlainSweep`](super::PlainSweep) as its
//! reference (`end_orders/equiv_tests.rs` compares the two bit for bit).
//!
//! Shadow rays from the nodes of one quadrature segment cross the same spheres (segments end
//! where a shadow ray grazes one, `optics::kinks`), and their chord ends mostly come in the
//! same order. The sweep over those ends (the open set, its canonical order, the sums
//! σ = Σσᵢ and S = Σσᵢ·Cᵢ: `optics::cutter`) depends on nothing but that order, so it is done
//! once and kept as an [`EndOrder`]; the next ray only checks that its ends are in it and
//! takes each interval's length from its own ends. Where they are not:
//!
//! * the same chords in another order (two ends crossed between nodes): the order is re-sorted
//!   in place ([`EndOrder::reorder`]); where just two neighbouring ends crossed only the
//!   intervals about them change ([`EndOrder::swap_neighbours`]), and where the ends moved
//!   within one stretch only the intervals about that stretch are formed anew
//!   ([`EndOrder::reform_between`]);
//! * the chords of the last ray with one more or one fewer (a segment that starts at a kink):
//!   the new end order is made from the last one without sorting ([`EndOrder::build_near`]),
//!   forming only the intervals about the changed chord's ends where the others keep their
//!   order ([`EndOrder::splice`]);
//! * otherwise a new end order is built ([`EndOrder::build`]).
//!
//! More than [`MAX_CHORDS`] chords (the open set is a 64-bit mask), or an interval whose Σσᵢ
//! is not finite (a Θmax = 1 particle, an overflow), take the plain sweep.
//!
//! **Same bits.** An end order holds for a ray with the same members (particle indices, in the
//! order of its hits) whose ends, taken in the end order's `order`, are equal (`==`) within each
//! group and strictly increasing from group to group: then the sweep would open and close the
//! same chords at the same events and form the same intervals with the same sums, and each
//! interval's length is the difference of the same two end values (the sweep's t is the first
//! of its group in `f64::total_cmp` order, as here). An interval formed anew whose open set
//! equals one formed before takes that one's sums: the same terms added in the same order.

// `!(a > b)` is deliberate throughout: unlike `a <= b` it is also true when a value is NaN, so
// degenerate input takes the safe branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{PlainSweep, ShadowCompositor};
use crate::geometry::Hit;
use crate::optics::cutter::IntervalCutter;
use crate::optics::emission::{Composite, FrontToBack};
use crate::optics::intervals::clipped_chords;
use crate::optics::Particle;
use glam::DVec3;
use std::cmp::Ordering;

#[cfg(test)]
mod equiv_tests;

/// How many [`EndOrder`]s are kept. The quadrature evaluates a segment's nodes in order along
/// it, so the most recent end order is the one that holds for most shadow rays; an older one
/// serves the Kronrod nodes of a segment raised later, between the nodes that made it.
const KEPT_ORDERS: usize = 4;

/// The most chords an [`EndOrder`] holds: its open set is a 64-bit mask.
const MAX_CHORDS: usize = 64;

/// How far from an interval's own place [`EndOrder::form_groups`] looks for its open set among
/// the intervals formed before (two ends that cross shift the intervals behind them by at most
/// one).
const SUMS_REACH: usize = 2;

/// The shadow-ray compositor of the volume renderer: the end orders of recent shadow rays, the
/// most recently used first, and the buffers of the composite.
#[derive(Debug, Default, Clone)]
pub struct KeptEndOrders {
    /// The particles of the current composite's clipped chords, in the order of its hits.
    members: Vec<u32>,
    /// Their clipped ends: `ends[2m]` where member m starts, `ends[2m + 1]` where it ends.
    ends: Vec<f64>,
    /// At most [`KEPT_ORDERS`].
    orders: Vec<EndOrder>,
    work: OrderWork,
    /// For the rays that take the plain sweep.
    plain: PlainSweep,
}

/// How [`KeptEndOrders::composite_with_path`] came to its end order (the tests count the paths).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Path {
    /// More chords than an end order holds: the plain sweep.
    TooMany,
    /// A kept end order held.
    Kept,
    /// A kept end order of the same chords, reordered.
    Reordered(Reorder),
    /// Made from the last end order, one chord more or fewer.
    Near(Near),
    /// Built anew.
    Built,
}

/// How [`EndOrder::reorder`] formed the intervals.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Reorder {
    /// Two neighbouring ends crossed ([`EndOrder::swap_neighbours`]).
    Swap,
    /// Only the stretch where ends moved ([`EndOrder::reform_between`]).
    Reform,
    /// All of them.
    Full,
}

/// How [`EndOrder::build_near`] formed the intervals.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Near {
    /// Only those about the changed chord ([`EndOrder::splice`]).
    Spliced,
    /// All of them, after an insertion sort of the ends.
    Sorted,
}

impl ShadowCompositor for KeptEndOrders {
    #[inline]
    fn composite(
        &mut self,
        cutter: &IntervalCutter,
        hits: &[Hit],
        range: (f64, f64),
        skip: impl Fn(u32) -> bool,
        (background, cut): (DVec3, Option<(f64, DVec3)>),
    ) -> (Composite, bool) {
        self.composite_with_path(cutter, hits, range, skip, (background, cut))
            .0
    }

    fn forget(&mut self) {
        for order in &mut self.orders {
            order.valid = false;
        }
    }
}

impl KeptEndOrders {
    /// [`ShadowCompositor::composite`], and how the end order was found.
    pub(crate) fn composite_with_path(
        &mut self,
        cutter: &IntervalCutter,
        hits: &[Hit],
        range: (f64, f64),
        skip: impl Fn(u32) -> bool,
        (background, cut): (DVec3, Option<(f64, DVec3)>),
    ) -> ((Composite, bool), Path) {
        let (particles, ranks) = (cutter.particles(), cutter.ranks());
        let acc = FrontToBack::new(cut);
        let KeptEndOrders {
            members,
            ends,
            orders,
            work,
            plain,
        } = self;
        members.clear();
        ends.clear();
        for h in clipped_chords(hits, range, particles, &skip) {
            members.push(h.index);
            ends.extend([h.chord.t_enter, h.chord.t_exit]);
        }
        if members.len() > MAX_CHORDS {
            let acc = cutter.composite(hits, range, &skip, &mut plain.sweep, acc);
            return (acc.finish(background, cut), Path::TooMany);
        }
        let path = match orders.iter().position(|o| o.fits(particles, members, ends)) {
            Some(0) => Path::Kept,
            Some(i) => {
                orders[..=i].rotate_right(1);
                Path::Kept
            }
            None => match orders
                .iter()
                .position(|o| o.same_members(particles, members))
            {
                // The same chords in another order: its order is nearly this one.
                Some(i) => {
                    orders[..=i].rotate_right(1);
                    Path::Reordered(orders[0].reorder(ends, work))
                }
                None => {
                    if orders.len() < KEPT_ORDERS {
                        orders.push(EndOrder::default());
                    }
                    orders.rotate_right(1);
                    let (new, kept) = orders.split_at_mut(1);
                    let near = kept.first().and_then(|neighbour| {
                        new[0].build_near(neighbour, particles, ranks, (members, ends))
                    });
                    match near {
                        Some(near) => Path::Near(near),
                        None => {
                            new[0].build(particles, ranks, (members, ends), work);
                            Path::Built
                        }
                    }
                }
            },
        };
        let order = &orders[0];
        let mut acc = acc;
        if order.general {
            acc = cutter.composite(hits, range, &skip, &mut plain.sweep, acc);
        } else {
            for iv in &order.intervals {
                let length = ends[iv.to as usize] - ends[iv.from as usize];
                if !acc.add_emission(iv.sigma, iv.emission, length) {
                    break;
                }
            }
        }
        (acc.finish(background, cut), path)
    }
}

/// The order of the chord ends of one shadow ray and the intervals it makes (module docs).
#[derive(Debug, Default, Clone)]
struct EndOrder {
    /// Whether the end order was built (and not forgotten).
    valid: bool,
    /// The particle slice it was built for (address and length): a guard against reuse with
    /// another scene's particles that [`KeptEndOrders::forget`] did not catch.
    scene: (usize, usize),
    members: Vec<u32>,
    /// Positions in the ends (2m: start of member m, 2m + 1: its end), sorted by value.
    order: Vec<u32>,
    /// `new_group[k]`: whether `order[k]` starts a new group (a larger value than `order[k − 1]`).
    new_group: Vec<bool>,
    intervals: Vec<OrderedInterval>,
    /// The mask bit of each member, and σᵢ, σᵢ·Cᵢ of the members in canonical order.
    bit: Vec<u64>,
    terms: Vec<(f64, DVec3)>,
    /// Some interval's Σσᵢ is not finite (a Θmax = 1 particle, or an overflow): the general
    /// sweep instead of the intervals.
    general: bool,
}

/// Buffers of [`EndOrder::build`] and [`EndOrder::reorder`].
#[derive(Debug, Default, Clone)]
struct OrderWork {
    /// (canonical key: rank, then index; member position), sorted.
    by_key: Vec<(u64, u32)>,
    /// (end value, end position), sorted.
    sorted: Vec<(f64, u32)>,
    /// The intervals of an end order before [`EndOrder::reorder`].
    before: Vec<OrderedInterval>,
}

/// Sorts the end positions `order` by value in `ends` (`total_cmp`), then position (a total
/// order, so that every way of making an end order of the same ends agrees with
/// [`EndOrder::build`]'s sort), by insertion: for an order that nearly holds already.
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

/// The key of the canonical order of an end order's members: rank, then index.
fn canonical_key(ranks: &[u32], index: u32) -> u64 {
    (u64::from(ranks[index as usize]) << 32) | u64::from(index)
}

/// One interval of a [`EndOrder`]: from the end at `from` to the end at `to` (positions in the
/// ends), with σ = Σσᵢ and E = S·(1/σ) of its particles.
#[derive(Debug, Clone, Copy)]
struct OrderedInterval {
    from: u32,
    to: u32,
    sigma: f64,
    emission: DVec3,
    /// The open set: the bits of its particles (members in canonical order).
    mask: u64,
    /// The place of `from` in the end order's order.
    at: u32,
}

impl EndOrder {
    /// Whether the end order holds for a ray with these `members` and `ends` (type docs).
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

    /// Whether the end order was built for these particles and members (in any order of ends).
    fn same_members(&self, particles: &[Particle], members: &[u32]) -> bool {
        self.same_scene(particles) && self.members == members
    }

    /// Whether the end order was built (and not forgotten) for these particles.
    fn same_scene(&self, particles: &[Particle]) -> bool {
        self.valid && self.scene == (particles.as_ptr() as usize, particles.len())
    }

    /// A new end order of a ray with these `members` and `ends`: the members' bits and terms in
    /// canonical order (rank, then index; bit b of the mask is the b-th), the ends sorted,
    /// and [`EndOrder::form_intervals`]. At most [`MAX_CHORDS`] members.
    fn build(
        &mut self,
        particles: &[Particle],
        ranks: &[u32],
        (members, ends): (&[u32], &[f64]),
        work: &mut OrderWork,
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

    /// [`EndOrder::build`] from the end order of the shadow ray before, `neighbour`, where the
    /// members are its members with one more or one fewer (a segment that starts at a kink,
    /// where one sphere begins or ceases to shade: three in four new end orders on 1UUN lit
    /// 128²), without sorting anew. The canonical order and the terms are the neighbour's with
    /// that member put in at its key or taken out; the order of the ends is the neighbour's
    /// (positions renumbered), with the new member's ends appended, re-sorted by insertion;
    /// then [`EndOrder::form_intervals`]. The same end order as [`EndOrder::build`] makes (a test
    /// compares them), and whether only the intervals about the changed member were formed
    /// ([`Near::Spliced`]); `None`, with nothing built, where the members are another case.
    fn build_near(
        &mut self,
        neighbour: &EndOrder,
        particles: &[Particle],
        ranks: &[u32],
        (members, ends): (&[u32], &[f64]),
    ) -> Option<Near> {
        let old = &neighbour.members;
        if !neighbour.same_scene(particles) || neighbour.general {
            return None;
        }
        // The place where the member lists part, and whether one was put in there.
        let part = old.iter().zip(members).position(|(a, b)| a != b);
        let (at, inserted) = if members.len() == old.len() + 1 {
            let at = part.unwrap_or(old.len());
            if old[at..] != members[at + 1..] {
                return None;
            }
            (at, true)
        } else if members.len() + 1 == old.len() {
            let at = part.unwrap_or(members.len());
            if old[at + 1..] != members[at..] {
                return None;
            }
            (at, false)
        } else {
            return None;
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
        let mut by_bit = [0u32; MAX_CHORDS];
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
        // The changed member's bit: in this end order's canonical order where it was put in,
        // in the neighbour's where it was taken out.
        let changed = if inserted {
            self.bit[at]
        } else {
            neighbour.bit[at]
        };
        if self.splice(neighbour, ends, (at, inserted, changed), renumber_end) {
            return Some(Near::Spliced);
        }
        if inserted {
            self.order.extend([2 * at as u32, 2 * at as u32 + 1]);
        }
        sort_nearly_sorted(&mut self.order, ends);
        self.intervals.clear();
        self.form_intervals(ends, &[]);
        Some(Near::Sorted)
    }

    /// The first part of [`EndOrder::splice`]: puts the changed member's ends into `order` at
    /// their places (put in), or finds where they were in the neighbour's (taken out, both
    /// alone in their groups), and makes `new_group` the neighbour's with the same change.
    /// Returns those places (the final ones where put in: the second end is one further),
    /// or `None`, with `order` as it was, where the case is another one.
    fn place_changed_ends(
        &mut self,
        neighbour: &EndOrder,
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

    /// [`EndOrder::build_near`] where the neighbour's ends keep their order and groups and the
    /// member put in or taken out has both its ends alone in their groups (and the ends after
    /// a member put in started groups in the neighbour too): only the intervals about those
    /// ends change. `self` holds the members, bits and terms, and in `order` the
    /// neighbour's ends renumbered (without the member put in). Puts the member's ends in at
    /// their places (or finds where they were), checks every group against the new ends as
    /// [`EndOrder::fits`] does (with the sort's order within a group), and forms the intervals
    /// anew only from the group before the first changed end to the end after the last one;
    /// the intervals before and after are the neighbour's, their masks moved to the new bits
    /// and their sums kept: a mask without the changed member's bit sums the same terms in the
    /// same order, so the same bits. The same end order as [`EndOrder::build`] makes (tested). False,
    /// with `order` as it was given, where the case is another one; `new_group` and
    /// `intervals` are then left to [`EndOrder::form_intervals`].
    fn splice(
        &mut self,
        neighbour: &EndOrder,
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
        let moved = |iv: &OrderedInterval, by: i64| {
            let (from, to) = (renumber_end(iv.from), renumber_end(iv.to));
            debug_assert!((iv.mask & if inserted { 0 } else { changed }) == 0);
            OrderedInterval {
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

    /// The end order of the same members for ends that came in another order (two ends crossed
    /// between the nodes of a quadrature segment),
    /// in place: the order re-sorted by insertion from the old one, which it nearly is, and
    /// the intervals formed again, where an interval with the same open set as one of the
    /// old intervals about its place takes its sums (the same terms added in the same order:
    /// the same bits). The same end order as [`EndOrder::build`] would make; which way it was
    /// formed.
    fn reorder(&mut self, ends: &[f64], work: &mut OrderWork) -> Reorder {
        let sorted = sort_nearly_sorted(&mut self.order, ends);
        // Where a single end moved back by one place: two neighbours crossed.
        if let (1, Some(p)) = (sorted.moves, sorted.swapped) {
            if self.swap_neighbours(ends, p) {
                return Reorder::Swap;
            }
        }
        std::mem::swap(&mut self.intervals, &mut work.before);
        if let Some(touched) = sorted.touched {
            if self.reform_between(ends, touched, &work.before) {
                return Reorder::Reform;
            }
        }
        self.intervals.clear();
        self.form_intervals(ends, &work.before);
        Reorder::Full
    }

    /// [`EndOrder::reorder`] where the ends changed places only between places `p0` and `p1`
    /// of `order` (re-sorted) and no group changed outside them: the intervals `before` (the
    /// end order's until now) from the groups before and after stay as they are (the same ends
    /// in the same places, and the same ends before each, so the same open sets), and the
    /// intervals from the group before `p0` up to the first group after `p1` that also
    /// started a group before (a group of equal ends may have come apart just after `p1`)
    /// are formed anew ([`EndOrder::form_groups`]). The same end order as
    /// [`EndOrder::form_intervals`] would make (tested). False, with `intervals` empty and
    /// `new_group` to be formed again, where a group changed elsewhere or a sum was not
    /// finite before.
    fn reform_between(
        &mut self,
        ends: &[f64],
        (p0, p1): (usize, usize),
        before: &[OrderedInterval],
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
    /// [`SUMS_REACH`] of its place where there is one (the same terms in the same order).
    fn form_groups(
        &mut self,
        (lo, end): (usize, usize),
        mut open: u64,
        before: &[OrderedInterval],
    ) {
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
                let near = j.saturating_sub(SUMS_REACH)..before.len().min(j + SUMS_REACH + 1);
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
                self.intervals.push(OrderedInterval {
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

    /// [`EndOrder::reorder`] where the ends at places p and p + 1 of `order` have just been
    /// swapped, both alone in their groups, and no group changed elsewhere: three intervals
    /// change at most. The one that ended at p now ends at the other end; the one from p
    /// (open set m₀ with the end now at p toggled, m₀ the open set before p) is formed anew,
    /// or appears or goes; the one from p + 1 keeps its open set and sums and starts at the
    /// other end. The same intervals as [`EndOrder::form_intervals`] would form (a test
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
        let middle = OrderedInterval {
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

    /// The intervals of `order` (empty before): the sweep of `optics::cutter` over groups of
    /// equal ends (a chord cannot start and end in one group, since t1 > t0), with the open
    /// set as a bit mask whose bits are the members in canonical order, so that its sums run
    /// in that order; the sums of an interval are taken from one of `before` with the same
    /// open set within [`SUMS_REACH`] of its place, where there is one. A sum that is not
    /// finite: the general sweep.
    fn form_intervals(&mut self, ends: &[f64], before: &[OrderedInterval]) {
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

//! How a ray is cut into intervals with a constant set of particles (docs/design.md §3).
//!
//! Every chord end on the ray (where it enters or leaves a particle) is a cut. Inside one
//! interval the set of particles is fixed, so its extinction σ = Σσᵢ, its emission colour
//! E = Σσᵢ·Cᵢ / Σσᵢ (docs/design.md §2, emission model) and its single-scatter albedo
//! α = Σσᵢ·αᵢ / Σσᵢ are constants ([`medium_of`]).
//!
//! **Order independence.** Floating-point sums depend on their order, and the renderer promises
//! that shuffling the particle list changes no pixel. The sums therefore run over the set
//! sorted by a *canonical rank*: the position of the particle in a total order of its content
//! (σ, radius, centre, colour, albedo, then an ellipsoid's axes and orientation), which does
//! not depend on where it sits in the input ([`canonical_ranks`]). Particles with equal content are interchangeable, so ties cannot
//! change a sum either.
//!
//! **Θmax = 0 and Θmax = 1.** Particles with σ = 0 are invisible and left out. Where a particle
//! with σ = +∞ is present the interval has σ = +∞; its colour and albedo are the plain mean over
//! the infinite particles present (the limit of equal, growing σ), never ∞/∞.
//!
//! This file is the definition: [`cut_by_events`] is the plain event sweep. The renderers cut
//! with `optics::cutter`, which gives the same intervals bit for bit with less work (a test
//! there compares the two).

// `!(a > b)` is deliberate throughout: unlike `a <= b` it is also true when a value is NaN, so
// degenerate input takes the safe branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::particle::Particle;
use crate::geometry::{Chord, Hit};
use glam::DVec3;
use std::cmp::Ordering;

/// A piece [t0, t1] of a ray with a fixed set of particles: what the models of docs/design.md
/// §2 need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Ray parameter where the interval starts (m).
    pub t0: f64,
    /// Ray parameter where the interval ends (m), > t0.
    pub t1: f64,
    /// Extinction σ = Σσᵢ (1/m), > 0; +∞ where a Θmax = 1 particle is present.
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
    // An ellipsoid's semi-axes and orientation; a sphere's are all zero (and it sorts before
    // every ellipsoid of the same σ, radius, centre and colours).
    let shape_key = |p: &Particle| {
        p.ellipsoid.map_or([0.0; 7], |e| {
            let (s, q) = (e.semi_axes(), e.rotation());
            [s.x, s.y, s.z, q.w, q.x, q.y, q.z]
        })
    };
    let compare = |ka: &[f64], kb: &[f64]| {
        ka.iter()
            .zip(kb)
            .map(|(x, y)| x.total_cmp(y))
            .find(|o| *o != Ordering::Equal)
            .unwrap_or(Ordering::Equal)
    };
    let mut order: Vec<u32> = (0..particles.len() as u32).collect();
    // Sequential: the comparison is heavy, and a parallel sort makes more calls of it.
    order.sort_by(|&a, &b| {
        let (pa, pb) = (&particles[a as usize], &particles[b as usize]);
        compare(&key(pa), &key(pb)).then_with(|| compare(&shape_key(pa), &shape_key(pb)))
    });
    let mut rank = vec![0u32; particles.len()];
    for (r, &i) in order.iter().enumerate() {
        rank[i as usize] = r as u32;
    }
    rank
}

/// The chords of `hits` clipped to (t_min, t_max), of particles with σ > 0 that `skip` does not
/// name, as hits whose chord is the clipped one (t_enter < t_exit), in the order of `hits`.
#[inline]
pub fn clipped_chords<'a>(
    hits: &'a [Hit],
    (t_min, t_max): (f64, f64),
    particles: &'a [Particle],
    skip: impl Fn(u32) -> bool + 'a,
) -> impl Iterator<Item = Hit> + 'a {
    hits.iter().filter_map(move |h| {
        let p = &particles[h.index as usize];
        if !(p.sigma > 0.0) || skip(h.index) {
            return None;
        }
        let t_enter = h.chord.t_enter.max(t_min);
        let t_exit = h.chord.t_exit.min(t_max);
        (t_exit > t_enter).then_some(Hit {
            index: h.index,
            chord: Chord { t_enter, t_exit },
        })
    })
}

/// σ, E and α of a fixed set of particles on [t0, t1], the particles given by index (in
/// canonical rank order, or at most two of them, so the sums do not depend on the input order).
pub fn medium_of(
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

/// The intervals of the chords `chords` (already clipped, in any order; [`clipped_chords`]) by
/// the plain event sweep: every chord end is an event; the events are sorted by t; all events
/// at one t are applied to the set of present particles, kept sorted by (canonical rank, index),
/// before the interval up to the next event is formed with [`medium_of`]. Gaps without
/// particles form no interval.
pub fn cut_by_events(chords: &[Hit], particles: &[Particle], ranks: &[u32]) -> Vec<Interval> {
    // (t, key, enters)
    let mut events: Vec<(f64, (u32, u32), bool)> = Vec::with_capacity(2 * chords.len());
    for h in chords {
        let key = (ranks[h.index as usize], h.index);
        events.push((h.chord.t_enter, key, true));
        events.push((h.chord.t_exit, key, false));
    }
    // Only t matters for the order: all events at one t are applied before the next interval.
    events.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let mut present: Vec<(u32, u32)> = Vec::new();
    let mut out = Vec::new();
    let mut i = 0;
    while i < events.len() {
        let t = events[i].0;
        while i < events.len() && events[i].0 == t {
            let (_, key, enters) = events[i];
            match present.binary_search(&key) {
                Ok(pos) if !enters => {
                    present.remove(pos);
                }
                Err(pos) if enters => present.insert(pos, key),
                // An exit without entry (or a double entry) cannot happen for chords with
                // t_enter < t_exit; ignoring it keeps the sweep total rather than panicking.
                _ => {}
            }
            i += 1;
        }
        if present.is_empty() || i >= events.len() {
            continue;
        }
        let set = present.iter().map(|&(_, index)| index);
        out.push(medium_of(set, particles, t, events[i].0));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn particle(sigma: f64, color: DVec3) -> Particle {
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

    fn hit(index: u32, t_enter: f64, t_exit: f64) -> Hit {
        Hit {
            index,
            chord: Chord { t_enter, t_exit },
        }
    }

    #[test]
    fn overlapping_chords_give_three_intervals_with_summed_sigma() {
        let ps = vec![particle(1.0, DVec3::X), particle(3.0, DVec3::Y)];
        let ranks = canonical_ranks(&ps);
        let out = cut_by_events(&[hit(1, 2.0, 5.0), hit(0, 1.0, 3.0)], &ps, &ranks);
        assert_eq!(out.len(), 3);
        assert_eq!((out[0].t0, out[0].t1, out[0].sigma), (1.0, 2.0, 1.0));
        assert_eq!((out[1].t0, out[1].t1, out[1].sigma), (2.0, 3.0, 4.0));
        assert_eq!(out[1].emission, DVec3::new(0.25, 0.75, 0.0));
        assert_eq!((out[2].t0, out[2].t1, out[2].sigma), (3.0, 5.0, 3.0));
    }

    #[test]
    fn clipping_skipping_and_infinite_sigma() {
        let ps = vec![
            particle(f64::INFINITY, DVec3::X),
            particle(0.0, DVec3::Y),
            particle(2.0, DVec3::Z),
        ];
        let ranks = canonical_ranks(&ps);
        let hits = [hit(0, -1.0, 1.0), hit(1, 0.0, 4.0), hit(2, 0.5, 2.0)];
        let chords: Vec<Hit> = clipped_chords(&hits, (0.0, 1.5), &ps, |_| false).collect();
        assert_eq!(chords.len(), 2, "σ = 0 is left out");
        let out = cut_by_events(&chords, &ps, &ranks);
        assert_eq!(out.len(), 3);
        assert_eq!((out[0].t0, out[0].t1), (0.0, 0.5));
        assert!(out[0].sigma.is_infinite());
        assert_eq!(out[0].emission, DVec3::X);
        assert!(out[1].sigma.is_infinite());
        assert_eq!((out[2].t0, out[2].t1, out[2].sigma), (1.0, 1.5, 2.0));
        let chords: Vec<Hit> = clipped_chords(&hits, (0.0, 1.5), &ps, |i| i == 0).collect();
        let out = cut_by_events(&chords, &ps, &ranks);
        assert_eq!(out.len(), 1);
        assert_eq!((out[0].t0, out[0].t1, out[0].sigma), (0.5, 1.5, 2.0));
    }

    #[test]
    fn shuffled_particles_give_the_same_bits() {
        let ps = vec![
            particle(0.3, DVec3::new(0.1, 0.7, 0.2)),
            particle(1.7, DVec3::new(0.9, 0.3, 0.05)),
            particle(0.3, DVec3::new(0.4, 0.4, 0.9)),
        ];
        let hits = [hit(0, 0.0, 2.0), hit(1, 0.5, 3.0), hit(2, 1.0, 1.5)];
        let want = cut_by_events(&hits, &ps, &canonical_ranks(&ps));
        // The same particles in the order 2, 0, 1.
        let shuffled = vec![ps[2], ps[0], ps[1]];
        let moved = [hit(1, 0.0, 2.0), hit(2, 0.5, 3.0), hit(0, 1.0, 1.5)];
        let got = cut_by_events(&moved, &shuffled, &canonical_ranks(&shuffled));
        assert_eq!(got, want);
        // Overlap of three at [1, 1.5]: σ = 2.3.
        assert_eq!(got[2].sigma, 0.3 + 0.3 + 1.7);
    }
}

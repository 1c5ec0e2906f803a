//! The end orders of [`KeptEndOrders`] give the plain sweep's composite bit for bit
//! ([`PlainSweep`]), and every end order made in place (reordered, spliced, made from a
//! neighbour) is the one a fresh build makes.

use super::*;
use crate::optics::cutter::tests::{hit, particle, random_particles};

/// The composite through kept end orders is the sweep's, bit for bit: on shadow rays that
/// follow one another as the nodes of a quadrature segment do (the same chords, ends that
/// move a little, so that their order sometimes changes), with ends that coincide (chords
/// clipped at 0, and a grid of values), a σ = ∞ particle, more than 64 chords, the stop at
/// ε, and hit lists that change between rays (other members, other order).
#[test]
fn kept_end_orders_give_the_sweeps_composite_bit_for_bit() {
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
    let mut kept = KeptEndOrders::default();
    let (mut reused, mut seeded, mut built, mut general) = (0, 0, 0, 0);
    let (mut swaps, mut reforms, mut nears, mut splices) = (0, 0, 0, 0);
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
            // Node 6 leaves out one chord (a new end order next to node 5's if that one
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
            if members.len() > MAX_CHORDS {
                general += 1;
            } else if kept.orders.iter().any(|l| l.fits(&ps, &members, &ends)) {
                reused += 1;
            } else if kept.orders.iter().any(|l| l.same_members(&ps, &members)) {
                seeded += 1;
            } else {
                built += 1;
            }
            let (got, path) =
                kept.composite_with_path(&cutter, &hits, range, skip, (background, cut));
            match path {
                Path::Reordered(Reorder::Swap) => swaps += 1,
                Path::Reordered(Reorder::Reform) => reforms += 1,
                Path::Near(near) => {
                    nears += 1;
                    splices += usize::from(near == Near::Spliced);
                }
                _ => {}
            }
            if members.len() <= MAX_CHORDS {
                general += usize::from(kept.orders[0].general);
                // A kept, reordered or patched end order is the one a new build makes.
                let mut fresh = EndOrder::default();
                let mut work = OrderWork::default();
                fresh.build(&ps, cutter.ranks(), (&members, &ends), &mut work);
                assert_eq!(
                    order_bits(&kept.orders[0]),
                    order_bits(&fresh),
                    "trial {trial}, node {node}"
                );
            }
            let want =
                PlainSweep::default().composite(&cutter, &hits, range, skip, (background, cut));
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
    assert!(
        swaps > 50 && swaps < seeded,
        "{swaps} of {seeded} reorders were one swap"
    );
    assert!(
        nears > 50 && nears < built,
        "{nears} of {built} new end orders from a neighbour"
    );
    assert!(
        reforms > 20 && reforms + swaps < seeded,
        "{reforms} of {seeded} reorders formed only the groups about the changes"
    );
    assert!(
        splices > 20 && splices < nears,
        "{splices} of {nears} end orders from a neighbour spliced"
    );
}

/// Runs `steps` random changes to a hit list (a chord put in or taken out at the front,
/// in the middle or at the back; ends moved a little or a lot, ends on a grid and
/// clipped at 0 that coincide), composites each through one scratch, and compares its
/// end order with a fresh build of the same ray. Returns the first difference, and how many
/// end orders were spliced and reformed.
fn end_orders_through_changes(seed: u64, steps: usize) -> Result<(usize, usize), String> {
    type Rng = crate::formats::random::SplitMix64;
    let mut rng = Rng::new(seed);
    let ps = random_particles(&mut rng, 24, 2.0, (0.05, 3.0));
    let cutter = IntervalCutter::new(&ps);
    let mut kept = KeptEndOrders::default();
    let pick = |rng: &mut Rng, n: usize| ((rng.next_f64() * n as f64) as usize).min(n - 1);
    // On the grid of quarters: `+ 0.0` makes a −0 of the rounding +0. (Where two ends are
    // −0 and +0, a kept end order may hold them in either order, since `==` cannot tell them
    // apart; the composite is the same, but not the end order's bits this test compares.)
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
    let (mut splices, mut reforms) = (0, 0);
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
        let before = kept.orders.first().map(order_bits);
        let (_, path) =
            kept.composite_with_path(&cutter, &hits, range, |_| false, (DVec3::ONE, None));
        splices += usize::from(path == Path::Near(Near::Spliced));
        reforms += usize::from(path == Path::Reordered(Reorder::Reform));
        // The composite's own ends: `t.max(0.0)` of a chord that starts at −0 may give
        // either zero, depending on how the compiler ordered the operands where it was
        // inlined (a group of equal ends sorts −0 first, and the composite is the same).
        let (members, ends) = (&kept.members, &kept.ends);
        let mut fresh = EndOrder::default();
        fresh.build(
            &ps,
            cutter.ranks(),
            (members, ends),
            &mut OrderWork::default(),
        );
        let (got, want) = (order_bits(&kept.orders[0]), order_bits(&fresh));
        if got != want {
            return Err(format!(
                "step {step}: members {members:?}, ends {ends:?}\n got {got:?}\nwant {want:?}\nlayout before {before:?}"
            ));
        }
    }
    Ok((splices, reforms))
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

    /// End orders changed in place ([`EndOrder::splice`] where a chord is put in or taken out,
    /// [`EndOrder::reform_between`] where ends moved within a stretch, the other reorders)
    /// are the end orders a fresh build makes, bit for bit, through a sequence of changes.
    #[test]
    fn end_orders_changed_in_place_are_the_fresh_builds(seed in 0u64..u64::MAX, steps in 20usize..80) {
        let paths = end_orders_through_changes(seed, steps);
        proptest::prop_assert!(paths.is_ok(), "{}", paths.unwrap_err());
    }
}

/// [`end_orders_through_changes`] on fixed seeds: no difference, and both in-place paths
/// taken many times (so that the property test above tests them).
#[test]
fn fixed_change_sequences_splice_and_reform_end_orders() {
    let (mut splices, mut reforms) = (0, 0);
    for seed in 0..60 {
        let (s, r) = end_orders_through_changes(seed, 60).unwrap_or_else(|e| panic!("{e}"));
        splices += s;
        reforms += r;
    }
    assert!(
        splices > 200 && reforms > 100,
        "{splices} spliced, {reforms} reformed"
    );
}

/// The two ways a group of equal ends (chords clipped at 0) that comes apart could leave
/// an interval out of an end order changed in place: a reorder whose last change is just
/// before an end that was in such a group (1UUN's dark roof found it), and a chord put in
/// between two ends that were one group. Each end order is the fresh build's.
#[test]
fn groups_that_come_apart_are_formed_anew() {
    let ps: Vec<Particle> = (0..4)
        .map(|i| particle(0.5 + i as f64, DVec3::new(0.1, 0.2 * i as f64, 0.3)))
        .collect();
    let cutter = IntervalCutter::new(&ps);
    let ranks = cutter.ranks();
    let fresh = |members: &[u32], ends: &[f64]| {
        let mut l = EndOrder::default();
        l.build(&ps, ranks, (members, ends), &mut OrderWork::default());
        order_bits(&l)
    };
    // Three chords from 0; then the first two starts swap and the third comes apart.
    let members = [0, 1, 2];
    let mut l = EndOrder::default();
    let mut work = OrderWork::default();
    l.build(
        &ps,
        ranks,
        (&members, &[0.0, 1.0, 0.0, 2.0, 0.0, 3.0]),
        &mut work,
    );
    let ends = [0.3, 1.0, 0.0, 2.0, 0.4, 3.0];
    let path = l.reorder(&ends, &mut work);
    assert_eq!(order_bits(&l), fresh(&members, &ends));
    assert_eq!(path, Reorder::Reform, "the reform path");
    // Two chords from 0; then the second starts later and a third lies between.
    let mut neighbour = EndOrder::default();
    neighbour.build(&ps, ranks, (&[0, 1], &[0.0, 1.0, 0.0, 2.0]), &mut work);
    let (members, ends) = ([0, 3, 1], [0.0, 1.0, 0.25, 0.3, 0.5, 2.0]);
    let mut near = EndOrder::default();
    assert!(near
        .build_near(&neighbour, &ps, ranks, (&members, &ends))
        .is_some());
    assert_eq!(order_bits(&near), fresh(&members, &ends));
}

/// Everything of an end order that its composites read, as bits.
#[allow(clippy::type_complexity)]
fn order_bits(
    l: &EndOrder,
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

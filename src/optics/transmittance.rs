//! The transmittance alone of a ray through overlapping particles (docs/design.md §2): what a model
//! that reads only E_l·T_l of a shadow ray (single-scatter, `LightNeed::IrradianceTransmittance`)
//! needs, without the interval cut and the emission composite of `cutter`.
//!
//! T = e^{−τ} with τ = Σᵢ σᵢ·|chordᵢ ∩ (t_min, t_max)|: the optical depth ∫Σσᵢ written per
//! particle instead of per interval (∫Σσᵢ = Σ∫σᵢ), so no sort by position, no sweep over the
//! chord ends and one exponential instead of one per interval. The composite's transmittance is the product of the
//! intervals' e^{−σΔ}; the two agree to rounding (a test in `cutter` compares them).

// `!(a > b)` is deliberate: unlike `a <= b` it is also true when σ is NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::cutter::IntervalCutter;
use crate::geometry::Hit;

/// e^{−τ} along the part (t_min, t_max) of a ray crossing the spheres `hits` (any order), the
/// particles with σ = 0 and those `skip` names left out, as the interval cut leaves them out.
/// The terms σᵢ·lengthᵢ are summed in canonical rank order (`IntervalCutter::ranks`), so
/// shuffling the particles changes no bit; a Θmax = 1 particle with a chord of positive length
/// gives exactly 0. `depths` is a buffer.
pub fn transmittance(
    cutter: &IntervalCutter,
    hits: &[Hit],
    (t_min, t_max): (f64, f64),
    skip: impl Fn(u32) -> bool,
    depths: &mut Vec<(u32, f64)>,
) -> f64 {
    let (particles, ranks) = (cutter.particles(), cutter.ranks());
    depths.clear();
    for h in hits {
        let p = &particles[h.index as usize];
        if !(p.sigma > 0.0) || skip(h.index) {
            continue;
        }
        let length = h.chord.t_exit.min(t_max) - h.chord.t_enter.max(t_min);
        if length > 0.0 {
            if p.sigma.is_infinite() {
                return 0.0;
            }
            depths.push((ranks[h.index as usize], p.sigma * length));
        }
    }
    depths.sort_unstable_by_key(|&(rank, _)| rank);
    let tau = depths.iter().fold(0.0, |sum, &(_, depth)| sum + depth);
    (-tau).exp()
}

//! Shadow rays of the volume renderer (docs/design.md §2, lit and single-scatter models): from a
//! point x towards a light, the emission model along the ray with the light's irradiance as its
//! background (L_l(x)), or its transmittance alone (T_l(x)).
//!
//! Two pieces of speed machinery serve them, each behind a small interface with a plain
//! reference beside it:
//!
//! * which spheres a shadow ray crosses: [`Occluders`] (`occluders.rs`), lists of candidates
//!   gathered once per piece of a camera ray, with the same hits, in the same order, as a
//!   traversal of the whole BVH (`Bvh::all_hits`, the reference; tested);
//! * the composite along the ray: a [`ShadowCompositor`], either [`PlainSweep`] (the interval
//!   sweep of `optics::cutter`, the reference) or [`KeptEndOrders`] (`end_orders.rs`), which
//!   reuses the order of chord ends of recent shadow rays and gives the same bits (tested in
//!   `end_orders/equiv_tests.rs`).

mod end_orders;
mod occluders;

pub use end_orders::KeptEndOrders;
pub use occluders::{Occluders, ShadowRay};

use crate::geometry::Hit;
use crate::optics::cutter::{IntervalCutter, SweepScratch};
use crate::optics::emission::{Composite, FrontToBack};
use glam::DVec3;

/// The emission model along a shadow ray (docs/design.md §2): the radiance that arrives at its
/// origin and the transmittance, given every sphere it crosses.
pub trait ShadowCompositor: Default {
    /// The composite along the part `range` = (t_min, t_max) of a ray crossing the spheres
    /// `hits` (any order) towards `background`, the particles that `skip` names left out.
    ///
    /// With `cut` = Some((ε, M)) it may stop where the transmittance has fallen to ε and take
    /// the middle of what lies behind ([`FrontToBack::finish`]); the flag says whether it did.
    fn composite(
        &mut self,
        cutter: &IntervalCutter,
        hits: &[Hit],
        range: (f64, f64),
        skip: impl Fn(u32) -> bool,
        background_and_cut: (DVec3, Option<(f64, DVec3)>),
    ) -> (Composite, bool);

    /// Forgets what is kept from earlier rays: for buffers that move on to another scene (what
    /// is kept names particles by index, which mean other particles there).
    fn forget(&mut self);
}

/// The reference [`ShadowCompositor`]: every ray swept anew ([`IntervalCutter::composite`]).
#[derive(Debug, Default, Clone)]
pub struct PlainSweep {
    sweep: SweepScratch,
}

impl ShadowCompositor for PlainSweep {
    fn composite(
        &mut self,
        cutter: &IntervalCutter,
        hits: &[Hit],
        range: (f64, f64),
        skip: impl Fn(u32) -> bool,
        (background, cut): (DVec3, Option<(f64, DVec3)>),
    ) -> (Composite, bool) {
        cutter
            .composite(hits, range, skip, &mut self.sweep, FrontToBack::new(cut))
            .finish(background, cut)
    }

    fn forget(&mut self) {}
}

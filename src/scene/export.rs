//! The rows of `pgt export` (docs/design.md §7): the resolved particles — centre,
//! radius, linear colour, extinction σ and opacity Θmax — exactly as pgt renders them (after
//! includes, defaults, `radius_scale`, filters and σ = λκ or −ln(1−Θmax)/(2r)), so that an
//! outside renderer draws the same data.
//!
//! * **CSV**: header `x,y,z,radius,red,green,blue,opacity,sigma`, one particle a line, every
//!   number in Rust's shortest round-trip notation (reading it back as f64 gives the same bits).
//!   σ = ∞ (Θmax = 1, a perfectly absorbing ball) is written `inf`, which C's `strtod`, Python's
//!   `float`, numpy and Rust's `f64::from_str` all read as +∞. The file is also a particle file
//!   pgt reads back without a warning: its CSV reader takes `sigma` as the particle's σ, bit for
//!   bit, and checks that `opacity` agrees with it (`crate::formats::xyz_csv`).
//! * **PLY**: `binary_little_endian 1.0`, one `vertex` element per particle with `double`
//!   properties `x y z radius red green blue opacity sigma`; σ = ∞ is the IEEE 754 +∞ double.
//!   pgt's PLY reader (`crate::formats::ply`) reads it back, σ bit for bit.
//!
//! Θmax = 1 − e^{−2rσ} (docs/design.md §1 inverted; for a particle given by κ it is the opacity that
//! the resolved σ has along a diameter).
//!
//! **Ellipsoids** (docs/design.md §9): where the scene has any, both formats replace `radius`
//! with the semi-axes `sx sy sz` and the unit quaternion `qw qx qy qz` (a sphere's row has three
//! equal semi-axes and the identity), the columns pgt's CSV reader takes, and Θmax is the
//! opacity along the shortest diameter (r the shortest semi-axis above).

//!
//! The writers themselves are the formats' ([`crate::formats::export`]).

use crate::formats::export::{self, ExportFormat};
use crate::scene::Particle;
use std::io::Write;

/// The column names, in the order both formats store them.
pub const COLUMNS: [&str; 9] = [
    "x", "y", "z", "radius", "red", "green", "blue", "opacity", "sigma",
];

/// The columns of a scene with ellipsoids, in the order both formats store them.
pub const ELLIPSOID_COLUMNS: [&str; 15] = [
    "x", "y", "z", "sx", "sy", "sz", "qw", "qx", "qy", "qz", "red", "green", "blue", "opacity",
    "sigma",
];

/// The columns for `particles`: [`ELLIPSOID_COLUMNS`] where any is an ellipsoid, else
/// [`COLUMNS`].
pub fn columns(particles: &[Particle]) -> &'static [&'static str] {
    if particles.iter().any(|p| p.ellipsoid.is_some()) {
        &ELLIPSOID_COLUMNS
    } else {
        &COLUMNS
    }
}

/// Θmax = 1 − e^{−2rσ}, the opacity along a diameter (docs/design.md §1), the shortest one of an
/// ellipsoid (§9); for a Gaussian 1 − e^{−√(2π)·s_min·σ}, the opacity through its centre along
/// its shortest axis (§9, "The opacity of a Gaussian"); 1 for σ = ∞. `expm1` keeps small
/// opacities exact.
pub fn opacity_of(p: &Particle) -> f64 {
    let r = p.ellipsoid.map_or(p.radius, |e| e.shortest_semi_axis());
    let depth = p.profile.centre_depth(r, p.sigma);
    if p.sigma == f64::INFINITY {
        1.0
    } else {
        -(-depth).exp_m1()
    }
}

/// A particle's row, in [`COLUMNS`] order.
pub fn row(p: &Particle) -> [f64; 9] {
    [
        p.center.x,
        p.center.y,
        p.center.z,
        p.radius,
        p.color.x,
        p.color.y,
        p.color.z,
        opacity_of(p),
        p.sigma,
    ]
}

/// A particle's row, in [`ELLIPSOID_COLUMNS`] order.
pub fn ellipsoid_row(p: &Particle) -> [f64; 15] {
    let (s, q) = p
        .ellipsoid
        .map_or((glam::DVec3::splat(p.radius), glam::DQuat::IDENTITY), |e| {
            (e.semi_axes(), e.rotation())
        });
    [
        p.center.x,
        p.center.y,
        p.center.z,
        s.x,
        s.y,
        s.z,
        q.w,
        q.x,
        q.y,
        q.z,
        p.color.x,
        p.color.y,
        p.color.z,
        opacity_of(p),
        p.sigma,
    ]
}

/// The rows of `particles` in the order of [`columns`].
fn rows(particles: &[Particle]) -> impl ExactSizeIterator<Item = Vec<f64>> + '_ {
    let ellipsoids = columns(particles).len() == ELLIPSOID_COLUMNS.len();
    particles.iter().map(move |p| {
        if ellipsoids {
            ellipsoid_row(p).to_vec()
        } else {
            row(p).to_vec()
        }
    })
}

/// Writes `particles` in `format`, with the columns of [`columns`].
pub fn write_particles(
    w: &mut impl Write,
    format: ExportFormat,
    particles: &[Particle],
) -> std::io::Result<()> {
    match format {
        ExportFormat::Csv => export::write_csv(w, columns(particles), rows(particles)),
        ExportFormat::Ply => export::write_ply(w, columns(particles), rows(particles)),
    }
}

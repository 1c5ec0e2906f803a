//! A particle as the renderers see it (docs/design.md §1, §9): a sphere or an ellipsoid with its
//! extinction σ already resolved from Θmax or κ (`extinction`), its density profile (constant or
//! Gaussian) and its colours.

pub use crate::formats::Profile;
use crate::geometry::{Ellipsoid, Shape};
use glam::DVec3;

/// One particle, resolved: σ computed from Θmax or κ, defaults applied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle {
    /// Centre in metres.
    pub center: DVec3,
    /// Radius in metres, > 0: the sphere's, or for an ellipsoid its longest semi-axis (the
    /// radius of the bounding sphere about the centre).
    pub radius: f64,
    /// Linear RGB colour C ≥ 0 (emission colour in volume mode, albedo-diffuse in opaque mode).
    pub color: DVec3,
    /// Extinction σ = λκ = −ln(1−Θmax)/(2r) in 1/m (docs/design.md §1, thesis eq. 5.1,
    /// [`super::extinction::Extinction::sigma`]), r the shortest semi-axis of an ellipsoid
    /// (docs/design.md §9); may be +∞ (Θmax = 1) or 0 (Θmax = 0).
    pub sigma: f64,
    /// Single-scatter albedo (defaults to `color`).
    pub albedo: DVec3,
    /// Blinn–Phong specular weight (opaque mode).
    pub ks: f64,
    /// Blinn–Phong exponent (opaque mode).
    pub shininess: f64,
    /// `Some` for an ellipsoid (its semi-axes and orientation about `center`), `None` for a
    /// sphere.
    pub ellipsoid: Option<Ellipsoid>,
    /// How the density varies inside the particle (docs/design.md §9).
    pub profile: Profile,
}

impl Particle {
    /// The particle's shape: every geometric question goes through it.
    #[inline]
    pub fn shape(&self) -> Shape<'_> {
        match &self.ellipsoid {
            None => Shape::Sphere {
                center: self.center,
                radius: self.radius,
            },
            Some(ellipsoid) => Shape::Ellipsoid {
                center: self.center,
                ellipsoid,
            },
        }
    }
}

//! A particle as the renderers see it (docs/design.md §1): a sphere with its extinction σ already
//! resolved from Θmax or κ (`extinction`), and its colours.

use glam::DVec3;

/// One sphere, resolved: σ computed from Θmax or κ, defaults applied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle {
    /// Centre in metres.
    pub center: DVec3,
    /// Radius in metres, > 0.
    pub radius: f64,
    /// Linear RGB colour C ≥ 0 (emission colour in volume mode, albedo-diffuse in opaque mode).
    pub color: DVec3,
    /// Extinction σ = λκ = −ln(1−Θmax)/(2r) in 1/m (docs/design.md §1, thesis eq. 5.1,
    /// [`super::extinction::Extinction::sigma`]); may be +∞ (Θmax = 1) or 0 (Θmax = 0).
    pub sigma: f64,
    /// Single-scatter albedo (defaults to `color`).
    pub albedo: DVec3,
    /// Blinn–Phong specular weight (opaque mode).
    pub ks: f64,
    /// Blinn–Phong exponent (opaque mode).
    pub shininess: f64,
}

//! The default scene for a bare particle file (docs/design.md §1).

use crate::geometry::Camera;
use crate::optics::light::Light;
use crate::optics::particle::Particle;
use crate::optics::Profile;
use glam::DVec3;

/// Vertical field of view of the default camera, degrees.
pub const DEFAULT_FOV_Y: f64 = 40.0;
/// Default image size.
pub const DEFAULT_SIZE: (u32, u32) = (512, 512);
/// The framed bounding sphere fills this fraction of the vertical field of view.
const FRAMING_MARGIN: f64 = 1.05;

/// A camera on the −z side of the particles' bounding sphere, looking along +z, at the distance
/// where the sphere just fits the vertical field of view (with a 5 % margin).
pub fn default_camera(particles: &[Particle], width: u32, height: u32) -> Camera {
    let (center, radius) = bounding_sphere(particles);
    let half = (DEFAULT_FOV_Y.to_radians() * 0.5).sin();
    let distance = (radius * FRAMING_MARGIN / half).max(1e-9);
    Camera::new(
        center - DVec3::Z * distance,
        center,
        DVec3::Y,
        DEFAULT_FOV_Y,
        width,
        height,
    )
}

/// Standard deviations of a Gaussian particle that framing and the near plane hold (docs/design.md
/// §1 "Default framing"): the footprint splatting rasterisers draw.
pub const GAUSSIAN_EXTENT_SIGMAS: f64 = 3.0;

/// The radius of the sphere about a particle's centre that framing and the near/far planes hold:
/// its bounding radius, or [`GAUSSIAN_EXTENT_SIGMAS`] times it for a Gaussian (whose radius is a
/// standard deviation).
pub fn extent_radius(p: &Particle) -> f64 {
    match p.profile {
        Profile::Gaussian => GAUSSIAN_EXTENT_SIGMAS * p.radius,
        _ => p.radius,
    }
}

/// The centre of the particles' bounding box and the radius of the sphere around it that holds
/// every particle whole ([`extent_radius`]). An empty set gives the unit sphere at the origin.
pub fn bounding_sphere(particles: &[Particle]) -> (DVec3, f64) {
    if particles.is_empty() {
        return (DVec3::ZERO, 1.0);
    }
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in particles {
        lo = lo.min(p.center - DVec3::splat(extent_radius(p)));
        hi = hi.max(p.center + DVec3::splat(extent_radius(p)));
    }
    let center = 0.5 * (lo + hi);
    let radius = particles
        .iter()
        .map(|p| (p.center - center).length() + extent_radius(p))
        .fold(0.0, f64::max);
    (center, radius)
}

/// The thesis's two directional lights: green from above, blue from below (irradiance 1).
pub fn thesis_lights() -> Vec<Light> {
    vec![
        Light::Directional {
            direction: DVec3::NEG_Y,
            irradiance: DVec3::new(0.0, 1.0, 0.0),
        },
        Light::Directional {
            direction: DVec3::Y,
            irradiance: DVec3::new(0.0, 0.0, 1.0),
        },
    ]
}

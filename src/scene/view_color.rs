//! The view-dependent colour of 3D Gaussian splatting particles (`sh = "view"`, docs/design.md
//! §9 "3D Gaussian splatting PLY"), evaluated for the eye of the frame being rendered: the
//! scene keeps each include's SH coefficients ([`ShCoefficients`]) beside its particles, and
//! every frame's particles take the colour their coefficients give for that frame's camera
//! position (frame 0 when the scene is loaded, every other frame in
//! [`super::SceneFrames::frame`]). A still camera gives the colour the PLY reader computes
//! for the same eye, bit for bit; a camera sequence or an orbit gives each frame its own.
//! Particles without coefficients (spheres, the DC colour) pay nothing.

use crate::formats::ShCoefficients;
use crate::optics::particle::Particle;
use glam::DVec3;
use std::sync::Arc;

/// The SH coefficients of one run of a scene's particles (an include's), by index.
#[derive(Debug, Clone)]
pub(super) struct ShRun {
    /// The run's particles in frame 0's particle list.
    pub range: std::ops::Range<usize>,
    pub sh: Arc<ShCoefficients>,
}

/// Gives `particles` (a run with one coefficient entry each, in order) the colour of their
/// coefficients seen from `eye`; the albedo follows the colour where `albedo_follows` (no
/// `[defaults] albedo`: a particle's albedo is its colour, as when it was made).
pub(super) fn recolor(
    particles: &mut [Particle],
    sh: &ShCoefficients,
    eye: DVec3,
    albedo_follows: bool,
) {
    debug_assert_eq!(particles.len(), sh.len());
    for (i, p) in particles.iter_mut().enumerate() {
        p.color = sh.color(i, p.center, eye);
        if albedo_follows {
            p.albedo = p.color;
        }
    }
}

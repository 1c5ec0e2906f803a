//! The quadrature's error estimate is honest (DESIGN.md §3): against a tol = 1e-10 render the
//! actual error is within the estimate at ≥ 99.9 % of pixel channels, at tol = 1e-4 and 1e-6,
//! and the summed estimate itself meets tol.

mod volume_support;

use glam::DVec3;
use pgt::optics::{models, OpticalModel};
use pgt::reference::volume::VolumeRenderer;
use pgt::reference::{Integrator, RadianceEstimator, Sample};
use pgt::scene::Scene;
use volume_support::*;

const SIZE: u32 = 32;

fn render_f64(scene: &Scene) -> Vec<Sample> {
    let r = VolumeRenderer::new(scene, Integrator::Adaptive);
    let mut out = Vec::with_capacity((SIZE * SIZE) as usize);
    for py in 0..SIZE {
        for px in 0..SIZE {
            out.push(r.radiance(&scene.camera.pixel_ray(px, py)));
        }
    }
    out
}

/// A 32×32 render of six overlapping particles, a directional and a point light, at tol 1e-4 and
/// 1e-6, against the same render at tol 1e-10.
fn honest_at(model: OpticalModel, seed: u64) {
    let mut rng = Rng::new(seed);
    let mut s = scene(model, random_particles(&mut rng, 6), two_lights(), SIZE);
    s.camera = pgt::geometry::Camera::new(
        DVec3::new(0.5, 0.8, -6.0),
        DVec3::ZERO,
        DVec3::Y,
        45.0,
        SIZE,
        SIZE,
    );
    s.render.tol = 1e-10;
    let truth = render_f64(&s);
    let covered = truth
        .iter()
        .filter(|t| t.radiance != s.render.background)
        .count();
    assert!(
        covered > 150,
        "the particles should cover a good part of the image: {covered}"
    );
    for tol in [1e-4, 1e-6] {
        s.render.tol = tol;
        let got = render_f64(&s);
        let mut violations = 0;
        let mut worst = 0.0f64;
        for (pix, (g, t)) in got.iter().zip(&truth).enumerate() {
            assert!(
                g.error.max_element() <= tol * (1.0 + 1e-9),
                "estimate {:?} above tol {tol}",
                g.error
            );
            for c in 0..3 {
                let actual = (g.radiance[c] - t.radiance[c]).abs();
                worst = worst.max(actual / tol);
                if actual > g.error[c] + t.error[c] {
                    eprintln!(
                        "  pixel {pix} channel {c}: actual {actual:.3e} > estimate {:.3e}",
                        g.error[c]
                    );
                    violations += 1;
                }
            }
        }
        let mean_estimate =
            got.iter().map(|g| g.error.element_sum()).sum::<f64>() / (3 * SIZE * SIZE) as f64;
        eprintln!("{model:?} tol {tol}: {violations} violations, worst actual {worst:.3e}·tol, mean estimate {mean_estimate:.3e}");
        let allowed = (3 * SIZE * SIZE) as usize / 1000;
        assert!(
            violations <= allowed,
            "{model:?} tol {tol}: {violations} of {} channels exceed their estimate",
            3 * SIZE * SIZE
        );
        // And the estimate is not vacuous: the result is within tol of the truth everywhere.
        assert!(
            worst <= 1.0,
            "{model:?} tol {tol}: worst actual error {worst}·tol"
        );
    }
}

#[test]
fn error_estimate_is_honest_for_the_lit_model() {
    for seed in [11, 21, 31] {
        honest_at(models::LIT, seed);
    }
}

#[test]
fn error_estimate_is_honest_for_the_single_scatter_model() {
    for seed in [12, 22] {
        honest_at(models::SINGLE_SCATTER, seed);
    }
}

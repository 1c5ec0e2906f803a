//! Huge σ (docs/design.md §3, issue 10): where the skin depth 1/σ falls below the f64 resolution of
//! the ray parameter, the reference converges to the Θmax = 1 limit (with its O(1/σ) remainder
//! in err), never to a collapsed quadrature; also where two huge σ add up to ∞ in an overlap.

use crate::support::volume::*;
use glam::DVec3;
use pgt::geometry::Ray;
use pgt::optics::{models, Light, Model};
use pgt::reference::Integrator;

fn lights() -> Vec<Light> {
    vec![Light::Directional {
        direction: DVec3::new(0.3, -1.0, 0.4).normalize(),
        irradiance: DVec3::new(0.3, 1.0, 0.6),
    }]
}

/// Camera rays at a few angles through a unit sphere seen from `distance`.
fn rays(distance: f64) -> Vec<Ray> {
    let o = DVec3::new(0.0, 0.0, -distance);
    [(0.0, 0.0), (0.3, 0.1), (-0.5, 0.6), (0.7, -0.2)]
        .iter()
        .map(|&(x, y)| Ray::new(o, DVec3::new(x, y, 0.0) - o))
        .collect()
}

/// κ from 1e7 to 1e300 (σ = κ here) on a unit sphere, lit and single-scatter, camera 8 m and
/// 1e4 m away: the pixel is the Θmax = 1 value within err, and err is small.
#[test]
fn huge_sigma_converges_to_the_opaque_limit() {
    for model in [models::LIT, models::SINGLE_SCATTER] {
        for distance in [8.0, 1e4] {
            for ray in rays(distance) {
                let limit_scene = one_sphere(model, f64::INFINITY);
                let limit = radiance(&limit_scene, Integrator::Adaptive, &ray);
                assert!(limit.radiance.is_finite());
                for sigma in [1e7, 1e10, 1e13, 1e16, 1e20, 1e100, 1e300] {
                    let s = one_sphere(model, sigma);
                    let got = radiance(&s, Integrator::Adaptive, &ray);
                    let diff = (got.radiance - limit.radiance).abs();
                    // The finite-σ value itself differs from the limit by O(1/σ).
                    let allowed = got.error + limit.error + DVec3::splat(1e-9 + 10.0 / sigma);
                    assert!(
                        diff.cmple(allowed).all(),
                        "{} σ {sigma:e} at {distance} m: {:?} vs limit {:?} (err {:?})",
                        model.name(),
                        got.radiance,
                        limit.radiance,
                        got.error
                    );
                    assert!(
                        got.error.max_element() <= 1e-3,
                        "{} σ {sigma:e}: err {:?} should be small",
                        model.name(),
                        got.error
                    );
                }
            }
        }
    }
}

/// Two overlapping spheres of σ = 1e308 each (their sum overflows to ∞) give the limit of two
/// overlapping Θmax = 1 spheres.
#[test]
fn overlapping_huge_sigmas_that_add_to_infinity_give_the_limit() {
    let build = |sigma: f64| {
        let mut s = scene(
            models::LIT,
            vec![
                particle(DVec3::ZERO, 1.0, DVec3::new(0.9, 0.2, 0.1), sigma),
                particle(
                    DVec3::new(0.0, 0.0, 0.05),
                    1.0,
                    DVec3::new(0.9, 0.2, 0.1),
                    sigma,
                ),
            ],
            lights(),
            8,
        );
        s.render.tol = 1e-8;
        s
    };
    let (huge, opaque) = (build(1e308), build(f64::INFINITY));
    for ray in rays(8.0) {
        let a = radiance(&huge, Integrator::Adaptive, &ray);
        let b = radiance(&opaque, Integrator::Adaptive, &ray);
        assert!(a.radiance.is_finite());
        let diff = (a.radiance - b.radiance).abs();
        assert!(
            diff.cmple(a.error + b.error + DVec3::splat(1e-12)).all(),
            "{:?} vs {:?}",
            a.radiance,
            b.radiance
        );
    }
}

fn one_sphere(model: Model, sigma: f64) -> pgt::scene::Scene {
    let mut s = scene(
        model,
        vec![particle(DVec3::ZERO, 1.0, DVec3::new(0.8, 0.3, 0.5), sigma)],
        lights(),
        8,
    );
    s.render.tol = 1e-8;
    s
}

/// docs/design.md §3: a pixel that does not converge is reported, not hidden. The centre pixel's ray
/// runs exactly through a point light inside gas (∫ dt/t² diverges there): the render counts it
/// and names it as the worst, and the CLI's warning says so.
#[test]
fn a_ray_through_a_point_light_inside_gas_is_reported() {
    let lights = vec![Light::Point {
        position: DVec3::ZERO,
        intensity: DVec3::splat(0.1),
        falloff: pgt::optics::Falloff::InverseSquare,
    }];
    let mut s = scene(
        models::LIT,
        vec![particle(DVec3::ZERO, 1.0, DVec3::ONE, 0.7)],
        lights,
        3,
    );
    s.render.tol = 1e-4;
    let out = pgt::reference::render(&s, &pgt::reference::RenderOptions::default()).unwrap();
    let st = &out.stats;
    assert!(st.unconverged >= 1, "{st:?}");
    let (x, y, e) = st.worst_unconverged.unwrap();
    assert_eq!((x, y), (1, 1));
    assert!(e > s.render.tol);
    let warning = pgt::reference::unconverged_warning(st, s.render.tol).unwrap();
    assert!(warning.contains("(1, 1)") && warning.contains("did not reach tol"));
    // Everything else converged, and a converged render has no warning.
    s.lights = vec![Light::Directional {
        direction: DVec3::NEG_Y,
        irradiance: DVec3::ONE,
    }];
    let out = pgt::reference::render(&s, &pgt::reference::RenderOptions::default()).unwrap();
    assert_eq!(out.stats.unconverged, 0);
    assert!(pgt::reference::unconverged_warning(&out.stats, s.render.tol).is_none());
}

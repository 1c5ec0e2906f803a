//! Closed-form oracles, limits and bad input for the volume renderer (docs/design.md §2, §3).

use crate::support::volume::Rng;
use crate::support::volume::*;
use glam::DVec3;
use pgt::geometry::Ray;
use pgt::optics::extinction::sigma_from_opacity;
use pgt::optics::models;
use pgt::optics::{Falloff, Light};
use pgt::reference::volume::VolumeRenderer;
use pgt::reference::{render, render_with, Integrator, RadianceEstimator, RenderOptions};
use proptest::prelude::*;

/// docs/design.md §2: one particle alone gives exactly L = L_bg·T + C·(1 − T), T = e^{−σ·chord},
/// along every ray; the chord comes from the distance b of the centre to the ray, 2√(r² − b²).
#[test]
fn one_sphere_emission_is_the_closed_form_along_every_ray() {
    let (c, r, sigma) = (DVec3::new(0.3, -0.2, 0.5), 1.3, 0.9);
    let color = DVec3::new(1.0, 0.4, 0.1);
    let s = scene(
        models::EMISSION,
        vec![particle(c, r, color, sigma)],
        vec![],
        41,
    );
    let renderer = VolumeRenderer::new(&s, Integrator::Adaptive);
    let mut inside = 0;
    for py in 0..41 {
        for px in 0..41 {
            let ray = s.camera.pixel_ray(px, py);
            let f = c - ray.origin;
            let b = (f - f.dot(ray.direction) * ray.direction).length();
            let chord = if b < r {
                2.0 * ((r - b) * (r + b)).sqrt()
            } else {
                0.0
            };
            inside += (chord > 0.0) as u32;
            let t = (-sigma * chord).exp();
            let expected = s.render.background * t + color * (1.0 - t);
            let got = renderer.radiance(&ray);
            assert!(
                (got.radiance - expected).abs().max_element() < 1e-12,
                "{px},{py}: {got:?} vs {expected}"
            );
            assert_eq!(got.error, DVec3::ZERO);
        }
    }
    assert!(inside > 200);
}

/// Through the centre the transmittance is 1 − Θmax (docs/design.md §1): black particle, white
/// background, so L = T.
#[test]
fn through_the_centre_transmittance_is_one_minus_opacity() {
    for opacity in [0.0, 1e-9, 0.25, 0.5, 0.9, 0.999_999, 1.0] {
        let r = 0.7;
        let mut s = scene(
            models::EMISSION,
            vec![particle(
                DVec3::ZERO,
                r,
                DVec3::ZERO,
                sigma_from_opacity(opacity, r),
            )],
            vec![],
            1,
        );
        s.render.background = DVec3::ONE;
        let ray = Ray::new(DVec3::new(0.0, 0.0, -8.0), DVec3::Z);
        let got = radiance(&s, Integrator::Adaptive, &ray).radiance;
        assert!(
            (got - DVec3::splat(1.0 - opacity)).abs().max_element() < 1e-14,
            "{opacity}: {got}"
        );
    }
}

/// Two identical coincident particles are one with 2σ (σ adds where particles overlap), in every
/// model and for both integrators.
#[test]
fn two_coincident_spheres_are_one_with_twice_sigma() {
    let (c, r, sigma, color) = (
        DVec3::new(0.1, 0.2, 0.0),
        1.0,
        0.8,
        DVec3::new(0.2, 0.9, 0.5),
    );
    for model in MODELS {
        let two = scene(
            model,
            vec![particle(c, r, color, sigma); 2],
            two_lights(),
            9,
        );
        let one = scene(
            model,
            vec![particle(c, r, color, 2.0 * sigma)],
            two_lights(),
            9,
        );
        for integrator in [Integrator::Adaptive, Integrator::Riemann { samples: 7 }] {
            let (a, b) = (
                VolumeRenderer::new(&two, integrator),
                VolumeRenderer::new(&one, integrator),
            );
            for py in 0..9 {
                for px in 0..9 {
                    let ray = two.camera.pixel_ray(px, py);
                    let (x, y) = (a.radiance(&ray), b.radiance(&ray));
                    assert!(
                        (x.radiance - y.radiance).abs().max_element() < 1e-14,
                        "{model:?} {px},{py}"
                    );
                }
            }
        }
    }
}

/// Shuffling the particles changes no pixel, bit for bit (canonical summation order), in any
/// model, with overlapping particles, both light kinds and the error layer included.
#[test]
fn shuffling_the_particles_changes_no_pixel() {
    let mut rng = Rng::new(7);
    for model in MODELS {
        let particles = random_particles(&mut rng, 12);
        let mut shuffled = particles.clone();
        for i in (1..shuffled.len()).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            shuffled.swap(i, j);
        }
        assert_ne!(particles, shuffled);
        let mut a = scene(model, particles, two_lights(), 12);
        a.render.tol = 1e-6;
        let mut b = a.clone();
        b.particles = shuffled;
        let (ra, rb) = (
            VolumeRenderer::new(&a, Integrator::Adaptive),
            VolumeRenderer::new(&b, Integrator::Adaptive),
        );
        let mut lit = 0;
        for py in 0..12 {
            for px in 0..12 {
                let ray = a.camera.pixel_ray(px, py);
                let (x, y) = (ra.radiance(&ray), rb.radiance(&ray));
                assert_eq!(
                    x.radiance.to_array().map(f64::to_bits),
                    y.radiance.to_array().map(f64::to_bits)
                );
                assert_eq!(
                    x.error.to_array().map(f64::to_bits),
                    y.error.to_array().map(f64::to_bits)
                );
                lit += (x.radiance != a.render.background) as u32;
            }
        }
        assert!(
            lit > 20,
            "{model:?}: the scene should cover part of the image"
        );
    }
}

/// Θmax = 1, lit model, one sphere, one directional light: the closed form of the σ → ∞ limit
/// (reference::volume, "Θmax = 1"): L = w·(E_l/(1 + c) + C·c/(1 + c)), c = μ_in/μ_l (∞ when the
/// light is behind the surface), and a very dense finite sphere converges to it.
#[test]
fn opaque_sphere_lit_model_is_the_sigma_to_infinity_limit() {
    let (r, color) = (1.0, DVec3::new(0.9, 0.3, 0.1));
    let toward = DVec3::new(1.0, 0.2, 0.1).normalize();
    let e = DVec3::new(1.0, 2.0, 0.5);
    let light = Light::Directional {
        direction: -toward,
        irradiance: e,
    };
    let opaque = scene(
        models::LIT,
        vec![particle(DVec3::ZERO, r, color, f64::INFINITY)],
        vec![light],
        15,
    );
    let mut dense = opaque.clone();
    dense.particles[0].sigma = 1e7;
    dense.render.tol = 1e-9;
    let (ro, rd) = (
        VolumeRenderer::new(&opaque, Integrator::Adaptive),
        VolumeRenderer::new(&dense, Integrator::Adaptive),
    );
    let mut both_sides = [0, 0];
    for py in 0..15 {
        for px in 0..15 {
            let ray = opaque.camera.pixel_ray(px, py);
            let f = -ray.origin;
            let t_c = f.dot(ray.direction);
            let b2 = (f - t_c * ray.direction).length_squared();
            if b2 >= 0.98 * r * r {
                continue; // near the silhouette a finite σ is not yet saturated
            }
            let x = ray.at(t_c - (r * r - b2).sqrt());
            let n = x / r;
            let (mu_in, mu_l) = (-ray.direction.dot(n), toward.dot(n));
            let expected = if mu_l > 0.0 {
                let c = mu_in / mu_l;
                both_sides[0] += 1;
                e / (1.0 + c) + color * (c / (1.0 + c))
            } else {
                both_sides[1] += 1;
                color
            };
            let got = ro.radiance(&ray).radiance;
            assert!(
                (got - expected).abs().max_element() < 1e-12,
                "{px},{py}: {got} vs {expected}"
            );
            let finite = rd.radiance(&ray).radiance;
            assert!(
                (finite - expected).abs().max_element() < 1e-4,
                "{px},{py}: σ = 1e7 gives {finite}, limit {expected}"
            );
        }
    }
    assert!(both_sides[0] > 10 && both_sides[1] > 10, "{both_sides:?}");
}

/// An eye inside a particle starts in it (t_min = 0 clipping): looking out from the centre the
/// chord is the radius, L = L_bg·e^{−σr} + C·(1 − e^{−σr}); a particle wholly behind the eye
/// changes nothing (emission model: it is on no camera ray).
#[test]
fn eye_inside_a_particle_and_particles_behind_the_eye() {
    let (r, sigma, color) = (2.0, 0.6, DVec3::new(0.3, 0.9, 0.2));
    let mut s = scene(
        models::EMISSION,
        vec![particle(DVec3::ZERO, r, color, sigma)],
        vec![],
        5,
    );
    s.camera = pgt::geometry::Camera::new(DVec3::ZERO, DVec3::Z, DVec3::Y, 60.0, 5, 5);
    let renderer = VolumeRenderer::new(&s, Integrator::Adaptive);
    let t = (-sigma * r).exp();
    let expected = s.render.background * t + color * (1.0 - t);
    for py in 0..5 {
        for px in 0..5 {
            let got = renderer.radiance(&s.camera.pixel_ray(px, py)).radiance;
            assert!(
                (got - expected).abs().max_element() < 1e-14,
                "{got} vs {expected}"
            );
        }
    }
    let mut behind = s.clone();
    behind
        .particles
        .push(particle(DVec3::new(0.0, 0.0, -5.0), 1.0, DVec3::ONE, 3.0));
    let other = VolumeRenderer::new(&behind, Integrator::Adaptive);
    for py in 0..5 {
        for px in 0..5 {
            let ray = s.camera.pixel_ray(px, py);
            assert_eq!(renderer.radiance(&ray), other.radiance(&ray));
        }
    }
}

/// The thesis's midpoint sums converge to the adaptive reference as the sample count grows
/// (lit and single-scatter, overlapping particles, both light kinds).
#[test]
fn riemann_sums_converge_to_the_adaptive_reference() {
    let mut rng = Rng::new(5);
    for model in [models::LIT, models::SINGLE_SCATTER] {
        let mut s = scene(model, random_particles(&mut rng, 6), two_lights(), 8);
        s.render.tol = 1e-10;
        let reference = VolumeRenderer::new(&s, Integrator::Adaptive);
        let errors: Vec<f64> = [4, 40, 400]
            .iter()
            .map(|&samples| {
                let r = VolumeRenderer::new(&s, Integrator::Riemann { samples });
                let mut worst = 0.0f64;
                for py in 0..8 {
                    for px in 0..8 {
                        let ray = s.camera.pixel_ray(px, py);
                        let d = r.radiance(&ray).radiance - reference.radiance(&ray).radiance;
                        worst = worst.max(d.abs().max_element());
                    }
                }
                worst
            })
            .collect();
        assert!(
            errors[0] > errors[1] && errors[1] > errors[2],
            "{model:?}: {errors:?}"
        );
        assert!(
            errors[2] < 1e-4 && errors[0] > 1e-4,
            "{model:?}: {errors:?}"
        );
    }
}

/// docs/design.md §3: the image (and its error layer) is bit-identical for any thread count.
#[test]
fn image_is_identical_for_any_thread_count() {
    let mut rng = Rng::new(9);
    let mut s = scene(models::LIT, random_particles(&mut rng, 8), two_lights(), 20);
    s.render.tol = 1e-5;
    let with = |threads| {
        let opts = RenderOptions {
            threads: Some(threads),
            ..RenderOptions::default()
        };
        render(&s, &opts).unwrap()
    };
    let (one, three) = (with(1), with(3));
    assert_eq!(one.image.pixels, three.image.pixels);
    assert_eq!(one.error.unwrap().pixels, three.error.unwrap().pixels);
}

/// An empty scene renders the background in every model, through the public `render`.
#[test]
fn empty_scene_renders_the_background() {
    for model in MODELS {
        let s = scene(model, vec![], two_lights(), 6);
        let out = render(&s, &RenderOptions::default()).unwrap();
        let bg = s.render.background.as_vec3().to_array();
        assert!(out.image.pixels.iter().all(|p| *p == bg));
        // err is exactly the rounding of the background to the stored float32, rounded up.
        let rounding = (0..3).map(|c| {
            let b = s.render.background[c];
            let e = (b as f32 as f64 - b).abs();
            let f = e as f32;
            if (f as f64) < e {
                f32::from_bits(f.to_bits() + 1)
            } else {
                f
            }
        });
        let expected: Vec<f32> = rounding.collect();
        assert!(expected.iter().any(|&e| e > 0.0));
        assert!(out
            .error
            .unwrap()
            .pixels
            .iter()
            .all(|p| p.as_slice() == expected.as_slice()));
    }
}

/// Bad and extreme input never gives NaN or ∞: Θmax = 1 and Θmax = 0 particles, σ near
/// f64::MAX (overlapping, so Σσ overflows), σ = 1e-300, the eye inside particles, particles behind
/// the eye, a point light inside a particle, at a particle's centre and on the optical axis
/// (where a sample point may fall on it), a light with zero intensity; every model, both
/// integrators.
#[test]
fn extreme_input_never_gives_non_finite_output() {
    let mut particles = vec![
        particle(DVec3::ZERO, 1.0, DVec3::new(1.0, 0.5, 0.0), f64::INFINITY),
        particle(DVec3::new(0.5, 0.0, 0.0), 1.0, DVec3::ONE, 0.0),
        particle(DVec3::new(-1.0, 0.5, 0.0), 0.8, DVec3::X, f64::MAX),
        particle(DVec3::new(-1.2, 0.5, 0.1), 0.8, DVec3::Y, f64::MAX),
        particle(DVec3::new(1.0, -1.0, 0.0), 0.5, DVec3::Z, 1e-300),
        particle(DVec3::new(0.0, 0.0, -8.0), 0.5, DVec3::ONE, 2.0),
        particle(DVec3::new(0.0, 0.0, -8.2), 3.0, DVec3::ONE, 0.1),
        particle(DVec3::new(0.0, 0.0, -12.0), 1.0, DVec3::ONE, 5.0),
        particle(DVec3::new(1.5, 1.5, 0.0), 0.6, DVec3::ONE, 1.0),
    ];
    particles.push(particle(DVec3::new(0.0, 1.8, -3.0), 0.4, DVec3::ONE, 3.0));
    let lights = vec![
        Light::Point {
            position: DVec3::new(1.5, 1.5, 0.0),
            intensity: DVec3::splat(5.0),
            falloff: Falloff::InverseSquare,
        },
        Light::Point {
            position: DVec3::new(0.0, 0.0, -5.0),
            intensity: DVec3::splat(1.0),
            falloff: Falloff::InverseSquare,
        },
        Light::Point {
            position: DVec3::new(0.0, 1.8, -3.0),
            intensity: DVec3::ZERO,
            falloff: Falloff::None,
        },
        Light::Directional {
            direction: DVec3::Y,
            irradiance: DVec3::ONE,
        },
    ];
    for model in MODELS {
        let mut s = scene(model, particles.clone(), lights.clone(), 9);
        s.render.tol = 1e-4;
        for integrator in [Integrator::Adaptive, Integrator::Riemann { samples: 3 }] {
            let opts = RenderOptions {
                integrator,
                ..RenderOptions::default()
            };
            let out = render_with(&s.camera, &VolumeRenderer::new(&s, integrator), &opts).unwrap();
            assert!(out.image.all_finite(), "{model:?} {integrator:?}");
            if let Some(e) = &out.error {
                assert!(e.all_finite());
            }
            // The exact ray through the point light on the axis, with a sample point on it.
            let ray = Ray::new(DVec3::new(0.0, 0.0, -8.0), DVec3::Z);
            let r = VolumeRenderer::new(&s, integrator).radiance(&ray);
            assert!(
                r.radiance.is_finite() && r.error.is_finite(),
                "{model:?}: {r:?}"
            );
        }
    }
}

/// A scene for the limit properties: up to five overlapping particles, both light kinds, a ray
/// from outside aimed into the cluster.
fn limit_case() -> impl Strategy<Value = (u64, usize, usize)> {
    (any::<u64>(), 1usize..6, 0usize..3)
}

fn case_scene(seed: u64, n: usize, model: usize) -> (pgt::scene::Scene, Ray) {
    let mut rng = Rng::new(seed);
    let particles = random_particles(&mut rng, n);
    let mut s = scene(MODELS[model], particles, two_lights(), 1);
    s.render.tol = 1e-9;
    let target = rng.vec3(-0.8, 0.8);
    let origin = rng.unit() * 6.0;
    (s, Ray::new(origin, target - origin))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Θmax → 0 (σ = 1e-13·σ): the radiance is the background, within O(σ·length·Q).
    #[test]
    fn vanishing_opacity_gives_the_background((seed, n, model) in limit_case()) {
        let (mut s, ray) = case_scene(seed, n, model);
        for p in &mut s.particles {
            p.sigma *= 1e-13;
        }
        let got = radiance(&s, Integrator::Adaptive, &ray).radiance;
        prop_assert!((got - s.render.background).abs().max_element() < 1e-10, "{got}");
    }

    /// Θmax → 1: a σ = 1e7 scene converges to the σ = ∞ one, whose value is the source at the
    /// entry point of the first particle (its σ → ∞ limit, reference::volume "Θmax = 1"). Rays
    /// that graze the first particle are left out (there σ = 1e7 is not saturated).
    #[test]
    fn full_opacity_is_the_limit_of_dense_particles((seed, n, model) in limit_case()) {
        let (mut s, ray) = case_scene(seed, n, model);
        for p in &mut s.particles {
            p.sigma = f64::INFINITY;
        }
        let first_chord = s.particles.iter()
            .filter_map(|p| pgt::geometry::intersect_sphere(&ray, p.center, p.radius))
            .filter(|c| c.t_exit > 0.0)
            .min_by(|a, b| a.t_enter.total_cmp(&b.t_enter));
        prop_assume!(first_chord.is_some_and(|c| c.length() > 1e-2 && c.t_enter > 0.0));
        let limit = radiance(&s, Integrator::Adaptive, &ray);
        for p in &mut s.particles {
            p.sigma = 1e7;
        }
        let dense = radiance(&s, Integrator::Adaptive, &ray);
        prop_assert!(limit.radiance.is_finite());
        prop_assert!((limit.radiance - dense.radiance).abs().max_element() < 1e-4,
            "∞: {} 1e7: {}", limit.radiance, dense.radiance);
    }

    /// Continuity at the silhouette: rays just inside and just outside a particle's silhouette
    /// differ by no more than the tiny chord between them can explain (σ·chord·max radiance).
    #[test]
    fn radiance_is_continuous_across_the_silhouette((seed, n, model) in limit_case(), which in 0usize..5, turn in 0.0f64..6.3) {
        let (s, ray) = case_scene(seed, n, model);
        let p = s.particles[which % s.particles.len()];
        let d = ray.direction;
        let side = d.any_orthonormal_vector() * turn.cos() + d.cross(d.any_orthonormal_vector()) * turn.sin();
        let delta = 1e-12;
        let offset_ray = |b: f64| Ray { origin: p.center + side * b - d * 6.0, direction: d };
        let inner = radiance(&s, Integrator::Adaptive, &offset_ray(p.radius * (1.0 - delta)));
        let outer = radiance(&s, Integrator::Adaptive, &offset_ray(p.radius * (1.0 + delta)));
        let chord = 2.0 * p.radius * (2.0 * delta).sqrt();
        let scale = 10.0; // bounds every radiance in these scenes (irradiances ≤ 9/d², colours ≤ 1)
        let bound = 2.0 * p.sigma * chord * scale + inner.error.max_element() + outer.error.max_element() + 1e-12;
        prop_assert!((inner.radiance - outer.radiance).abs().max_element() <= bound,
            "{} vs {} (bound {bound})", inner.radiance, outer.radiance);
    }
}

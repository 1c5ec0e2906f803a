//! Unit tests of the volume renderer: honesty of err where shadow rays stop early, where segments start at R5, near point lights inside gas; buffers reused across camera rays change no bit.

use super::per_light::{t_at, POINT_LIGHT_GRADING};
use super::*;
use crate::geometry::Camera;
use crate::optics::light::Light;
use crate::optics::{models, Model, Particle};
use crate::reference::shadow::Occluders;
use crate::scene::{LightWeight, RenderMode, RenderSettings};

/// A gas sphere of the given opacity Θmax, its albedo its colour.
fn sphere(center: DVec3, radius: f64, color: DVec3, opacity: f64) -> Particle {
    Particle {
        ellipsoid: None,
        profile: crate::optics::Profile::Constant,
        center,
        radius,
        color,
        sigma: crate::optics::extinction::sigma_from_opacity(opacity, radius),
        albedo: color,
        ks: 0.0,
        shininess: 32.0,
    }
}

/// One sphere under a roof of 3×3×3 overlapping spheres of opacity 0.999 (optical depth 6.9
/// through a centre), lit from straight above: every shadow ray from the sphere crosses
/// three layers of the roof, most of them near a centre, and its transmittance falls far
/// below the cut's ε at tol 1e-4 (about 2.5e-8); near the gaps between the columns it
/// does not, so the cut comes and goes along each camera ray.
fn roof_scene(model: Model, tol: f64) -> Scene {
    let mut particles = vec![sphere(DVec3::ZERO, 1.0, DVec3::new(0.9, 0.6, 0.3), 0.5)];
    for i in 0..27 {
        let c = DVec3::new((i % 3) as f64, 3.0 + (i / 9) as f64, ((i / 3) % 3) as f64);
        let color = DVec3::new(0.2, 0.5, 0.9) * (0.5 + 0.05 * i as f64 % 0.5);
        particles.push(sphere(
            1.4 * (c - DVec3::new(1.0, 0.0, 1.0)),
            1.0,
            color,
            0.999,
        ));
    }
    Scene {
        source: "test".into(),
        camera: Camera::new(
            DVec3::new(0.0, 0.0, -8.0),
            DVec3::ZERO,
            DVec3::Y,
            30.0,
            8,
            8,
        ),
        render: RenderSettings {
            mode: RenderMode::Volume,
            model,
            light_weight: LightWeight::Mean,
            tol,
            ..RenderSettings::default()
        },
        lights: vec![Light::Directional {
            direction: -DVec3::Y,
            irradiance: DVec3::new(1.0, 2.0, 0.5),
        }],
        particles,
        warnings: vec![],
        provenance: Default::default(),
    }
}

/// A camera ray's sample at tol 1e-4 against its truth (a much tighter render): both
/// converged, err covers the difference (with the truth's own err), and err meets tol.
fn assert_honest(model: Model, (x, y): (f64, f64), got: &Sample, want: &Sample) {
    assert!(!got.unconverged && !want.unconverged);
    let actual = (got.radiance - want.radiance).abs();
    assert!(
        actual.cmple(got.error + want.error).all(),
        "{model} ({x}, {y}): off by {actual}, err {}",
        got.error
    );
    assert!(got.error.max_element() <= 1e-4 * (1.0 + 1e-9));
}

/// The lit model's shadow rays under a dark roof are cut, and err covers the cut;
/// single-scatter's are not (it traces the transmittance alone, exactly,
/// `VolumeRenderer::shadow_transmittance`), and its err covers the rest.
#[test]
fn shadow_rays_under_a_dark_roof_are_cut_and_err_covers_the_cut() {
    for model in [models::LIT, models::SINGLE_SCATTER] {
        let scene = roof_scene(model, 1e-4);
        let truth_scene = roof_scene(model, 1e-11);
        let (r, truth) = (
            VolumeRenderer::new(&scene, Integrator::Adaptive),
            VolumeRenderer::new(&truth_scene, Integrator::Adaptive),
        );
        for (x, y) in [(0.0, 0.0), (0.3, -0.2), (-0.5, 0.6), (0.8, 0.1)] {
            let ray = Ray::new(DVec3::new(x, y, -8.0), DVec3::Z);
            let mut buffers = ShadowBuffers::default();
            let got = r.radiance_with(&ray, &mut buffers);
            assert_eq!(
                buffers.was_cut,
                model == models::LIT,
                "{model} ({x}, {y}): whether a shadow ray was cut"
            );
            let want = truth.radiance(&ray);
            assert_honest(model, (x, y), &got, &want);
        }
    }
}

/// Segments of small weight start at R5 ([`R5_START_LIMIT`]): fewer shadow rays in all than with
/// every segment at G7 or above, and err still covers |value − tol 1e-11 render|, on rays
/// through the sphere, its shadow and the roof, for both models with a per-light part.
#[test]
fn segments_of_small_weight_start_at_five_nodes_and_stay_honest() {
    for model in [models::LIT, models::SINGLE_SCATTER] {
        let scene = roof_scene(model, 1e-4);
        let truth_scene = roof_scene(model, 1e-11);
        let r = VolumeRenderer::new(&scene, Integrator::Adaptive);
        let mut no_r5 = VolumeRenderer::new(&scene, Integrator::Adaptive);
        no_r5.r5_start_limit = 0.0;
        let truth = VolumeRenderer::new(&truth_scene, Integrator::Adaptive);
        let (mut rays, mut rays_no_r5) = (0, 0);
        for i in 0..36 {
            let (x, y) = (-1.2 + 0.4 * (i % 6) as f64, -1.1 + 0.9 * (i / 6) as f64);
            let ray = Ray::new(DVec3::new(x, y, -8.0), DVec3::Z);
            let (got, want) = (r.radiance(&ray), truth.radiance(&ray));
            rays += got.shadow_rays;
            rays_no_r5 += no_r5.radiance(&ray).shadow_rays;
            assert_honest(model, (x, y), &got, &want);
        }
        assert!(rays < rays_no_r5, "{model}: {rays} against {rays_no_r5}");
        eprintln!("{model}: {rays} shadow rays, {rays_no_r5} with every segment at G7");
    }
}

/// The shadow-ray buffers are kept per thread from one camera ray to the next
/// (`RadianceEstimator::radiance`): a camera ray gives the same bits whatever ray came
/// before it on the thread, as with fresh buffers. The occluder lists are keyed by interval
/// and light, which the next ray reuses; a list left keyed would give it the wrong
/// occluders.
#[test]
fn reused_shadow_buffers_change_no_bit() {
    for model in [models::LIT, models::SINGLE_SCATTER] {
        let scene = roof_scene(model, 1e-4);
        let r = VolumeRenderer::new(&scene, Integrator::Adaptive);
        let rays: Vec<Ray> = (0..24)
            .map(|i| {
                let (x, y) = (-1.2 + 0.1 * i as f64, 0.9 - 0.07 * i as f64);
                Ray::new(DVec3::new(x, y, -8.0), DVec3::Z)
            })
            .collect();
        let bits = |s: Sample| {
            (
                s.radiance.to_array().map(f64::to_bits),
                s.error.to_array().map(f64::to_bits),
                s.shadow_rays,
            )
        };
        let fresh: Vec<_> = rays
            .iter()
            .map(|ray| bits(r.radiance_with(ray, &mut ShadowBuffers::default())))
            .collect();
        assert!(fresh.iter().filter(|f| f.2 > 0).count() > 12, "{model}");
        // Forwards, backwards and forwards again on this thread's buffers.
        for pass in 0..3 {
            let order: Vec<usize> = if pass == 1 {
                (0..rays.len()).rev().collect()
            } else {
                (0..rays.len()).collect()
            };
            for i in order {
                assert_eq!(bits(r.radiance(&rays[i])), fresh[i], "{model} ray {i}");
            }
        }
    }
}

/// Camera rays that pass a point light inside a gas sphere at distances h from 1e-4 to 0.3
/// of its radius: the peak of I/d² is as narrow as h. err covers |value − tol 1e-7
/// render| in every channel, for both models with a per-light part, and the breakpoints
/// hold the light's closest approach t* with the graded mesh t* ± h·3ᵏ around it.
#[test]
fn rays_passing_close_to_a_point_light_inside_gas_are_honest() {
    let gas = |center: DVec3, color: DVec3| sphere(center, 1.0, color, 0.9);
    for model in [models::LIT, models::SINGLE_SCATTER] {
        let scene = |tol: f64| {
            let mut s = roof_scene(model, tol);
            s.particles = vec![
                gas(DVec3::ZERO, DVec3::new(0.9, 0.6, 0.3)),
                gas(DVec3::new(0.4, 0.3, 0.5), DVec3::new(0.2, 0.5, 0.9)),
            ];
            s.lights = vec![Light::Point {
                position: DVec3::new(0.1, 0.05, 0.2),
                intensity: DVec3::new(1.0, 0.5, 0.25),
                falloff: crate::optics::Falloff::InverseSquare,
            }];
            s
        };
        // At h = 1e-4 the pixel is about 1e4 (I/d² peaks at 1e8): a truth at tol 1e-7 is
        // already 1e-11 relative.
        let (coarse, fine) = (scene(1e-4), scene(1e-7));
        let (r, truth) = (
            VolumeRenderer::new(&coarse, Integrator::Adaptive),
            VolumeRenderer::new(&fine, Integrator::Adaptive),
        );
        let light = coarse.lights[0];
        for h in [1e-4, 1e-3, 1e-2, 0.1, 0.3] {
            // Along z, passing the light at distance h in x.
            let origin = DVec3::new(0.1 + h, 0.05, -8.0);
            let ray = Ray::new(origin, DVec3::Z);
            let mut marks = Vec::new();
            let mut wide = Occluders::default();
            wide.gather(&r.bvh, &ray, (0, 0), &light, (6.0, 10.0));
            r.breakpoints(&ray, (6.0, 10.0), &light, &wide, &mut marks);
            let t_star = 8.2;
            let near = |x: f64| {
                marks
                    .iter()
                    .any(|&(m, _)| (m - x).abs() <= 1e-9 * (1.0 + x))
            };
            assert!(near(t_star), "{model} h {h}: {marks:?}");
            let mut graded = 0;
            let mut d = h;
            while d < 1.5 {
                assert!(
                    near(t_star - d) && near(t_star + d),
                    "{model} h {h}: {marks:?}"
                );
                graded += 2;
                d *= POINT_LIGHT_GRADING;
            }
            assert!(graded >= 2, "{model} h {h}");
            let got = r.radiance(&ray);
            let want = truth.radiance(&ray);
            assert!(
                !got.unconverged && !want.unconverged,
                "{model} h {h}: {} {}",
                got.unconverged,
                want.unconverged
            );
            let actual = (got.radiance - want.radiance).abs();
            assert!(
                actual.cmple(got.error + want.error).all(),
                "{model} h {h}: off by {actual}, err {}",
                got.error
            );
            assert!(
                got.error.max_element() <= 1e-4 * (1.0 + 1e-9),
                "{model} h {h}"
            );
        }
    }
}

#[test]
fn t_of_u_stays_in_the_interval_for_deep_intervals() {
    // Optical depth 50: U = 1 − e^{−50} rounds to 1; a segment end widened by a hair lies
    // above it and must give the interval's end, not NaN.
    let iv = Interval {
        t0: 2.0,
        t1: 3.0,
        sigma: 50.0,
        emission: DVec3::ONE,
        albedo: DVec3::ONE,
    };
    let u_max = crate::optics::emission::opacity(iv.sigma * iv.length());
    assert_eq!(u_max, 1.0);
    for u in [u_max, u_max + 1e-9, 1.5, f64::INFINITY] {
        assert_eq!(t_at(&iv, u_max, u), iv.t1, "u = {u}");
    }
    assert_eq!(t_at(&iv, u_max, -1e-9), iv.t0);
    let mid = t_at(&iv, u_max, 0.5);
    assert!((mid - (2.0 + std::f64::consts::LN_2 / 50.0)).abs() < 1e-15);
}

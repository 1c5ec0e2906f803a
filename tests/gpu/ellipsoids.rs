//! The GPU methods on ellipsoids (docs/design.md §9, §4) against the CPU reference and against
//! the sphere images: an ellipsoid with equal semi-axes is the sphere for every method, the
//! methods that are exact without overlaps are exact on disjoint elongated ellipsoids, opaque
//! ellipsoids match the reference off their silhouettes, and `ever` is exact on overlaps up to
//! float32 and its cut-offs, each cut-off costing what it should.

use crate::support::gpu::*;
use glam::{DQuat, DVec3};
use pgt::approx::{render_approx_with, ApproxParams, N_EXACT_ALL};
use pgt::geometry::Ellipsoid;
use pgt::optics::extinction::sigma_from_opacity;
use pgt::optics::models;
use pgt::reference::{self, RenderOptions};
use pgt::scene::{Particle, RenderMode};

fn method(name: &str, values: &[(&str, u32)]) -> ApproxParams {
    ApproxParams::for_method(name, values).unwrap()
}

/// `ever` without its cut-offs: what remains is float32.
fn ever_uncut() -> ApproxParams {
    method("ever", &[("stop_below", 0), ("max_batches", 1 << 24)])
}

/// An ellipsoid of gas: semi-axes, turned by `angle` degrees about `axis`; Θmax along the
/// shortest diameter (docs/design.md §9).
fn ellipsoid(
    center: [f64; 3],
    semi_axes: [f64; 3],
    (axis, angle): ([f64; 3], f64),
    color: [f64; 3],
    opacity: f64,
) -> Particle {
    let semi = DVec3::from(semi_axes);
    let rotation = DQuat::from_axis_angle(DVec3::from(axis).normalize(), angle.to_radians());
    Particle {
        ellipsoid: Some(Ellipsoid::new(semi, rotation)),
        radius: semi.max_element(),
        sigma: sigma_from_opacity(opacity, semi.min_element()),
        ..particle(center, 1.0, color, opacity)
    }
}

/// Three elongated ellipsoids (1:6, 1:4, 1:3), turned, pairwise disjoint (their bounding
/// spheres are, checked), one of them Θmax = 1.
fn disjoint_ellipsoids() -> Vec<Particle> {
    let ps = vec![
        ellipsoid(
            [-2.0, 0.2, 0.0],
            [1.8, 0.3, 0.5],
            ([0.3, 0.2, 1.0], 35.0),
            [1.0, 0.3, 0.2],
            0.8,
        ),
        ellipsoid(
            [1.7, -0.4, 1.0],
            [0.4, 1.6, 0.6],
            ([1.0, 0.0, 0.4], -50.0),
            [0.2, 0.9, 0.4],
            0.6,
        ),
        ellipsoid(
            [0.3, 2.2, 3.0],
            [1.5, 0.5, 0.5],
            ([0.0, 1.0, 0.3], 70.0),
            [0.3, 0.4, 1.0],
            1.0,
        ),
    ];
    for (i, a) in ps.iter().enumerate() {
        for b in &ps[i + 1..] {
            assert!(
                a.center.distance(b.center) > a.radius + b.radius,
                "test scene overlaps"
            );
        }
    }
    ps
}

#[test]
fn an_ellipsoid_with_equal_axes_draws_as_the_sphere_in_every_method() {
    let Some(ctx) = gpu() else { return };
    let spheres = disjoint_particles();
    let round: Vec<Particle> = spheres
        .iter()
        .enumerate()
        .map(|(i, p)| Particle {
            ellipsoid: Some(Ellipsoid::new(
                DVec3::splat(p.radius),
                DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7 * i as f64),
            )),
            ..*p
        })
        .collect();
    let cases = [
        (
            RenderMode::Volume,
            models::EMISSION,
            method("emission", &[]),
        ),
        (
            RenderMode::Volume,
            models::EMISSION,
            method("sorted-blend", &[]),
        ),
        (RenderMode::Volume, models::EMISSION, ever_uncut()),
        (
            RenderMode::Volume,
            models::LIT,
            method("thesis", &[("samples", 8), ("n_exact", N_EXACT_ALL)]),
        ),
        (RenderMode::Opaque, models::LIT, method("opaque", &[])),
    ];
    for (mode, model, params) in cases {
        let a = render_approx_with(ctx, &scene(spheres.clone(), lights(), mode, model), &params)
            .unwrap();
        let b =
            render_approx_with(ctx, &scene(round.clone(), lights(), mode, model), &params).unwrap();
        let e = rmse(&a.image, &b.image);
        let name = params.method.as_ref().unwrap().name();
        eprintln!("{name}: round ellipsoids vs spheres RMSE {e:.3e}");
        // float32 rounding of the map to the unit sphere (a silhouette pixel may flip).
        assert!(e <= 1e-5, "{name}: RMSE {e}");
        let differing = a
            .image
            .pixels
            .iter()
            .zip(&b.image.pixels)
            .filter(|(x, y)| (0..3).any(|c| (x[c] - y[c]).abs() > 1e-3))
            .count();
        assert!(
            differing <= 2,
            "{name}: {differing} pixels differ by > 1e-3"
        );
    }
}

#[test]
fn methods_exact_without_overlaps_are_exact_on_disjoint_ellipsoids() {
    let Some(ctx) = gpu() else { return };
    let s = scene(
        disjoint_ellipsoids(),
        vec![],
        RenderMode::Volume,
        models::EMISSION,
    );
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    let bg = s.render.background.as_vec3().to_array();
    let covered = reference
        .image
        .pixels
        .iter()
        .filter(|p| (0..3).any(|c| (p[c] - bg[c]).abs() > 0.05))
        .count();
    assert!(covered > 150, "the ellipsoids cover {covered} pixels");
    for params in [
        method("emission", &[]),
        method("thesis", &[]),
        method("ever", &[]),
        ever_uncut(),
    ] {
        let gpu = render_approx_with(ctx, &s, &params).unwrap();
        let e = rmse(&gpu.image, &reference.image);
        let name = params.method.as_ref().unwrap().name();
        eprintln!("{name} {:?}: RMSE vs reference {e:.3e}", params.values);
        assert!(e <= 2e-5, "{name}: RMSE {e}");
    }
}

#[test]
fn thesis_converges_to_the_lit_model_on_disjoint_ellipsoids() {
    let Some(ctx) = gpu() else { return };
    let s = scene(
        disjoint_ellipsoids(),
        lights(),
        RenderMode::Volume,
        models::LIT,
    );
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    let mut previous = f64::INFINITY;
    for samples in [4, 16, 64] {
        let params = method("thesis", &[("samples", samples), ("n_exact", N_EXACT_ALL)]);
        let gpu = render_approx_with(ctx, &s, &params).unwrap();
        let e = rmse(&gpu.image, &reference.image);
        eprintln!("thesis samples {samples:>3} on ellipsoids: RMSE vs reference {e:.3e}");
        assert!(e < 0.5 * previous, "RMSE {e} after {previous}");
        previous = e;
    }
    assert!(previous < 5e-5, "RMSE at 64 samples {previous}");
}

#[test]
fn opaque_ellipsoids_match_the_reference_except_on_silhouettes() {
    let Some(ctx) = gpu() else { return };
    let mut ps = disjoint_ellipsoids();
    ps[1].ks = 0.5;
    ps[1].shininess = 20.0;
    let mut s = scene(ps, lights(), RenderMode::Opaque, models::LIT);
    s.render.ambient = 0.05;
    let bvh = s.build_bvh();
    let gpu = render_approx_with(ctx, &s, &method("opaque", &[])).unwrap();
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    let mask = silhouette_mask(&s, &bvh);
    let (worst, compared) = max_error_off_mask(&gpu.image, &reference.image, &mask);
    eprintln!("opaque ellipsoids: max abs error {worst:.3e} over {compared} pixels");
    assert!(compared > 1500, "{compared}");
    assert!(worst <= 1e-4, "max abs error {worst}");
}

/// A needle through a disc through a sphere, all overlapping: the emission model's σ adds.
fn overlapping() -> Vec<Particle> {
    vec![
        ellipsoid(
            [0.0, 0.0, 0.0],
            [3.0, 0.25, 0.25],
            ([0.0, 0.0, 1.0], 20.0),
            [1.0, 0.4, 0.1],
            0.7,
        ),
        ellipsoid(
            [0.5, 0.2, 0.3],
            [0.2, 1.6, 1.6],
            ([0.0, 1.0, 0.0], -25.0),
            [0.2, 0.6, 1.0],
            0.8,
        ),
        particle([-0.6, -0.3, -0.2], 1.1, [0.9, 0.9, 0.9], 0.5),
    ]
}

#[test]
fn ever_is_exact_on_overlaps_where_per_particle_methods_are_not() {
    let Some(ctx) = gpu() else { return };
    let s = scene(overlapping(), vec![], RenderMode::Volume, models::EMISSION);
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    let ever = render_approx_with(ctx, &s, &ever_uncut()).unwrap();
    let e_ever = rmse(&ever.image, &reference.image);
    let emission = render_approx_with(ctx, &s, &method("emission", &[])).unwrap();
    let e_emission = rmse(&emission.image, &reference.image);
    let blend = render_approx_with(ctx, &s, &method("sorted-blend", &[])).unwrap();
    let e_blend = rmse(&blend.image, &reference.image);
    eprintln!(
        "overlapping ellipsoids, RMSE vs reference: ever {e_ever:.3e}, emission {e_emission:.3e}, sorted-blend {e_blend:.3e}"
    );
    assert!(e_ever <= 1e-5, "ever RMSE {e_ever}");
    assert!(e_emission > 100.0 * e_ever, "emission RMSE {e_emission}");
    assert!(e_blend > 100.0 * e_ever, "sorted-blend RMSE {e_blend}");
    // The batch size changes how the events are fetched, not which or in what order.
    for batch in [1, 3, 64] {
        let other = render_approx_with(
            ctx,
            &s,
            &method(
                "ever",
                &[
                    ("batch", batch),
                    ("stop_below", 0),
                    ("max_batches", 1 << 24),
                ],
            ),
        )
        .unwrap();
        assert_eq!(other.image.pixels, ever.image.pixels, "batch {batch}");
    }
}

#[test]
fn evers_cut_offs_cost_what_they_bound() {
    let Some(ctx) = gpu() else { return };
    // A nearly opaque disc (Θmax = 0.999) in front of a bright sphere: the transmittance falls
    // below EVER's 0.004 inside the disc, so the default stops there.
    let ps = vec![
        ellipsoid(
            [0.0, 0.0, -2.0],
            [2.5, 2.5, 0.3],
            ([0.0, 0.0, 1.0], 0.0),
            [0.1, 0.1, 0.1],
            0.999,
        ),
        particle([0.0, 0.0, 1.0], 1.5, [1.0, 1.0, 1.0], 0.9),
    ];
    let s = scene(ps, vec![], RenderMode::Volume, models::EMISSION);
    let uncut = render_approx_with(ctx, &s, &ever_uncut()).unwrap();
    let cut = render_approx_with(ctx, &s, &method("ever", &[])).unwrap();
    let mut worst = 0.0f32;
    for (a, b) in uncut.image.pixels.iter().zip(&cut.image.pixels) {
        for c in 0..3 {
            worst = worst.max((a[c] - b[c]).abs());
        }
    }
    eprintln!("ever's stop at T < 0.004: max change {worst:.3e}");
    // What the stop drops is the gas behind it, seen through T < 0.004: at most 0.004·max C.
    assert!(worst > 1e-5, "the stop changed nothing ({worst})");
    assert!(worst <= 0.004 * 1.0 + 1e-6, "max change {worst}");
    // One batch of one event shows only the first event: the ray ends inside the disc.
    let one = render_approx_with(
        ctx,
        &s,
        &method(
            "ever",
            &[("batch", 1), ("max_batches", 1), ("stop_below", 0)],
        ),
    )
    .unwrap();
    let centre = (SIDE / 2 * SIDE + SIDE / 2) as usize;
    let bg = s.render.background.as_vec3();
    for c in 0..3 {
        assert!(
            (one.image.pixels[centre][c] - bg[c]).abs() < 1e-6,
            "after one entry event no gas is crossed: {:?}",
            one.image.pixels[centre]
        );
    }
}

#[test]
fn pgt_approx_draws_the_ellipsoid_example_with_every_volume_method() {
    if gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/ellipsoids.toml");
    for name in ["emission", "sorted-blend", "thesis", "ever"] {
        let out = dir.path().join(format!("{name}.exr"));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_pgt"))
            .args(["approx", scene, "--model", "emission", "--method", name])
            .args(["--size", "32x24", "-o", out.to_str().unwrap()])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{name}: {err}");
        assert!(out.exists(), "{name}: no image");
    }
}

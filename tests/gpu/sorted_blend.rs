//! The `sorted-blend` method (docs/design.md §4) against the exact emission reference
//! (`pgt::reference`, emission model) and an f64 oracle of what it claims to compute, on
//! whatever adapter wgpu finds (lavapipe in CI).

use crate::support::gpu::*;
use glam::DVec3;
use pgt::approx::{render_approx_with, ApproxParams};
use pgt::geometry::{Bvh, Hit, Ray};
use pgt::optics::models;
use pgt::reference::{self, RenderOptions};
use pgt::scene::{RenderMode, Scene};

fn sorted_blend() -> ApproxParams {
    ApproxParams::for_method("sorted-blend", &[]).unwrap()
}

/// Oracle, f64: the particles on the ray sorted by dot(centre − eye, forward), each composited
/// whole over its own chord (the part in front of the eye) with the emission closed form.
fn centre_sorted_oracle(scene: &Scene, bvh: &Bvh, ray: &Ray) -> DVec3 {
    let mut hits: Vec<Hit> = Vec::new();
    bvh.all_hits(ray, 0.0, f64::INFINITY, &mut hits);
    let depth = |h: &Hit| {
        (scene.particles[h.index as usize].center - scene.camera.position).dot(scene.camera.forward)
    };
    hits.sort_by(|a, b| depth(a).total_cmp(&depth(b)).then(a.index.cmp(&b.index)));
    let mut l = scene.render.background;
    for h in hits.iter().rev() {
        let p = &scene.particles[h.index as usize];
        let length = h.chord.t_exit - h.chord.t_enter.max(0.0);
        let t = if p.sigma.is_infinite() {
            0.0
        } else {
            (-p.sigma * length).exp()
        };
        l = l * t + p.color * (1.0 - t);
    }
    l
}

#[test]
fn sorted_blend_is_exact_where_centre_order_is_entry_order() {
    let Some(ctx) = gpu() else { return };
    // Spheres in disjoint slabs of z along the view axis (+z): every ray meets them in centre
    // order. They overlap on screen, so the order matters; one is Θmax = 1.
    let ps = vec![
        particle([0.0, 0.0, -3.0], 1.0, [1.0, 0.2, 0.2], 0.6),
        particle([0.4, 0.3, 0.0], 1.2, [0.2, 1.0, 0.3], 0.5),
        particle([-0.3, -0.2, 3.0], 1.5, [0.3, 0.3, 1.0], 1.0),
        particle([0.5, 0.5, 7.0], 2.0, [1.0, 1.0, 0.0], 0.7),
    ];
    for (i, a) in ps.iter().enumerate() {
        for b in &ps[i + 1..] {
            assert!(
                (a.center.z - b.center.z).abs() > a.radius + b.radius,
                "slabs overlap"
            );
        }
    }
    let s = scene(ps, vec![], RenderMode::Volume, models::EMISSION);
    let bvh = s.build_bvh();
    let layered = (0..SIDE * SIDE)
        .filter(|i| {
            let mut hits = Vec::new();
            bvh.all_hits(
                &s.camera.pixel_ray(i % SIDE, i / SIDE),
                0.0,
                f64::INFINITY,
                &mut hits,
            );
            hits.len() >= 2
        })
        .count();
    assert!(
        layered > 200,
        "pixels whose ray crosses two or more spheres: {layered}"
    );
    let gpu = render_approx_with(ctx, &s, &sorted_blend()).unwrap();
    assert_eq!(gpu.hit_overflow_pixels, 0);
    let r = reference::render(&s, &RenderOptions::default()).unwrap();
    let e = rmse(&gpu.image, &r.image);
    eprintln!("sorted-blend vs exact emission reference (disjoint slabs): RMSE {e:.3e}");
    assert!(e <= 1e-5, "RMSE {e}");
}

#[test]
fn sorted_blend_on_overlapping_particles_measures_its_error() {
    let Some(ctx) = gpu() else { return };
    // Two half-overlapping particles and a large third one overlapping both: in the shared
    // lenses the gas mixes, which whole-particle blending in any order cannot reproduce.
    let ps = vec![
        particle([-0.6, 0.0, 0.0], 1.5, [1.0, 0.1, 0.1], 0.9),
        particle([0.6, 0.2, 0.8], 1.5, [0.1, 0.2, 1.0], 0.7),
        particle([0.0, -1.0, 1.5], 2.5, [0.2, 0.9, 0.2], 0.5),
    ];
    let s = scene(ps, vec![], RenderMode::Volume, models::EMISSION);
    let bvh = s.build_bvh();
    let gpu = render_approx_with(ctx, &s, &sorted_blend()).unwrap();
    // It does what it claims, to f32 precision …
    let oracle = cpu_image(&s.camera, |r| centre_sorted_oracle(&s, &bvh, r));
    let e_oracle = rmse(&gpu.image, &oracle);
    // … and that is measurably not the exact answer.
    let r = reference::render(&s, &RenderOptions::default()).unwrap();
    let e = rmse(&gpu.image, &r.image);
    eprintln!(
        "sorted-blend on overlapping particles: RMSE {e:.3e} vs the exact emission reference, {e_oracle:.3e} vs its f64 oracle"
    );
    assert!(e_oracle <= 1e-5, "{e_oracle}");
    assert!(e.is_finite() && e > 1e-3, "{e}");
    assert!(e < 0.2, "{e}: beyond any sane error for colours in [0, 1]");
}

#[test]
fn sorted_blend_refuses_opaque_scenes() {
    let s = scene(
        disjoint_particles(),
        vec![],
        RenderMode::Opaque,
        models::EMISSION,
    );
    // The scene check runs before any adapter is needed.
    let Some(ctx) = gpu() else { return };
    let e = render_approx_with(ctx, &s, &sorted_blend())
        .unwrap_err()
        .to_string();
    assert!(e.contains("sorted-blend") && e.contains("volume"), "{e}");
}

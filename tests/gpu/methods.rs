//! The GPU methods against exact answers (docs/design.md §4), on whatever adapter wgpu finds
//! (lavapipe in CI). Images are 48×48: lavapipe on two cores is slow.

use crate::support::gpu::*;
use glam::DVec3;
use pgt::approx::{render_approx_with, ApproxParams, Method, N_EXACT_ALL};
use pgt::optics::models;
use pgt::reference::{self, RenderOptions};
use pgt::scene::{Light, RenderMode, Scene};
use std::path::PathBuf;

/// A built-in method with no parameters chosen (its defaults).
fn plain(name: &str) -> ApproxParams {
    ApproxParams::for_method(name, &[]).unwrap()
}

/// The thesis method with these parameters.
fn thesis(samples: u32, n_exact: u32) -> ApproxParams {
    ApproxParams::for_method("thesis", &[("samples", samples), ("n_exact", n_exact)]).unwrap()
}

/// A user shader with these parameters.
fn user(shader: PathBuf, samples: u32, n_exact: u32) -> ApproxParams {
    ApproxParams {
        method: Some(Method::User(shader)),
        values: vec![("samples".into(), samples), ("n_exact".into(), n_exact)],
        adapter: None,
    }
}

#[test]
fn emission_matches_the_exact_answer_on_disjoint_particles() {
    let Some(ctx) = gpu() else { return };
    let s = scene(
        disjoint_particles(),
        vec![],
        RenderMode::Volume,
        models::EMISSION,
    );
    let bvh = s.build_bvh();
    let gpu = render_approx_with(ctx, &s, &plain("emission")).unwrap();
    assert_eq!(gpu.hit_overflow_pixels, 0);
    let oracle = cpu_image(&s.camera, |r| {
        emission_per_particle(&s, &bvh, r, 0.0, f64::INFINITY, s.render.background)
    });
    let e = rmse(&gpu.image, &oracle);
    eprintln!("emission vs f64 per-particle oracle: RMSE {e:.3e}");
    assert!(e <= 1e-5, "RMSE {e}");
    // The scene is not trivial: many pixels differ from the background.
    let bg = s.render.background.as_vec3().to_array();
    let covered = oracle
        .pixels
        .iter()
        .filter(|p| (p[0] - bg[0]).abs() > 0.05)
        .count();
    assert!(covered > 300, "{covered}");
    // And against the reference renderer (exact interval cutting, docs/design.md §3).
    let r = reference::render(&s, &RenderOptions::default()).unwrap();
    let e = rmse(&gpu.image, &r.image);
    eprintln!("emission vs reference: RMSE {e:.3e}");
    assert!(e <= 1e-5, "RMSE vs reference {e}");
}

#[test]
fn thesis_on_an_emission_scene_is_the_emission_method() {
    let Some(ctx) = gpu() else { return };
    let s = scene(
        disjoint_particles(),
        lights(),
        RenderMode::Volume,
        models::EMISSION,
    );
    let a = render_approx_with(ctx, &s, &plain("emission")).unwrap();
    let b = render_approx_with(ctx, &s, &thesis(16, N_EXACT_ALL)).unwrap();
    // The thesis method composites front to back, emission back to front: rounding only.
    let e = rmse(&a.image, &b.image);
    assert!(e <= 1e-6, "{e}");
}

#[test]
fn opaque_matches_the_reference_except_on_silhouettes() {
    let Some(ctx) = gpu() else { return };
    let mut ps = disjoint_particles();
    ps[1].ks = 0.5;
    ps[1].shininess = 20.0;
    let mut s = scene(ps, lights(), RenderMode::Opaque, models::LIT);
    s.render.ambient = 0.05;
    let bvh = s.build_bvh();
    let gpu = render_approx_with(ctx, &s, &plain("opaque")).unwrap();
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    let mask = silhouette_mask(&s, &bvh);
    let (worst, compared) = max_error_off_mask(&gpu.image, &reference.image, &mask);
    let silhouettes = mask.iter().filter(|&&m| m).count();
    eprintln!("opaque: max abs error {worst:.3e} over {compared} pixels ({silhouettes} silhouette pixels left out)");
    assert!(compared > 1500, "{compared}");
    assert!(worst <= 1e-4, "max abs error {worst}");
}

#[test]
fn thesis_converges_to_the_lit_model_on_disjoint_particles() {
    let Some(ctx) = gpu() else { return };
    let s = scene(
        disjoint_particles(),
        lights(),
        RenderMode::Volume,
        models::LIT,
    );
    let bvh = s.build_bvh();
    let oracle = cpu_image(&s.camera, |r| lit_oracle(&s, &bvh, r, 2048));
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    let mut previous = (f64::INFINITY, f64::INFINITY);
    for samples in [4, 16, 64, 256] {
        let gpu = render_approx_with(ctx, &s, &thesis(samples, N_EXACT_ALL)).unwrap();
        let e = (
            rmse(&gpu.image, &reference.image),
            rmse(&gpu.image, &oracle),
        );
        eprintln!(
            "thesis samples {samples:>3}: RMSE vs reference {:.3e}, vs f64 oracle {:.3e}",
            e.0, e.1
        );
        // The midpoint rule converges at least like 1/samples here (shadow edges of the Θmax = 1
        // particle make the source discontinuous along the chord): each 4× must at least halve it.
        assert!(
            e.0 < 0.5 * previous.0,
            "RMSE must fall with samples: {e:?} after {previous:?}"
        );
        assert!(
            e.1 < 0.5 * previous.1,
            "RMSE must fall with samples: {e:?} after {previous:?}"
        );
        previous = e;
    }
    assert!(
        previous.0 < 1e-4 && previous.1 < 1e-4,
        "RMSE at 256 samples {previous:?}"
    );
}

#[test]
fn thesis_on_overlapping_lit_particles_stays_away_from_the_reference() {
    let Some(ctx) = gpu() else { return };
    let ps = vec![
        particle([-0.6, 0.0, 0.0], 1.5, [1.0, 0.1, 0.1], 0.9),
        particle([0.6, 0.2, 0.8], 1.5, [0.1, 0.2, 1.0], 0.7),
    ];
    let s = scene(ps, lights(), RenderMode::Volume, models::LIT);
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    let e = |samples| {
        let out = render_approx_with(ctx, &s, &thesis(samples, N_EXACT_ALL)).unwrap();
        rmse(&out.image, &reference.image)
    };
    let (e64, e256) = (e(64), e(256));
    eprintln!("overlapping lit: thesis vs reference RMSE {e64:.3e} (64 samples), {e256:.3e} (256 samples)");
    // More samples do not help: the error is the overlap, not the quadrature.
    assert!(e256 > 1e-3, "{e256}");
    assert!(e256 > 0.5 * e64, "{e64} {e256}");
}

#[test]
fn thesis_with_fewer_exact_particles_is_further_from_the_lit_model() {
    let Some(ctx) = gpu() else { return };
    let s = scene(
        disjoint_particles(),
        lights(),
        RenderMode::Volume,
        models::LIT,
    );
    let bvh = s.build_bvh();
    let oracle = cpu_image(&s.camera, |r| lit_oracle(&s, &bvh, r, 1024));
    let e = |n_exact| {
        rmse(
            &render_approx_with(ctx, &s, &thesis(64, n_exact))
                .unwrap()
                .image,
            &oracle,
        )
    };
    let (e0, e1, eall) = (e(0), e(1), e(N_EXACT_ALL));
    eprintln!("thesis n_exact 0: {e0:.3e}, 1: {e1:.3e}, all: {eall:.3e}");
    assert!(e0 > e1 && e1 > eall, "{e0} {e1} {eall}");
}

#[test]
fn thesis_ignores_overlaps_and_differs_from_exact_intervals() {
    let Some(ctx) = gpu() else { return };
    // Two half-overlapping particles on the axis: per-particle compositing counts the shared
    // lens as if it were in front of or behind, not mixed.
    let ps = vec![
        particle([-0.6, 0.0, 0.0], 1.5, [1.0, 0.1, 0.1], 0.9),
        particle([0.6, 0.2, 0.8], 1.5, [0.1, 0.2, 1.0], 0.7),
    ];
    let s = scene(ps, vec![], RenderMode::Volume, models::EMISSION);
    let bvh = s.build_bvh();
    let exact = cpu_image(&s.camera, |r| emission_exact_intervals(&s, &bvh, r));
    let per_particle = cpu_image(&s.camera, |r| {
        emission_per_particle(&s, &bvh, r, 0.0, f64::INFINITY, s.render.background)
    });
    let gpu = render_approx_with(ctx, &s, &thesis(16, N_EXACT_ALL)).unwrap();
    let e_exact = rmse(&gpu.image, &exact);
    let e_model = rmse(&gpu.image, &per_particle);
    eprintln!("overlap: thesis vs exact intervals RMSE {e_exact:.3e}, vs per-particle oracle {e_model:.3e}");
    // The GPU does what the thesis does (per-particle) to f32 precision …
    assert!(e_model <= 1e-5, "{e_model}");
    // … which is measurably not the exact answer.
    assert!(e_exact > 1e-3, "{e_exact}");
    let r = reference::render(&s, &RenderOptions::default()).unwrap();
    let e = rmse(&gpu.image, &r.image);
    eprintln!("overlap: thesis vs reference RMSE {e:.3e}");
    assert!(e > 1e-3, "{e}");
}

#[test]
fn an_empty_scene_renders_the_background() {
    let Some(ctx) = gpu() else { return };
    for method in pgt::approx::METHODS {
        // Each method on a scene of a mode and model it computes (it refuses any other).
        let (mode, model) = [
            (RenderMode::Volume, models::LIT),
            (RenderMode::Volume, models::EMISSION),
            (RenderMode::Opaque, models::LIT),
        ]
        .into_iter()
        .find(|&(mode, model)| method.computes().covers(mode, model))
        .expect("every method computes one of these");
        let s = scene(vec![], vec![], mode, model);
        let out = render_approx_with(ctx, &s, &plain(method.name())).unwrap();
        let bg = s.render.background.as_vec3().to_array();
        assert!(out.image.pixels.iter().all(|p| *p == bg));
    }
}

#[test]
fn a_crowded_ray_reports_hit_list_overflow() {
    let Some(ctx) = gpu() else { return };
    // 200 spheres in a row along the view axis (overlapping: this is about counting): the
    // rays near the centre cross all of them, more than MAX_HITS (128).
    let s = row_of_spheres(200);
    let out = render_approx_with(ctx, &s, &plain("emission")).unwrap();
    assert!(out.hit_overflow_pixels > 0);
    assert!(out.image.all_finite());
}

#[test]
fn a_full_hit_list_keeps_its_nearest_entries_sorted() {
    let Some(ctx) = gpu() else { return };
    // 200 spheres in a row along the view axis, particle i entered at t ≈ 4.5 + 0.1·i: a ray
    // near the axis crosses all of them, in the order of their indices, while the BVH hands
    // them to the sorted insert in its own order. A full list keeps the nearest MAX_HITS (128):
    // particles 0..=127, sorted by entry, flagged as overflowed. The shader returns (count,
    // index of the last entry, 1 if sorted and flagged).
    let dir = tempfile::tempdir().unwrap();
    let shader = dir.path().join("hit_list.wgsl");
    std::fs::write(
        &shader,
        "fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    collect_hits(ray, 0.0, T_FAR, &camera_hits);
    let n = camera_hits.count;
    if (n == 0u) {
        return vec3<f32>(0.0, -1.0, 0.0);
    }
    var sorted = camera_hits.overflowed;
    for (var k = 1u; k < n; k = k + 1u) {
        count_iteration();
        sorted = sorted && camera_hits.t_enter[k - 1u] < camera_hits.t_enter[k]
            && camera_hits.index[k - 1u] < camera_hits.index[k];
    }
    return vec3<f32>(f32(n), f32(camera_hits.index[n - 1u]), select(0.0, 1.0, sorted));
}
",
    )
    .unwrap();
    let s = row_of_spheres(200);
    let out = render_approx_with(ctx, &s, &user(shader, 1, 0)).unwrap();
    let centre = (SIDE / 2 * SIDE + SIDE / 2) as usize;
    assert_eq!(out.image.pixels[centre], [128.0, 127.0, 1.0]);
    assert!(out.hit_overflow_pixels > 0);
    assert_eq!(
        out.image.pixels[0],
        [0.0, -1.0, 0.0],
        "a corner ray misses them all"
    );
}

#[test]
fn a_point_light_inside_no_particle_lights_the_gas() {
    let Some(ctx) = gpu() else { return };
    // One sphere, one point light: the lit source must vary with the light's position.
    let light = |x: f64| Light::Point {
        position: DVec3::new(x, 0.0, -3.0),
        intensity: DVec3::splat(10.0),
        falloff: pgt::scene::Falloff::InverseSquare,
    };
    let ps = vec![particle([0.0, 0.0, 0.0], 1.5, [0.2, 0.2, 0.2], 0.6)];
    let near = scene(
        ps.clone(),
        vec![light(0.0)],
        RenderMode::Volume,
        models::LIT,
    );
    let far = scene(ps, vec![light(8.0)], RenderMode::Volume, models::LIT);
    let a = render_approx_with(ctx, &near, &thesis(16, N_EXACT_ALL)).unwrap();
    let b = render_approx_with(ctx, &far, &thesis(16, N_EXACT_ALL)).unwrap();
    let centre = (SIDE / 2 * SIDE + SIDE / 2) as usize;
    assert!(a.image.pixels[centre][0] > b.image.pixels[centre][0] + 0.01);
}

#[test]
fn the_opaque_gas_limit_agrees_with_nearly_opaque_gas() {
    let Some(ctx) = gpu() else { return };
    // The thesis method gives a Θmax = 1 particle the closed-form limit of the lit integral;
    // the f64 oracle integrates the same particle with σ = 10⁴ /m (depth scale 0.1 mm on a
    // 0.7 m sphere) without any limit formula. They must agree.
    let ps = disjoint_particles();
    let s_inf = scene(ps.clone(), lights(), RenderMode::Volume, models::LIT);
    assert!(s_inf.particles[2].sigma.is_infinite());
    let mut s_big = s_inf.clone();
    s_big.particles[2].sigma = 1e4;
    let bvh = s_big.build_bvh();
    let oracle = cpu_image(&s_big.camera, |r| lit_oracle(&s_big, &bvh, r, 2048));
    let gpu = render_approx_with(ctx, &s_inf, &thesis(256, N_EXACT_ALL)).unwrap();
    let e = rmse(&gpu.image, &oracle);
    eprintln!("Θmax = 1 limit vs σ = 1e4: RMSE {e:.3e}");
    assert!(e < 1e-3, "{e}");
}

#[test]
fn pixels_beyond_lavapipes_loop_limit_are_reported() {
    let Some(ctx) = gpu() else { return };
    // A user method that walks a crowded ray (200 spheres: ~13,000 loop iterations per walk)
    // 50 times: far beyond lavapipe's 65,535 loop iterations per invocation.
    let dir = tempfile::tempdir().unwrap();
    let shader = dir.path().join("heavy.wgsl");
    std::fs::write(
        &shader,
        "fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {\n    var sum = vec3<f32>(0.0);\n    for (var i = 0u; i < 50u; i = i + 1u) {\n        sum = sum + emission_along(ray, 0.0, T_FAR, frame.background);\n    }\n    return sum / 50.0;\n}\n",
    )
    .unwrap();
    let s = row_of_spheres(200);
    let out = render_approx_with(ctx, &s, &user(shader, 1, 0)).unwrap();
    if ctx.adapter.is_cpu {
        assert!(out.loop_limited_pixels > 0);
    } else {
        assert_eq!(out.loop_limited_pixels, 0, "only lavapipe has the limit");
    }
    // The thesis method itself stays below it by splitting its samples into passes.
    let s = scene(
        disjoint_particles(),
        lights(),
        RenderMode::Volume,
        models::LIT,
    );
    let out = render_approx_with(ctx, &s, &thesis(400, N_EXACT_ALL)).unwrap();
    assert_eq!(out.loop_limited_pixels, 0);
    if ctx.adapter.is_cpu {
        assert!(out.passes > 1);
    }
}

#[test]
fn thesis_stays_right_on_a_crowded_random_scene() {
    let Some(ctx) = gpu() else { return };
    // 200 overlapping particles: each pixel needs thousands of shadow rays, beyond what lavapipe
    // runs in one invocation (its loops stop after 65535 iterations). Before pgt split the work
    // into passes, this image was 0.1 RMSE off and darkened as samples grew.
    let mut state = 12345u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let cube = (200.0f64 / 0.05).cbrt();
    let ps: Vec<_> = (0..200)
        .map(|_| {
            let c = [
                (next() - 0.5) * cube,
                (next() - 0.5) * cube,
                (next() - 0.5) * cube,
            ];
            particle(c, 1.2 + 0.7 * next(), [next(), next(), next()], 0.5)
        })
        .collect();
    let mut s = scene(
        ps,
        pgt::scene::thesis_lights(),
        RenderMode::Volume,
        models::LIT,
    );
    s.camera = pgt::geometry::Camera::new(
        DVec3::new(0.0, 0.0, -3.0 * cube),
        DVec3::ZERO,
        DVec3::Y,
        40.0,
        32,
        32,
    );
    let bvh = s.build_bvh();
    let oracle = cpu_image(&s.camera, |r| lit_oracle(&s, &bvh, r, 512));
    let out = render_approx_with(ctx, &s, &thesis(64, N_EXACT_ALL)).unwrap();
    let e = rmse(&out.image, &oracle);
    eprintln!(
        "crowded random scene: RMSE {e:.3e} in {} passes",
        out.passes
    );
    assert_eq!(out.loop_limited_pixels, 0);
    assert!(e < 5e-4, "{e}");
}

#[test]
fn the_example_user_methods_are_measurably_worse_than_the_thesis_method() {
    let Some(ctx) = gpu() else { return };
    // What pgt is for: measure a user's shortcut against the exact reference.
    let s = scene(
        disjoint_particles(),
        lights(),
        RenderMode::Volume,
        models::LIT,
    );
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let thesis = render_approx_with(ctx, &s, &thesis(64, N_EXACT_ALL)).unwrap();
    let e_thesis = rmse(&thesis.image, &reference.image);
    for example in ["centre_shadow", "no_shadows"] {
        let shader = root.join(format!("shaders/examples/{example}.wgsl"));
        let out = render_approx_with(ctx, &s, &user(shader, 64, N_EXACT_ALL)).unwrap();
        let e = rmse(&out.image, &reference.image);
        eprintln!("{example}: RMSE vs lit reference {e:.3e} (thesis, 64 samples: {e_thesis:.3e})");
        assert!(out.image.all_finite());
        assert!(e > 10.0 * e_thesis, "{example}: {e} vs thesis {e_thesis}");
    }
}

/// The dispatch reports every pass to its progress callback (issue 14 item 6, the spinner of
/// `pgt approx`): as many calls as passes, numbered 1..=N, the work items done never going back
/// and, on lavapipe, a thesis run with many samples taking several passes.
#[test]
fn progress_is_reported_once_per_pass() {
    let Some(ctx) = gpu() else { return };
    let s = scene(
        disjoint_particles(),
        lights(),
        RenderMode::Volume,
        models::LIT,
    );
    let params = thesis(256, N_EXACT_ALL);
    let method = Method::named("thesis").unwrap();
    let pipeline = pgt::approx::ApproxPipeline::new(ctx, &method, &params).unwrap();
    let mut calls = Vec::new();
    let out = pipeline
        .render_with_progress(ctx, &s, &params, &mut |p| calls.push(p))
        .unwrap();
    eprintln!("{} passes: {calls:?}", out.passes);
    assert_eq!(calls.len() as u32, out.passes);
    for (i, p) in calls.iter().enumerate() {
        assert_eq!(p.passes, i as u32 + 1);
    }
    assert!(calls.windows(2).all(|w| w[1].items_done >= w[0].items_done));
    if ctx.adapter.is_cpu {
        assert!(
            out.passes > 1,
            "lavapipe should split 256 samples into passes"
        );
    }
}

/// `n` overlapping spheres of radius 0.5 in a row along the camera's axis, 0.1 apart from
/// z = −5, emission model.
fn row_of_spheres(n: usize) -> Scene {
    let ps: Vec<_> = (0..n)
        .map(|i| {
            particle(
                [0.0, 0.0, -5.0 + 0.1 * i as f64],
                0.5,
                [1.0, 1.0, 1.0],
                0.01,
            )
        })
        .collect();
    scene(ps, vec![], RenderMode::Volume, models::EMISSION)
}

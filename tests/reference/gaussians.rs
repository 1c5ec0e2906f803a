//! Particles of Gaussian density (docs/design.md §9) in the exact reference: one Gaussian and
//! well-separated ones against their closed forms, overlapping ones against a brute-force
//! Riemann sum of the 3D densities, coincident ones against one of twice σ, the opacity
//! mapping through a scene file, the bound on the cut-off for k from 2 to 8, the coverage of
//! err on a scene of a few thousand overlapping Gaussians, the single-scatter model against a
//! brute-force nested sum and its err against a much tighter render with a point light inside
//! the gas, a sun through a layer of small Gaussians against a sum over every Gaussian's shadow
//! depth in closed form, and the refusals by name.
//!
//! The oracles evaluate σ(x) = σᵢ·exp(−½(x − c)ᵀΣ⁻¹(x − c)) in 3D with Σ = R·S²·Rᵀ built here
//! from the quaternion, never through `optics::gaussian`.

use crate::support::{self, volume::Rng};
use glam::{DMat3, DQuat, DVec3};
use pgt::geometry::{Camera, Ellipsoid, Ray};
use pgt::optics::light::{Falloff, Light};
use pgt::optics::{models, Particle, Profile};
use pgt::reference::gaussian::GaussianRenderer;
use pgt::reference::{render, Integrator, RadianceEstimator, RenderOptions};
use pgt::scene::{RenderMode, Scene, SceneLoadOptions};
use std::path::Path;

const SQRT_TAU: f64 = 2.506_628_274_631_000_5;

fn gaussian(center: DVec3, std: DVec3, rotation: DQuat, color: DVec3, sigma: f64) -> Particle {
    Particle {
        center,
        radius: std.max_element(),
        color,
        sigma,
        albedo: color,
        ks: 0.0,
        shininess: 32.0,
        ellipsoid: (std.x != std.y || std.y != std.z).then(|| Ellipsoid::new(std, rotation)),
        profile: Profile::Gaussian,
    }
}

/// The volume tests' scene (emission, its background), seen from further away, at `tol` and
/// the cut-off `cutoff`.
fn scene(particles: Vec<Particle>, size: u32, tol: f64, cutoff: Option<f64>) -> Scene {
    let mut s = support::volume::scene(models::EMISSION, particles, vec![], size);
    s.camera = Camera::new(
        DVec3::new(0.0, 0.0, -12.0),
        DVec3::ZERO,
        DVec3::Y,
        30.0,
        size,
        size,
    );
    s.render.tol = tol;
    s.render.gaussian_cutoff = cutoff;
    s
}

/// σ of one Gaussian at x, from its covariance in 3D.
fn density(p: &Particle, x: DVec3) -> f64 {
    let (std, rotation) = match &p.ellipsoid {
        Some(e) => (e.semi_axes(), e.rotation()),
        None => (DVec3::splat(p.radius), DQuat::IDENTITY),
    };
    let r = DMat3::from_quat(rotation);
    let inv_var = DMat3::from_diagonal(DVec3::ONE / (std * std));
    let inv_cov = r * inv_var * r.transpose();
    let d = x - p.center;
    p.sigma * (-0.5 * d.dot(inv_cov * d)).exp()
}

/// The emission integral by `n` midpoint steps over [0, t_max], each step exact for the
/// constant density of its midpoint.
fn riemann(particles: &[Particle], bg: DVec3, ray: &Ray, t_max: f64, n: usize) -> DVec3 {
    riemann_stretches(particles, bg, ray, &[(t_max, n)])
}

/// The same over consecutive stretches of the ray, each `(end, steps)`, from 0.
fn riemann_stretches(
    particles: &[Particle],
    bg: DVec3,
    ray: &Ray,
    stretches: &[(f64, usize)],
) -> DVec3 {
    let (mut l, mut t, mut start) = (DVec3::ZERO, 1.0, 0.0);
    for &(end, n) in stretches {
        let dt = (end - start) / n as f64;
        for k in 0..n {
            let x = ray.at(start + (k as f64 + 0.5) * dt);
            let (mut sigma, mut emitted) = (0.0, DVec3::ZERO);
            for p in particles {
                let s = density(p, x);
                sigma += s;
                emitted += s * p.color;
            }
            if sigma > 0.0 {
                let a = -(-sigma * dt).exp_m1();
                l += t * a * emitted / sigma;
                t *= 1.0 - a;
            }
        }
        start = end;
    }
    l + t * bg
}

/// The optical depth of one Gaussian along the whole ray by composite Simpson on [0, t_max].
fn line_depth(p: &Particle, ray: &Ray, t_max: f64, n: usize) -> f64 {
    let h = t_max / n as f64;
    let f = |k: usize| density(p, ray.at(k as f64 * h));
    let mut sum = f(0) + f(n);
    for k in 1..n {
        sum += if k % 2 == 1 { 4.0 } else { 2.0 } * f(k);
    }
    sum * h / 3.0
}

fn turned(angle: f64) -> DQuat {
    DQuat::from_axis_angle(DVec3::new(0.4, 1.0, -0.3).normalize(), angle)
}

fn renderer(s: &Scene) -> GaussianRenderer {
    GaussianRenderer::new(s, Integrator::Adaptive).expect("a Gaussian scene")
}

/// How many pixel channels of `coarse` lie within the two renders' err of `tight` (of how many),
/// and the largest difference between them.
fn coverage(
    coarse: &pgt::reference::RenderOutput,
    tight: &pgt::reference::RenderOutput,
) -> (usize, usize, f32) {
    let (ce, te) = (
        coarse.error.as_ref().unwrap(),
        tight.error.as_ref().unwrap(),
    );
    let (mut covered, mut total, mut off) = (0usize, 0usize, 0.0f32);
    for i in 0..coarse.image.pixels.len() {
        for c in 0..3 {
            let diff = (coarse.image.pixels[i][c] - tight.image.pixels[i][c]).abs();
            total += 1;
            covered += usize::from(diff <= ce.pixels[i][c] + te.pixels[i][c]);
            off = off.max(diff);
        }
    }
    (covered, total, off)
}

#[test]
fn one_gaussian_is_its_closed_form() {
    let p = gaussian(
        DVec3::new(0.2, -0.1, 1.0),
        DVec3::new(1.1, 0.4, 0.7),
        turned(0.8),
        DVec3::new(0.9, 0.5, 0.2),
        1.7,
    );
    let s = scene(vec![p], 16, 1e-9, None);
    let r = renderer(&s);
    let bg = s.render.background;
    let mut checked = 0;
    for (x, y) in [(8.0, 8.0), (5.5, 9.5), (11.2, 3.3), (2.0, 14.0), (8.5, 4.0)] {
        let ray = s.camera.ray_at(x, y);
        let tau = line_depth(&p, &ray, 40.0, 200_000);
        let truth = p.color * -(-tau).exp_m1() + bg * (-tau).exp();
        let got = r.radiance(&ray);
        for c in 0..3 {
            let diff = (got.radiance[c] - truth[c]).abs();
            assert!(
                diff <= got.error[c] + 1e-12,
                "pixel ({x}, {y}) channel {c}: {} against {} (err {})",
                got.radiance[c],
                truth[c],
                got.error[c]
            );
            assert!(got.error[c] <= 1e-9, "err {} above tol", got.error[c]);
        }
        if tau > 1e-3 {
            checked += 1;
        }
    }
    assert!(checked >= 3, "too few rays cross the Gaussian");
}

#[test]
fn well_separated_gaussians_composite_in_their_closed_forms() {
    // Three Gaussians 2.5 apart along the view with standard deviations ≤ 0.2: more than 12
    // standard deviations apart, so along any ray each one's depth is its own.
    let particles = vec![
        gaussian(
            DVec3::new(0.1, 0.0, -2.5),
            DVec3::new(0.15, 0.2, 0.1),
            turned(0.3),
            DVec3::new(1.0, 0.2, 0.1),
            6.0,
        ),
        gaussian(
            DVec3::new(0.0, 0.05, 0.0),
            DVec3::splat(0.2),
            DQuat::IDENTITY,
            DVec3::new(0.1, 1.0, 0.2),
            4.0,
        ),
        gaussian(
            DVec3::new(-0.05, 0.0, 2.5),
            DVec3::new(0.2, 0.1, 0.2),
            turned(1.2),
            DVec3::new(0.2, 0.3, 1.0),
            8.0,
        ),
    ];
    let s = scene(particles.clone(), 64, 1e-9, None);
    let r = renderer(&s);
    let bg = s.render.background;
    let mut covered = 0;
    for (x, y) in [(32.0, 32.0), (32.6, 31.2), (33.5, 32.5), (31.0, 33.0)] {
        let ray = s.camera.ray_at(x, y);
        // Front to back: C₁(1 − e^{−τ₁}) + e^{−τ₁}(C₂(1 − e^{−τ₂}) + e^{−τ₂}(…)).
        let mut truth = bg;
        for p in particles.iter().rev() {
            let tau = line_depth(p, &ray, 40.0, 200_000);
            truth = p.color * -(-tau).exp_m1() + truth * (-tau).exp();
        }
        let got = r.radiance(&ray);
        for c in 0..3 {
            assert!(
                (got.radiance[c] - truth[c]).abs() <= got.error[c] + 1e-12,
                "({x}, {y}) channel {c}: {} against {}",
                got.radiance[c],
                truth[c]
            );
        }
        if (truth - bg).abs().max_element() > 0.05 {
            covered += 1;
        }
    }
    assert!(covered >= 3, "the rays miss the Gaussians");
}

fn overlapping(rng: &mut Rng, n: usize, spread: f64) -> Vec<Particle> {
    (0..n)
        .map(|_| {
            gaussian(
                rng.vec3(-spread, spread),
                DVec3::new(
                    rng.range(0.2, 0.9),
                    rng.range(0.2, 0.9),
                    rng.range(0.2, 0.9),
                ),
                turned(rng.range(0.0, 3.0)),
                rng.vec3(0.0, 1.0),
                rng.range(0.3, 3.0),
            )
        })
        .collect()
}

/// A thick cloud that stops every ray long before its far side: the gather goes front to back
/// and leaves out what lies behind where the ray stops; the result still matches a brute-force
/// Riemann sum over every Gaussian within err, and err keeps to tol.
#[test]
fn a_ray_stopped_in_a_thick_cloud_matches_a_riemann_sum_over_every_gaussian() {
    let mut rng = Rng::new(4701);
    let particles: Vec<Particle> = (0..240)
        .map(|_| {
            let c = DVec3::new(
                rng.range(-1.5, 1.5),
                rng.range(-1.5, 1.5),
                rng.range(-2.0, 6.0),
            );
            let std = DVec3::new(
                rng.range(0.2, 0.5),
                rng.range(0.2, 0.5),
                rng.range(0.2, 0.5),
            );
            gaussian(c, std, turned(rng.range(0.0, 3.0)), rng.vec3(0.0, 1.0), 3.0)
        })
        .collect();
    let tol = 1e-5;
    let s = scene(particles.clone(), 16, tol, None);
    let r = renderer(&s);
    let bg = s.render.background;
    for (x, y) in [(8.0, 8.0), (6.5, 9.5), (9.2, 7.1)] {
        let ray = s.camera.ray_at(x, y);
        let fine = riemann(&particles, bg, &ray, 24.0, 100_000);
        let coarse = riemann(&particles, bg, &ray, 24.0, 50_000);
        let riemann_error = (fine - coarse).abs();
        let (got, parts) = r.radiance_and_parts(&ray);
        assert!(
            parts.ray_stop != DVec3::ZERO,
            "({x}, {y}) did not stop: {got:?}"
        );
        assert!(got.error.max_element() <= tol, "({x}, {y}): {got:?}");
        for c in 0..3 {
            assert!(
                (got.radiance[c] - fine[c]).abs() <= got.error[c] + riemann_error[c] + 1e-12,
                "({x}, {y}) channel {c}: {} against the Riemann sum {} (err {}, Riemann {})",
                got.radiance[c],
                fine[c],
                got.error[c],
                riemann_error[c]
            );
        }
    }
}

#[test]
fn overlapping_gaussians_match_a_riemann_sum_of_1e5_steps() {
    let mut rng = Rng::new(35);
    let particles = overlapping(&mut rng, 8, 1.0);
    let s = scene(particles.clone(), 16, 1e-8, None);
    let r = renderer(&s);
    let bg = s.render.background;
    for (x, y) in [(8.0, 8.0), (6.5, 9.5), (10.0, 7.0), (7.3, 5.1)] {
        let ray = s.camera.ray_at(x, y);
        let fine = riemann(&particles, bg, &ray, 24.0, 100_000);
        let coarse = riemann(&particles, bg, &ray, 24.0, 50_000);
        // The midpoint sum's error falls as h²: at 10⁵ steps it is about a third of the
        // difference to 5·10⁴.
        let riemann_error = (fine - coarse).abs();
        let got = r.radiance(&ray);
        for c in 0..3 {
            assert!(
                (got.radiance[c] - fine[c]).abs() <= got.error[c] + riemann_error[c] + 1e-12,
                "({x}, {y}) channel {c}: {} against the Riemann sum {} (err {}, Riemann {})",
                got.radiance[c],
                fine[c],
                got.error[c],
                riemann_error[c]
            );
        }
        assert!(riemann_error.max_element() < 1e-6, "{riemann_error}");
        assert!(
            (fine - bg).abs().max_element() > 0.1,
            "the ray misses the gas"
        );
    }
}

#[test]
fn two_coincident_gaussians_equal_one_with_twice_sigma() {
    let mut rng = Rng::new(7);
    let base = overlapping(&mut rng, 3, 0.8);
    let mut doubled = base.clone();
    doubled.push(base[1]);
    let mut twice = base.clone();
    twice[1].sigma *= 2.0;
    let options = RenderOptions::default();
    let a = render(&scene(doubled, 12, 1e-8, Some(6.0)), &options).unwrap();
    let b = render(&scene(twice, 12, 1e-8, Some(6.0)), &options).unwrap();
    let (ea, eb) = (a.error.unwrap(), b.error.unwrap());
    for i in 0..a.image.pixels.len() {
        for c in 0..3 {
            let diff = (a.image.pixels[i][c] - b.image.pixels[i][c]).abs();
            assert!(
                diff <= ea.pixels[i][c] + eb.pixels[i][c],
                "pixel {i} channel {c}: {diff}"
            );
        }
    }
}

#[test]
fn a_scene_files_opacity_is_seen_along_the_shortest_axis() {
    // A Gaussian whose shortest standard deviation (0.2) lies along the view, opacity 0.6:
    // the centre pixel is 0.6·C + 0.4·L_bg.
    let text = r#"
[camera]
position = [0.0, 0.0, -10.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 20.0
width = 9
height = 9
[render]
model = "emission"
background = [0.2, 0.3, 0.4]
tol = 1e-9
[[particles]]
center = [0.0, 0.0, 0.0]
semi_axes = [0.2, 0.9, 0.5]
rotation = [0.70710678118654752, 0.0, 0.70710678118654752, 0.0]
color = [1.0, 0.5, 0.25]
opacity = 0.6
density = "gaussian"
"#;
    let s = Scene::from_toml_str(
        text,
        Path::new("opacity.toml"),
        &SceneLoadOptions::default(),
    )
    .unwrap();
    assert_eq!(s.particles[0].profile, Profile::Gaussian);
    let r = renderer(&s);
    let got = r.radiance(&s.camera.ray_at(4.5, 4.5));
    let want = 0.6 * DVec3::new(1.0, 0.5, 0.25) + 0.4 * DVec3::new(0.2, 0.3, 0.4);
    assert!(
        (got.radiance - want).abs().max_element() <= got.error.max_element() + 1e-12,
        "{} against {want}",
        got.radiance
    );
    // Seen along its longest axis the same Gaussian is more opaque than 0.6.
    let side = text.replace(
        "rotation = [0.70710678118654752, 0.0, 0.70710678118654752, 0.0]",
        "rotation = [0.70710678118654752, 0.70710678118654752, 0.0, 0.0]",
    );
    let s =
        Scene::from_toml_str(&side, Path::new("side.toml"), &SceneLoadOptions::default()).unwrap();
    let got = renderer(&s).radiance(&s.camera.ray_at(4.5, 4.5));
    assert!(got.radiance.x > want.x + 0.1, "{}", got.radiance);
}

#[test]
fn the_cutoff_bound_holds_for_k_from_2_to_8() {
    let mut rng = Rng::new(11);
    let particles = overlapping(&mut rng, 60, 2.0);
    let options = RenderOptions::default();
    let truth = render(&scene(particles.clone(), 24, 1e-9, None), &options).unwrap();
    let truth_err = truth.error.unwrap();
    let mut errors = Vec::new();
    for k in 2..=8 {
        let s = scene(particles.clone(), 24, 1e-9, Some(k as f64));
        let cut = render(&s, &options).unwrap();
        let err = cut.error.unwrap();
        let mut worst: f32 = 0.0;
        for i in 0..cut.image.pixels.len() {
            for c in 0..3 {
                let diff = (cut.image.pixels[i][c] - truth.image.pixels[i][c]).abs();
                assert!(
                    diff <= err.pixels[i][c] + truth_err.pixels[i][c],
                    "k {k}, pixel {i} channel {c}: off by {diff}, err {}",
                    err.pixels[i][c]
                );
                worst = worst.max(diff);
            }
        }
        errors.push((k, worst, cut.stats.max_error.unwrap()));
    }
    // The cut matters at k = 2 (the bound is not vacuous there) and err shrinks with k.
    assert!(errors[0].1 > 1e-4, "k = 2 changes nothing: {errors:?}");
    assert!(errors[0].2 > errors[6].2, "{errors:?}");
}

#[test]
fn err_covers_the_truth_on_thousands_of_overlapping_gaussians() {
    let mut rng = Rng::new(2024);
    let particles: Vec<Particle> = (0..3000)
        .map(|_| {
            gaussian(
                rng.vec3(-3.0, 3.0),
                DVec3::new(
                    rng.range(0.05, 0.3),
                    rng.range(0.05, 0.3),
                    rng.range(0.05, 0.3),
                ),
                turned(rng.range(0.0, 3.0)),
                rng.vec3(0.0, 1.0),
                rng.range(0.5, 6.0),
            )
        })
        .collect();
    let options = RenderOptions::default();
    let coarse = render(&scene(particles.clone(), 40, 1e-3, None), &options).unwrap();
    let tight = render(&scene(particles, 40, 1e-8, None), &options).unwrap();
    let (covered, total, off) = coverage(&coarse, &tight);
    assert!(
        covered as f64 >= 0.999 * total as f64,
        "err covers {covered} of {total} channels"
    );
    assert!(
        off > 1e-6,
        "the coarse render is as good as the tight one: nothing is tested"
    );
    assert!(tight.stats.max_error.unwrap() <= 1e-7);
}

#[test]
fn what_the_reference_does_not_render_is_refused_by_name() {
    let mut rng = Rng::new(3);
    let particles = overlapping(&mut rng, 2, 1.0);
    let refused = |s: &Scene, words: &str| {
        let Err(e) = render(s, &RenderOptions::default()) else {
            panic!("not refused: {words}")
        };
        assert!(e.to_string().contains(words), "{e}");
    };
    let mut s = scene(particles.clone(), 4, 1e-5, None);
    s.render.model = models::LIT;
    refused(&s, "lit model");
    let mut s = scene(particles.clone(), 4, 1e-5, None);
    s.render.mode = RenderMode::Opaque;
    refused(&s, "opaque mode");
    let mut s = scene(particles.clone(), 4, 1e-5, None);
    s.particles[0].profile = Profile::Constant;
    refused(&s, "mixes particles of constant and Gaussian density");
    let mut s = scene(particles, 4, 1e-5, None);
    s.particles[1].sigma = f64::INFINITY;
    refused(&s, "infinite peak density");
    let Err(e) = Scene::from_toml_str(
        "[defaults]\ndensity = \"gaussian\"\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nopacity = 1.0\n",
        Path::new("full.toml"),
        &SceneLoadOptions::default(),
    ) else {
        panic!("opacity 1 not refused")
    };
    assert!(e.to_string().contains("opacity must be < 1"), "{e}");
    assert!(e.to_string().contains("full.toml"), "{e}");
}

/// The depth through a Gaussian's centre along its shortest axis is −ln(1 − o): the mapping
/// as `[defaults] opacity` gives it, checked against the 3D density.
#[test]
fn the_peak_density_of_the_mapping_gives_the_files_opacity() {
    let s = Scene::from_toml_str(
        "[defaults]\ndensity = \"gaussian\"\nopacity = 0.35\n[[particles]]\ncenter = [1.0, 2.0, 3.0]\nsemi_axes = [0.5, 0.25, 1.0]\n",
        Path::new("mapping.toml"),
        &SceneLoadOptions::default(),
    )
    .unwrap();
    let p = &s.particles[0];
    let ray = Ray::new(p.center - 10.0 * DVec3::Y, DVec3::Y);
    let tau = line_depth(p, &ray, 20.0, 100_000);
    assert!((tau - -(0.65f64).ln()).abs() < 1e-10, "{tau}");
    assert!((p.sigma * 0.25 * SQRT_TAU - -(0.65f64).ln()).abs() < 1e-14);
}

#[test]
fn a_flat_gaussian_inside_a_wide_one_is_not_stepped_over() {
    // A splat 10⁻⁸ thick along the view at the centre of a wide Gaussian of another colour
    // (real splatting files hold such flat ones): along the axis the flat one is a slab at t_f,
    // so L = C_w(1 − e^{−τ₁}) + e^{−τ₁}[C_f(1 − e^{−τ_f}) + e^{−τ_f}(C_w(1 − e^{−τ₂}) + e^{−τ₂}L_bg)]
    // with τ₁ = τ₂ half the wide one's depth; the slab's own width moves L by < 1e-6.
    let wide = gaussian(
        DVec3::ZERO,
        DVec3::splat(0.8),
        DQuat::IDENTITY,
        DVec3::new(0.1, 0.2, 1.0),
        1.5,
    );
    let flat = gaussian(
        DVec3::ZERO,
        DVec3::new(0.5, 0.4, 1e-8),
        DQuat::IDENTITY,
        DVec3::new(1.0, 0.8, 0.1),
        0.9 / (1e-8 * SQRT_TAU),
    );
    let s = scene(vec![wide, flat], 9, 1e-7, None);
    let got = renderer(&s).radiance(&s.camera.ray_at(4.5, 4.5));
    let half = 0.5 * wide.sigma * 0.8 * SQRT_TAU;
    let tau_f: f64 = 0.9;
    let bg = s.render.background;
    let behind = wide.color * -(-half).exp_m1() + (-half).exp() * bg;
    let at_flat = flat.color * -(-tau_f).exp_m1() + (-tau_f).exp() * behind;
    let want = wide.color * -(-half).exp_m1() + (-half).exp() * at_flat;
    for c in 0..3 {
        assert!(
            (got.radiance[c] - want[c]).abs() <= got.error[c] + 1e-6,
            "channel {c}: {} against {} (err {})",
            got.radiance[c],
            want[c],
            got.error[c]
        );
    }
}

/// σ·Q of the single-scatter model (docs/design.md §2) at x, from the 3D densities: a·ΣσᵢCᵢ +
/// Σσᵢαᵢ/(4π)·Σ_l E_l·T_l, each T_l by composite Simpson of the summed density over the shadow
/// stretch (at most `reach` long) in `steps` steps; and σ.
fn scattering_source(
    particles: &[Particle],
    lights: &[Light],
    a: f64,
    x: DVec3,
    steps: usize,
    reach: f64,
) -> (DVec3, f64) {
    let (mut sigma, mut emitted, mut albedo) = (0.0, DVec3::ZERO, DVec3::ZERO);
    for p in particles {
        let d = density(p, x);
        sigma += d;
        emitted += d * p.color;
        albedo += d * p.albedo;
    }
    if sigma == 0.0 {
        return (DVec3::ZERO, 0.0);
    }
    let mut light_sum = DVec3::ZERO;
    for l in lights {
        let (toward, distance, irradiance) = match *l {
            Light::Directional {
                direction,
                irradiance,
            } => (-direction, f64::INFINITY, irradiance),
            Light::Point {
                position,
                intensity,
                ..
            } => {
                let d = (position - x).length();
                ((position - x) / d, d, intensity / (d * d))
            }
        };
        let length = distance.min(reach);
        let h = length / steps as f64;
        let f = |k: usize| -> f64 {
            let y = x + (k as f64 * h) * toward;
            particles.iter().map(|p| density(p, y)).sum()
        };
        let mut depth = f(0) + f(steps);
        for k in 1..steps {
            depth += if k % 2 == 1 { 4.0 } else { 2.0 } * f(k);
        }
        light_sum += irradiance * (-depth * h / 3.0).exp();
    }
    let q = a * emitted + albedo * light_sum / (4.0 * std::f64::consts::PI);
    (q, sigma)
}

/// The single-scatter integral along `ray` by `n` midpoint steps over [0, t_max], each step
/// exact for the density and source of its midpoint.
fn single_scatter_sum(s: &Scene, ray: &Ray, t_max: f64, n: usize, shadow_steps: usize) -> DVec3 {
    let dt = t_max / n as f64;
    let (mut l, mut t) = (DVec3::ZERO, 1.0);
    for k in 0..n {
        let x = ray.at((k as f64 + 0.5) * dt);
        let (sigma_q, sigma) = scattering_source(
            &s.particles,
            &s.lights,
            s.render.emission_weight,
            x,
            shadow_steps,
            16.0,
        );
        if sigma > 0.0 {
            let absorbed = -(-sigma * dt).exp_m1();
            l += t * absorbed * sigma_q / sigma;
            t *= 1.0 - absorbed;
        }
    }
    l + t * s.render.background
}

/// A directional light and a point light in the tails of the gas.
fn two_lights(point: DVec3) -> Vec<Light> {
    vec![
        Light::Directional {
            direction: DVec3::new(-0.5, -1.0, 0.3).normalize(),
            irradiance: DVec3::new(1.0, 0.9, 0.7),
        },
        Light::Point {
            position: point,
            intensity: DVec3::new(2.0, 1.5, 2.5),
            falloff: Falloff::InverseSquare,
        },
    ]
}

fn single_scatter_scene(
    particles: Vec<Particle>,
    lights: Vec<Light>,
    size: u32,
    tol: f64,
) -> Scene {
    let mut s = scene(particles, size, tol, None);
    s.render.model = models::SINGLE_SCATTER;
    s.render.emission_weight = 0.3;
    s.lights = lights;
    s
}

#[test]
fn single_scatter_matches_a_nested_brute_force_sum() {
    // Three overlapping turned Gaussians, albedo unlike colour, a sun and a point light 1.1 off
    // the central ray inside the gas's tails.
    let mut rng = Rng::new(41);
    let mut particles = overlapping(&mut rng, 3, 0.6);
    for p in &mut particles {
        p.albedo = rng.vec3(0.2, 1.0);
    }
    let s = single_scatter_scene(
        particles.clone(),
        two_lights(DVec3::new(0.3, 1.1, 0.2)),
        16,
        1e-8,
    );
    let r = renderer(&s);
    let mut dark = s.clone();
    dark.lights.clear();
    for (x, y) in [(8.0, 8.0), (6.5, 9.5), (10.2, 6.1)] {
        let ray = s.camera.ray_at(x, y);
        let fine = single_scatter_sum(&s, &ray, 24.0, 6000, 600);
        let coarse = single_scatter_sum(&s, &ray, 24.0, 3000, 300);
        // Both sums' errors fall at least as h²: the difference bounds the finer one's.
        let sum_error = (fine - coarse).abs();
        let got = r.radiance(&ray);
        assert!(got.shadow_rays > 0 && !got.unconverged);
        for c in 0..3 {
            assert!(
                (got.radiance[c] - fine[c]).abs() <= got.error[c] + sum_error[c] + 1e-10,
                "({x}, {y}) channel {c}: {} against the nested sum {} (err {}, sum {})",
                got.radiance[c],
                fine[c],
                got.error[c],
                sum_error[c]
            );
        }
        assert!(sum_error.max_element() < 1e-5, "{sum_error}");
        assert!(got.error.max_element() < 1e-7, "{}", got.error);
        // The lights are what is tested: without them the pixel is far from it.
        let unlit = single_scatter_sum(&dark, &ray, 24.0, 6000, 600);
        assert!(
            (fine - unlit).abs().max_element() > 0.02,
            "{fine} vs {unlit}"
        );
    }
}

/// The optical depth over [0, ∞) of one Gaussian along `ray`, in closed form from its 3D
/// covariance (not through `optics::gaussian`): with A = Σ⁻¹ the exponent along x + r·u is
/// −½(αr² + 2βr + γ), α = uᵀAu, β = uᵀA(x − c), γ = (x − c)ᵀA(x − c), so the depth is
/// σ·e^{−½(γ − β²/α)}·√(π/(2α))·erfc(β/√(2α)).
fn half_line_depth(p: &Particle, ray: &Ray) -> f64 {
    let (std, rotation) = match &p.ellipsoid {
        Some(e) => (e.semi_axes(), e.rotation()),
        None => (DVec3::splat(p.radius), DQuat::IDENTITY),
    };
    let r = DMat3::from_quat(rotation);
    let a = r * DMat3::from_diagonal(DVec3::ONE / (std * std)) * r.transpose();
    let (u, x) = (ray.direction, ray.origin - p.center);
    let (alpha, beta, gamma) = (u.dot(a * u), u.dot(a * x), x.dot(a * x));
    let least = (gamma - beta * beta / alpha).max(0.0);
    p.sigma
        * (-0.5 * least).exp()
        * (std::f64::consts::PI / (2.0 * alpha)).sqrt()
        * libm::erfc(beta / (2.0 * alpha).sqrt())
}

/// The single-scatter integral of a sun alone along `ray` by `n` midpoint steps over
/// [0, t_max], each step exact for its midpoint's density and source, with the sun's
/// transmittance from the depth of every Gaussian of the scene in closed form
/// ([`half_line_depth`]: no cut-off, no list, no BVH).
fn sunlit_sum(s: &Scene, ray: &Ray, t_max: f64, n: usize) -> DVec3 {
    let [Light::Directional {
        direction,
        irradiance,
    }] = s.lights[..]
    else {
        panic!("one sun");
    };
    let a = s.render.emission_weight;
    let dt = t_max / n as f64;
    let (mut l, mut t) = (DVec3::ZERO, 1.0);
    for k in 0..n {
        let x = ray.at((k as f64 + 0.5) * dt);
        let (mut sigma, mut emitted, mut albedo) = (0.0, DVec3::ZERO, DVec3::ZERO);
        for p in &s.particles {
            let d = density(p, x);
            sigma += d;
            emitted += d * p.color;
            albedo += d * p.albedo;
        }
        if sigma <= 0.0 {
            continue;
        }
        let shadow = Ray::new(x, -direction);
        let depth: f64 = s
            .particles
            .iter()
            .map(|p| half_line_depth(p, &shadow))
            .sum();
        let q = a * emitted + albedo * irradiance * (-depth).exp() / (4.0 * std::f64::consts::PI);
        let absorbed = -(-sigma * dt).exp_m1();
        l += t * absorbed * q / sigma;
        t *= 1.0 - absorbed;
    }
    l + t * s.render.background
}

/// A sun above a cloud on the camera's axis, and between them a layer of small round and flat
/// Gaussians whose shadows stripe the cloud: the shadow rays of each piece of a camera ray take
/// their Gaussians from one list per piece (`reference::sun_lists`), and a list that left out
/// a Gaussian a shadow ray meets would brighten a stripe far beyond err. Against a midpoint sum
/// whose shadow rays take every Gaussian of the scene in closed form.
#[test]
fn a_sun_through_a_layer_of_small_gaussians_matches_a_sum_over_every_gaussian() {
    let mut rng = Rng::new(2047);
    let mut particles: Vec<Particle> = (0..3)
        .map(|_| {
            gaussian(
                rng.vec3(-0.3, 0.3),
                DVec3::new(
                    rng.range(0.6, 1.0),
                    rng.range(0.6, 1.0),
                    rng.range(0.6, 1.0),
                ),
                turned(rng.range(0.0, 3.0)),
                rng.vec3(0.2, 1.0),
                rng.range(0.3, 0.8),
            )
        })
        .collect();
    for k in 0..80 {
        let mut std = DVec3::new(
            rng.range(0.03, 0.2),
            rng.range(0.03, 0.2),
            rng.range(0.03, 0.2),
        );
        if k % 2 == 0 {
            std.y = 1e-3 * std.x;
        }
        let center = DVec3::new(
            rng.range(-1.2, 1.8),
            rng.range(0.6, 2.5),
            rng.range(-2.0, 1.5),
        );
        let p = gaussian(
            center,
            std,
            turned(rng.range(0.0, 3.0)),
            rng.vec3(0.0, 1.0),
            1.0,
        );
        // Each stops about half the light through its centre across its thinnest axis.
        let sigma = 0.7 / (std.min_element() * SQRT_TAU);
        particles.push(Particle { sigma, ..p });
    }
    let sun = vec![Light::Directional {
        direction: DVec3::new(-0.4, -1.0, 0.3).normalize(),
        irradiance: DVec3::new(1.0, 0.9, 0.7),
    }];
    let s = single_scatter_scene(particles.clone(), sun.clone(), 16, 1e-7);
    let r = renderer(&s);
    let mut open = s.clone();
    open.particles.truncate(3);
    let mut striped = 0;
    for (x, y) in [(8.0, 8.0), (7.3, 8.6), (8.9, 7.7), (8.2, 9.4), (6.6, 7.1)] {
        let ray = s.camera.ray_at(x, y);
        let fine = sunlit_sum(&s, &ray, 24.0, 40_000);
        let coarse = sunlit_sum(&s, &ray, 24.0, 20_000);
        let sum_error = (fine - coarse).abs();
        let got = r.radiance(&ray);
        assert!(got.shadow_rays > 0 && !got.unconverged, "{got:?}");
        for c in 0..3 {
            assert!(
                (got.radiance[c] - fine[c]).abs() <= got.error[c] + sum_error[c] + 1e-10,
                "({x}, {y}) channel {c}: {} against the sum over every Gaussian {} (err {}, sum {})",
                got.radiance[c],
                fine[c],
                got.error[c],
                sum_error[c]
            );
        }
        assert!(sum_error.max_element() < 1e-6, "{sum_error}");
        // The layer's shadows are what is tested: without it the pixel is far off.
        let unshadowed = sunlit_sum(&open, &ray, 24.0, 40_000);
        striped += usize::from((fine - unshadowed).abs().max_element() > 1e-3);
    }
    assert!(striped >= 4, "the layer shades {striped} of 5 rays");
}

#[test]
fn single_scatter_err_covers_a_much_tighter_render_with_a_light_inside_the_gas() {
    let mut rng = Rng::new(77);
    let particles: Vec<Particle> = (0..400)
        .map(|_| {
            let mut p = gaussian(
                rng.vec3(-2.0, 2.0),
                DVec3::new(
                    rng.range(0.05, 0.4),
                    rng.range(0.05, 0.4),
                    rng.range(0.05, 0.4),
                ),
                turned(rng.range(0.0, 3.0)),
                rng.vec3(0.0, 1.0),
                rng.range(2.0, 12.0),
            );
            p.albedo = rng.vec3(0.0, 1.0);
            p
        })
        .collect();
    // Light scattered from a bright point light in the middle of dense gas is all there is (no
    // emission, a = 0), so the rays that stop where T·M is small stop on the lights' bound.
    let mut lights = two_lights(DVec3::new(0.1, -0.2, 0.05));
    if let Light::Point { intensity, .. } = &mut lights[1] {
        *intensity *= 10.0;
    }
    let ss = |tol| {
        let mut s = single_scatter_scene(particles.clone(), lights.clone(), 24, tol);
        s.render.emission_weight = 0.0;
        s
    };
    let options = RenderOptions::default();
    let coarse = render(&ss(1e-2), &options).unwrap();
    let tight = render(&ss(1e-7), &options).unwrap();
    let (covered, total, off) = coverage(&coarse, &tight);
    assert!(
        covered as f64 >= 0.999 * total as f64,
        "err covers {covered} of {total} channels"
    );
    assert!(off > 1e-6, "the coarse render is as good as the tight one");
    assert!(tight.stats.max_error.unwrap() <= 1e-6);
    assert!(tight.stats.shadow_rays > 0);
}

#[test]
fn a_ray_through_a_point_light_in_gaussian_gas_is_reported() {
    // The light on the central pixel's ray: Q has no bound there, the pixel is not converged
    // and its err is not finite, never a quiet number.
    let g = gaussian(
        DVec3::ZERO,
        DVec3::splat(0.7),
        DQuat::IDENTITY,
        DVec3::ONE,
        1.0,
    );
    let s = single_scatter_scene(vec![g], two_lights(DVec3::ZERO), 9, 1e-6);
    let ray = Ray::new(s.camera.position, -s.camera.position);
    let got = renderer(&s).radiance(&ray);
    assert!(got.unconverged, "{got:?}");
    assert!(!got.error.is_finite(), "{got:?}");
    let beside = renderer(&s).radiance(&s.camera.ray_at(2.0, 2.0));
    assert!(
        !beside.unconverged && beside.error.max_element() < 1e-5,
        "{beside:?}"
    );
}

#[test]
fn each_pixels_err_is_the_sum_of_its_parts_each_within_its_share() {
    use pgt::reference::budget::gaussian as share;
    // Emission over dense overlapping Gaussians (faint ones, tails and stopped rays all occur),
    // then single-scatter with a sun and a point light (shadow rays that stop).
    let mut rng = Rng::new(47);
    let particles = overlapping(&mut rng, 40, 1.5);
    let tol = 1e-5;
    let emission = scene(particles.clone(), 12, tol, None);
    let lit = single_scatter_scene(particles, two_lights(DVec3::new(0.3, 1.1, 0.2)), 12, tol);
    let (mut stopped, mut left_out, mut shadow_stopped, mut bounded, mut series) = (0, 0, 0, 0, 0);
    for s in [&emission, &lit] {
        let r = renderer(s);
        for y in 0..12 {
            for x in 0..12 {
                let ray = s.camera.ray_at(x as f64 + 0.5, y as f64 + 0.5);
                let (sample, parts) = r.radiance_and_parts(&ray);
                assert_eq!(sample.error, parts.total(), "({x}, {y})");
                assert_eq!(sample, r.radiance(&ray));
                if sample.unconverged {
                    continue;
                }
                let within = |part: DVec3, fraction: f64, what: &str| {
                    assert!(
                        part.max_element() <= fraction * tol * (1.0 + 1e-9),
                        "({x}, {y}), {} lights, {what}: {part} over its share {fraction} of tol",
                        s.lights.len()
                    );
                };
                within(parts.ray_stop, share::RAY_STOP, "ray stop");
                within(parts.bounded, share::BOUNDED, "bounded deviations");
                within(parts.series, share::SERIES, "wide windows as polynomials");
                within(parts.shadow_stop, share::SHADOW_STOP, "shadow stop");
                within(
                    parts.quadrature,
                    share::QUADRATURE + share::SHADOW_STOP + share::BOUNDED,
                    "quadrature",
                );
                if s.lights.is_empty() {
                    // Where lights scatter, a ray's M may exceed the scene's M that chose k
                    // (a point light near the ray), and the far part its share (§9).
                    within(
                        parts.left_out,
                        share::FAINT + share::TAILS + share::FAR,
                        "left out",
                    );
                    within(
                        parts.quadrature,
                        share::QUADRATURE + share::SHADOW_STOP,
                        "quadrature",
                    );
                    assert_eq!(parts.shadow_missed, DVec3::ZERO);
                    assert!(sample.error.max_element() <= tol);
                } else if parts.shadow_stop != DVec3::ZERO {
                    within(
                        parts.quadrature,
                        share::QUADRATURE + share::BOUNDED,
                        "quadrature",
                    );
                    assert_eq!(parts.bounded, DVec3::ZERO);
                    shadow_stopped += 1;
                }
                stopped += usize::from(parts.ray_stop != DVec3::ZERO);
                bounded += usize::from(parts.bounded != DVec3::ZERO);
                series += usize::from(parts.series != DVec3::ZERO);
                left_out += usize::from(parts.left_out != DVec3::ZERO);
            }
        }
    }
    assert!(
        stopped > 0 && left_out > 0 && shadow_stopped > 0 && bounded > 0 && series > 0,
        "a part never occurs: {stopped} stopped rays, {left_out} with depth left out, {shadow_stopped} with stopped shadow rays, {bounded} with bounded deviations, {series} with wide windows as polynomials"
    );
}

/// Flat splats (one axis 10⁻³ of the others) crossing round Gaussians of other colours, as the
/// donut's hair crosses itself: err at tol 1e-5 covers a render at tol/100 at ≥ 99.9 % of
/// pixel channels, whichever parts (quadrature, bounded deviations, left-out depth) it holds.
#[test]
fn err_covers_a_hundred_times_tighter_render_of_flat_and_round_gaussians() {
    let mut rng = Rng::new(4747);
    let mut particles = overlapping(&mut rng, 60, 1.2);
    for p in particles.iter_mut().step_by(2) {
        let e = p
            .ellipsoid
            .unwrap_or_else(|| Ellipsoid::new(DVec3::splat(p.radius), DQuat::IDENTITY));
        let axes = e.semi_axes();
        *p = gaussian(
            p.center,
            DVec3::new(axes.x, axes.y, 1e-3 * axes.z),
            e.rotation(),
            p.color,
            p.sigma * 20.0,
        );
    }
    let options = RenderOptions::default();
    let coarse = render(&scene(particles.clone(), 24, 1e-5, None), &options).unwrap();
    let tight = render(&scene(particles, 24, 1e-7, None), &options).unwrap();
    let (covered, total, off) = coverage(&coarse, &tight);
    assert!(
        covered as f64 >= 0.999 * total as f64,
        "err covers {covered} of {total} channels"
    );
    assert!(off > 1e-8, "the renders agree exactly: nothing is tested");
}

/// Gaussians long along the view, overlapping by the dozen, with flat ones across it among
/// them (a ray along hair-like splats): the reference cuts such a ray into long pieces and
/// counts every window open on a piece whole; it still matches a brute-force Riemann sum over
/// every Gaussian within err.
#[test]
fn long_pieces_over_many_overlapping_gaussians_match_a_riemann_sum() {
    let mut rng = Rng::new(4702);
    let mut particles: Vec<Particle> = (0..90)
        .map(|_| {
            let c = DVec3::new(
                rng.range(-0.15, 0.15),
                rng.range(-0.15, 0.15),
                rng.range(-2.5, 2.5),
            );
            let std = DVec3::new(
                rng.range(0.3, 0.5),
                rng.range(0.3, 0.5),
                rng.range(1.0, 2.0),
            );
            gaussian(c, std, DQuat::IDENTITY, rng.vec3(0.0, 1.0), 0.015)
        })
        .collect();
    // Two grazing ones, far longer along the ray than the rest, which widen the thinned cuts'
    // gap beyond most windows: those keep their own cuts, as on a ray along hair-like splats.
    for z in [-1.0, 1.0] {
        let std = DVec3::new(0.4, 0.4, 300.0);
        particles.push(gaussian(
            DVec3::new(0.0, 0.0, z),
            std,
            DQuat::IDENTITY,
            DVec3::ONE,
            1e-4,
        ));
    }
    for _ in 0..6 {
        let c = DVec3::new(
            rng.range(-0.1, 0.1),
            rng.range(-0.1, 0.1),
            rng.range(-2.0, 2.0),
        );
        let std = DVec3::new(0.6, 0.5, rng.range(0.02, 0.04));
        particles.push(gaussian(c, std, DQuat::IDENTITY, rng.vec3(0.0, 1.0), 4.0));
    }
    let tol = 1e-5;
    let s = scene(particles.clone(), 16, tol, None);
    let r = renderer(&s);
    let bg = s.render.background;
    for (x, y) in [(8.0, 8.0), (7.6, 8.3), (8.4, 7.8)] {
        let ray = s.camera.ray_at(x, y);
        // Beyond t = 40 only the grazing ones are left, smooth over 0.1.
        let fine = riemann_stretches(&particles, bg, &ray, &[(40.0, 300_000), (3000.0, 30_000)]);
        let coarse = riemann_stretches(&particles, bg, &ray, &[(40.0, 150_000), (3000.0, 15_000)]);
        let riemann_error = (fine - coarse).abs();
        let got = r.radiance(&ray);
        assert!(got.error.max_element() <= tol, "({x}, {y}): {got:?}");
        assert!(riemann_error.max_element() < 1e-6, "{riemann_error}");
        assert!(
            (fine - bg).abs().max_element() > 0.1,
            "the ray misses the gas"
        );
        for c in 0..3 {
            assert!(
                (got.radiance[c] - fine[c]).abs() <= got.error[c] + riemann_error[c] + 1e-12,
                "({x}, {y}) channel {c}: {} against the Riemann sum {} (err {}, Riemann {})",
                got.radiance[c],
                fine[c],
                got.error[c],
                riemann_error[c]
            );
        }
    }
}

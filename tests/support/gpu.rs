//! Shared by the GPU tests: one GPU context per test binary (lavapipe in CI), small scenes, and
//! independent f64 oracles written for the tests (not the code under test).
//!
//! A GPU test must FAIL, not skip, when no adapter exists and `CI=true`; elsewhere it skips
//! with a message.

#![allow(dead_code)]

use super::skip;

use glam::DVec3;
use pgt::approx::GpuContext;
use pgt::geometry::{Bvh, Camera, Hit, Ray};
use pgt::image_io::RgbImage;
use pgt::optics::extinction::sigma_from_opacity;
use pgt::scene::{Light, LightWeight, Model, Particle, RenderMode, RenderSettings, Scene};
use rayon::prelude::*;
use std::sync::OnceLock;

/// The context, or `None` outside CI when there is no adapter. The adapter is looked for once
/// per test binary; each test that gets `None` says that it skips, on a line of its own.
pub fn gpu() -> Option<&'static GpuContext> {
    static CTX: OnceLock<Result<GpuContext, String>> = OnceLock::new();
    let ctx = CTX.get_or_init(|| {
        GpuContext::new(None)
            .inspect(|ctx| eprintln!("GPU tests run on {}", ctx.adapter))
            .map_err(|e| e.to_string())
    });
    match ctx {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            if std::env::var("CI").is_ok_and(|v| v == "true") {
                panic!("CI=true and no GPU adapter: {e} (CI must install mesa-vulkan-drivers)");
            }
            skip::skipped(&format!("no GPU adapter: {e}"));
            None
        }
    }
}

/// Image side of GPU test scenes: lavapipe on two cores is slow.
pub const SIDE: u32 = 48;

pub fn particle(center: [f64; 3], radius: f64, color: [f64; 3], opacity: f64) -> Particle {
    Particle {
        ellipsoid: None,
        profile: pgt::optics::Profile::Constant,
        center: DVec3::from(center),
        radius,
        color: DVec3::from(color),
        sigma: sigma_from_opacity(opacity, radius),
        albedo: DVec3::from(color),
        ks: 0.0,
        shininess: 32.0,
    }
}

pub fn scene(
    particles: Vec<Particle>,
    lights: Vec<Light>,
    mode: RenderMode,
    model: Model,
) -> Scene {
    Scene {
        source: "gpu-test".into(),
        camera: Camera::new(
            DVec3::new(0.0, 0.0, -10.0),
            DVec3::ZERO,
            DVec3::Y,
            40.0,
            SIDE,
            SIDE,
        ),
        render: RenderSettings {
            mode,
            model,
            background: DVec3::new(0.1, 0.2, 0.3),
            light_weight: LightWeight::Mean,
            ..RenderSettings::default()
        },
        lights,
        particles,
        warnings: vec![],
        provenance: Default::default(),
    }
}

/// Five particles, pairwise disjoint (checked), one of them Θmax = 1 (σ = ∞).
pub fn disjoint_particles() -> Vec<Particle> {
    let ps = vec![
        particle([-1.5, 0.0, 0.0], 1.0, [1.0, 0.2, 0.2], 0.8),
        particle([1.5, 0.3, 1.0], 1.2, [0.2, 1.0, 0.3], 0.5),
        particle([0.0, 1.8, 2.0], 0.7, [0.3, 0.3, 1.0], 1.0),
        particle([0.2, -1.6, -1.0], 0.9, [1.0, 1.0, 0.0], 0.3),
        particle([0.0, 0.0, 5.0], 2.5, [0.5, 0.5, 0.5], 0.6),
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

/// Two lights as in the thesis (green from above, blue from below) plus a point light.
pub fn lights() -> Vec<Light> {
    vec![
        Light::Directional {
            direction: DVec3::new(0.0, -1.0, 0.0),
            irradiance: DVec3::new(0.0, 1.0, 0.0),
        },
        Light::Directional {
            direction: DVec3::new(0.2, 1.0, 0.1).normalize(),
            irradiance: DVec3::new(0.0, 0.0, 1.0),
        },
        Light::Point {
            position: DVec3::new(4.0, 3.0, -4.0),
            intensity: DVec3::new(20.0, 16.0, 12.0),
            falloff: pgt::scene::Falloff::InverseSquare,
        },
    ]
}

/// Per-channel RMSE over all pixels.
pub fn rmse(a: &RgbImage, b: &RgbImage) -> f64 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] as f64 - q[c] as f64).powi(2)))
        .sum();
    (sum / (3 * a.pixels.len()) as f64).sqrt()
}

/// Renders an image on the CPU pixel by pixel with `f`, one ray through each pixel centre.
pub fn cpu_image(camera: &Camera, f: impl Fn(&Ray) -> DVec3 + Sync) -> RgbImage {
    let (w, h) = (camera.width, camera.height);
    let pixels: Vec<[f32; 3]> = (0..w * h)
        .into_par_iter()
        .map(|i| f(&camera.pixel_ray(i % w, i / w)).as_vec3().to_array())
        .collect();
    RgbImage {
        width: w,
        height: h,
        pixels,
    }
}

fn transmittance(sigma: f64, length: f64) -> f64 {
    if length <= 0.0 {
        1.0
    } else if sigma.is_infinite() {
        0.0
    } else {
        (-sigma * length).exp()
    }
}

/// Oracle, f64: the emission model along (t_min, t_max) composited particle by particle
/// (exact when particles are disjoint: then the intervals are the particles' chords).
pub fn emission_per_particle(
    scene: &Scene,
    bvh: &Bvh,
    ray: &Ray,
    t_min: f64,
    t_max: f64,
    background: DVec3,
) -> DVec3 {
    let mut hits: Vec<Hit> = Vec::new();
    bvh.all_hits(ray, t_min, t_max, &mut hits);
    let mut l = background;
    for h in hits.iter().rev() {
        let p = &scene.particles[h.index as usize];
        let len = h.chord.t_exit.min(t_max) - h.chord.t_enter.max(t_min);
        let t = transmittance(p.sigma, len);
        l = l * t + p.color * (1.0 - t);
    }
    l
}

/// Oracle, f64: the emission model with exact intervals (docs/design.md §3) — overlaps handled:
/// in each interval σ = Σσᵢ and E = Σσᵢ·Cᵢ/Σσᵢ. Finite σ only.
pub fn emission_exact_intervals(scene: &Scene, bvh: &Bvh, ray: &Ray) -> DVec3 {
    let mut hits: Vec<Hit> = Vec::new();
    bvh.all_hits(ray, 0.0, f64::INFINITY, &mut hits);
    let mut cuts: Vec<f64> = hits
        .iter()
        .flat_map(|h| [h.chord.t_enter.max(0.0), h.chord.t_exit.max(0.0)])
        .collect();
    cuts.sort_by(f64::total_cmp);
    let mut l = scene.render.background;
    for w in cuts.windows(2).rev() {
        let (a, b) = (w[0], w[1]);
        if b <= a {
            continue;
        }
        let mid = 0.5 * (a + b);
        let (mut sigma, mut sc) = (0.0, DVec3::ZERO);
        for h in &hits {
            if h.chord.t_enter < mid && mid < h.chord.t_exit {
                let p = &scene.particles[h.index as usize];
                sigma += p.sigma;
                sc += p.sigma * p.color;
            }
        }
        if sigma > 0.0 {
            let t = (-sigma * (b - a)).exp();
            l = l * t + sc / sigma * (1.0 - t);
        }
    }
    l
}

/// Oracle, f64: the lit model's source Q(x) = w·Σ_l L_l(x) (docs/design.md §2), each L_l the
/// emission model along the shadow ray with the light as background (disjoint particles).
pub fn lit_source(scene: &Scene, bvh: &Bvh, x: DVec3) -> DVec3 {
    let w = match scene.render.light_weight {
        LightWeight::Mean => 1.0 / scene.lights.len().max(1) as f64,
        LightWeight::Sum => 1.0,
    };
    let mut q = DVec3::ZERO;
    for light in &scene.lights {
        let Some(inc) = light.incident_at(x) else {
            continue;
        };
        let ray = Ray {
            origin: x,
            direction: inc.toward,
        };
        q += emission_per_particle(scene, bvh, &ray, 0.0, inc.distance, inc.irradiance);
    }
    w * q
}

/// Oracle, f64: what a Θmax = 1 particle shows at the entry point x of a camera ray under the
/// lit model, the limit σ → ∞ of ∫σe^{−σs}Q ds: with depth z below the surface, the view path is
/// z/μ_v and the light's path through the particle z/μ_l, so the integral is
/// Σ_l (L_rest·μ_l + C·μ_v)/(μ_l + μ_v) (L_rest: light through the other particles), or C for a
/// light behind the surface.
fn lit_opaque_surface(scene: &Scene, bvh: &Bvh, ray: &Ray, index: u32, t0: f64) -> DVec3 {
    let p = &scene.particles[index as usize];
    let x = ray.at(t0);
    let n = (x - p.center).normalize();
    let mu_v = (-ray.direction).dot(n);
    let w = match scene.render.light_weight {
        LightWeight::Mean => 1.0 / scene.lights.len().max(1) as f64,
        LightWeight::Sum => 1.0,
    };
    let mut q = DVec3::ZERO;
    for light in &scene.lights {
        let Some(inc) = light.incident_at(x) else {
            continue;
        };
        let mu_l = n.dot(inc.toward);
        if mu_l <= 0.0 {
            q += p.color;
            continue;
        }
        let shadow = Ray {
            origin: x,
            direction: inc.toward,
        };
        let mut hits: Vec<Hit> = Vec::new();
        bvh.all_hits(&shadow, 0.0, inc.distance, &mut hits);
        let mut rest = inc.irradiance;
        for h in hits.iter().rev().filter(|h| h.index != index) {
            let o = &scene.particles[h.index as usize];
            let t = transmittance(
                o.sigma,
                h.chord.t_exit.min(inc.distance) - h.chord.t_enter.max(0.0),
            );
            rest = rest * t + o.color * (1.0 - t);
        }
        q += (rest * mu_l + p.color * mu_v) / (mu_l + mu_v);
    }
    w * q
}

/// Oracle, f64: the lit model on a scene of disjoint particles, each chord integrated as
/// ∫ Q(t)·σe^{−σ(t−t0)} dt by the midpoint rule in u = 1 − e^{−σ(t−t0)} (the transmittance
/// weight becomes du) with `n` panels; Θmax = 1 by its limit, [`lit_opaque_surface`].
pub fn lit_oracle(scene: &Scene, bvh: &Bvh, ray: &Ray, n: usize) -> DVec3 {
    let mut hits: Vec<Hit> = Vec::new();
    bvh.all_hits(ray, 0.0, f64::INFINITY, &mut hits);
    let mut l = scene.render.background;
    for h in hits.iter().rev() {
        let p = &scene.particles[h.index as usize];
        let t0 = h.chord.t_enter.max(0.0);
        let t1 = h.chord.t_exit;
        if p.sigma.is_infinite() {
            l = lit_opaque_surface(scene, bvh, ray, h.index, t0);
            continue;
        }
        let u_max = 1.0 - (-p.sigma * (t1 - t0)).exp();
        let du = u_max / n as f64;
        let mut sum = DVec3::ZERO;
        for k in 0..n {
            let u = (k as f64 + 0.5) * du;
            let t = t0 - (1.0 - u).ln() / p.sigma;
            sum += lit_source(scene, bvh, ray.at(t)) * du;
        }
        l = l * (1.0 - u_max) + sum;
    }
    l
}

/// Pixels whose 3×3 neighbourhood mixes rays that hit a sphere and rays that miss, decided in
/// f64 by the CPU BVH (independent of both renderers' shading): the silhouettes.
pub fn silhouette_mask(scene: &Scene, bvh: &Bvh) -> Vec<bool> {
    let cam = &scene.camera;
    let (w, h) = (cam.width as i64, cam.height as i64);
    let hit: Vec<bool> = (0..w * h)
        .map(|i| {
            bvh.first_hit(
                &cam.pixel_ray((i % w) as u32, (i / w) as u32),
                0.0,
                f64::INFINITY,
            )
            .is_some()
        })
        .collect();
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut any = false;
            let mut all = true;
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= w || ny >= h {
                        continue;
                    }
                    let v = hit[(ny * w + nx) as usize];
                    any |= v;
                    all &= v;
                }
            }
            any && !all
        })
        .collect()
}

/// A small deterministic generator (SplitMix64): the benchmarks need no statistical quality,
/// only the same scene every run.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The GPU benchmarks' random set, like the thesis's (chapter 6): `count` particles of radius
/// 1.2–1.9 (Å, used as the length unit), uniform in a cube at about protein atom density
/// (0.05 Å⁻³), Θmax 0.5, the thesis's two lights, lit; seen from −z, framing the cube's bounding
/// sphere with fov_y 40° (like the default camera), `side`² pixels.
pub fn random_cube_scene(count: usize, side: u32) -> Scene {
    let cube = (count as f64 / 0.05).cbrt();
    let mut rng = SplitMix(count as u64);
    let particles = (0..count)
        .map(|_| {
            let c = [
                (rng.next() - 0.5) * cube,
                (rng.next() - 0.5) * cube,
                (rng.next() - 0.5) * cube,
            ];
            let r = 1.2 + 0.7 * rng.next();
            particle(c, r, [rng.next(), rng.next(), rng.next()], 0.5)
        })
        .collect();
    let mut s = scene(
        particles,
        pgt::scene::thesis_lights(),
        RenderMode::Volume,
        pgt::optics::models::LIT,
    );
    let distance = 0.5 * cube * 3f64.sqrt() / (20f64.to_radians().sin());
    s.camera = Camera::new(
        DVec3::new(0.0, 0.0, -distance),
        DVec3::ZERO,
        DVec3::Y,
        40.0,
        side,
        side,
    );
    s
}

/// The benchmarks' settings: the environment variable `name`, or `default`.
pub fn env_or(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

/// (worst absolute channel difference, pixels compared) of two images over the pixels that
/// `mask` does not mark.
pub fn max_error_off_mask(a: &RgbImage, b: &RgbImage, mask: &[bool]) -> (f64, usize) {
    let mut worst = 0.0f64;
    let mut compared = 0;
    for ((x, y), masked) in a.pixels.iter().zip(&b.pixels).zip(mask) {
        if !masked {
            compared += 1;
            for c in 0..3 {
                worst = worst.max((x[c] as f64 - y[c] as f64).abs());
            }
        }
    }
    (worst, compared)
}

//! `cargo bench --bench gpu`: GPU time of the `thesis` method on random particle sets like the
//! thesis's (chapter 6): radius 1.2–1.9 (Å, the length unit), uniform in a cube at about protein
//! atom density (0.05 Å⁻³), the thesis's two directional lights, Θmax 0.5, lit model. Minutes on
//! lavapipe; the environment selects the work:
//!
//!     PGT_BENCH_SIDE=64 PGT_BENCH_COUNTS=2758,73642 PGT_BENCH_N_EXACT=1,5,all \
//!         PGT_BENCH_SAMPLES=100 cargo bench --bench gpu
//!
//! Prints one line per (count, n_exact): GPU seconds and their source (timestamp queries or
//! wall), wall seconds with the BVH build and upload, passes, the adapter, and the pixels whose
//! hit list overflowed or whose loop was cut short. Without an adapter it says so and measures
//! nothing.

use glam::DVec3;
use pgt::approx::{render_approx_with, ApproxParams, GpuContext, Timing, N_EXACT_ALL};
use pgt::formats::random::SplitMix64;
use pgt::geometry::Camera;
use pgt::optics::extinction::sigma_from_opacity;
use pgt::optics::models;
use pgt::scene::{thesis_lights, LightWeight, Particle, RenderMode, RenderSettings, Scene};

fn env_or(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

/// `count` spheres at 0.05 Å⁻³ (seeded with the count, so every run measures the same scene),
/// framed from −z by a 40° camera like the default one.
fn random_scene(count: usize, side: u32) -> Scene {
    let cube = (count as f64 / 0.05).cbrt();
    let mut rng = SplitMix64::new(count as u64);
    let particles: Vec<Particle> = (0..count)
        .map(|_| {
            let center = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            ) * cube;
            let radius = 1.2 + 0.7 * rng.next_f64();
            let color = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            Particle {
                center,
                radius,
                color,
                sigma: sigma_from_opacity(0.5, radius),
                albedo: color,
                ks: 0.0,
                shininess: 32.0,
            }
        })
        .collect();
    // The cube's bounding sphere fills the 40° field of view.
    let distance = 0.5 * cube * 3f64.sqrt() / (20f64.to_radians().sin());
    Scene {
        source: "bench".into(),
        camera: Camera::new(
            DVec3::new(0.0, 0.0, -distance),
            DVec3::ZERO,
            DVec3::Y,
            40.0,
            side,
            side,
        ),
        render: RenderSettings {
            mode: RenderMode::Volume,
            model: models::LIT,
            background: DVec3::new(0.1, 0.2, 0.3),
            light_weight: LightWeight::Mean,
            ..RenderSettings::default()
        },
        lights: thesis_lights(),
        particles,
        warnings: vec![],
    }
}

fn main() {
    let ctx = match GpuContext::new(None) {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("bench gpu: no GPU adapter ({e}); nothing measured");
            return;
        }
    };
    let side: u32 = env_or("PGT_BENCH_SIDE", "64").parse().unwrap();
    let samples: u32 = env_or("PGT_BENCH_SAMPLES", "100").parse().unwrap();
    let counts: Vec<usize> = env_or("PGT_BENCH_COUNTS", "2758,73642")
        .split(',')
        .map(|c| c.trim().parse().unwrap())
        .collect();
    let n_exacts: Vec<u32> = env_or("PGT_BENCH_N_EXACT", "1,5,all")
        .split(',')
        .map(|n| match n.trim() {
            "all" => N_EXACT_ALL,
            n => n.parse().unwrap(),
        })
        .collect();
    for count in counts {
        let s = random_scene(count, side);
        // Warm-up: lavapipe compiles the shader at its first dispatch, inside the first timing.
        let warm = ApproxParams::for_method("thesis", &[("samples", 1), ("n_exact", 1)]).unwrap();
        render_approx_with(&ctx, &s, &warm).unwrap();
        for n_exact in n_exacts.iter().copied() {
            let params =
                ApproxParams::for_method("thesis", &[("samples", samples), ("n_exact", n_exact)])
                    .unwrap();
            let wall = std::time::Instant::now();
            let out = render_approx_with(&ctx, &s, &params).unwrap();
            let wall = wall.elapsed().as_secs_f64();
            let n = if n_exact == N_EXACT_ALL {
                "all".to_string()
            } else {
                n_exact.to_string()
            };
            println!(
                "bench: {count} particles, {side}x{side}, samples {samples}, n_exact {n}: {:.3} s GPU ({}), {wall:.3} s wall incl. BVH and upload, {} passes, on {}, {} overflow / {} loop-limited pixels",
                out.gpu_seconds,
                if out.timing == Timing::Timestamps { "timestamps" } else { "wall" },
                out.passes,
                out.adapter_name,
                out.hit_overflow_pixels,
                out.loop_limited_pixels
            );
        }
    }
}

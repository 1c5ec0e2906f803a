//! `cargo bench --bench gpu_ellipsoids`: what an ellipsoid costs the GPU methods against a
//! sphere (issue 34's target: at most 1.5×). A random set like `gpu_thesis`'s (radius 1.2–1.9,
//! uniform in a cube at protein atom density, the thesis's two lights, Θmax 0.5), once as
//! spheres and once with every sphere turned into an ellipsoid of the same volume, axis ratios
//! up to 1:4 and a random orientation (`pgt bench`'s `1uun-ellipsoids` rule,
//! [`pgt::cli::bench::as_ellipsoids`]). Each method runs on both, taking turns, best of
//! `PGT_BENCH_REPEAT`; the defaults:
//!
//!     PGT_BENCH_SIDE=128 PGT_BENCH_COUNT=11032 PGT_BENCH_REPEAT=3 cargo bench --bench gpu_ellipsoids
//!
//! Prints one line per method: GPU seconds of each shape and their ratio. Without a GPU adapter
//! it says so and measures nothing.

#[path = "../tests/support/mod.rs"]
mod support;

use support::gpu;

use glam::DVec3;
use pgt::approx::{render_approx_with, ApproxParams};
use pgt::geometry::Camera;
use pgt::optics::models;
use pgt::scene::{RenderMode, Scene};

fn env_or(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

/// SplitMix64, as in `gpu_thesis`: the same scene every run.
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

fn random_scene(count: usize, side: u32) -> Scene {
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
            gpu::particle(c, r, [rng.next(), rng.next(), rng.next()], 0.5)
        })
        .collect();
    let mut s = gpu::scene(
        particles,
        pgt::scene::thesis_lights(),
        RenderMode::Volume,
        models::LIT,
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

fn main() {
    let Some(ctx) = gpu::gpu() else { return };
    let side: u32 = env_or("PGT_BENCH_SIDE", "128").parse().unwrap();
    let count: usize = env_or("PGT_BENCH_COUNT", "11032").parse().unwrap();
    let repeat: usize = env_or("PGT_BENCH_REPEAT", "3").parse().unwrap();
    let spheres = random_scene(count, side);
    let mut ellipsoids = spheres.clone();
    pgt::cli::bench::as_ellipsoids(&mut ellipsoids.particles);
    // (method, parameters, mode, model)
    let cases: [(&str, &[(&str, u32)], RenderMode, _); 5] = [
        ("emission", &[], RenderMode::Volume, models::EMISSION),
        ("sorted-blend", &[], RenderMode::Volume, models::EMISSION),
        ("ever", &[], RenderMode::Volume, models::EMISSION),
        (
            "thesis",
            &[("samples", 16), ("n_exact", 2)],
            RenderMode::Volume,
            models::LIT,
        ),
        ("opaque", &[], RenderMode::Opaque, models::LIT),
    ];
    for (name, values, mode, model) in cases {
        let params = ApproxParams::for_method(name, values).unwrap();
        let scenes: Vec<Scene> = [&spheres, &ellipsoids]
            .iter()
            .map(|s| {
                let mut s = (*s).clone();
                s.render.mode = mode;
                s.render.model = model;
                s
            })
            .collect();
        // Warm-up: lavapipe compiles each pipeline at its first dispatch.
        for s in &scenes {
            render_approx_with(ctx, s, &params).unwrap();
        }
        let mut best = [f64::INFINITY; 2];
        for _ in 0..repeat {
            for (b, s) in best.iter_mut().zip(&scenes) {
                let out = render_approx_with(ctx, s, &params).unwrap();
                *b = b.min(out.gpu_seconds);
            }
        }
        eprintln!(
            "bench: {name:<12} {count} particles, {side}x{side}: spheres {:.4} s, ellipsoids {:.4} s GPU (best of {repeat}), ratio {:.2}",
            best[0],
            best[1],
            best[1] / best[0]
        );
    }
}

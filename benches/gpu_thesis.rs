//! `cargo bench --bench gpu_thesis`: timings of the `thesis` method on random particle sets like
//! the thesis's (chapter 6): radius 1.2–1.9 (Å, used as the length unit), uniform in a cube at
//! about protein atom density (0.05 Å⁻³), the thesis's two directional lights, Θmax 0.5. Minutes
//! on lavapipe; the environment variables below choose the sizes (their defaults shown):
//!
//!     PGT_BENCH_SIDE=64 PGT_BENCH_SAMPLES=100 PGT_BENCH_COUNTS=2758,73642 \
//!         PGT_BENCH_N_EXACT=1,5,all cargo bench --bench gpu_thesis
//!
//! Prints one line per (count, n_exact): GPU seconds and the timing source. Without a GPU adapter
//! it says so and measures nothing.

#[path = "../tests/support/mod.rs"]
mod support;

use support::gpu;

use glam::DVec3;
use pgt::approx::{render_approx_with, ApproxParams, Timing, N_EXACT_ALL};
use pgt::geometry::Camera;
use pgt::optics::models;
use pgt::scene::RenderMode;

fn env_or(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

/// A small deterministic generator (SplitMix64): the benchmark needs no statistical quality,
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

fn main() {
    let Some(ctx) = gpu::gpu() else { return };
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
        let cube = (count as f64 / 0.05).cbrt();
        let mut rng = SplitMix(count as u64);
        let particles: Vec<_> = (0..count)
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
        // From −z, framing the cube (its bounding sphere) with fov_y 40°, like the default camera.
        let distance = 0.5 * cube * 3f64.sqrt() / (20f64.to_radians().sin());
        s.camera = Camera::new(
            DVec3::new(0.0, 0.0, -distance),
            DVec3::ZERO,
            DVec3::Y,
            40.0,
            side,
            side,
        );
        // Warm-up: lavapipe compiles the shader at its first dispatch, inside the first timing.
        let warm = ApproxParams::for_method("thesis", &[("samples", 1), ("n_exact", 1)]).unwrap();
        render_approx_with(ctx, &s, &warm).unwrap();
        for n_exact in n_exacts.iter().copied() {
            let params =
                ApproxParams::for_method("thesis", &[("samples", samples), ("n_exact", n_exact)])
                    .unwrap();
            let wall = std::time::Instant::now();
            let out = render_approx_with(ctx, &s, &params).unwrap();
            let wall = wall.elapsed().as_secs_f64();
            let n = if n_exact == N_EXACT_ALL {
                "all".to_string()
            } else {
                n_exact.to_string()
            };
            eprintln!(
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

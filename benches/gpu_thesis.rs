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

use pgt::approx::{render_approx_with, ApproxParams, Timing, N_EXACT_ALL};

fn main() {
    let Some(ctx) = gpu::gpu() else { return };
    let side: u32 = gpu::env_or("PGT_BENCH_SIDE", "64").parse().unwrap();
    let samples: u32 = gpu::env_or("PGT_BENCH_SAMPLES", "100").parse().unwrap();
    let counts: Vec<usize> = gpu::env_or("PGT_BENCH_COUNTS", "2758,73642")
        .split(',')
        .map(|c| c.trim().parse().unwrap())
        .collect();
    let n_exacts: Vec<u32> = gpu::env_or("PGT_BENCH_N_EXACT", "1,5,all")
        .split(',')
        .map(|n| match n.trim() {
            "all" => N_EXACT_ALL,
            n => n.parse().unwrap(),
        })
        .collect();
    for count in counts {
        let s = gpu::random_cube_scene(count, side);
        // Warm-up: a first run, so that the first timing is like the others (pgt keeps the
        // pipeline's compile out of the GPU time itself).
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

//! `cargo bench --bench gpu_gaussians`: what the Gaussian methods cost the GPU (docs/design.md
//! §4 `splat`, `splat-pixel-sort`, `gauss-ray`) against `emission` on the same particles as
//! constant-density spheres. The random set of the GPU benchmarks (`support::gpu`: radius
//! 1.2–1.9, uniform in a cube at protein atom density), once as spheres (Θmax 0.5) and once as
//! Gaussians of standard deviation = the radius and splatting opacity 0.5, emission model. Each
//! method runs best of `PGT_BENCH_REPEAT`; `splat`'s time includes its CPU projection and tile
//! lists. The defaults:
//!
//!     PGT_BENCH_SIDE=512 PGT_BENCH_COUNT=100000 PGT_BENCH_REPEAT=3 \
//!         PGT_BENCH_METHODS=splat,splat-pixel-sort,gauss-ray cargo bench --bench gpu_gaussians
//!
//! Prints one line per method: GPU seconds, its ratio to `emission` on the spheres, and the
//! pixels whose hit lists overflowed or whose loops reached lavapipe's budget (such a pixel is
//! not what the method computes), and first the time of `splat`'s CPU projection and tile lists
//! alone. Without a GPU adapter it says so and measures nothing.

#[path = "../tests/support/mod.rs"]
mod support;

use support::gpu;

use pgt::approx::layout::{GpuFrame, SceneBuffers};
use pgt::approx::{render_approx_with, splat_tiles, ApproxOutput, ApproxParams, GpuContext};
use pgt::optics::gaussian::sigma_from_peak_opacity;
use pgt::optics::{models, Profile};
use pgt::scene::{RenderMode, Scene};

/// Best of `repeat` runs (after one warm-up run) of `method` on `scene`.
fn best(ctx: &GpuContext, scene: &Scene, method: &str, repeat: usize) -> (f64, ApproxOutput) {
    let params = ApproxParams::for_method(method, &[]).unwrap();
    let mut out = render_approx_with(ctx, scene, &params).unwrap();
    let mut seconds = f64::INFINITY;
    for _ in 0..repeat {
        out = render_approx_with(ctx, scene, &params).unwrap();
        seconds = seconds.min(out.gpu_seconds);
    }
    (seconds, out)
}

fn main() {
    let Some(ctx) = gpu::gpu() else { return };
    let side: u32 = gpu::env_or("PGT_BENCH_SIDE", "512").parse().unwrap();
    let count: usize = gpu::env_or("PGT_BENCH_COUNT", "100000").parse().unwrap();
    let repeat: usize = gpu::env_or("PGT_BENCH_REPEAT", "3").parse().unwrap();
    let methods = gpu::env_or("PGT_BENCH_METHODS", "splat,splat-pixel-sort,gauss-ray");
    let mut spheres = gpu::random_cube_scene(count, side);
    spheres.render.mode = RenderMode::Volume;
    spheres.render.model = models::EMISSION;
    let mut gaussians = spheres.clone();
    for p in &mut gaussians.particles {
        p.profile = Profile::Gaussian;
        p.sigma = sigma_from_peak_opacity(0.5, p.radius);
    }
    // splat's share on the CPU: the projection and tile lists alone.
    let bvh = gaussians.build_bvh();
    let mut buffers = SceneBuffers::new(&gaussians, &bvh);
    let frame = GpuFrame::new(&gaussians, &[]);
    let started = std::time::Instant::now();
    splat_tiles::build(
        &mut buffers,
        &frame,
        &splat_tiles::SplatConstants::three_dgs(),
    );
    eprintln!(
        "bench: splat's CPU projection and tile lists: {:.4} s ({} splats, {} tile entries)",
        started.elapsed().as_secs_f64(),
        buffers.splats.len(),
        buffers.tile_entries.len()
    );
    let (base, out) = best(ctx, &spheres, "emission", repeat);
    eprintln!(
        "bench: {:<16} {count} spheres, {side}x{side}: {base:.4} s GPU (best of {repeat}); {} pixels overflowed, {} loop-limited",
        "emission", out.hit_overflow_pixels, out.loop_limited_pixels
    );
    for method in methods.split(',').filter(|m| !m.is_empty()) {
        let (seconds, out) = best(ctx, &gaussians, method, repeat);
        eprintln!(
            "bench: {method:<16} {count} Gaussians, {side}x{side}: {seconds:.4} s GPU (best of {repeat}), {:.2}x emission; {} pixels overflowed, {} loop-limited",
            seconds / base,
            out.hit_overflow_pixels,
            out.loop_limited_pixels
        );
    }
}

//! `cargo bench --bench gpu_ellipsoids`: what an ellipsoid costs the GPU methods against a
//! sphere (issue 34's target: at most 1.5×). A random set like `gpu_thesis`'s (radius 1.2–1.9,
//! uniform in a cube at protein atom density, the thesis's two lights, Θmax 0.5), once as
//! spheres and once with every sphere turned into an ellipsoid of the same volume, axis ratios
//! up to 1:4 and a random orientation (`pgt bench`'s `1uun-ellipsoids` rule,
//! [`pgt::bench::as_ellipsoids`]). Each method runs on both, taking turns, best of
//! `PGT_BENCH_REPEAT`; the defaults:
//!
//!     PGT_BENCH_SIDE=128 PGT_BENCH_COUNT=11032 PGT_BENCH_REPEAT=3 cargo bench --bench gpu_ellipsoids
//!
//! Prints one line per method: GPU seconds of each shape and their ratio. Without a GPU adapter
//! it says so and measures nothing.

#[path = "../tests/support/mod.rs"]
mod support;

use support::gpu;

use pgt::approx::{render_approx_with, ApproxParams};
use pgt::optics::models;
use pgt::scene::{Model, RenderMode, Scene};

/// A method with its parameters, on the scene in this mode and model.
struct Case {
    name: &'static str,
    values: &'static [(&'static str, u32)],
    mode: RenderMode,
    model: Model,
}

fn main() {
    let Some(ctx) = gpu::gpu() else { return };
    let side: u32 = gpu::env_or("PGT_BENCH_SIDE", "128").parse().unwrap();
    let count: usize = gpu::env_or("PGT_BENCH_COUNT", "11032").parse().unwrap();
    let repeat: usize = gpu::env_or("PGT_BENCH_REPEAT", "3").parse().unwrap();
    let spheres = gpu::random_cube_scene(count, side);
    let mut ellipsoids = spheres.clone();
    pgt::bench::as_ellipsoids(&mut ellipsoids.particles);
    let volume = |name: &'static str, values: &'static [(&'static str, u32)], model: Model| Case {
        name,
        values,
        mode: RenderMode::Volume,
        model,
    };
    let cases = [
        volume("emission", &[], models::EMISSION),
        volume("sorted-blend", &[], models::EMISSION),
        volume("ever", &[], models::EMISSION),
        volume("thesis", &[("samples", 16), ("n_exact", 2)], models::LIT),
        Case {
            name: "opaque",
            values: &[],
            mode: RenderMode::Opaque,
            model: models::LIT,
        },
    ];
    for Case {
        name,
        values,
        mode,
        model,
    } in cases
    {
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
        // Warm-up: each scene's first run (the pipeline variant's compile stays out of the
        // GPU time already; this keeps the first timing like the others).
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

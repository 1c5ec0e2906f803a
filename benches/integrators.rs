//! `cargo bench --bench integrators`: adaptive Gauss–Kronrod against the thesis's Riemann sums
//! on a protein-like random scene, lit model, the thesis's two directional lights; the image side
//! is `$PGT_BENCH_SIZE` (default 64):
//!
//!   PGT_BENCH_SIZE=64 cargo bench --bench integrators
//!
//! 2,758 spheres (the particle count of the thesis's 1UUN protein), radii uniform in
//! [1.2, 1.9] Å, centres uniform in a cube of 2758·20 Å³ (one atom per 20 Å³, about a protein's
//! density), Θmax = 0.3, random colours; the camera frames the bounding sphere (docs/design.md §1
//! default). Errors are against an adaptive render at tol 1e-8.

#[path = "../tests/support/mod.rs"]
mod support;

use glam::DVec3;
use pgt::optics::extinction::sigma_from_opacity;
use pgt::optics::models;
use pgt::reference::volume::VolumeRenderer;
use pgt::reference::{Integrator, RadianceEstimator, Sample};
use pgt::scene::{default_camera, thesis_lights};
use rayon::prelude::*;
use std::time::Instant;
use support::volume::*;

const PARTICLES: usize = 2758;
const VOLUME_PER_ATOM: f64 = 20.0;
const OPACITY: f64 = 0.3;

/// Renders every pixel in f64 (the library's `render_with` stores f32, which would hide errors
/// below ~1e-7), in parallel over rows like the renderer; returns the samples and the seconds.
fn run(s: &pgt::scene::Scene, integrator: Integrator) -> (Vec<Sample>, f64) {
    let start = Instant::now();
    let r = VolumeRenderer::new(s, integrator);
    let (w, h) = (s.camera.width, s.camera.height);
    let rows: Vec<Vec<Sample>> = (0..h)
        .into_par_iter()
        .map(|py| {
            (0..w)
                .map(|px| r.radiance(&s.camera.pixel_ray(px, py)))
                .collect()
        })
        .collect();
    (rows.concat(), start.elapsed().as_secs_f64())
}

fn main() {
    let size: u32 = std::env::var("PGT_BENCH_SIZE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(64);
    let side = (PARTICLES as f64 * VOLUME_PER_ATOM).cbrt();
    let mut rng = Rng::new(1);
    let particles: Vec<_> = (0..PARTICLES)
        .map(|_| {
            let r = rng.range(1.2, 1.9);
            particle(
                rng.vec3(0.0, side),
                r,
                rng.vec3(0.0, 1.0),
                sigma_from_opacity(OPACITY, r),
            )
        })
        .collect();
    let mut s = scene(models::LIT, particles, thesis_lights(), size);
    s.camera = default_camera(&s.particles, size, size);
    s.render.background = DVec3::ZERO;
    s.render.tol = 1e-8;
    eprintln!(
        "{PARTICLES} spheres in a {side:.1} Å cube, {size}×{size}, lit, 2 directional lights"
    );
    // The closed-form kink search alone (both lights, whole camera ray), for the overhead.
    let start = Instant::now();
    let bvh = s.build_bvh();
    let kinks: usize = (0..size)
        .into_par_iter()
        .map(|py| {
            let mut out = Vec::new();
            let mut n = 0;
            for px in 0..size {
                let ray = s.camera.pixel_ray(px, py);
                for light in &s.lights {
                    out.clear();
                    pgt::optics::kinks::shadow_tangencies(
                        &ray,
                        (0.0, 1e3),
                        light,
                        &bvh,
                        &s.particles,
                        &mut out,
                    );
                    n += out.len();
                }
            }
            n
        })
        .sum();
    eprintln!(
        "kink search alone: {:.2} s, {kinks} kinks",
        start.elapsed().as_secs_f64()
    );
    let (truth, seconds) = run(&s, Integrator::Adaptive);
    let max_estimate = |v: &[Sample]| v.iter().map(|x| x.error.max_element()).fold(0.0, f64::max);
    let rays = |v: &[Sample]| v.iter().map(|x| x.shadow_rays).sum::<u64>();
    eprintln!(
        "reference tol 1e-8: {seconds:.2} s, {} shadow rays, estimate max {:.2e}",
        rays(&truth),
        max_estimate(&truth)
    );
    let cases: Vec<(String, Integrator, f64)> = vec![
        ("adaptive tol 1e-4".into(), Integrator::Adaptive, 1e-4),
        ("adaptive tol 1e-6".into(), Integrator::Adaptive, 1e-6),
        (
            "riemann 10".into(),
            Integrator::Riemann { samples: 10 },
            0.0,
        ),
        (
            "riemann 100".into(),
            Integrator::Riemann { samples: 100 },
            0.0,
        ),
        (
            "riemann 1000".into(),
            Integrator::Riemann { samples: 1000 },
            0.0,
        ),
    ];
    for (name, integrator, tol) in cases {
        if tol > 0.0 {
            s.render.tol = tol;
        }
        let (out, seconds) = run(&s, integrator);
        let (mut max, mut sum) = (0.0f64, 0.0f64);
        for (a, b) in out.iter().zip(&truth) {
            let e = (a.radiance - b.radiance).abs();
            max = max.max(e.max_element());
            sum += e.element_sum();
            assert!(a.radiance.is_finite());
        }
        let mean = sum / (3 * out.len()) as f64;
        let estimate = if tol > 0.0 {
            format!("{:.2e}", max_estimate(&out))
        } else {
            "-".into()
        };
        eprintln!(
            "{name:>18}: {seconds:8.2} s  {:>12} shadow rays  error mean {mean:.2e} max {max:.2e}  estimate max {estimate}",
            rays(&out)
        );
    }
}

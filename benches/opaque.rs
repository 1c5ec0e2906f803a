//! `cargo bench --bench opaque`: primary + shadow rays per second of the opaque reference
//! (docs/design.md §2 opaque mode) for the thesis's particle counts, 512×512, two directional lights;
//! and the BVH build for a million spheres. Plain timing (no harness): run it on a quiet machine
//! and compare ratios within one run.

use glam::DVec3;
use pgt::formats::random::SplitMix64;
use pgt::geometry::Camera;
use pgt::reference::{render, RenderOptions};
use pgt::scene::{thesis_lights, Particle, RenderMode, RenderSettings, Scene};
use std::time::Instant;

/// `n` spheres of radius 1.2–1.9 Å in a cube holding one sphere per 20 Å³ (about a protein's
/// atom density).
fn random_scene(n: usize, size: u32) -> Scene {
    // Deterministic (the library's SplitMix64), so every run measures the same scene.
    let mut rng = SplitMix64::new(n as u64);
    let side = (n as f64 * 20.0).cbrt();
    let particles: Vec<Particle> = (0..n)
        .map(|_| {
            let c = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * side;
            let color = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            Particle {
                ellipsoid: None,
                profile: pgt::optics::Profile::Constant,
                center: c,
                radius: 1.2 + 0.7 * rng.next_f64(),
                color,
                sigma: 0.5,
                albedo: color,
                ks: 0.0,
                shininess: 32.0,
            }
        })
        .collect();
    let camera = pgt::scene::default_camera(&particles, size, size);
    Scene {
        source: "bench".into(),
        camera: Camera { ..camera },
        render: RenderSettings {
            mode: RenderMode::Opaque,
            ..RenderSettings::default()
        },
        lights: thesis_lights(),
        particles,
        warnings: vec![],
        provenance: Default::default(),
    }
}

fn main() {
    let threads = rayon::current_num_threads();
    println!("opaque reference, 512x512, 2 directional lights, {threads} threads");
    for n in [2_758usize, 73_642] {
        let scene = random_scene(n, 512);
        let t = Instant::now();
        let bvh = scene.build_bvh();
        let build = t.elapsed().as_secs_f64();
        drop(bvh);
        // One warm-up, then the best of three.
        let mut best = f64::INFINITY;
        let mut rays = 0;
        for _ in 0..4 {
            let out = render(&scene, &RenderOptions::default()).expect("render");
            best = best.min(out.stats.seconds);
            rays = out.stats.primary_rays + out.stats.shadow_rays;
        }
        println!(
            "{n:>8} spheres: BVH build {:.1} ms, render {:.3} s (best of 3), {} rays, {:.2} Mrays/s",
            build * 1e3,
            best,
            rays,
            rays as f64 / best / 1e6
        );
    }
    let n = 1_000_000;
    let scene = random_scene(n, 8);
    let t = Instant::now();
    let bvh = scene.build_bvh();
    println!(
        "{n:>8} spheres: BVH build {:.2} s, {} nodes ({:.1} bytes per sphere incl. indices)",
        t.elapsed().as_secs_f64(),
        bvh.nodes.len(),
        (bvh.nodes.len() * std::mem::size_of::<pgt::geometry::BvhNode>() + bvh.indices.len() * 4)
            as f64
            / n as f64
    );
}

//! `cargo bench --bench opaque`: primary + shadow rays per second of the opaque reference
//! (DESIGN.md §2 opaque mode) for the thesis's particle counts, 512×512, two directional lights;
//! and the BVH build for a million spheres. Plain timing (no harness): run it on a quiet machine
//! and compare ratios within one run.

use glam::DVec3;
use pgt::geometry::Camera;
use pgt::reference::{render, RenderOptions};
use pgt::scene::{thesis_lights, Particle, RenderMode, RenderSettings, Scene};
use std::time::Instant;

/// Deterministic uniform numbers in [0, 1) (SplitMix64), so every run measures the same scene.
struct SplitMix(u64);
impl SplitMix {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` spheres of radius 1.2–1.9 Å in a cube holding one sphere per 20 Å³ (about a protein's
/// atom density).
fn random_scene(n: usize, size: u32) -> Scene {
    let mut rng = SplitMix(n as u64);
    let side = (n as f64 * 20.0).cbrt();
    let particles: Vec<Particle> = (0..n)
        .map(|_| {
            let c = DVec3::new(rng.next(), rng.next(), rng.next()) * side;
            let color = DVec3::new(rng.next(), rng.next(), rng.next());
            Particle {
                center: c,
                radius: 1.2 + 0.7 * rng.next(),
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

//! `cargo bench --bench gpu_reference_gaussians`: CPU seconds of the exact reference of
//! Gaussian particles on the CPU (`--threads 2`) and on the GPU in f64 (`pgt render --gpu`,
//! docs/design.md §12), on the same scene in one process, alternating, twice each: the Gaussian
//! example at 128² and the 300 Gaussians of the donut splat file nearest to one of its
//! particles, framed, at 64² (skipped without `../shared/data` or `$PGT_SHARED_DATA`). CPU
//! seconds of the whole process (all threads, lavapipe's included) from /proc/self/stat, so a
//! loaded machine changes them little; the GPU's include compiling its program. Without an
//! adapter with f64 it says so and measures nothing.

use glam::DVec3;
use pgt::approx::GpuContext;
use pgt::geometry::Camera;
use pgt::reference::{self, gpu, RenderOptions};
use pgt::scene::{Scene, SceneLoadOptions};
use std::path::{Path, PathBuf};

/// User + system seconds of this process so far (Linux; 0 elsewhere).
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    let Some(end) = stat.rfind(')') else {
        return 0.0;
    };
    let fields: Vec<&str> = stat[end + 2..].split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn shared_data() -> PathBuf {
    std::env::var_os("PGT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"))
}

/// The `n` Gaussians of the donut nearest to one of its particles, framed, `size`².
fn donut_crop(n: usize, size: u32) -> Option<Scene> {
    let ply = shared_data().join("splats/GSHairLoD_donut_fused.ply");
    if !ply.exists() {
        println!("no {}: the donut crop is skipped", ply.display());
        return None;
    }
    let toml = std::env::temp_dir().join(format!("pgt-bench-donut-{}.toml", std::process::id()));
    let text = format!(
        "[camera]\nposition = [0.0, 0.0, -5.0]\nlook_at = [0.0, 0.0, 0.0]\nwidth = {size}\nheight = {size}\n\n[render]\nmode = \"volume\"\nmodel = \"emission\"\n\n[[include]]\npath = \"{}\"\ndensity = \"gaussian\"\n",
        ply.display()
    );
    std::fs::write(&toml, text).unwrap();
    let mut scene = Scene::load(&toml, &SceneLoadOptions::default()).unwrap();
    let _ = std::fs::remove_file(&toml);
    let anchor = scene.particles[scene.particles.len() / 3].center;
    scene.particles.sort_by(|a, b| {
        a.center
            .distance(anchor)
            .total_cmp(&b.center.distance(anchor))
    });
    scene.particles.truncate(n);
    let mean = scene.particles.iter().map(|p| p.center).sum::<DVec3>() / n as f64;
    let reach = scene
        .particles
        .iter()
        .map(|p| p.center.distance(mean) + p.radius)
        .fold(0.0, f64::max);
    let eye = mean + DVec3::new(0.3, 0.2, -1.0).normalize() * (3.0 * reach);
    scene.camera = Camera::new(eye, mean, DVec3::Y, 30.0, size, size);
    Some(scene)
}

fn main() {
    let ctx = match GpuContext::with_f64(None) {
        Ok(ctx) => ctx,
        Err(e) => {
            println!("no GPU adapter with f64 ({e}): nothing measured");
            return;
        }
    };
    let example = Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gaussians.toml"),
        &SceneLoadOptions {
            size: Some((128, 128)),
            ..SceneLoadOptions::default()
        },
    )
    .unwrap();
    let mut scenes = vec![("examples/gaussians.toml, 128²", example)];
    if let Some(donut) = donut_crop(300, 64) {
        scenes.push(("donut crop (300 Gaussians), 64²", donut));
    }
    println!("adapter: {}", ctx.adapter);
    for (what, scene) in scenes {
        let options = RenderOptions {
            threads: Some(2),
            ..RenderOptions::default()
        };
        for round in 1..=2 {
            let c0 = cpu_seconds();
            let cpu = reference::render(&scene, &options).unwrap();
            let c1 = cpu_seconds();
            let g = gpu::render_on(&ctx, &scene, &options).unwrap();
            let c2 = cpu_seconds();
            println!(
                "{what}, round {round}: CPU reference {:.2} CPU s, GPU reference {:.2} CPU s ({:.1}×); err max CPU {:.3e}, GPU {:.3e}; GPU pixels not converged {}",
                c1 - c0,
                c2 - c1,
                (c2 - c1) / (c1 - c0),
                cpu.stats.max_error.unwrap_or(0.0),
                g.stats.max_error.unwrap_or(0.0),
                g.stats.unconverged
            );
        }
    }
}

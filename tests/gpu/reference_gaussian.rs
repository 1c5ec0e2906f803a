//! The exact reference of Gaussian particles on the GPU in f64 (docs/design.md §12): its images
//! against the CPU reference (`reference::gaussian`) within err_gpu + err_cpu at every pixel
//! channel on the Gaussian example, random overlapping flat and round Gaussians, crops of the
//! donut splat file and of a trained tile of very flat Gaussians, a row of Gaussians more than
//! a batch holds; the same bits on every run; err_gpu within a small factor of the
//! CPU's; the refusals by name.

use super::reference::{
    emission_at, gpu64, pgt, repo, same_bits, same_bits_twice, within_both_errs,
};
use super::support::volume::{self, Rng};
use glam::{DQuat, DVec3};
use pgt::approx::GpuContext;
use pgt::geometry::{Camera, Ellipsoid};
use pgt::optics::{models, Particle, Profile};
use pgt::reference::gpu;
use pgt::reference::{self, RenderOptions, RenderOutput};
use pgt::scene::{RenderMode, Scene, SceneLoadOptions};

fn gaussian(center: DVec3, std: DVec3, rotation: DQuat, color: DVec3, sigma: f64) -> Particle {
    Particle {
        center,
        radius: std.max_element(),
        color,
        sigma,
        albedo: color,
        ks: 0.0,
        shininess: 32.0,
        ellipsoid: (std.x != std.y || std.y != std.z).then(|| Ellipsoid::new(std, rotation)),
        profile: Profile::Gaussian,
    }
}

/// `n` overlapping Gaussians, every other one flat (one axis 10⁻³ of the others, 20 times the
/// peak density), as in tests/reference/gaussians.rs's coverage test.
fn flat_and_round(seed: u64, n: usize, size: u32) -> Scene {
    let mut rng = Rng::new(seed);
    let mut particles = Vec::new();
    for k in 0..n {
        let center = rng.vec3(-1.2, 1.2);
        let mut std = DVec3::new(
            rng.range(0.2, 0.9),
            rng.range(0.2, 0.9),
            rng.range(0.2, 0.9),
        );
        let axis = rng.vec3(-1.0, 1.0).normalize_or(DVec3::Y);
        let rotation = DQuat::from_axis_angle(axis, rng.range(0.0, 3.0));
        let color = rng.vec3(0.0, 1.0);
        let mut sigma = rng.range(0.3, 3.0);
        if k % 2 == 0 {
            std.z *= 1e-3;
            sigma *= 20.0;
        }
        particles.push(gaussian(center, std, rotation, color, sigma));
    }
    let mut s = volume::scene(models::EMISSION, particles, vec![], size);
    s.camera = Camera::new(
        DVec3::new(0.0, 0.0, -12.0),
        DVec3::ZERO,
        DVec3::Y,
        30.0,
        size,
        size,
    );
    s.render.tol = 1e-5;
    s
}

/// Renders `scene` on both, checks |gpu − cpu| ≤ err_gpu + err_cpu at every pixel channel, that
/// every GPU pixel converged, and that the GPU's err is within a factor 8 of the CPU's (mean
/// and max); returns the GPU render.
fn check_gaussian_scene(ctx: &GpuContext, what: &str, scene: &Scene) -> RenderOutput {
    let options = RenderOptions::default();
    let cpu = reference::render(scene, &options).expect("CPU render");
    let g = gpu::render_on(ctx, scene, &options).expect("GPU render");
    let worst = within_both_errs(what, &g, &cpu);
    assert_eq!(
        g.stats.unconverged, 0,
        "{what}: {} GPU pixels not converged (worst {:?})",
        g.stats.unconverged, g.stats.worst_unconverged
    );
    let (gm, cm) = (g.stats.mean_error.unwrap(), cpu.stats.mean_error.unwrap());
    let (gx, cx) = (g.stats.max_error.unwrap(), cpu.stats.max_error.unwrap());
    eprintln!(
        "{what}: |gpu − cpu| ≤ {worst:.3}·(err_gpu + err_cpu); err mean gpu {gm:.3e} cpu {cm:.3e}, max gpu {gx:.3e} cpu {cx:.3e}"
    );
    assert!(
        gm <= 8.0 * cm && cm <= 8.0 * gm,
        "{what}: mean err gpu {gm:e} against cpu {cm:e}"
    );
    assert!(
        gx <= 8.0 * cx,
        "{what}: max err gpu {gx:e} against cpu {cx:e}"
    );
    g
}

#[test]
fn the_gaussian_example_agrees_with_the_cpu_reference_within_both_errs() {
    let Some(ctx) = gpu64() else { return };
    let scene = emission_at(&repo("examples/gaussians.toml"), (20, 16)).unwrap();
    assert!(scene.has_gaussians());
    check_gaussian_scene(ctx, "examples/gaussians.toml", &scene);
}

#[test]
fn random_flat_and_round_gaussians_agree_with_the_cpu_reference_within_both_errs() {
    let Some(ctx) = gpu64() else { return };
    for (seed, n) in [(4801, 12), (4802, 40)] {
        let scene = flat_and_round(seed, n, 16);
        check_gaussian_scene(ctx, &format!("{n} flat and round, seed {seed}"), &scene);
    }
}

/// Per pixel channel of the GPU render `g` against the tighter CPU render `t`: (pixel, channel,
/// |g − t|, err_gpu, err of `t`).
fn channels_against(g: &RenderOutput, t: &RenderOutput) -> Vec<(usize, usize, f64, f64, f64)> {
    let (ge, te) = (g.error.as_ref().unwrap(), t.error.as_ref().unwrap());
    let mut out = Vec::with_capacity(3 * g.image.pixels.len());
    for i in 0..g.image.pixels.len() {
        for c in 0..3 {
            let d = (g.image.pixels[i][c] as f64 - t.image.pixels[i][c] as f64).abs();
            out.push((i, c, d, ge.pixels[i][c] as f64, te.pixels[i][c] as f64));
        }
    }
    out
}

/// err_gpu alone against the truth: a CPU render at tol/100 stands for it (its err, about
/// 100 times smaller, added), and the GPU's err at tol 1e-5 covers the distance at ≥ 99.9 % of
/// pixel channels, as the CPU's err does in tests/reference/gaussians.rs.
#[test]
fn err_gpu_covers_a_hundred_times_tighter_cpu_render() {
    let Some(ctx) = gpu64() else { return };
    let scene = flat_and_round(4805, 30, 16);
    let mut tight = scene.clone();
    tight.render.tol = 1e-7;
    let options = RenderOptions::default();
    let g = gpu::render_on(ctx, &scene, &options).unwrap();
    let t = reference::render(&tight, &options).unwrap();
    let (mut covered, mut total, mut off) = (0, 0, 0.0f64);
    for (i, c, d, e, te) in channels_against(&g, &t) {
        assert!(d <= e + te, "pixel {i} channel {c}: {d:e} > {e:e}");
        covered += usize::from(d <= e);
        total += 1;
        off = off.max(d);
    }
    eprintln!("err_gpu covers {covered} of {total} channels; largest distance {off:.3e}");
    assert!(
        covered as f64 >= 0.999 * total as f64,
        "{covered} of {total}"
    );
    assert!(off > 1e-8, "the renders agree exactly: nothing is tested");
}

/// The `n` Gaussians of the donut splat file nearest to one of its particles, framed: flat,
/// hair-like splats crossing one another.
fn donut_crop(n: usize, size: u32) -> Option<Scene> {
    splat_crop("GSHairLoD_donut_fused.ply", n, size)
}

/// The `n` Gaussians of `../shared/data/splats/FILE` nearest to one of its particles, framed.
fn splat_crop(file: &str, n: usize, size: u32) -> Option<Scene> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/splats")
        .join(file);
    let path = if path.exists() {
        path
    } else {
        std::path::Path::new("/work/shared/data/splats").join(file)
    };
    if !path.exists() {
        super::support::skip::skipped(&format!("no {file} in ../shared/data/splats"));
        return None;
    }
    let dir = std::env::temp_dir().join(format!("pgt-gpu-crop-{file}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let toml = dir.join("donut.toml");
    std::fs::write(
        &toml,
        format!(
            "[camera]\nposition = [0.0, 0.0, -5.0]\nlook_at = [0.0, 0.0, 0.0]\nwidth = {size}\nheight = {size}\n\n[render]\nmode = \"volume\"\nmodel = \"emission\"\n\n[[include]]\npath = \"{}\"\ndensity = \"gaussian\"\n",
            path.display()
        ),
    )
    .unwrap();
    let mut scene = Scene::load(&toml, &SceneLoadOptions::default()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let anchor = scene.particles[scene.particles.len() / 3].center;
    scene.particles.sort_by(|a, b| {
        let (da, db) = (a.center.distance(anchor), b.center.distance(anchor));
        da.total_cmp(&db)
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

#[test]
fn a_crop_of_the_donut_agrees_with_the_cpu_reference_within_both_errs() {
    let Some(ctx) = gpu64() else { return };
    let Some(scene) = donut_crop(300, 16) else {
        return;
    };
    assert_eq!(scene.render.mode, RenderMode::Volume);
    check_gaussian_scene(ctx, "donut crop, 300 Gaussians", &scene);
    // The rays' work is split into passes by the loop budget, and the split changes no value
    // (the render above is checked against the CPU).
    let camera = &scene.camera;
    let directions: Vec<DVec3> = (0..camera.height)
        .flat_map(|y| (0..camera.width).map(move |x| camera.pixel_ray(x, y).direction))
        .collect();
    let traced = gpu::gaussian::trace(
        ctx,
        &scene,
        camera.position,
        &directions,
        gpu::direction_error(camera),
    )
    .unwrap();
    eprintln!("donut crop: {} passes", traced.passes);
    if ctx.adapter.is_cpu {
        assert!(traced.passes > 1, "one pass: the split is not tested");
    }
}

/// A crop of a trained tile whose Gaussians are very flat (standard deviations from 1e-10,
/// axis ratios to 3e8): the GPU agrees with the CPU within both errs, every pixel converged,
/// err_gpu alone covers the distance to a CPU render at tol/100 at every channel, and err_gpu
/// is at most twice the CPU's (an isotropic bound of the profiles' rounding and a shift bound of
/// 2·peak·δ made it 4.7 times the CPU's here, docs/design.md §12).
#[test]
fn a_crop_of_a_trained_tile_of_very_flat_gaussians_agrees_with_the_cpu() {
    let Some(ctx) = gpu64() else { return };
    let Some(scene) = splat_crop("lod3_tile_0.ply", 150, 12) else {
        return;
    };
    let smallest = scene
        .particles
        .iter()
        .filter_map(|p| p.ellipsoid.as_ref())
        .map(|e| e.shortest_semi_axis())
        .fold(f64::INFINITY, f64::min);
    assert!(
        smallest < 1e-6,
        "no very flat Gaussian in the crop: {smallest:e}"
    );
    let options = RenderOptions::default();
    let cpu = reference::render(&scene, &options).unwrap();
    let g = gpu::render_on(ctx, &scene, &options).unwrap();
    let worst = within_both_errs("lod3 crop", &g, &cpu);
    assert_eq!(g.stats.unconverged, 0, "{:?}", g.stats.worst_unconverged);
    let mut tight = scene.clone();
    tight.render.tol = scene.render.tol / 100.0;
    let t = reference::render(&tight, &options).unwrap();
    let mut off = 0.0f64;
    for (i, c, d, e, te) in channels_against(&g, &t) {
        assert!(
            d <= e,
            "pixel {i} channel {c}: {d:e} > err_gpu {e:e} (cpu tol/100 err {te:e})"
        );
        off = off.max(d);
    }
    let (gx, cx) = (g.stats.max_error.unwrap(), cpu.stats.max_error.unwrap());
    eprintln!(
        "lod3 crop: |gpu − cpu| ≤ {worst:.3}·(err_gpu + err_cpu); to tol/100 at most {off:.3e}; err max gpu {gx:.3e} cpu {cx:.3e}"
    );
    assert!(gx <= 2.0 * cx, "err max gpu {gx:e} against cpu {cx:e}");
}

/// 10,000 Gaussians with trained-scene statistics (`pgt gen gaussians`), 16²: on lavapipe some
/// rays run past the loop budget, and lavapipe then ends the loops of the rays beside them with
/// wrong values (`taint_loop_limited_workgroups`). Every pixel agrees with the CPU within both
/// errs, the loop-limited workgroups' pixels with err = |L| + M; the others converge.
#[test]
fn rays_beside_a_loop_limited_ray_are_never_trusted() {
    let Some(ctx) = gpu64() else { return };
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("trained.ply");
    let records = pgt::formats::trained::generate(10_000, 1);
    std::fs::write(&ply, pgt::formats::trained::to_ply(&records)).unwrap();
    let toml = dir.path().join("trained.toml");
    std::fs::write(
        &toml,
        format!(
            "[render]\nmodel = \"emission\"\n\n[[include]]\npath = \"{}\"\ndensity = \"gaussian\"\n",
            ply.display()
        ),
    )
    .unwrap();
    let load = SceneLoadOptions {
        size: Some((16, 16)),
        ..Default::default()
    };
    let scene = Scene::load(&toml, &load).unwrap();
    let options = RenderOptions::default();
    let cpu = reference::render(&scene, &options).unwrap();
    let g = gpu::render_on(ctx, &scene, &options).unwrap();
    within_both_errs("10,000 trained Gaussians", &g, &cpu);
    let err = g.error.as_ref().unwrap();
    let trusted = err
        .pixels
        .iter()
        .filter(|e| e.iter().all(|&v| v < 1e-3))
        .count() as u64;
    eprintln!(
        "10,000 trained Gaussians: {} of 256 pixels not converged, {trusted} trusted",
        g.stats.unconverged
    );
    assert_eq!(trusted + g.stats.unconverged, 256);
    if ctx.adapter.is_cpu {
        assert!(
            g.stats.unconverged > 0,
            "no ray ran past the loop budget: the taint is not tested"
        );
        assert!(
            trusted > 0,
            "every workgroup tainted: the agreement is not tested"
        );
    }
}

/// `n` Gaussians of standard deviation `std` along the line of sight from `start` to `end` in z,
/// seen by a 5×5 camera whose centre ray runs along the row.
fn row_scene(n: usize, start: f64, end: f64, std: f64) -> Scene {
    let particles = (0..n)
        .map(|k| {
            let z = start + (end - start) * k as f64 / n as f64;
            // A little colour change along the row, so that pieces deviate.
            let c = DVec3::new(0.5, 0.7 - 0.3 * (k % 3) as f64, 0.2);
            gaussian(
                DVec3::new(0.0, 0.0, z),
                DVec3::splat(std),
                DQuat::IDENTITY,
                c,
                0.02,
            )
        })
        .collect();
    let mut scene = volume::scene(models::EMISSION, particles, vec![], 5);
    scene.camera = Camera::new(
        DVec3::new(0.0, 0.0, -12.0),
        DVec3::ZERO,
        DVec3::Y,
        20.0,
        5,
        5,
    );
    scene
}

/// A row of Gaussians along the line of sight, more than twice as many as a batch holds but
/// never many open at once: the centre ray takes them batch by batch and agrees with the CPU
/// within both errs.
#[test]
fn a_ray_through_more_gaussians_than_a_batch_holds_takes_them_batch_by_batch() {
    let Some(ctx) = gpu64() else { return };
    let n = 2 * gpu::gaussian::WINDOWS_MAX as usize + 40;
    let scene = row_scene(n, -3.0, 3.0, 0.05);
    let g = check_gaussian_scene(ctx, "a row of 552 Gaussians", &scene);
    let err = g.error.as_ref().unwrap();
    assert!(err.pixels[2 * 5 + 2].iter().all(|e| e.is_finite()));
}

/// More Gaussians open at one depth than a ray holds: those rays are reported not converged with
/// err = |L| + M (M the largest colour or background per channel), never a value with a small
/// err; the rays beside them are rendered.
#[test]
fn a_ray_with_more_gaussians_open_at_once_than_it_holds_is_not_converged() {
    let Some(ctx) = gpu64() else { return };
    let n = gpu::gaussian::WINDOWS_MAX as usize + 20;
    let scene = row_scene(n, -0.01, 0.01, 0.05);
    let out = gpu::render_on(ctx, &scene, &RenderOptions::default()).unwrap();
    let err = out.error.as_ref().unwrap();
    let (centre, value) = (err.pixels[2 * 5 + 2], out.image.pixels[2 * 5 + 2]);
    let m = [0.5f32, 0.7, 0.2];
    for c in 0..3 {
        assert!(
            centre[c] >= (value[c].abs() + m[c]) * (1.0 - 1e-6),
            "{centre:?} for {value:?}"
        );
    }
    assert!(out.stats.unconverged >= 1);
    let (x, y, _) = out.stats.worst_unconverged.unwrap();
    assert_eq!((x, y), (2, 2));
    let corner = err.pixels[0];
    assert!(corner.iter().all(|e| e.is_finite()), "{corner:?}");
}

#[test]
fn the_gaussian_gpu_reference_gives_the_same_bits_on_every_run() {
    let Some(ctx) = gpu64() else { return };
    let scene = flat_and_round(4803, 20, 12);
    same_bits_twice(ctx, &scene);
}

#[test]
fn gaussian_scenes_it_cannot_render_are_refused_by_name() {
    let mut scene = flat_and_round(4804, 4, 8);
    scene.render.model = models::SINGLE_SCATTER;
    let e = gpu::check_supported(&scene, &RenderOptions::default()).unwrap_err();
    assert!(e.to_string().contains("single-scatter"), "{e}");
    let mut scene = flat_and_round(4804, 4, 8);
    scene.particles[1].profile = Profile::Constant;
    let e = gpu::check_supported(&scene, &RenderOptions::default()).unwrap_err();
    assert!(e.to_string().contains("mixes Gaussian particles"), "{e}");
    // What the CPU renderer refuses, the GPU refuses with the same words.
    let Some(ctx) = gpu64() else { return };
    let mut scene = flat_and_round(4804, 4, 8);
    scene.particles[2].sigma = f64::INFINITY;
    let e = gpu::render_on(ctx, &scene, &RenderOptions::default()).unwrap_err();
    assert!(e.to_string().contains("infinite peak density"), "{e}");
}

/// `pgt render --gpu` on the Gaussian example writes the library's image and err bit for bit;
/// a scene mixing Gaussian and constant density exits 2 naming why, and writes nothing.
#[test]
fn pgt_render_gpu_renders_the_gaussian_example_as_the_library_does() {
    let Some(ctx) = gpu64() else { return };
    let dir = tempfile::tempdir().unwrap();
    let path = repo("examples/gaussians.toml");
    let out = dir.path().join("out.exr");
    let run = pgt(&[
        "render",
        "--gpu",
        path.to_str().unwrap(),
        "--size",
        "12x10",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let scene = Scene::load(
        &path,
        &SceneLoadOptions {
            size: Some((12, 10)),
            ..SceneLoadOptions::default()
        },
    )
    .unwrap();
    let want = gpu::render_on(ctx, &scene, &RenderOptions::default()).unwrap();
    let image = pgt::image_io::read_image(&out).unwrap();
    let err = pgt::image_io::read_exr_layer(&out, "err").unwrap();
    assert!(same_bits(&image, &want.image));
    assert!(same_bits(&err, want.error.as_ref().unwrap()));
    let mixed = dir.path().join("mixed.toml");
    std::fs::write(
        &mixed,
        "[camera]\nposition = [0.0, 0.0, -6.0]\nlook_at = [0.0, 0.0, 0.0]\nwidth = 8\nheight = 8\n\n[render]\nmodel = \"emission\"\n\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 0.5\ndensity = \"gaussian\"\n\n[[particles]]\ncenter = [0.5, 0.0, 0.0]\nradius = 0.5\n",
    )
    .unwrap();
    let refused = dir.path().join("mixed.exr");
    let run = pgt(&[
        "render",
        "--gpu",
        mixed.to_str().unwrap(),
        "-o",
        refused.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("Gaussian"), "{stderr}");
    assert!(!refused.exists());
}

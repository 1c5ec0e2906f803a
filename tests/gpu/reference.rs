//! The exact reference on the GPU in f64 (docs/design.md §12): its exp, expm1 and log1p against
//! the CPU's libm, no transcendental builtin on f64 in its program, and its images against the
//! CPU reference within err_gpu + err_cpu, the same bits on every run.

use super::support::skip;
use super::support::volume::Rng;
use glam::{DQuat, DVec3};
use pgt::approx::GpuContext;
use pgt::geometry::Ellipsoid;
use pgt::image_io::RgbImage;
use pgt::reference::gpu::{self, math};
use pgt::reference::{self, RenderOptions, RenderOutput};
use pgt::scene::{Profile, RenderMode, Scene, SceneLoadOptions};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// A context with f64, or `None` outside CI where there is none (a failure under `CI=true`).
pub(super) fn gpu64() -> Option<&'static GpuContext> {
    static CTX: OnceLock<Result<GpuContext, String>> = OnceLock::new();
    let ctx = CTX.get_or_init(|| GpuContext::with_f64(None).map_err(|e| e.to_string()));
    match ctx {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            if std::env::var("CI").is_ok_and(|v| v == "true") {
                panic!("CI=true and no GPU adapter with f64: {e}");
            }
            skip::skipped(&format!("no GPU adapter with f64: {e}"));
            None
        }
    }
}

/// |got − want| in ulps of `want` (the spacing of f64 at |want|).
fn ulps(got: f64, want: f64) -> f64 {
    if got == want {
        return 0.0;
    }
    let a = want.abs();
    let spacing = f64::from_bits(a.to_bits() + 1) - a;
    (got - want).abs() / spacing
}

/// Dense grids over each function's range and its tails, and uniform random arguments.
fn arguments() -> Vec<f64> {
    let mut xs = Vec::new();
    let n = 100_000;
    for k in 0..=n {
        xs.push(-745.0 + 1454.7 * k as f64 / n as f64); // the whole range of exp
        xs.push(-1.0 + 3.0 * k as f64 / n as f64); // around 0 and the reduction's seams
    }
    for k in 0..=6000 {
        let m = 10f64.powf(-300.0 + 302.0 * k as f64 / 6000.0); // tiny to 100
        xs.extend([m, -m.min(0.999_999)]);
    }
    for k in 1..=2000 {
        xs.push(-1.0 + 1e-16 * 1.02f64.powi(k)); // log1p near −1
        xs.push(10f64.powf(300.0 * k as f64 / 2000.0)); // log1p's large arguments
    }
    let mut rng = Rng::new(48);
    for _ in 0..100_000 {
        xs.push(rng.range(-745.0, 709.7));
        xs.push(rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-20.0, 0.0)));
    }
    xs
}

#[test]
fn f64_exp_expm1_log1p_are_within_their_ulp_bounds() {
    let Some(ctx) = gpu64() else { return };
    let xs = arguments();
    let got = math::evaluate(ctx, &xs).expect("the math harness runs");
    let (mut worst_exp, mut worst_expm1, mut worst_log1p) =
        ((0.0f64, 0.0), (0.0f64, 0.0), (0.0f64, 0.0));
    for (&x, g) in xs.iter().zip(&got) {
        let want = x.exp();
        if want >= f64::MIN_POSITIVE && want.is_finite() {
            let u = ulps(g[0], want);
            if u > worst_exp.0 {
                worst_exp = (u, x);
            }
        } else if g[0] != want {
            // Subnormal or zero results: within the smallest normal in absolute terms.
            assert!(
                (g[0] - want).abs() <= f64::MIN_POSITIVE,
                "exp({x}) = {} want {want}",
                g[0]
            );
        }
        let u = ulps(g[1], x.exp_m1());
        if u > worst_expm1.0 {
            worst_expm1 = (u, x);
        }
        if x > -1.0 {
            let u = ulps(g[2], x.ln_1p());
            if u > worst_log1p.0 {
                worst_log1p = (u, x);
            }
        }
    }
    eprintln!(
        "f64 on {} over {} arguments: exp {:.3} ulp (at {:e}), expm1 {:.3} ulp (at {:e}), log1p {:.3} ulp (at {:e})",
        ctx.adapter, xs.len(), worst_exp.0, worst_exp.1, worst_expm1.0, worst_expm1.1, worst_log1p.0, worst_log1p.1
    );
    // libm is within an ulp of the truth: the bounds carry that ulp on top of the measured.
    assert!(worst_exp.0 + 1.0 <= math::EXP_ULPS, "exp: {worst_exp:?}");
    assert!(
        worst_expm1.0 + 1.0 <= math::EXPM1_ULPS,
        "expm1: {worst_expm1:?}"
    );
    assert!(
        worst_log1p.0 + 1.0 <= math::LOG1P_ULPS,
        "log1p: {worst_log1p:?}"
    );
}

/// Dense grids over erfc's range (−6 to 28, where it underflows, and its seams), the small
/// arguments, and uniform random ones.
fn erfc_arguments() -> Vec<f64> {
    let mut xs = Vec::new();
    let n = 200_000;
    for k in 0..=n {
        xs.push(-7.0 + 36.0 * k as f64 / n as f64);
    }
    for seam in [0.25, 0.84375, 1.25, 2.8571414947509766, 6.0, 28.0] {
        for sign in [1.0, -1.0] {
            for k in -2000..=2000 {
                xs.push(sign * seam * (1.0 + k as f64 * 1e-13));
                xs.push(sign * seam * (1.0 + k as f64 * 1e-6));
            }
        }
    }
    for k in 0..=6000 {
        let m = 10f64.powf(-300.0 + 300.0 * k as f64 / 6000.0);
        xs.extend([m, -m]);
    }
    let mut rng = Rng::new(4748);
    for _ in 0..200_000 {
        xs.push(rng.range(-8.0, 30.0));
        xs.push(rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-20.0, 0.0)));
    }
    xs
}

#[test]
fn f64_erfc_is_within_its_ulp_bound() {
    let Some(ctx) = gpu64() else { return };
    let xs = erfc_arguments();
    let got = math::evaluate(ctx, &xs).expect("the math harness runs");
    let mut worst = (0.0f64, 0.0);
    let mut worst_small = (0.0f64, 0.0);
    for (&x, g) in xs.iter().zip(&got) {
        let want = libm::erfc(x);
        if want >= math::ERFC_NORMAL {
            let u = ulps(g[3], want);
            if u > worst.0 {
                worst = (u, x);
            }
        } else {
            let d = (g[3] - want).abs();
            if d > worst_small.0 {
                worst_small = (d, x);
            }
        }
    }
    eprintln!(
        "f64 erfc on {} over {} arguments: {:.3} ulp (at {:e}); below 2^-1000 {:e} absolute (at {:e})",
        ctx.adapter,
        xs.len(),
        worst.0,
        worst.1,
        worst_small.0,
        worst_small.1
    );
    // libm's erfc is within an ulp of the truth: the bound carries that ulp on top.
    assert!(worst.0 + 1.0 <= math::ERFC_ULPS, "erfc: {worst:?}");
    assert!(worst_small.0 <= math::ERFC_NORMAL, "erfc: {worst_small:?}");
    // The tails are there: erfc(26) is about 5.7e-296, erfc(−6) rounds to 2.
    let at = |x: f64| math::evaluate(ctx, &[x]).unwrap()[0][3];
    assert!(at(26.0) > 0.0 && at(26.0) < 1e-295);
    assert_eq!(at(-6.5), 2.0);
    assert_eq!(at(30.0), 0.0);
}

/// Every `MathFunction` that Vulkan defines for 16- and 32-bit floats only.
fn transcendental(fun: naga::MathFunction) -> bool {
    use naga::MathFunction as F;
    matches!(
        fun,
        F::Exp
            | F::Exp2
            | F::Log
            | F::Log2
            | F::Pow
            | F::Sin
            | F::Cos
            | F::Tan
            | F::Asin
            | F::Acos
            | F::Atan
            | F::Atan2
            | F::Sinh
            | F::Cosh
            | F::Tanh
            | F::Asinh
            | F::Acosh
            | F::Atanh
            | F::InverseSqrt
            | F::Modf
            | F::Frexp
    )
}

fn transcendental_calls(source: &str) -> Vec<String> {
    let module = naga::front::wgsl::parse_str(source).expect("the program parses");
    let functions = module
        .functions
        .iter()
        .map(|(_, f)| f)
        .chain(module.entry_points.iter().map(|e| &e.function));
    let mut calls = Vec::new();
    for f in functions {
        for (_, e) in f.expressions.iter() {
            if let naga::Expression::Math { fun, .. } = e {
                if transcendental(*fun) {
                    calls.push(format!("{:?} in {:?}", fun, f.name));
                }
            }
        }
    }
    calls
}

#[test]
fn the_gpu_reference_calls_no_transcendental_builtin() {
    for (what, source) in [
        ("reference", gpu::program::program().source().to_string()),
        ("math harness", math::harness_program().source().to_string()),
        (
            "Gaussian reference",
            gpu::gaussian::program().source().to_string(),
        ),
    ] {
        let calls = transcendental_calls(&source);
        assert!(calls.is_empty(), "the {what} program calls {calls:?}");
    }
    // The scan sees a call where there is one.
    let probe = "fn f(x: f32) -> f32 { return exp(x) + 1.0; }";
    assert_eq!(transcendental_calls(probe).len(), 1);
}

/// Every pixel channel: |gpu − cpu| ≤ err_gpu + err_cpu; the worst ratio of the difference to
/// that sum.
pub(super) fn within_both_errs(what: &str, gpu: &RenderOutput, cpu: &RenderOutput) -> f64 {
    let (ge, ce) = (gpu.error.as_ref().unwrap(), cpu.error.as_ref().unwrap());
    let mut worst = 0.0f64;
    for i in 0..gpu.image.pixels.len() {
        for c in 0..3 {
            let (g, v) = (gpu.image.pixels[i][c] as f64, cpu.image.pixels[i][c] as f64);
            let allowed = ge.pixels[i][c] as f64 + ce.pixels[i][c] as f64;
            let d = (g - v).abs();
            assert!(
                d <= allowed,
                "{what}: pixel {i} channel {c}: gpu {g} cpu {v} differ by {d:e} > err_gpu {} + err_cpu {}",
                ge.pixels[i][c],
                ce.pixels[i][c]
            );
            if allowed > 0.0 {
                worst = worst.max(d / allowed);
            }
        }
    }
    worst
}

/// Renders `scene` twice on the GPU reference and asserts the same bits in image and err.
pub(super) fn same_bits_twice(ctx: &GpuContext, scene: &Scene) {
    let options = RenderOptions::default();
    let a = gpu::render_on(ctx, scene, &options).unwrap();
    let b = gpu::render_on(ctx, scene, &options).unwrap();
    assert!(same_bits(&a.image, &b.image));
    assert!(same_bits(
        a.error.as_ref().unwrap(),
        b.error.as_ref().unwrap()
    ));
}

pub(super) fn same_bits(a: &RgbImage, b: &RgbImage) -> bool {
    a.pixels
        .iter()
        .flatten()
        .zip(b.pixels.iter().flatten())
        .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Renders `scene` on both and checks the bound, and that the f64 answers per ray differ by at
/// most twice the GPU's f64 bound (the CPU's own rounding is of the same kind and size).
fn check_scene(ctx: &GpuContext, what: &str, scene: &Scene, spp: u32) {
    let options = RenderOptions {
        spp,
        ..RenderOptions::default()
    };
    let cpu = reference::render(scene, &options).expect("CPU render");
    let g = gpu::render_on(ctx, scene, &options).expect("GPU render");
    let worst = within_both_errs(what, &g, &cpu);
    let estimator = reference::estimator_for(scene, &options).unwrap();
    let camera = &scene.camera;
    let rays: Vec<_> = (0..camera.height)
        .flat_map(|y| (0..camera.width).map(move |x| camera.pixel_ray(x, y)))
        .collect();
    let directions: Vec<DVec3> = rays.iter().map(|r| r.direction).collect();
    let samples = gpu::trace(
        ctx,
        scene,
        camera.position,
        &directions,
        gpu::direction_error(camera),
    )
    .unwrap()
    .samples;
    let mut worst_f64 = 0.0f64;
    for (ray, s) in rays.iter().zip(&samples) {
        let want = estimator.radiance(ray).radiance;
        for c in 0..3 {
            let d = (s.radiance[c] - want[c]).abs();
            assert!(
                d <= 2.0 * s.error[c],
                "{what}: a ray's f64 radiance {} vs the CPU's {} differs by {d:e} > 2·err {:e}",
                s.radiance[c],
                want[c],
                s.error[c]
            );
            if s.error[c] > 0.0 {
                worst_f64 = worst_f64.max(d / s.error[c]);
            }
        }
    }
    eprintln!(
        "{what}: |gpu − cpu| ≤ {worst:.3}·(err_gpu + err_cpu) (stored), ≤ {worst_f64:.3}·err_gpu (f64); GPU err max {:.3e}",
        g.stats.max_error.unwrap_or(0.0)
    );
}

pub(super) fn emission_at(path: &Path, size: (u32, u32)) -> pgt::Result<Scene> {
    Scene::load(
        path,
        &SceneLoadOptions {
            size: Some(size),
            mode: Some(RenderMode::Volume),
            model: Some(pgt::optics::models::EMISSION),
            ..SceneLoadOptions::default()
        },
    )
}

pub(super) fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

#[test]
fn examples_agree_with_the_cpu_reference_within_both_errs() {
    let Some(ctx) = gpu64() else { return };
    let mut checked = 0;
    let mut paths: Vec<PathBuf> = std::fs::read_dir(repo("examples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    for path in paths {
        let scene = emission_at(&path, (24, 20)).unwrap();
        if scene
            .particles
            .iter()
            .any(|p| p.profile != Profile::Constant)
        {
            continue; // Gaussians: tests/gpu/reference_gaussian.rs
        }
        check_scene(ctx, &path.display().to_string(), &scene, 1);
        checked += 1;
    }
    assert!(checked >= 4, "only {checked} examples checked");
}

#[test]
fn thesis_scenes_agree_with_the_cpu_reference_within_both_errs() {
    let Some(ctx) = gpu64() else { return };
    for name in ["cool_random.toml", "1uun.toml"] {
        let path = repo("reports/thesis/scenes").join(name);
        match emission_at(&path, (24, 20)) {
            Ok(scene) => check_scene(ctx, name, &scene, 1),
            Err(e) if !super::support::in_ci() => {
                skip::skipped(&format!("{name}: {e}"));
            }
            Err(e) => panic!("{name}: {e}"),
        }
    }
}

/// Overlapping spheres and ellipsoids of random sizes, colours and opacities, some with
/// Θmax = 1, some holding the eye, in front of a grey background.
fn random_scene(seed: u64, n: usize) -> Scene {
    let mut rng = Rng::new(seed);
    let mut particles = Vec::new();
    for i in 0..n {
        let center = rng.vec3(-1.5, 1.5);
        let radius = rng.range(0.2, 1.0);
        let color = rng.vec3(0.0, 1.0);
        let sigma = if i % 7 == 3 {
            f64::INFINITY
        } else {
            rng.range(0.05, 6.0)
        };
        let mut p = super::support::volume::particle(center, radius, color, sigma);
        if i % 2 == 1 {
            let axes = DVec3::new(
                rng.range(0.1, 1.0),
                rng.range(0.1, 1.0),
                rng.range(0.1, 1.0),
            );
            let q = DQuat::from_xyzw(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                1.0,
            )
            .normalize();
            p.ellipsoid = Some(Ellipsoid::new(axes, q));
            p.radius = axes.max_element();
        }
        particles.push(p);
    }
    // One large particle holds the eye.
    particles.push(super::support::volume::particle(
        DVec3::new(0.0, 0.0, -7.5),
        1.5,
        DVec3::new(0.3, 0.6, 0.9),
        0.4,
    ));
    let mut scene =
        super::support::volume::scene(pgt::optics::models::EMISSION, particles, Vec::new(), 24);
    scene.render.background = DVec3::new(0.25, 0.5, 0.125);
    scene
}

#[test]
fn random_overlapping_scenes_agree_with_the_cpu_reference_within_both_errs() {
    let Some(ctx) = gpu64() else { return };
    for seed in [1, 2, 3] {
        let scene = random_scene(seed, 40);
        assert!(
            scene.camera.position.distance(DVec3::new(0.0, 0.0, -7.5)) < 1.5,
            "the eye is inside"
        );
        check_scene(ctx, &format!("random scene {seed}"), &scene, 1);
    }
    check_scene(ctx, "random scene 4, 2×2 samples", &random_scene(4, 30), 2);
}

/// Many overlapping spheres in a row along the view axis: hundreds of events per ray, more than
/// one pass on lavapipe (its loop budget), with the eye inside the first.
fn row_scene(n: usize) -> Scene {
    let particles = (0..n)
        .map(|i| {
            let t = i as f64 / n as f64;
            let center = DVec3::new(
                0.02 * (7.0 * t).sin(),
                0.02 * (5.0 * t).cos(),
                -8.0 + 14.0 * t,
            );
            let color = DVec3::new(t, 1.0 - t, 0.5);
            super::support::volume::particle(center, 0.05, color, 0.02 + 0.5 * t)
        })
        .collect();
    super::support::volume::scene(pgt::optics::models::EMISSION, particles, Vec::new(), 13)
}

#[test]
fn rays_with_many_events_go_on_over_passes_and_agree() {
    let Some(ctx) = gpu64() else { return };
    let scene = row_scene(1500);
    let camera = &scene.camera;
    let ray = camera.pixel_ray(camera.width / 2, camera.height / 2);
    let mut found = Vec::new();
    scene
        .build_gas_bvh()
        .all_hits(&ray, 0.0, f64::INFINITY, &mut found);
    assert!(
        found.len() > 400,
        "the centre ray crosses {} particles",
        found.len()
    );
    let traced = gpu::trace(
        ctx,
        &scene,
        camera.position,
        &[ray.direction],
        gpu::direction_error(camera),
    )
    .unwrap();
    if ctx.adapter.is_cpu {
        assert!(traced.passes > 1, "{} pass(es)", traced.passes);
    }
    eprintln!(
        "the centre ray: {} particles, {} passes",
        found.len(),
        traced.passes
    );
    check_scene(ctx, "a row of 1500 spheres", &scene, 1);
}

#[test]
fn the_gpu_reference_gives_the_same_bits_on_every_run() {
    let Some(ctx) = gpu64() else { return };
    let scene = random_scene(9, 60);
    same_bits_twice(ctx, &scene);
}

#[test]
fn scenes_it_cannot_render_are_refused_by_name() {
    let mut scene = random_scene(5, 4);
    scene.render.model = pgt::optics::models::LIT;
    let e = gpu::check_supported(&scene, &RenderOptions::default()).unwrap_err();
    assert!(e.to_string().contains("lit"), "{e}");
    let mut scene = random_scene(5, 4);
    scene.particles[0].profile = Profile::Gaussian;
    let e = gpu::check_supported(&scene, &RenderOptions::default()).unwrap_err();
    assert!(e.to_string().contains("Gaussian"), "{e}");
}

const CLI_SCENE: &str = r#"
[camera]
position = [0.0, 0.0, -6.0]
look_at  = [0.0, 0.0, 0.0]
width    = 20
height   = 16

[render]
mode  = "volume"
model = "emission"
background = [0.1, 0.2, 0.3]

[[particles]]
center = [-0.4, 0.0, 0.0]
radius = 1.0
color  = [1.0, 0.3, 0.1]
opacity = 0.7

[[particles]]
center = [0.5, 0.2, 0.3]
radius = 0.8
color  = [0.1, 0.6, 1.0]
opacity = 1.0
"#;

pub(super) fn pgt(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .output()
        .expect("pgt runs")
}

#[test]
fn pgt_render_gpu_writes_the_library_s_image_and_err() {
    let Some(ctx) = gpu64() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("scene.toml");
    std::fs::write(&scene_path, CLI_SCENE).unwrap();
    let out = dir.path().join("out.exr");
    let run = pgt(&[
        "render",
        "--gpu",
        scene_path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains(" on "),
        "the summary names the adapter: {stderr}"
    );
    let scene = Scene::load(&scene_path, &SceneLoadOptions::default()).unwrap();
    let want = gpu::render_on(ctx, &scene, &RenderOptions::default()).unwrap();
    let image = pgt::image_io::read_image(&out).unwrap();
    let err = pgt::image_io::read_exr_layer(&out, "err").unwrap();
    assert!(same_bits(&image, &want.image));
    assert!(same_bits(&err, want.error.as_ref().unwrap()));
}

#[test]
fn pgt_render_gpu_refuses_what_it_cannot_render_with_exit_2_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("scene.toml");
    std::fs::write(&scene_path, CLI_SCENE).unwrap();
    let out = dir.path().join("out.exr");
    let (scene, out_s) = (scene_path.to_str().unwrap(), out.to_str().unwrap());
    for (args, says) in [
        (
            vec!["render", "--gpu", "--model", "lit", scene, "-o", out_s],
            "lit",
        ),
        (
            vec![
                "render",
                "--gpu",
                "--integrator",
                "riemann",
                scene,
                "-o",
                out_s,
            ],
            "riemann",
        ),
        (
            vec![
                "render", "--gpu", "--model", "lit", "--part", "0/2", scene, "-o", out_s,
            ],
            "lit",
        ),
    ]
    .into_iter()
    // Without any adapter the message names what to install instead (a skip outside CI).
    .chain(gpu64().map(|_| {
        (
            vec![
                "render",
                "--gpu",
                "--adapter",
                "no such adapter",
                scene,
                "-o",
                out_s,
            ],
            "no such adapter",
        )
    })) {
        let run = pgt(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!out.exists(), "{args:?} left {out_s}");
    }
}

#[test]
fn a_ray_inside_more_particles_than_it_holds_is_refused_by_name() {
    let Some(ctx) = gpu64() else { return };
    // Concentric spheres: the ray through the centre is inside all of them at once.
    let n = gpu::program::INSIDE_MAX as usize + 6;
    let particles = (0..n)
        .map(|i| {
            let r = 0.5 + 0.01 * i as f64;
            super::support::volume::particle(DVec3::ZERO, r, DVec3::new(0.5, 0.5, 0.5), 0.1)
        })
        .collect();
    let scene =
        super::support::volume::scene(pgt::optics::models::EMISSION, particles, Vec::new(), 5);
    let e = gpu::render_on(ctx, &scene, &RenderOptions::default()).unwrap_err();
    assert!(
        e.to_string()
            .contains(&format!("more than {}", gpu::program::INSIDE_MAX)),
        "{e}"
    );
}

/// Double-double arithmetic (a value as hi + lo, about 106 bits) for the oracle below.
#[derive(Clone, Copy, Debug)]
struct Dd(f64, f64);

impl Dd {
    fn of(x: f64) -> Dd {
        Dd(x, 0.0)
    }
    fn two_sum(a: f64, b: f64) -> Dd {
        let s = a + b;
        let v = s - a;
        Dd(s, (a - (s - v)) + (b - v))
    }
    fn add(self, o: Dd) -> Dd {
        let s = Dd::two_sum(self.0, o.0);
        let lo = s.1 + self.1 + o.1;
        Dd::two_sum(s.0, lo)
    }
    fn neg(self) -> Dd {
        Dd(-self.0, -self.1)
    }
    fn sub(self, o: Dd) -> Dd {
        self.add(o.neg())
    }
    fn mul(self, o: Dd) -> Dd {
        let p = self.0 * o.0;
        let e = self.0.mul_add(o.0, -p);
        Dd::two_sum(p, e + self.0 * o.1 + self.1 * o.0)
    }
    fn div(self, o: Dd) -> Dd {
        let q = self.0 / o.0;
        let r = self.sub(o.mul(Dd::of(q)));
        Dd::two_sum(q, r.0 / o.0)
    }
    fn sqrt(self) -> Dd {
        if self.0 <= 0.0 {
            return Dd::of(0.0);
        }
        let s = self.0.sqrt();
        let r = self.sub(Dd::of(s).mul(Dd::of(s)));
        Dd::two_sum(s, r.0 / (2.0 * s))
    }
}

fn dot_dd(a: [Dd; 3], b: [Dd; 3]) -> Dd {
    a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2]))
}

/// The emission model along o + t·d/|d| through one sphere, its chord in double-double:
/// bg·T + C·(1 − T), T = e^{−σ·chord} (the exponential in f64, relative error ~1e-16).
fn one_sphere_oracle(
    o: DVec3,
    d: DVec3,
    c: DVec3,
    r: f64,
    sigma: f64,
    color: DVec3,
    bg: DVec3,
) -> DVec3 {
    let f = [0, 1, 2].map(|i| Dd::of(o[i]).sub(Dd::of(c[i])));
    let dd = [0, 1, 2].map(|i| Dd::of(d[i]));
    let norm = dot_dd(dd, dd).sqrt();
    let u = dd.map(|x| x.div(norm));
    let t_c = dot_dd(f, u).neg();
    let l = [0, 1, 2].map(|i| f[i].add(t_c.mul(u[i])));
    let h2 = Dd::of(r).mul(Dd::of(r)).sub(dot_dd(l, l));
    if h2.0 <= 0.0 {
        return bg;
    }
    let h = h2.sqrt();
    let enter = t_c.sub(h);
    let exit = t_c.add(h);
    let start = if enter.0 > 0.0 { enter } else { Dd::of(0.0) };
    let chord = exit.sub(start);
    if chord.0 <= 0.0 {
        return bg;
    }
    let t = (-sigma * (chord.0 + chord.1)).exp();
    bg * t + color * (1.0 - t)
}

#[test]
fn err_bounds_the_distance_from_a_double_double_oracle_where_f64_geometry_is_off() {
    let Some(ctx) = gpu64() else { return };
    // A far eye and a unit sphere: the chord loses digits to |o − c| ≫ r, the most near the
    // silhouette, and err (f64, before any float32 storage) must cover it.
    let mut rng = Rng::new(4848);
    let mut worst = 0.0f64;
    let mut covered = 0;
    for distance in [1e3, 1e5, 1e6] {
        let center = DVec3::new(0.3, -0.2, 0.1);
        let (radius, sigma) = (1.0, 3.0);
        let (color, bg) = (DVec3::new(0.9, 0.5, 0.2), DVec3::new(0.1, 0.2, 0.3));
        let mut scene = super::support::volume::scene(
            pgt::optics::models::EMISSION,
            vec![super::support::volume::particle(
                center, radius, color, sigma,
            )],
            Vec::new(),
            4,
        );
        scene.render.background = bg;
        let origin = DVec3::new(0.1, 0.05, -distance);
        // Directions towards points across the disc, a third of them within 1e-6 of the rim.
        let directions: Vec<DVec3> = (0..3000)
            .map(|k| {
                let angle = rng.range(0.0, std::f64::consts::TAU);
                let rho = if k % 3 == 0 {
                    1.0 - rng.range(0.0, 1e-6)
                } else {
                    rng.range(0.0, 1.0)
                };
                let target = center + rho * DVec3::new(angle.cos(), angle.sin(), 0.0);
                (target - origin).normalize()
            })
            .collect();
        let traced = gpu::trace(
            ctx,
            &scene,
            origin,
            &directions,
            gpu::NORMALIZED_DIRECTION_ERROR,
        )
        .unwrap();
        for (d, s) in directions.iter().zip(&traced.samples) {
            let want = one_sphere_oracle(origin, *d, center, radius, sigma, color, bg);
            for c in 0..3 {
                let off = (s.radiance[c] - want[c]).abs();
                let slack = 4.0 * f64::EPSILON * want[c].abs();
                assert!(
                    off <= s.error[c] + slack,
                    "distance {distance:e}, direction {d:?}: off by {off:e} > err {:e}",
                    s.error[c]
                );
                if off > 0.0 {
                    worst = worst.max(off / s.error[c]);
                    covered += 1;
                }
            }
        }
    }
    eprintln!("double-double oracle: the f64 value is off by at most {worst:.3e} of err ({covered} channels off at all)");
    assert!(covered > 100, "the f64 geometry should be off somewhere");
}

#[test]
fn a_scene_without_visible_gas_is_the_background() {
    let Some(ctx) = gpu64() else { return };
    let invisible = super::support::volume::particle(DVec3::ZERO, 1.0, DVec3::ONE, 0.0);
    for particles in [Vec::new(), vec![invisible]] {
        let mut scene =
            super::support::volume::scene(pgt::optics::models::EMISSION, particles, Vec::new(), 6);
        scene.render.background = DVec3::new(0.2, 0.3, 0.4);
        let out = gpu::render_on(ctx, &scene, &RenderOptions::default()).unwrap();
        let cpu = reference::render(&scene, &RenderOptions::default()).unwrap();
        assert!(out.image.pixels.iter().all(|p| *p == [0.2f32, 0.3, 0.4]));
        // err: the CPU's float32 rounding, and the GPU's bound on its own f64 rounding on top.
        let (ge, ce) = (out.error.as_ref().unwrap(), cpu.error.as_ref().unwrap());
        for (g, c) in ge.pixels.iter().flatten().zip(ce.pixels.iter().flatten()) {
            assert!(
                *g >= *c && (*g as f64) <= 1.01 * *c as f64 + 1e-15,
                "err {g:e} against the CPU's {c:e}"
            );
        }
    }
}

//! `pgt approx` end to end (docs/design.md §4, §7): the shipped example shaders run through
//! `--shader`, a broken shader gives exit 2 and the user's line, no adapter gives exit 2 and the
//! message saying what to install.

use crate::support::gpu;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const SCENE: &str = r#"
[camera]
position = [0.0, 0.0, -10.0]
look_at  = [0.0, 0.0, 0.0]
up       = [0.0, 1.0, 0.0]
fov_y    = 40.0
width    = 32
height   = 32

[render]
mode  = "volume"
model = "lit"
background = [0.05, 0.05, 0.05]

[[lights]]
type = "directional"
direction  = [0.0, -1.0, 0.0]
irradiance = [0.0, 1.0, 0.0]

[[lights]]
type = "directional"
direction  = [0.0, 1.0, 0.0]
irradiance = [0.0, 0.0, 1.0]

[[particles]]
center = [-1.0, 0.0, 0.0]
radius = 1.2
color  = [1.0, 0.2, 0.2]
opacity = 0.8

# Above the first: it shadows it from the green light.
[[particles]]
center = [-0.5, 2.5, 0.5]
radius = 1.0
color  = [0.2, 0.8, 0.2]
opacity = 0.5
"#;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn pgt(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_pgt"));
    cmd.args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("pgt runs")
}

fn scene_file(dir: &Path) -> PathBuf {
    let p = dir.join("scene.toml");
    std::fs::write(&p, SCENE).unwrap();
    p
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn the_example_shaders_run_through_shader() {
    if gpu::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path());
    let mut images = Vec::new();
    for example in [
        "shaders/examples/centre_shadow.wgsl",
        "shaders/examples/no_shadows.wgsl",
    ] {
        let out = dir.path().join("out.exr");
        let o = pgt(
            &[
                "approx",
                scene.to_str().unwrap(),
                "--shader",
                repo(example).to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ],
            &[],
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{example}: {err}");
        assert!(
            err.contains("approximated") && err.contains(" s GPU"),
            "{err}"
        );
        let image = pgt::image_io::read_image(&out).unwrap();
        assert_eq!((image.width, image.height), (32, 32));
        assert!(image.all_finite());
        images.push(image);
    }
    // The particles shadow each other, which only centre_shadow sees: the images differ.
    assert_ne!(images[0], images[1]);
}

#[test]
fn a_broken_user_shader_reports_its_own_line_and_exits_2() {
    // No GPU needed: the WGSL is validated before an adapter is opened.
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path());
    let shader = dir.path().join("broken.wgsl");
    std::fs::write(
        &shader,
        "// my method\n\nfn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {\n    let x = 1.0;\n    return vec3<f32>(x, no_such_value, 0.0);\n}\n",
    )
    .unwrap();
    let out = dir.path().join("out.png");
    let o = pgt(
        &[
            "approx",
            scene.to_str().unwrap(),
            "--shader",
            shader.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        &[],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("{}:5:", shader.display())), "{err}");
    assert!(err.contains("no_such_value"), "{err}");
    assert!(!out.exists());
}

#[test]
fn a_shader_without_shade_is_refused_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path());
    let shader = dir.path().join("empty.wgsl");
    std::fs::write(&shader, "fn helper() -> f32 { return 1.0; }\n").unwrap();
    let o = pgt(
        &[
            "approx",
            scene.to_str().unwrap(),
            "--shader",
            shader.to_str().unwrap(),
            "-o",
            "x.exr",
        ],
        &[],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("fn shade"), "{err}");
}

#[test]
fn no_adapter_is_a_clear_error_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path());
    let out = dir.path().join("out.exr");
    // Point the Vulkan loader at no driver at all: wgpu then finds no adapter.
    let o = pgt(
        &[
            "approx",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        &[
            ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
            ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
        ],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(pgt::approx::NO_ADAPTER), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn an_unknown_adapter_name_lists_the_adapters_and_exits_2() {
    if gpu::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path());
    let o = pgt(
        &[
            "approx",
            scene.to_str().unwrap(),
            "--adapter",
            "no-such-adapter-xyz",
            "-o",
            "x.exr",
        ],
        &[],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no GPU adapter matches --adapter 'no-such-adapter-xyz'"),
        "{err}"
    );
}

#[test]
fn the_thesis_method_runs_from_the_command_line_and_names_the_adapter() {
    let Some(ctx) = gpu::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path());
    let out = dir.path().join("out.exr");
    let o = pgt(
        &[
            "approx",
            scene.to_str().unwrap(),
            "--method",
            "thesis",
            "--samples",
            "8",
            "--n-exact",
            "1",
            "-o",
            out.to_str().unwrap(),
        ],
        &[],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains(&ctx.adapter.name), "{err}");
    assert!(err.contains("samples 8, n_exact 1"), "{err}");
    assert!(out.exists());
}

#[test]
fn a_particle_buffer_beyond_the_storage_buffer_limit_is_refused_with_exit_2() {
    // Images beyond the limit are rendered in bands (tests/gpu/bands.rs); the scene's buffers
    // are not split: 64 bytes a particle, so 2.2 million exceed lavapipe's 128 MiB.
    let Some(ctx) = gpu::gpu() else { return };
    let limits = ctx.device.limits();
    let limit = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let count: u64 = 2_200_000;
    if count * 64 <= limit {
        crate::support::skipped(&format!("{} binds {limit} bytes", ctx.adapter));
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("many.csv");
    let mut text = String::with_capacity(count as usize * 24);
    text.push_str("x,y,z,radius\n");
    for i in 0..count {
        let (x, y, z) = (i % 200, (i / 200) % 200, i / 40000);
        text.push_str(&format!("{x},{y},{z},0.4\n"));
    }
    std::fs::write(&csv, text).unwrap();
    let out = dir.path().join("out.exr");
    let o = pgt(
        &[
            "approx",
            csv.to_str().unwrap(),
            "--method",
            "emission",
            "--model",
            "emission",
            "--size",
            "16x16",
            "-o",
            out.to_str().unwrap(),
        ],
        &[],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "its particle buffer needs 134.3 MiB (140800000 bytes), the adapter allows {}",
            if limit == 128 << 20 {
                "128.0 MiB (134217728 bytes) per storage buffer"
            } else {
                ""
            }
        )) && err.contains(&ctx.adapter.name),
        "{err}"
    );
    assert!(!out.exists());
}

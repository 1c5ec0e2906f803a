//! Images whose output exceeds one storage buffer (issue 13 item 5): the GPU renders them in
//! bands of rows, several dispatches writing into one image, bit-identical to a run in one
//! band. A forced small per-buffer limit (`dispatch::run_with_limit`) makes bands of a small
//! image, so the test runs on lavapipe in seconds; scene buffers over the limit are refused
//! with the limit and the size.

use crate::support::gpu::*;
use pgt::approx::dispatch::{self, Pipeline};
use pgt::approx::layout::{GpuFrame, SceneBuffers};
use pgt::approx::{ApproxParams, GpuContext, Method};
use pgt::scene::{Model, RenderMode, Scene};

/// The compiled method, the scene's buffers and frame, as `ApproxPipeline::render` makes them.
fn prepare(
    ctx: &GpuContext,
    scene: &Scene,
    method: &str,
    values: &[(&str, u32)],
) -> (Pipeline, SceneBuffers, GpuFrame) {
    let params = ApproxParams::for_method(method, values).unwrap();
    let method = Method::named(method).unwrap();
    let values = params.resolve(&method).unwrap();
    let program = method.program(&values).unwrap();
    program.validate().unwrap();
    let pipeline = Pipeline::new(ctx, &program).unwrap();
    let buffers = SceneBuffers::new(scene, &scene.build_bvh());
    let slots: Vec<u32> = values.iter().map(|(_, v)| *v).collect();
    (pipeline, buffers, GpuFrame::new(scene, &slots))
}

/// A scene of `width`×`height` (neither a multiple of the workgroup side).
fn odd_scene(model: Model, mode: RenderMode, width: u32, height: u32) -> Scene {
    let mut s = scene(disjoint_particles(), lights(), mode, model);
    s.camera = pgt::geometry::Camera::new(
        s.camera.position,
        glam::DVec3::ZERO,
        glam::DVec3::Y,
        40.0,
        width,
        height,
    );
    s
}

/// A method, its parameter values, and the scene's model and mode.
type Case = (
    &'static str,
    &'static [(&'static str, u32)],
    Model,
    RenderMode,
);

#[test]
fn banded_images_are_bit_identical_to_one_band() {
    let Some(ctx) = gpu() else { return };
    let (w, h) = (37, 29);
    let row = w as u64 * 16;
    let cases: &[Case] = &[
        // The thesis method takes several passes on lavapipe: every band must see the same
        // pass ranges as the whole image does, or the sums would be grouped differently.
        (
            "thesis",
            &[("samples", 24), ("n_exact", 3)],
            pgt::optics::models::LIT,
            RenderMode::Volume,
        ),
        (
            "sorted-blend",
            &[],
            pgt::optics::models::EMISSION,
            RenderMode::Volume,
        ),
        ("opaque", &[], pgt::optics::models::LIT, RenderMode::Opaque),
    ];
    for &(method, values, model, mode) in cases {
        let scene = odd_scene(model, mode, w, h);
        let (pipeline, buffers, frame) = prepare(ctx, &scene, method, values);
        let whole = dispatch::run(ctx, &pipeline, &buffers, &frame).unwrap();
        if method == "thesis" && ctx.adapter.is_cpu {
            assert!(whole.passes > 1, "the case is meant to take several passes");
        }
        assert!(
            whole
                .image
                .pixels
                .iter()
                .flatten()
                .any(|&v| v != whole.image.pixels[0][0]),
            "{method}: a blank image proves nothing"
        );
        // 1 row a band (fewer than a workgroup), 3 rows, 8 (one workgroup), 16 (two), 28.
        for rows in [1u64, 3, 8, 16, 28] {
            let banded =
                dispatch::run_with_limit(ctx, &pipeline, &buffers, &frame, rows * row).unwrap();
            let differing = whole
                .image
                .pixels
                .iter()
                .zip(&banded.image.pixels)
                .filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
                .count();
            assert_eq!(differing, 0, "{method}, bands of {rows} rows");
            assert_eq!(
                (whole.passes, whole.hit_overflows, whole.loop_limited),
                (banded.passes, banded.hit_overflows, banded.loop_limited),
                "{method}, bands of {rows} rows: the counters are the whole image's"
            );
        }
    }
}

#[test]
fn scene_buffers_beyond_the_limit_are_refused_with_the_limit_and_the_size() {
    let Some(ctx) = gpu() else { return };
    let scene = odd_scene(pgt::optics::models::LIT, RenderMode::Volume, 16, 16);
    let (pipeline, buffers, frame) = prepare(ctx, &scene, "thesis", &[("samples", 4)]);
    // Five particles of 64 bytes: 320 bytes; allow 256 (a row of 16 pixels needs 256 too).
    let e = dispatch::run_with_limit(ctx, &pipeline, &buffers, &frame, 256)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "its particle buffer needs 320 bytes, the adapter allows 256 bytes per storage buffer"
        ),
        "{e}"
    );
    // The scene fits in 512 bytes, a row of 64 pixels (1 KiB) does not.
    let scene = odd_scene(pgt::optics::models::LIT, RenderMode::Volume, 64, 4);
    let (pipeline, buffers, frame) = prepare(ctx, &scene, "thesis", &[("samples", 4)]);
    let e = dispatch::run_with_limit(ctx, &pipeline, &buffers, &frame, 512)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("one image row of 64 pixels needs 1.0 KiB, the adapter allows 512 bytes"),
        "{e}"
    );
}

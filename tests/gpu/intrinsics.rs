//! GPU methods with a camera of intrinsics (docs/design.md §1 "Intrinsics"): an off-centre
//! principal point and fx ≠ fy draw where the reference's rays go. The methods exact without
//! overlaps match the reference to float32 (so the silhouettes sit on the same pixels), the opaque
//! method matches it off the silhouettes, and `splat`'s projected centre is the pixel through
//! which the reference's ray meets the particle's centre.

use crate::support::gpu::*;
use glam::DVec3;
use pgt::approx::layout::{GpuFrame, SceneBuffers};
use pgt::approx::splat_tiles::{project, SplatConstants};
use pgt::approx::{render_approx_with, ApproxParams};
use pgt::geometry::Intrinsics;
use pgt::optics::models;
use pgt::reference::{self, RenderOptions};
use pgt::scene::{RenderMode, Scene};

/// An off-centre pinhole for the support's 48×48 scenes, the camera at (0.4, −0.3, −10).
fn pinhole(mut s: Scene) -> Scene {
    let k = Intrinsics {
        fx: 70.0,
        fy: 55.0,
        cx: 21.3,
        cy: 27.9,
    };
    s.camera.position = DVec3::new(0.4, -0.3, -10.0);
    s.camera = s.camera.with_intrinsics(k);
    s
}

#[test]
fn methods_with_intrinsics_agree_with_the_reference_at_the_silhouette() {
    let Some(ctx) = gpu() else { return };
    let s = pinhole(scene(
        disjoint_particles(),
        vec![],
        RenderMode::Volume,
        models::EMISSION,
    ));
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    for name in ["emission", "thesis", "ever"] {
        let params = ApproxParams::for_method(name, &[]).unwrap();
        let gpu = render_approx_with(ctx, &s, &params).unwrap();
        let e = rmse(&gpu.image, &reference.image);
        eprintln!("{name} with intrinsics: RMSE vs reference {e:.3e}");
        assert!(e <= 2e-5, "{name}: RMSE {e}");
    }
    let s = pinhole(scene(
        disjoint_particles(),
        lights(),
        RenderMode::Opaque,
        models::LIT,
    ));
    let bvh = s.build_bvh();
    let params = ApproxParams::for_method("opaque", &[]).unwrap();
    let gpu = render_approx_with(ctx, &s, &params).unwrap();
    let reference = reference::render(&s, &RenderOptions::default()).unwrap();
    let (worst, compared) =
        max_error_off_mask(&gpu.image, &reference.image, &silhouette_mask(&s, &bvh));
    assert!(
        compared > 1000 && worst <= 1e-4,
        "opaque: {worst} over {compared} pixels"
    );
}

#[test]
fn splat_projects_a_centre_to_the_pixel_of_the_reference_ray() {
    let mut ps = disjoint_particles();
    for p in &mut ps {
        p.profile = pgt::optics::Profile::Gaussian;
        p.radius *= 0.2;
    }
    let s = pinhole(scene(ps, vec![], RenderMode::Volume, models::EMISSION));
    let bvh = s.build_bvh();
    let buffers = SceneBuffers::new(&s, &bvh);
    let frame = GpuFrame::new(&s, &[]);
    let cam = s.camera;
    let k = cam.intrinsics.unwrap();
    for (i, p) in s.particles.iter().enumerate() {
        let Some(proj) = project(&buffers, &frame, &SplatConstants::three_dgs(), i) else {
            continue;
        };
        // OpenCV coordinates of the centre: (r·v, −u·v, f·v), v from the eye.
        let v = p.center - cam.position;
        let (x, y, z) = (cam.right.dot(v), -cam.up.dot(v), cam.forward.dot(v));
        let want = [k.fx * x / z + k.cx, k.fy * y / z + k.cy];
        let back = cam.ray_at(want[0], want[1]);
        assert!((v.cross(back.direction)).length() < 1e-9 * v.length());
        for c in 0..2 {
            assert!(
                (proj.mean[c] as f64 - want[c]).abs() < 1e-3,
                "particle {i}: {:?} vs {want:?}",
                proj.mean
            );
        }
    }
}

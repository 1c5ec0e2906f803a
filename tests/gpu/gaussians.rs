//! The methods that draw particles of Gaussian density (docs/design.md §4 `splat`,
//! `splat-pixel-sort`, `gauss-ray`; §9) against closed forms computed here in f64 from the
//! definitions (3D Gaussian splatting's EWA footprint and blending, the maximum response along
//! a ray), never from the shaders, on whatever adapter wgpu finds (lavapipe in CI).

use crate::support::gpu::*;
use glam::{DQuat, DVec3};
use pgt::approx::{render_approx_with, ApproxParams};
use pgt::error::PgtError;
use pgt::geometry::{Camera, Ellipsoid, Ray};
use pgt::image_io::RgbImage;
use pgt::optics::{models, Profile};
use pgt::scene::{Particle, RenderMode, Scene};

/// √(2π).
const SQRT_TAU: f64 = 2.506_628_274_631_000_5;

/// A Gaussian particle of splatting opacity `o`: standard deviation `std` (a sphere) or the
/// ellipsoid's semi-axes, σ from docs/design.md §9's mapping, σ = −ln(1 − o)/(√(2π)·s_min).
fn gaussian(center: [f64; 3], shape: Result<Ellipsoid, f64>, color: [f64; 3], o: f64) -> Particle {
    let (ellipsoid, radius, shortest) = match shape {
        Ok(e) => (
            Some(e),
            e.semi_axes().max_element(),
            e.semi_axes().min_element(),
        ),
        Err(std) => (None, std, std),
    };
    Particle {
        ellipsoid,
        profile: Profile::Gaussian,
        center: DVec3::from(center),
        radius,
        color: DVec3::from(color),
        sigma: -(1.0 - o).ln() / (SQRT_TAU * shortest),
        albedo: DVec3::from(color),
        ks: 0.0,
        shininess: 32.0,
    }
}

/// An emission-model scene of these particles seen from (0, 0, −10) towards the origin, fov_y
/// 40°, `side`² pixels.
fn gaussian_scene(particles: Vec<Particle>, side: u32) -> Scene {
    let mut s = scene(particles, vec![], RenderMode::Volume, models::EMISSION);
    s.camera = Camera::new(
        DVec3::new(0.0, 0.0, -10.0),
        DVec3::ZERO,
        DVec3::Y,
        40.0,
        side,
        side,
    );
    s
}

fn render(method: &str, scene: &Scene) -> RgbImage {
    let ctx = gpu().expect("checked by the caller");
    render_approx_with(ctx, scene, &ApproxParams::for_method(method, &[]).unwrap())
        .unwrap_or_else(|e| panic!("{method}: {e}"))
        .image
}

/// 3DGS's rules, written here from its forward.cu: α = min(0.99, o·G), skipped below 1/255.
fn splat_alpha(o: f64, g: f64) -> f64 {
    let alpha = (o * g).min(0.99);
    if alpha < 1.0 / 255.0 {
        0.0
    } else {
        alpha
    }
}

/// Oracle, f64: the footprint of an axis-aligned Gaussian (semi-axes `sx`, `sy` along the
/// image's axes) centred on the optical axis at depth `z`: the Jacobian there is diag(f/z, f/z)
/// (f = H/(2·tan(fov_y/2))), so Σ₂D = diag((f·sx/z)² + 0.3, (f·sy/z)² + 0.3) (3DGS's
/// dilation); returns (Σ₂D's diagonal, the footprint radius ⌈3·√λ_max⌉ with 3DGS's floor 0.1
/// on the discriminant).
fn on_axis_footprint(cam: &Camera, sx: f64, sy: f64, z: f64) -> ([f64; 2], f64) {
    let f = cam.height as f64 / (2.0 * cam.tan_half_fov);
    let (a, c) = ((f * sx / z).powi(2) + 0.3, (f * sy / z).powi(2) + 0.3);
    let mid = 0.5 * (a + c);
    let root = (mid * mid - a * c).max(0.1).sqrt();
    ([a, c], (3.0 * (mid + root).max(mid - root).sqrt()).ceil())
}

/// 3DGS's `getRect` along one axis for a centre `m` in pgt's pixel coordinates (its own are
/// m − 0.5): the tiles [lo, hi) of 16 pixels, truncated towards zero and clamped to the grid.
fn tile_span(m: f64, radius: f64, tiles: u32) -> (u32, u32) {
    let p = m - 0.5;
    let lo = ((p - radius) / 16.0).trunc().clamp(0.0, tiles as f64) as u32;
    let hi = ((p + radius + 15.0) / 16.0)
        .trunc()
        .clamp(0.0, tiles as f64) as u32;
    (lo, hi)
}

#[test]
fn splat_of_one_gaussian_on_the_axis_is_the_ewa_closed_form() {
    if gpu().is_none() {
        return;
    }
    let side = 80;
    let color = [0.9, 0.5, 0.2];
    let o = 0.8;
    let shapes = [
        (Err(0.3), 0.3, 0.3),
        (
            Ok(Ellipsoid::new(DVec3::new(0.45, 0.2, 0.3), DQuat::IDENTITY)),
            0.45,
            0.2,
        ),
    ];
    for (shape, sx, sy) in shapes {
        let s = gaussian_scene(vec![gaussian([0.0; 3], shape, color, o)], side);
        let cam = &s.camera;
        assert!(
            cam.right.x.abs() > 0.999_999 && cam.up.y > 0.999_999,
            "axis-aligned view"
        );
        let ([a, c], radius) = on_axis_footprint(cam, sx, sy, 10.0);
        let centre = side as f64 / 2.0;
        let tiles = side.div_ceil(16);
        let (tx, ty) = (
            tile_span(centre, radius, tiles),
            tile_span(centre, radius, tiles),
        );
        assert!(tx.0 > 0 && ty.0 > 0, "some tiles are untouched");
        let image = render("splat", &s);
        let bg = s.render.background;
        let (mut checked, mut background) = (0, 0);
        for py in 0..side {
            for px in 0..side {
                let got = image.pixels[(py * side + px) as usize];
                let (dx, dy) = (px as f64 + 0.5 - centre, py as f64 + 0.5 - centre);
                let g = (-0.5 * (dx * dx / a + dy * dy / c)).exp();
                let touched =
                    (tx.0..tx.1).contains(&(px / 16)) && (ty.0..ty.1).contains(&(py / 16));
                if touched && ((o * g) * 255.0 - 1.0).abs() < 1e-4 {
                    continue; // at the 1/255 threshold f32 may round either way
                }
                let alpha = if touched { splat_alpha(o, g) } else { 0.0 };
                if alpha == 0.0 {
                    background += 1;
                    let want = bg.as_vec3().to_array();
                    assert_eq!(got, want, "pixel ({px}, {py}) must be exactly background");
                    continue;
                }
                checked += 1;
                for k in 0..3 {
                    let want = bg[k] * (1.0 - alpha) + alpha * color[k];
                    assert!(
                        (got[k] as f64 - want).abs() < 1e-5,
                        "pixel ({px}, {py}) channel {k}: {} vs {want} (α {alpha})",
                        got[k]
                    );
                }
            }
        }
        assert!(checked > 100 && background > 100, "{checked} {background}");
    }
}

#[test]
fn a_splat_just_below_one_255th_leaves_the_background() {
    if gpu().is_none() {
        return;
    }
    let side = 48;
    let std = 0.3;
    let probe = (30u32, 24u32);
    let s0 = gaussian_scene(vec![gaussian([0.0; 3], Err(std), [1.0; 3], 0.5)], side);
    let ([a, _], _) = on_axis_footprint(&s0.camera, std, std, 10.0);
    let dx = probe.0 as f64 + 0.5 - side as f64 / 2.0;
    let dy = probe.1 as f64 + 0.5 - side as f64 / 2.0;
    let g = (-0.5 * (dx * dx + dy * dy) / a).exp();
    assert!(
        g > 1.0 / 255.0,
        "o ≤ 1 can reach the threshold at the probe"
    );
    let bg = s0.render.background.as_vec3().to_array();
    for (factor, left) in [(0.999, true), (1.001, false)] {
        let o = factor / (255.0 * g);
        let s = gaussian_scene(vec![gaussian([0.0; 3], Err(std), [1.0; 3], o)], side);
        let image = render("splat", &s);
        let got = image.pixels[(probe.1 * side + probe.0) as usize];
        assert_eq!(
            got == bg,
            left,
            "o·G₂D = {factor}/255: {got:?} vs background {bg:?}"
        );
    }
}

/// Oracle, f64: the maximum response of a Gaussian along a ray, from the definition: the
/// mapped ray u(t) = M(o − c) + t·Md, t* = −u₀·v/|v|² clamped to t ≥ 0, m* = |u(t*)|.
fn peak(p: &Particle, ray: &Ray) -> (f64, f64) {
    let m = p
        .ellipsoid
        .map_or(glam::DMat3::IDENTITY / p.radius, |e| e.to_unit_matrix());
    let (u0, v) = (m * (ray.origin - p.center), m * ray.direction);
    let t_star = (-u0.dot(v) / v.length_squared()).max(0.0);
    (t_star, (u0 + t_star * v).length())
}

#[test]
fn gauss_ray_of_one_turned_gaussian_is_its_peak_response() {
    if gpu().is_none() {
        return;
    }
    let shape = Ellipsoid::new(
        DVec3::new(0.8, 0.3, 0.2),
        DQuat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 0.3),
    );
    let (color, o) = ([0.2, 0.7, 0.9], 0.9);
    let p = gaussian([0.3, -0.2, 0.5], Ok(shape), color, o);
    let s = gaussian_scene(vec![p], 48);
    let image = render("gauss-ray", &s);
    let bg = s.render.background;
    let (mut inside, mut outside) = (0, 0);
    for py in 0..48 {
        for px in 0..48 {
            let (_, m) = peak(&p, &s.camera.pixel_ray(px, py));
            if (m - 3.0).abs() < 1e-4 {
                continue; // the 3-σ silhouette: f32 may round either way
            }
            // Traced only within the 3-σ ellipsoid.
            let alpha = if m < 3.0 {
                inside += 1;
                (o * (-0.5 * m * m).exp()).min(0.99)
            } else {
                outside += 1;
                0.0
            };
            let got = image.pixels[(py * 48 + px) as usize];
            for k in 0..3 {
                let want = alpha * color[k] + (1.0 - alpha) * bg[k];
                assert!(
                    (got[k] as f64 - want).abs() < 2e-5,
                    "pixel ({px}, {py}) channel {k}: {} vs {want} (m* {m})",
                    got[k]
                );
            }
        }
    }
    assert!(inside > 100 && outside > 100, "{inside} {outside}");
}

#[test]
fn splat_orders_by_centre_depth_and_splat_pixel_sort_by_the_peak_along_the_ray() {
    if gpu().is_none() {
        return;
    }
    // A red needle turned 45° in depth (its +x end comes towards the eye), centre depth 10, and
    // a small green Gaussian at x = 1.5, centre depth 9.7: in front by centre, but the ray to it
    // meets the needle's peak nearer (depth ≈ 8.7).
    let needle = Ellipsoid::new(
        DVec3::new(3.0, 0.3, 0.3),
        DQuat::from_rotation_y(std::f64::consts::FRAC_PI_4),
    );
    let red = gaussian([0.0; 3], Ok(needle), [1.0, 0.0, 0.0], 0.95);
    let green = gaussian([1.5, 0.0, -0.3], Err(0.3), [0.0, 1.0, 0.0], 0.95);
    let s = gaussian_scene(vec![red, green], 64);
    let cam = &s.camera;
    assert!(
        (needle.rotation() * DVec3::X).z < -0.7,
        "the needle's +x end is nearer the eye"
    );
    // The pixel whose ray passes nearest the green centre.
    let (mut best, mut probe) = (f64::INFINITY, (0, 0));
    for py in 0..64 {
        for px in 0..64 {
            let ray = cam.pixel_ray(px, py);
            let off = green.center - ray.origin;
            let d = (off - off.dot(ray.direction) * ray.direction).length();
            if d < best {
                (best, probe) = (d, (px, py));
            }
        }
    }
    let ray = cam.pixel_ray(probe.0, probe.1);
    let (t_red, _) = peak(&red, &ray);
    let (t_green, _) = peak(&green, &ray);
    assert!(
        t_red + 0.5 < t_green,
        "the needle peaks first: {t_red} {t_green}"
    );
    let depth = |p: &Particle| (p.center - cam.position).dot(cam.forward);
    assert!(
        depth(&green) < depth(&red),
        "green is in front by centre depth"
    );
    let at = |image: &RgbImage| image.pixels[(probe.1 * 64 + probe.0) as usize];
    let by_centre = at(&render("splat", &s));
    let by_peak = at(&render("splat-pixel-sort", &s));
    assert!(
        by_centre[1] > 2.0 * by_centre[0],
        "splat: green in front {by_centre:?}"
    );
    assert!(
        by_peak[0] > 2.0 * by_peak[1],
        "splat-pixel-sort: red in front {by_peak:?}"
    );
    // Where the order does not matter (the needle alone), the two agree.
    let far = (4u32, 32u32);
    let (a, b) = (render("splat", &s), render("splat-pixel-sort", &s));
    let i = (far.1 * 64 + far.0) as usize;
    assert_eq!(a.pixels[i], b.pixels[i]);
}

#[test]
fn the_gaussian_methods_refuse_constant_density_and_lit_scenes_by_name() {
    let constant = scene(
        vec![particle([0.0; 3], 1.0, [1.0; 3], 0.5)],
        vec![],
        RenderMode::Volume,
        models::EMISSION,
    );
    let mut lit = gaussian_scene(vec![gaussian([0.0; 3], Err(0.5), [1.0; 3], 0.5)], 16);
    lit.render.model = models::LIT;
    let mut opaque = lit.clone();
    opaque.render.mode = RenderMode::Opaque;
    for name in ["splat", "splat-pixel-sort", "gauss-ray"] {
        let method = pgt::approx::find_method(name).unwrap();
        assert!(method.draws_gaussians(), "{name}");
        for (what, s, word) in [
            ("constant density", &constant, "constant density"),
            ("lit", &lit, "lit"),
            ("opaque", &opaque, "opaque mode"),
        ] {
            match method.check_scene(s) {
                Err(PgtError::Usage(e)) => {
                    assert!(e.contains(&format!("the {name} method")), "{what}: {e}");
                    assert!(e.contains(word), "{what}: {e}");
                }
                other => panic!("{name} on a {what} scene: {other:?}"),
            }
        }
    }
    // The constant-density methods keep refusing Gaussians.
    let gaussians = gaussian_scene(vec![gaussian([0.0; 3], Err(0.5), [1.0; 3], 0.5)], 16);
    for name in ["emission", "sorted-blend", "ever", "thesis"] {
        let e = pgt::approx::find_method(name)
            .unwrap()
            .check_scene(&gaussians)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("splat") && e.contains("gauss-ray"),
            "{name}: {e}"
        );
    }
}

#[test]
fn pgt_approx_refuses_a_constant_density_scene_with_the_gaussian_methods_with_exit_2() {
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/ellipsoids.toml");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.exr");
    let out = out.to_str().unwrap();
    for (name, extra, word) in [
        ("splat", vec!["--model", "emission"], "constant density"),
        ("gauss-ray", vec!["--model", "emission"], "constant density"),
        ("splat-pixel-sort", vec![], "lit"),
    ] {
        let mut args = vec!["approx", example, "--method", name, "-o", out];
        args.extend(extra);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_pgt"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains(&format!("the {name} method")) && err.contains(word),
            "{name}: {err}"
        );
    }
}

#[test]
fn gauss_ray_blends_many_hits_in_order_of_their_peaks_across_batches() {
    if gpu().is_none() {
        return;
    }
    // 40 overlapping Gaussians in a row along the view axis, more than one batch (16) per ray.
    let ps: Vec<Particle> = (0..40)
        .map(|i| {
            let f = i as f64;
            let shape = Ellipsoid::new(
                DVec3::new(0.6 + 0.01 * f, 0.4, 0.3),
                DQuat::from_rotation_z(0.3 * f),
            );
            let color = [(f * 0.37).fract(), (f * 0.61).fract(), (f * 0.13).fract()];
            gaussian(
                [0.05 * (f % 3.0), -0.04 * (f % 5.0), -4.0 + 0.2 * f],
                Ok(shape),
                color,
                0.15,
            )
        })
        .collect();
    let s = gaussian_scene(ps.clone(), 32);
    let image = render("gauss-ray", &s);
    let bg = s.render.background;
    let mut many = 0;
    for py in 0..32 {
        for px in 0..32 {
            let ray = s.camera.pixel_ray(px, py);
            let mut hits: Vec<(f64, usize, f64)> = Vec::new();
            let mut near_cut = false;
            for (i, p) in ps.iter().enumerate() {
                let (t, m) = peak(p, &ray);
                near_cut |= (m - 3.0).abs() < 1e-4;
                if m < 3.0 {
                    hits.push((t, i, (p_opacity(p) * (-0.5 * m * m).exp()).min(0.99)));
                }
            }
            if near_cut {
                continue;
            }
            hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            many += (hits.len() > 16) as usize;
            let (mut l, mut t) = (DVec3::ZERO, 1.0);
            for &(_, i, alpha) in &hits {
                if t * (1.0 - alpha) < 1e-4 {
                    break;
                }
                l += ps[i].color * alpha * t;
                t *= 1.0 - alpha;
            }
            let want = l + t * bg;
            let got = image.pixels[(py * 32 + px) as usize];
            for k in 0..3 {
                assert!(
                    (got[k] as f64 - want[k]).abs() < 1e-4,
                    "pixel ({px}, {py}) channel {k}: {} vs {} ({} hits)",
                    got[k],
                    want[k],
                    hits.len()
                );
            }
        }
    }
    assert!(many > 50, "{many} pixels with more than one batch of hits");
}

/// The splatting opacity o back from σ (docs/design.md §9): o = 1 − exp(−σ·s_min·√(2π)).
fn p_opacity(p: &Particle) -> f64 {
    let shortest = p
        .ellipsoid
        .map_or(p.radius, |e| e.semi_axes().min_element());
    1.0 - (-p.sigma * shortest * SQRT_TAU).exp()
}

/// The fixture's tensors as f32, by name.
fn fixture_tensor(tensors: &safetensors::SafeTensors<'_>, name: &str) -> Vec<f32> {
    let t = tensors
        .tensor(name)
        .unwrap_or_else(|e| panic!("fixture tensor {name}: {e}"));
    assert_eq!(t.dtype(), safetensors::Dtype::F32, "{name}");
    t.data()
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// The scene of the gsplat fixture (../shared/data/SOURCES.md, `render_fixtures`): its 4
/// Gaussians (log scales, w-x-y-z quaternions, logit opacities, SH degree 3), its camera
/// 123×82, fx = fy = 61.5 at the centre, world→camera the translation t = (−0.123, −0.456, 8)
/// in OpenCV axes (x right, y down, z forward): the eye at −t, looking down +z with pgt's up
/// = −y; colours clamp(SH(mean − eye) + 0.5, ≥ 0), black background, the emission model.
fn gsplat_fixture_scene(tensors: &safetensors::SafeTensors<'_>) -> Scene {
    let (means, scales) = (
        fixture_tensor(tensors, "means"),
        fixture_tensor(tensors, "scales"),
    );
    let (quats, opacities) = (
        fixture_tensor(tensors, "quats"),
        fixture_tensor(tensors, "opacities"),
    );
    let coeffs = fixture_tensor(tensors, "coeffs");
    let eye = DVec3::new(0.123, 0.456, -8.0);
    let v =
        |a: &[f32], i: usize| DVec3::new(a[3 * i] as f64, a[3 * i + 1] as f64, a[3 * i + 2] as f64);
    let particles = (0..opacities.len())
        .map(|i| {
            let center = v(&means, i);
            let semi_axes = v(&scales, i).exp();
            let q = &quats[4 * i..4 * i + 4];
            let rotation =
                DQuat::from_xyzw(q[1] as f64, q[2] as f64, q[3] as f64, q[0] as f64).normalize();
            let sh: Vec<DVec3> = (0..16).map(|k| v(&coeffs, 16 * i + k)).collect();
            let color =
                pgt::formats::ply::view_color(sh[0], &sh[1..], center - eye).max(DVec3::ZERO);
            let o = 1.0 / (1.0 + (-(opacities[i] as f64)).exp());
            gaussian(
                center.to_array(),
                Ok(Ellipsoid::new(semi_axes, rotation)),
                color.to_array(),
                o,
            )
        })
        .collect();
    let mut s = scene(particles, vec![], RenderMode::Volume, models::EMISSION);
    s.render.background = DVec3::ZERO;
    let fov_y = 2.0 * (41.0f64 / 61.5).atan().to_degrees();
    s.camera = Camera::new(eye, eye + DVec3::Z, -DVec3::Y, fov_y, 123, 82);
    s
}

/// `splat` with the gsplat preset reproduces gsplat 1.5.3's image of the fixture to ≤ 1e-5 per
/// pixel channel (docs/design.md §4 `splat`, rasteriser presets). The 3dgs preset's figure is
/// printed beside it: on this fixture its constants do not bind (no α reaches 0.99, every
/// pixel above 1/255 lies in a tile of the 3σ footprint), so the two agree here; the unit test
/// `approx::splat_tiles::tests::gsplats_box_lists_a_splat_that_3dgs_radius_leaves_out` shows
/// where they part.
#[test]
fn splat_with_the_gsplat_preset_reproduces_gsplats_image_of_the_fixture() {
    let path = crate::support::shared_or_skip!(
        "cameras/render_fixtures/brush_tiny_case_gsplat153.safetensors"
    );
    let Some(ctx) = gpu() else { return };
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let tensors = safetensors::SafeTensors::deserialize(&bytes)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let want = fixture_tensor(&tensors, "out_img");
    let scene = gsplat_fixture_scene(&tensors);
    let (w, h) = (123usize, 82usize);
    assert_eq!(want.len(), w * h * 4, "out_img is 82×123×4");
    let max_difference = |values: Vec<(String, u32)>| {
        let params = ApproxParams {
            method: Some(pgt::approx::Method::named("splat").unwrap()),
            values,
            adapter: None,
        };
        let image = render_approx_with(ctx, &scene, &params)
            .unwrap_or_else(|e| panic!("splat: {e}"))
            .image;
        let mut worst = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let got = image.get(x as u32, y as u32);
                for c in 0..3 {
                    let d = (got[c] as f64 - want[4 * (y * w + x) + c] as f64).abs();
                    worst = worst.max(d);
                }
            }
        }
        worst
    };
    let gsplat = max_difference(pgt::approx::methods::splat::preset("gsplat").unwrap());
    let three_dgs = max_difference(vec![]);
    eprintln!("gsplat fixture: max |splat − gsplat 1.5.3| = {gsplat:.3e} with the gsplat preset, {three_dgs:.3e} with 3dgs");
    assert!(
        gsplat <= 1e-5,
        "gsplat preset: max |difference| {gsplat:e} > 1e-5"
    );
}

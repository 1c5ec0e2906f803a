//! The splatting methods' preprocessing (docs/design.md §4, `splat`): each Gaussian projected to
//! a 2D Gaussian on the image (EWA), its footprint binned into 16×16-pixel tiles, and one list
//! per tile in order of the centres' view depth. This is the forward model of the reference 3D
//! Gaussian splatting rasteriser (graphdeco-inria `diff-gaussian-rasterization`,
//! `cuda_rasterizer/forward.cu` `preprocessCUDA` and `computeCov2D`, `auxiliary.h` `getRect`,
//! `rasterizer_impl.cu` `duplicateWithKeys`, `identifyTileRanges`) and, with the `gsplat`
//! preset, of gsplat's (nerfstudio-project `gsplat` 1.5.3, `gsplat/cuda/csrc/`
//! `ProjectionEWA3DGSFused.cu`, `IntersectTile.cu`), computed here **on the CPU in f32** before
//! the dispatch, because pgt's dispatch runs one per-pixel pass and has no place for a
//! preprocessing pass; its time is counted in the method's time
//! ([`crate::approx::ApproxOutput::gpu_seconds`]). The per-pixel blending is the shader's
//! (`shaders/splat.wgsl`).
//!
//! The constants are the method's parameters ([`SplatConstants`], `approx::methods::splat`'s
//! table, a preset per rasteriser); the fixed ones are 3DGS's and gsplat's alike:
//!
//! | constant | value | where |
//! |---|---|---|
//! | [`EIGEN_FLOOR`] | 0.1 | 3DGS `forward.cu` `preprocessCUDA`: `sqrt(max(0.1f, mid * mid - det))` (3DGS footprint only) |
//! | [`FOOTPRINT_SIGMAS`] | 3 | 3DGS `forward.cu` `preprocessCUDA`: `ceil(3.f * sqrt(max(lambda1, lambda2)))` |
//! | [`BOX_SIGMAS`] | 3.33 | gsplat `ProjectionEWA3DGSFused.cu`: `extend = 3.33f`, `ceilf(extend * sqrtf(covar2d[0][0]))` |
//! | `TILE_SIDE` | 16 | 3DGS `config.h` `BLOCK_X`, `BLOCK_Y`; gsplat `tile_size` 16 |
//!
//! Pixel coordinates: pgt's (docs/design.md §1), pixel (px, py) has its centre at
//! (px + 0.5, py + 0.5), y down, as gsplat's (`mean2d = fx·x/z + cx`). 3DGS's `ndc2Pix` puts
//! pixel centres at integers; its `getRect` is applied here to the same point in its
//! coordinates (x − 0.5), so a splat touches the same tiles as in 3DGS.

use super::contract::{ratio_f32, PROFILE_GAUSSIAN, TILE_SIDE};
use super::layout::{GpuFrame, GpuSplat, SceneBuffers};
use glam::{Mat3, Vec3};

/// Floor of the discriminant in the 2D covariance's eigenvalues (3DGS `preprocessCUDA`).
pub const EIGEN_FLOOR: f32 = 0.1;
/// The 3DGS footprint's radius in standard deviations of the 2D covariance's major axis.
pub const FOOTPRINT_SIGMAS: f32 = 3.0;
/// The gsplat box's half-sides in standard deviations of the 2D covariance along x and y:
/// exp(−3.33²/2) < 1/255, so the box holds every pixel whose α reaches the skip threshold.
pub const BOX_SIGMAS: f32 = 3.33;

/// Which tiles a splat is listed in (the method's parameter `footprint`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Footprint {
    /// 3DGS: the square of radius ⌈3·√λ_max⌉ about the centre, binned by `getRect`.
    Radius3dgs,
    /// gsplat: the box ⌈3.33·√Σxx⌉ × ⌈3.33·√Σyy⌉ about the centre, binned by `isect_tiles`
    /// (tiles ⌊(x − r)/16⌋ to ⌈(x + r)/16⌉).
    BoxGsplat,
}

/// The rasteriser's constants: the method's parameters in their units (docs/design.md §4,
/// `splat`; `approx::methods::splat` lists them with their sources).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplatConstants {
    pub footprint: Footprint,
    /// The most opacity one splat gives a pixel.
    pub alpha_cap: f32,
    /// Centres at view depth ≤ this (scene units) are culled.
    pub near: f32,
    /// The centre's x/z and y/z are clamped to this many times the tangent of the half field
    /// of view before the Jacobian is taken.
    pub jacobian_clamp: f32,
    /// Added to the diagonal of the 2D covariance, px² (the low-pass filter).
    pub dilation: f32,
    /// A splat whose α at a pixel is below this is skipped.
    pub alpha_skip: f32,
    /// A pixel stops at the splat that would take its transmittance below this.
    pub stop_below: f32,
    /// Whether the stop also takes a transmittance equal to `stop_below`.
    pub stop_inclusive: bool,
}

impl SplatConstants {
    /// The constants of the method's parameter values by name (as `ApproxParams::resolve`
    /// gives them); a parameter not among them takes its default (3DGS's value).
    pub fn from_values(values: &[(String, u32)]) -> SplatConstants {
        let get = |name: &str| {
            values
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, v)| *v)
                .or_else(|| {
                    super::methods::splat::PARAMS
                        .iter()
                        .find(|p| p.name == name)
                        .map(|p| p.default)
                })
                .unwrap_or(0)
        };
        let ratio = |name: &str, unit: f64| ratio_f32(get(name), unit);
        SplatConstants {
            footprint: match get("footprint") {
                0 => Footprint::Radius3dgs,
                _ => Footprint::BoxGsplat,
            },
            alpha_cap: ratio("alpha_cap", 1e6),
            near: ratio("near", 1e6),
            jacobian_clamp: ratio("jacobian_clamp", 100.0),
            dilation: ratio("dilation", 1000.0),
            alpha_skip: ratio_f32(1, get("skip_denominator").max(1) as f64),
            stop_below: ratio("stop_below", 1e6),
            stop_inclusive: get("stop_inclusive") != 0,
        }
    }

    /// 3DGS's constants (the parameters' defaults).
    pub fn three_dgs() -> SplatConstants {
        SplatConstants::from_values(&[])
    }

    /// Writes the per-pixel constants (α cap, skip, stop) into the frame for the shader.
    pub fn apply_to(&self, frame: &mut GpuFrame) {
        frame.splat_alpha_cap = self.alpha_cap;
        frame.splat_alpha_skip = self.alpha_skip;
        frame.splat_stop_below = self.stop_below;
        frame.splat_stop_inclusive = self.stop_inclusive as u32;
    }
}

/// A Gaussian projected to the image: its 2D mean (pgt pixel coordinates), the inverse of its
/// dilated 2D covariance (the conic), its view depth and the tiles its footprint touches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projected {
    /// Centre on the image, pixel centres at +0.5.
    pub mean: [f32; 2],
    /// (a, b, c) of the conic Σ₂D⁻¹ = [[a, b], [b, c]].
    pub conic: [f32; 3],
    /// The dilated 2D covariance (xx, xy, yy), px².
    pub cov: [f32; 3],
    /// View depth of the centre, dot(centre − eye, forward).
    pub depth: f32,
    /// Footprint radius, px: ⌈3·√λ_max⌉ (3DGS), the box's larger half-side (gsplat).
    pub radius: f32,
    /// Tiles [min, max) in x and y.
    pub tiles_x: (u32, u32),
    pub tiles_y: (u32, u32),
}

/// The image's tile grid: columns and rows of `TILE_SIDE`-pixel tiles.
pub fn tile_grid(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE_SIDE), height.div_ceil(TILE_SIDE))
}

/// The 3D covariance Σ = R·S²·Rᵀ of particle `i` (f32, camera axes as the scene's): a sphere's
/// r²·I, an ellipsoid's Σⱼ sⱼ²·aⱼaⱼᵀ with aⱼ = sⱼ·rowⱼ its unit axis (rowⱼ = row j of M).
fn covariance(buffers: &SceneBuffers, i: usize) -> Mat3 {
    let p = &buffers.particles[i];
    match buffers.ellipsoids.get(p.ellipsoid as usize) {
        None => Mat3::from_diagonal(Vec3::splat(p.radius * p.radius)),
        Some(e) => {
            let mut sigma = Mat3::ZERO;
            for (row, s) in [
                (e.row_x, e.semi_x),
                (e.row_y, e.semi_y),
                (e.row_z, e.semi_z),
            ] {
                let axis = Vec3::from(row) * s;
                let s2 = s * s;
                sigma += Mat3::from_cols(axis * axis.x, axis * axis.y, axis * axis.z) * s2;
            }
            sigma
        }
    }
}

/// Focal lengths, principal point (pixels) and the Jacobian's clamp of x/z and y/z as
/// (−low, high) limits, for the clamp factor `clamp` (1.3 in both presets). A fov_y camera's
/// are 3DGS's (`fov2focal`: focal = pixels/(2·tan(fov/2)), fx = fy; centre W/2, H/2; limits
/// ±clamp·tan(fov/2)); a camera with intrinsics (docs/design.md §1 "Intrinsics") uses fx, fy,
/// cx, cy and gsplat's asymmetric limits (`proj_ewa`: cx/fx + (clamp − 1)·tan_fovx below,
/// (W − cx)/fx + (clamp − 1)·tan_fovx above, tan_fovx = (W/2)/fx), which are 3DGS's for a
/// centred principal point.
#[allow(clippy::type_complexity)]
fn lens(frame: &GpuFrame, clamp: f32) -> (f32, f32, [f32; 2], ((f32, f32), (f32, f32))) {
    let (w, h) = (frame.width as f32, frame.height as f32);
    if frame.pinhole == 0 {
        let tan_fovy = frame.tan_half_fov;
        let tan_fovx = tan_fovy * w / h;
        let (lim_x, lim_y) = (clamp * tan_fovx, clamp * tan_fovy);
        return (
            w / (2.0 * tan_fovx),
            h / (2.0 * tan_fovy),
            [0.5 * w, 0.5 * h],
            ((lim_x, lim_x), (lim_y, lim_y)),
        );
    }
    let (fx, fy, cx, cy) = (frame.fx, frame.fy, frame.cx, frame.cy);
    let margin = clamp - 1.0;
    let (tan_fovx, tan_fovy) = (0.5 * w / fx, 0.5 * h / fy);
    (
        fx,
        fy,
        [cx, cy],
        (
            (
                cx / fx + margin * tan_fovx,
                (w - cx) / fx + margin * tan_fovx,
            ),
            (
                cy / fy + margin * tan_fovy,
                (h - cy) / fy + margin * tan_fovy,
            ),
        ),
    )
}

/// Projects particle `i` as 3DGS's `preprocessCUDA` (or gsplat's projection) does with the
/// constants `k`; `None` where the rasteriser drops it (near culling, a singular covariance,
/// a footprint that touches no tile).
pub fn project(
    buffers: &SceneBuffers,
    frame: &GpuFrame,
    k: &SplatConstants,
    i: usize,
) -> Option<Projected> {
    let p = &buffers.particles[i];
    let c = Vec3::from(p.center);
    // View axes as 3DGS's (x right, y down, z forward): W has the rows r, −u, f.
    let (right, down, forward) = (
        Vec3::from(frame.right),
        -Vec3::from(frame.up),
        Vec3::from(frame.forward),
    );
    let t = Vec3::new(c.dot(right), c.dot(down), c.dot(forward));
    if t.z <= k.near {
        return None;
    }
    let (focal_x, focal_y, principal, (lim_x, lim_y)) = lens(frame, k.jacobian_clamp);
    // The Jacobian of the perspective projection at the (clamped) centre.
    let tx = (t.x / t.z).clamp(-lim_x.0, lim_x.1) * t.z;
    let ty = (t.y / t.z).clamp(-lim_y.0, lim_y.1) * t.z;
    let j0 = Vec3::new(focal_x / t.z, 0.0, -(focal_x * tx) / (t.z * t.z));
    let j1 = Vec3::new(0.0, focal_y / t.z, -(focal_y * ty) / (t.z * t.z));
    // Rows of T = J·W in scene axes (Wᵀ·j: W's rows are r, −u, f); Σ₂D = T·Σ·Tᵀ.
    let t0 = right * j0.x + down * j0.y + forward * j0.z;
    let t1 = right * j1.x + down * j1.y + forward * j1.z;
    let sigma = covariance(buffers, i);
    let (s_t0, s_t1) = (sigma * t0, sigma * t1);
    let a = t0.dot(s_t0) + k.dilation;
    let b = t0.dot(s_t1);
    let cc = t1.dot(s_t1) + k.dilation;
    let det = a * cc - b * b;
    // 3DGS drops a singular covariance, gsplat also a negative determinant.
    if det == 0.0 || (k.footprint == Footprint::BoxGsplat && det < 0.0) {
        return None;
    }
    let det_inv = 1.0 / det;
    let conic = [cc * det_inv, -b * det_inv, a * det_inv];
    // The mean, pixel centres at +0.5 (docs/design.md §1).
    let mean = [
        focal_x * t.x / t.z + principal[0],
        focal_y * t.y / t.z + principal[1],
    ];
    let (radius, tiles_x, tiles_y) = footprint_tiles(k.footprint, mean, [a, b, cc], det, frame);
    if (tiles_x.1 - tiles_x.0) * (tiles_y.1 - tiles_y.0) == 0 {
        return None;
    }
    Some(Projected {
        mean,
        conic,
        cov: [a, b, cc],
        depth: t.z,
        radius,
        tiles_x,
        tiles_y,
    })
}

/// The footprint's radius (px, the larger half-side for gsplat's box) and the tiles
/// [min, max) in x and y it is listed in, by `rule`, for the dilated 2D covariance `cov`
/// (xx, xy, yy) of determinant `det` centred at `mean`.
fn footprint_tiles(
    rule: Footprint,
    mean: [f32; 2],
    cov: [f32; 3],
    det: f32,
    frame: &GpuFrame,
) -> (f32, (u32, u32), (u32, u32)) {
    let (cols, rows) = tile_grid(frame.width, frame.height);
    let side = TILE_SIDE as f32;
    match rule {
        Footprint::Radius3dgs => {
            let mid = 0.5 * (cov[0] + cov[2]);
            let root = (mid * mid - det).max(EIGEN_FLOOR).sqrt();
            let radius = (FOOTPRINT_SIGMAS * (mid + root).max(mid - root).sqrt()).ceil();
            // 3DGS `getRect` on its pixel coordinates (centres at integers: x − 0.5),
            // truncating.
            let rect = |centre: f32, grid: u32| {
                let lo = (((centre - radius) / side) as i64).clamp(0, grid as i64) as u32;
                let hi =
                    (((centre + radius + side - 1.0) / side) as i64).clamp(0, grid as i64) as u32;
                (lo, hi)
            };
            (radius, rect(mean[0] - 0.5, cols), rect(mean[1] - 0.5, rows))
        }
        Footprint::BoxGsplat => {
            let rx = (BOX_SIGMAS * cov[0].sqrt()).ceil();
            let ry = (BOX_SIGMAS * cov[2].sqrt()).ceil();
            // gsplat `isect_tiles`: ⌊(x − r)/16⌋ inclusive to ⌈(x + r)/16⌉ exclusive.
            let rect = |centre: f32, r: f32, grid: u32| {
                let (c, tr) = (centre / side, r / side);
                let lo = ((c - tr).floor() as i64).clamp(0, grid as i64) as u32;
                let hi = ((c + tr).ceil() as i64).clamp(0, grid as i64) as u32;
                (lo, hi)
            };
            (rx.max(ry), rect(mean[0], rx, cols), rect(mean[1], ry, rows))
        }
    }
}

/// The splat lists of a scene: [`SceneBuffers::splats`], the projected Gaussians in order of
/// view depth (ties: particle index; 3DGS sorts the keys (tile, depth) with a stable radix sort
/// of the Gaussians in index order), and [`SceneBuffers::tile_entries`]: for tile k (row-major)
/// the range `[tile_entries[2k], tile_entries[2k + 1])` of `tile_entries` that lists its splats
/// front to back. Particles of constant density are left out (the methods refuse them).
pub fn build(buffers: &mut SceneBuffers, frame: &GpuFrame, k: &SplatConstants) {
    let mut projected: Vec<(u32, Projected)> = (0..buffers.particles.len())
        .filter(|&i| buffers.particles[i].profile == PROFILE_GAUSSIAN)
        .filter_map(|i| project(buffers, frame, k, i).map(|p| (i as u32, p)))
        .collect();
    projected.sort_by(|a, b| a.1.depth.total_cmp(&b.1.depth).then(a.0.cmp(&b.0)));
    let (cols, rows) = tile_grid(frame.width, frame.height);
    let tiles = (cols * rows) as usize;
    // Counting sort into tiles, each tile's list in the global depth order.
    let mut count = vec![0u32; tiles];
    for (_, p) in &projected {
        for y in p.tiles_y.0..p.tiles_y.1 {
            for x in p.tiles_x.0..p.tiles_x.1 {
                count[(y * cols + x) as usize] += 1;
            }
        }
    }
    let mut entries = vec![0u32; 2 * tiles];
    let mut next = Vec::with_capacity(tiles);
    let mut at = 2 * tiles as u32;
    for (k, n) in count.iter().enumerate() {
        entries[2 * k] = at;
        entries[2 * k + 1] = at + n;
        next.push(at);
        at += n;
    }
    entries.resize(at as usize, 0);
    for (s, (_, p)) in projected.iter().enumerate() {
        for y in p.tiles_y.0..p.tiles_y.1 {
            for x in p.tiles_x.0..p.tiles_x.1 {
                let k = (y * cols + x) as usize;
                entries[next[k] as usize] = s as u32;
                next[k] += 1;
            }
        }
    }
    buffers.splats = projected
        .iter()
        .map(|&(i, p)| GpuSplat {
            mean_x: p.mean[0],
            mean_y: p.mean[1],
            conic_a: p.conic[0],
            conic_b: p.conic[1],
            conic_c: p.conic[2],
            opacity: buffers.particles[i as usize].opacity,
            depth: p.depth,
            particle: i,
        })
        .collect();
    buffers.tile_entries = entries;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Profile, Scene, SceneLoadOptions};

    /// A grid of Gaussians, some in front of the near cull, seen by a 100×70 camera.
    fn buffers() -> (SceneBuffers, GpuFrame) {
        let mut text = String::from(
            "[camera]\nposition = [0.0, 0.0, -8.0]\nlook_at = [0.0, 0.0, 0.0]\nwidth = 100\nheight = 70\n",
        );
        for i in 0..60 {
            let (x, y, z) = (
                (i % 6) as f64 - 2.5,
                (i / 6 % 5) as f64 - 2.0,
                (i % 7) as f64,
            );
            text += &format!(
                "[[particles]]\ncenter = [{x}, {y}, {}]\nradius = {}\n",
                z - 8.0 + 0.1 * (i % 3) as f64,
                0.1 + 0.05 * (i % 4) as f64
            );
        }
        let mut scene = Scene::from_toml_str(
            &text,
            std::path::Path::new("s.toml"),
            &SceneLoadOptions::default(),
        )
        .unwrap();
        for p in &mut scene.particles {
            p.profile = Profile::Gaussian;
        }
        let frame = GpuFrame::new(&scene, &[]);
        (SceneBuffers::new(&scene, &scene.build_bvh()), frame)
    }

    /// Every tile lists exactly the splats whose rectangle covers it, front to back.
    #[test]
    fn each_tile_lists_the_splats_that_touch_it_in_depth_order() {
        let (mut b, frame) = buffers();
        let constants = SplatConstants::three_dgs();
        build(&mut b, &frame, &constants);
        let (cols, rows) = tile_grid(frame.width, frame.height);
        let culled = (0..b.particles.len())
            .filter(|&i| project(&b, &frame, &constants, i).is_none())
            .count();
        assert!(culled > 0, "some Gaussians are culled");
        assert_eq!(b.splats.len() + culled, b.particles.len());
        for w in b.splats.windows(2) {
            assert!(
                w[0].depth < w[1].depth
                    || (w[0].depth == w[1].depth && w[0].particle < w[1].particle)
            );
        }
        let mut at = 2 * cols * rows;
        for y in 0..rows {
            for x in 0..cols {
                let k = (y * cols + x) as usize;
                let (begin, end) = (b.tile_entries[2 * k], b.tile_entries[2 * k + 1]);
                assert_eq!(begin, at, "tile lists are contiguous");
                at = end;
                let listed: Vec<u32> = b.tile_entries[begin as usize..end as usize].to_vec();
                assert!(listed.windows(2).all(|w| w[0] < w[1]), "front to back");
                let want: Vec<u32> = (0..b.splats.len() as u32)
                    .filter(|&s| {
                        let p = project(
                            &b,
                            &frame,
                            &constants,
                            b.splats[s as usize].particle as usize,
                        )
                        .unwrap();
                        (p.tiles_x.0..p.tiles_x.1).contains(&x)
                            && (p.tiles_y.0..p.tiles_y.1).contains(&y)
                    })
                    .collect();
                assert_eq!(listed, want, "tile ({x}, {y})");
            }
        }
        assert_eq!(at as usize, b.tile_entries.len());
    }

    /// A round splat of σ = 10 px at x = 47.5: 3DGS's radius ⌈3·√λ⌉ = 31 px starts at tile 1,
    /// gsplat's box ⌈3.33·σ⌉ = 34 px at tile 0, where pixel 15 (32 px from the centre, beyond
    /// 3σ) still has α = exp(−3.2²/2) ≈ 0.006 ≥ 1/255 for opacity 1.
    #[test]
    fn gsplats_box_lists_a_splat_that_3dgs_radius_leaves_out() {
        let (b, frame) = buffers();
        let three = SplatConstants::three_dgs();
        let gsplat_values: Vec<(String, u32)> =
            crate::approx::methods::splat::preset("gsplat").expect("the gsplat preset");
        let gsplat = SplatConstants::from_values(&gsplat_values);
        assert_eq!(gsplat.footprint, Footprint::BoxGsplat);
        assert_eq!((gsplat.alpha_cap, gsplat.near), (0.999, 0.01));
        assert_eq!(
            (three.alpha_cap, three.near, three.dilation),
            (0.99, 0.2, 0.3)
        );
        assert_eq!((three.alpha_skip, three.stop_below), (1.0 / 255.0, 1e-4));
        let cov = [100.0, 0.0, 100.0];
        let det = 10000.0;
        let mean = [47.5, 35.0];
        let (r3, x3, _) = footprint_tiles(Footprint::Radius3dgs, mean, cov, det, &frame);
        let (rg, xg, _) = footprint_tiles(Footprint::BoxGsplat, mean, cov, det, &frame);
        assert_eq!((r3, rg), (31.0, 34.0));
        assert_eq!(x3.0, 1, "3DGS: from tile 1");
        assert_eq!(xg.0, 0, "gsplat: from tile 0");
        // Pixel 15 (centre 15.5) is 32 px left of the centre: beyond 3σ, yet above 1/255.
        let alpha = (-0.5f64 * (32.0 / 10.0f64).powi(2)).exp();
        assert!(alpha > 1.0 / 255.0, "{alpha}");
        drop(b);
    }
}

// Method `splat` (docs/design.md §4): the forward model of the reference 3D Gaussian splatting
// rasteriser (graphdeco-inria diff-gaussian-rasterization, cuda_rasterizer/forward.cu
// renderCUDA) or, by its parameters, gsplat's (rasterize_to_pixels). The projection, the
// footprints and the tile lists are made on the CPU (src/approx/splat_tiles.rs); here each
// pixel walks its tile's list front to back (one global order by the centres' view depth),
// α = min(cap, o·G₂D) per splat, splats with α below the skip threshold skipped, and stops at
// the first splat that would take the transmittance below the stop threshold (that splat not
// added): L = Σ αᵢTᵢCᵢ + T·L_bg. The thresholds are the frame's splat_* (3DGS: 0.99, 1/255,
// 1e-4).
fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    let tile = pixel_tile(pixel);
    let end = tile_entries[2u * tile + 1u];
    var blend = alpha_blend_start();
    for (var k = tile_entries[2u * tile]; k < end; k = k + 1u) {
        count_iteration();
        let s = splats[tile_entries[k]];
        let alpha = splat_alpha(s, pixel);
        if (alpha < frame.splat_alpha_skip) {
            continue;
        }
        if (!alpha_blend_over(&blend, particles[s.particle].color, alpha)) {
            break;
        }
    }
    return alpha_blend_end(blend);
}

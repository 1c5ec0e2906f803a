// Method `splat` (docs/design.md §4): the forward model of the reference 3D Gaussian splatting
// rasteriser (graphdeco-inria diff-gaussian-rasterization, cuda_rasterizer/forward.cu
// renderCUDA). The projection, the 3-σ footprints and the tile lists are made on the CPU
// (src/approx/splat_tiles.rs); here each pixel walks its tile's list front to back (one global
// order by the centres' view depth), α = min(0.99, o·G₂D) per splat, splats with α < 1/255
// skipped, and stops at the first splat that would take the transmittance below 1e-4 (that
// splat not added): L = Σ αᵢTᵢCᵢ + T·L_bg.
fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    let tile = pixel_tile(pixel);
    let end = tile_entries[2u * tile + 1u];
    var radiance = vec3<f32>(0.0);
    var transmittance = 1.0;
    for (var k = tile_entries[2u * tile]; k < end; k = k + 1u) {
        count_iteration();
        let s = splats[tile_entries[k]];
        let alpha = splat_alpha(s, pixel);
        if (alpha < SPLAT_ALPHA_MIN) {
            continue;
        }
        let next = transmittance * (1.0 - alpha);
        if (next < SPLAT_T_MIN) {
            break;
        }
        radiance = radiance + particles[s.particle].color * (alpha * transmittance);
        transmittance = next;
    }
    return radiance + transmittance * frame.background;
}

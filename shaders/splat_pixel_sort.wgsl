// Method `splat-pixel-sort` (docs/design.md §4): `splat` with a per-pixel order, StopThePop's
// idea (Radl et al. 2024): the splats of the pixel's tile with α ≥ 1/255 at the pixel are
// ordered by the depth t* of each Gaussian's maximum response along the pixel's ray (the
// closest approach in its Mahalanobis metric), not by their centres' depth; α, the skip and
// the stop are splat's. A pixel keeps its MAX_HITS nearest splats by t* (an overflow is
// counted, as a hit list's).

// The pixel's splats: t_enter holds t*, t_exit holds α, index the splat (hit_list_insert
// keeps them sorted by t*, ties by the splat's place in the depth order).
var<private> pixel_splats: HitList;

fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    let tile = pixel_tile(pixel);
    let end = tile_entries[2u * tile + 1u];
    pixel_splats.count = 0u;
    pixel_splats.overflowed = false;
    for (var k = tile_entries[2u * tile]; k < end; k = k + 1u) {
        count_iteration();
        let index = tile_entries[k];
        let s = splats[index];
        let alpha = splat_alpha(s, pixel);
        if (alpha < frame.splat_alpha_skip) {
            continue;
        }
        let peak = gaussian_peak(ray, particles[s.particle], 1.0);
        hit_list_insert(&pixel_splats, index, Chord(peak.t_star, alpha, true));
    }
    var blend = alpha_blend_start();
    for (var k = 0u; k < pixel_splats.count; k = k + 1u) {
        count_iteration();
        let p = particles[splats[pixel_splats.index[k]].particle];
        if (!alpha_blend_over(&blend, p.color, pixel_splats.t_exit[k])) {
            break;
        }
    }
    return alpha_blend_end(blend);
}

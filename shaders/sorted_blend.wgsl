// Method `sorted-blend` (docs/design.md §4): what rasterising renderers do with transparent particles
// (3D Gaussian splatting, Mol* and MegaMol transparency). The particles a camera ray crosses are
// sorted by the view-space depth of their centres, dot(centre − eye, forward) (the eye is the
// origin of the camera-relative coordinates), and each is composited whole, back to front, with
// the emission model's closed form over its own chord: L = L_behind·T + C·(1 − T). Where centre
// order and entry order agree and particles do not overlap, this is the exact emission model;
// elsewhere the order, and so the image, differs.

// Slots k of camera_hits in order of increasing centre depth (ties: lower particle index).
var<private> blend_order: array<u32, MAX_HITS>;

// View-space depth of a particle's centre: dot(centre − eye, forward), the eye at the origin.
fn centre_depth(index: u32) -> f32 {
    return dot(particles[index].center, frame.forward);
}

fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    collect_hits(ray, 0.0, T_FAR, &camera_hits);
    let n = camera_hits.count;
    // Insertion sort of the hit slots by centre depth (a ray crosses few particles).
    for (var k = 0u; k < n; k = k + 1u) {
        count_iteration();
        let index = camera_hits.index[k];
        let depth = centre_depth(index);
        var slot = k;
        loop {
            if (slot == 0u) {
                break;
            }
            count_iteration();
            let prev = blend_order[slot - 1u];
            let prev_index = camera_hits.index[prev];
            let prev_depth = centre_depth(prev_index);
            if (prev_depth < depth || (prev_depth == depth && prev_index < index)) {
                break;
            }
            blend_order[slot] = prev;
            slot = slot - 1u;
        }
        blend_order[slot] = k;
    }
    // Back to front: the deepest centre first.
    var radiance = frame.background;
    var k = n;
    while (k > 0u) {
        count_iteration();
        k = k - 1u;
        let h = blend_order[k];
        let p = particles[camera_hits.index[h]];
        // Each particle whole, over its own chord (a camera inside it sees the part in front).
        let length = camera_hits.t_exit[h] - max(camera_hits.t_enter[h], 0.0);
        radiance = composite_emission(p, length, radiance);
    }
    return radiance;
}

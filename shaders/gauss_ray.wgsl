// Method `gauss-ray` (docs/design.md §4): 3D Gaussian ray tracing (3DGRT, Moenne-Loccoz et al.
// 2024). The BVH and the shapes are the Gaussians' 3-σ ellipsoids (GAUSSIAN_TRACE_SIGMAS; pgt
// widens them before the upload); every Gaussian whose 3-σ ellipsoid the ray crosses
// contributes α = min(0.99, o·exp(−½m*²)) at the depth t* of its maximum response along the
// ray (m* the Mahalanobis distance there), the hits blended front to back in order of t* and
// the ray stopped at the first hit that would take the transmittance below 1e-4 (that hit not
// added, as splat does). The hits are taken a batch at a time, as `ever` takes its events: each
// batch is one BVH traversal that keeps the GAUSS_RAY_BATCH nearest hits by (t*, index) beyond
// the last one blended (3DGRT: k nearest hits per trace).

// The batch: hits sorted by (t*, particle index), with their α.
var<private> batch_t: array<f32, GAUSS_RAY_BATCH>;
var<private> batch_index: array<u32, GAUSS_RAY_BATCH>;
var<private> batch_alpha: array<f32, GAUSS_RAY_BATCH>;
var<private> batch_count: u32;

fn batch_before(t_a: f32, i_a: u32, t_b: f32, i_b: u32) -> bool {
    return t_a < t_b || (t_a == t_b && i_a < i_b);
}

// Inserts a hit into the batch, keeping the nearest GAUSS_RAY_BATCH.
fn batch_insert(t: f32, index: u32, alpha: f32) {
    var slot = batch_count;
    if (slot >= GAUSS_RAY_BATCH) {
        let last = GAUSS_RAY_BATCH - 1u;
        if (!batch_before(t, index, batch_t[last], batch_index[last])) {
            return;
        }
        slot = last;
    } else {
        batch_count = slot + 1u;
    }
    loop {
        count_iteration();
        if (slot == 0u || !batch_before(t, index, batch_t[slot - 1u], batch_index[slot - 1u])) {
            break;
        }
        batch_t[slot] = batch_t[slot - 1u];
        batch_index[slot] = batch_index[slot - 1u];
        batch_alpha[slot] = batch_alpha[slot - 1u];
        slot = slot - 1u;
    }
    batch_t[slot] = t;
    batch_index[slot] = index;
    batch_alpha[slot] = alpha;
}

// One traversal: the GAUSS_RAY_BATCH nearest hits after (t_last, index_last), or from the start
// (`first`). A hit's t* lies in its chord, so boxes that end before t_last or start beyond a
// full batch's farthest t* hold none.
fn gauss_ray_collect(ray: Ray, t_last: f32, index_last: u32, first: bool) {
    batch_count = 0u;
    if (frame.particle_count == 0u) {
        return;
    }
    let inv = safe_inverse(ray.direction);
    traversal_stack[0] = 0u;
    var sp = 1u;
    while (sp > 0u) {
        count_iteration();
        sp = sp - 1u;
        let node = nodes[traversal_stack[sp]];
        var t_max = T_FAR;
        if (batch_count >= GAUSS_RAY_BATCH) {
            t_max = batch_t[GAUSS_RAY_BATCH - 1u];
        }
        if (!ray_box(ray.origin, inv, node.min, node.max, t_last, t_max)) {
            continue;
        }
        if (node.count > 0u) {
            for (var k = 0u; k < node.count; k = k + 1u) {
                count_iteration();
                let i = leaf_indices[node.first + k];
                let p = particles[i];
                let c = intersect_particle(ray, p);
                if (!c.hit || c.t_exit <= 0.0) {
                    continue;
                }
                let peak = gaussian_peak(ray, p, GAUSSIAN_TRACE_SIGMAS);
                if (!first && !batch_before(t_last, index_last, peak.t_star, i)) {
                    continue;
                }
                let alpha = min(SPLAT_ALPHA_MAX, p.opacity * exp(-0.5 * peak.m * peak.m));
                batch_insert(peak.t_star, i, alpha);
            }
        } else if (sp + 2u <= STACK_SIZE) {
            traversal_stack[sp] = node.first;
            traversal_stack[sp + 1u] = node.first + 1u;
            sp = sp + 2u;
        }
    }
}

fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    var transmittance = 1.0;
    var t_last = 0.0;
    var index_last = 0u;
    var first = true;
    loop {
        count_iteration();
        gauss_ray_collect(ray, t_last, index_last, first);
        first = false;
        var stopped = false;
        for (var k = 0u; k < batch_count; k = k + 1u) {
            count_iteration();
            let alpha = batch_alpha[k];
            let next = transmittance * (1.0 - alpha);
            if (next < SPLAT_T_MIN) {
                stopped = true;
                break;
            }
            radiance = radiance + particles[batch_index[k]].color * (alpha * transmittance);
            transmittance = next;
        }
        if (stopped || batch_count < GAUSS_RAY_BATCH) {
            break;
        }
        t_last = batch_t[GAUSS_RAY_BATCH - 1u];
        index_last = batch_index[GAUSS_RAY_BATCH - 1u];
    }
    return radiance + transmittance * frame.background;
}

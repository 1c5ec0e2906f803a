// Method `gauss-ray` (docs/design.md §4): 3D Gaussian ray tracing (3DGRT, Moenne-Loccoz et al.
// 2024). The BVH and the shapes are the Gaussians' 3-σ ellipsoids (GAUSSIAN_TRACE_SIGMAS; pgt
// widens them before the upload); every Gaussian whose 3-σ ellipsoid the ray crosses
// contributes α = min(0.99, o·exp(−½m*²)) at the depth t* of its maximum response along the
// ray (m* the Mahalanobis distance there), the hits blended front to back in order of t* and
// the ray stopped at the first hit that would take the transmittance below 1e-4 (that hit not
// added, as splat does). The hits are taken a batch at a time, as `ever` takes its events: each
// batch is one BVH traversal that keeps the GAUSS_RAY_BATCH nearest hits by (t*, index) beyond
// the last one blended (3DGRT: k nearest hits per trace).

// The batch of shaders/nearest_events.wgsl: hits sorted by (t*, particle index), each with its α.
alias EventT = f32;
alias EventValue = f32;
const EVENT_CAPACITY: u32 = GAUSS_RAY_BATCH;
const EVENT_T_FAR: f32 = T_FAR;
const EVENT_IN_BOX: bool = true;

// Gaussian i's hit, if its t* comes after (t_after, index_after). A hit's t* lies in its chord,
// so the boxes the traversal prunes (ending before t_after, starting beyond a full batch's
// farthest t*) hold none.
fn event_visit(ray: EventRay, i: u32, t_after: f32, index_after: u32, capacity: u32) {
    let p = particles[i];
    let r = Ray(ray.origin, ray.direction);
    let c = intersect_particle(r, p);
    if (!c.hit || c.t_exit <= 0.0) {
        return;
    }
    let peak = gaussian_peak(r, p, GAUSSIAN_TRACE_SIGMAS);
    if (!event_before(t_after, index_after, peak.t_star, i)) {
        return;
    }
    let alpha = min(SPLAT_ALPHA_MAX, p.opacity * exp(-0.5 * peak.m * peak.m));
    event_insert(peak.t_star, i, alpha, capacity);
}

fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    let traced = EventRay(ray.origin, ray.origin, ray.direction, safe_inverse(ray.direction));
    var blend = alpha_blend_start();
    // Before every hit (t* ≥ 0).
    var t_last = -1.0;
    var index_last = 0u;
    loop {
        count_iteration();
        events_collect(traced, t_last, index_last, GAUSS_RAY_BATCH, frame.particle_count);
        var stopped = false;
        for (var k = 0u; k < events_count; k = k + 1u) {
            count_iteration();
            if (!alpha_blend_over(&blend, particles[events_key[k]].color, events_value[k])) {
                stopped = true;
                break;
            }
        }
        if (stopped || events_count < GAUSS_RAY_BATCH) {
            break;
        }
        t_last = events_t[GAUSS_RAY_BATCH - 1u];
        index_last = events_key[GAUSS_RAY_BATCH - 1u];
    }
    return alpha_blend_end(blend);
}

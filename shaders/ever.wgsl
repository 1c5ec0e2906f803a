// Method `ever` (docs/design.md §4): the algorithm of EVER (Mai et al. 2024, "EVER: Exact
// Volumetric Ellipsoid Rendering for Real-time View Synthesis") in float32, with its cut-offs as
// parameters. Along the camera ray the particles' entry and exit points are events; between two
// events the gas is constant — σ = Σ σ_i over the particles the ray is inside, colour
// C̄ = Σ σ_i·C_i / σ — so each segment of length Δt adds T·C̄·(1 − e^{−σΔt}) and multiplies T by
// e^{−σΔt}: the emission model of docs/design.md §2, overlaps included, exact but for float32
// and the cut-offs. The events are taken in order of t a batch at a time: each batch is one BVH
// traversal that keeps the `batch` nearest events beyond the last one taken (EVER: 16 hits per
// trace). The sums σ and Σσ_i·C_i are kept running — added at an entry, subtracted at an exit —
// as EVER keeps them, and set to exactly 0 where the ray is inside no particle. The ray stops
// when T < stop_below·10⁻⁶ (EVER: 0.004) or after max_batches batches (EVER: 400 iterations);
// the background then still shows through the T left, the gas behind the stop does not.

// The batch of shaders/nearest_events.wgsl: events sorted by (t, key), key = 2·particle index
// + (0 entry, 1 exit); EVER_MAX_BATCH is generated (the `batch` parameter's maximum). An event
// carries nothing besides.
alias EventT = f32;
alias EventValue = u32;
const EVENT_CAPACITY: u32 = EVER_MAX_BATCH;
const EVENT_T_FAR: f32 = T_FAR;
const EVENT_IN_BOX: bool = true;

// Particle i's entry and exit after (t_after, key_after). An entry behind the camera (a camera
// inside the particle) is an event at t = 0; a particle wholly behind it has none.
fn event_visit(ray: EventRay, i: u32, t_after: f32, key_after: u32, capacity: u32) {
    let c = intersect_particle(Ray(ray.origin, ray.direction), particles[i]);
    if (!c.hit || c.t_exit <= 0.0) {
        return;
    }
    let t_enter = max(c.t_enter, 0.0);
    if (event_before(t_after, key_after, t_enter, 2u * i)) {
        event_insert(t_enter, 2u * i, 0u, capacity);
    }
    if (event_before(t_after, key_after, c.t_exit, 2u * i + 1u)) {
        event_insert(c.t_exit, 2u * i + 1u, 0u, capacity);
    }
}

fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    let capacity = clamp(method_param(PARAM_BATCH), 1u, EVER_MAX_BATCH);
    let stop = f32(method_param(PARAM_STOP_BELOW)) * 1e-6;
    let max_batches = method_param(PARAM_MAX_BATCHES);
    var radiance = vec3<f32>(0.0);
    var transmittance = 1.0;
    // The running sums over the particles the ray is inside: finite σ_i and σ_i·C_i, and the
    // particles with σ = ∞ (Θmax = 1) by count and colour sum.
    var sigma_sum = 0.0;
    var source_sum = vec3<f32>(0.0);
    var inside = 0u;
    var opaque_inside = 0u;
    var opaque_colors = vec3<f32>(0.0);
    var t_cur = 0.0;
    var t_last = -1.0;
    var key_last = 0u;
    var done = false;
    let traced = EventRay(ray.origin, ray.origin, ray.direction, safe_inverse(ray.direction));
    for (var b = 0u; b < max_batches && !done; b = b + 1u) {
        count_iteration();
        events_collect(traced, t_last, key_last, capacity, frame.particle_count);
        if (events_count == 0u) {
            break;
        }
        for (var e = 0u; e < events_count; e = e + 1u) {
            count_iteration();
            let t = events_t[e];
            let key = events_key[e];
            let dt = t - t_cur;
            if (dt > 0.0) {
                if (opaque_inside > 0u) {
                    // σ = ∞ ahead: this segment's colour, nothing behind it.
                    radiance = radiance + transmittance * opaque_colors / f32(opaque_inside);
                    transmittance = 0.0;
                } else if (sigma_sum > 0.0) {
                    let a = exp(-sigma_sum * dt);
                    radiance = radiance + transmittance * (source_sum / sigma_sum) * (1.0 - a);
                    transmittance = transmittance * a;
                }
            }
            t_cur = max(t_cur, t);
            t_last = t;
            key_last = key;
            let p = particles[key / 2u];
            let entering = (key & 1u) == 0u;
            if (p.sigma < 0.0) {
                if (entering) {
                    opaque_inside = opaque_inside + 1u;
                    opaque_colors = opaque_colors + p.color;
                } else {
                    opaque_inside = opaque_inside - 1u;
                    opaque_colors = opaque_colors - p.color;
                }
            } else if (entering) {
                sigma_sum = sigma_sum + p.sigma;
                source_sum = source_sum + p.sigma * p.color;
            } else {
                sigma_sum = sigma_sum - p.sigma;
                source_sum = source_sum - p.sigma * p.color;
            }
            if (entering) {
                inside = inside + 1u;
            } else {
                inside = inside - 1u;
            }
            if (inside == 0u) {
                sigma_sum = 0.0;
                source_sum = vec3<f32>(0.0);
                opaque_colors = vec3<f32>(0.0);
            }
            if (transmittance < stop || transmittance <= 0.0) {
                done = true;
                break;
            }
        }
    }
    return radiance + transmittance * frame.background;
}

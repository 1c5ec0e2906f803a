// The exact reference of the emission model on the GPU in f64 (docs/design.md §12): spheres and
// ellipsoids, one invocation per camera ray, with a bound on its own rounding.
//
// The constants REF_*, STATE_*, SCENE_*, PARAM_*, STATUS_*, the struct BvhNode and the bindings
// are generated from src/reference/gpu/program.rs and prepended, with shaders/f64_math.wgsl (no
// transcendental builtin is ever called on f64: lavapipe's return garbage) and
// shaders/nearest_events.wgsl (the batch and its BVH traversal, shared with ever and gauss-ray).
//
// Along the ray the particles' entry and exit points are events, taken in order of (t, key),
// key = 4·index + kind (0 entry, 1 exit, 2 ghost), a batch of REF_BATCH at a time: each batch is
// one BVH traversal that keeps the nearest events beyond the last one taken and rebuilds the set
// of particles the ray is inside there (sorted by index, so the sums below do not depend on how
// the work was split into passes). Between two events the set is fixed, and the interval adds
// T·E·(1 − e^{−σΔ}) with σ = Σσᵢ and E = Σσᵢ·Cᵢ/σ summed afresh (docs/design.md §2, §3).
//
// Error bound, carried per ray (`ray_error` in src/reference/gpu/mod.rs turns it into err):
// * each chord end's distance from the exact one (the ray's direction, the subtraction o − c and
//   every rounding of the stable intersection), as optical depth σᵢ·δt: moving one chord end by
//   δt changes L by at most σᵢ·δt·Cmax (a sliver of gas of that depth in front of radiance at
//   most Cmax). A line that misses in f64 but may cross the exact particle is a "ghost" event
//   whose depth is the longest exact chord it could have. A Θmax = 1 particle's entry moves the
//   end of the ray: its depth is δt times the scene's total finite σ.
// * the rounding of the composite: relative bounds of σ, S, τ, the opacity, T (running) and each
//   term, and half an ulp of every addition to the radiance, in `error`.

var<private> loop_iterations: u32 = 0u;

fn count_iteration() {
    loop_iterations = loop_iterations + 1u;
}

var<private> traversal_stack: array<u32, STACK_SIZE>;

// The batch of shaders/nearest_events.wgsl: events sorted by (t, key), each with the optical
// depth by which it may be off.
alias EventT = f64;
alias EventValue = f64;
const EVENT_CAPACITY: u32 = REF_BATCH;
const EVENT_T_FAR: f64 = REF_HUGE;
const EVENT_IN_BOX: bool = true;

// The particles the ray is inside at the last event taken, sorted by index.
var<private> inside: array<u32, REF_INSIDE_MAX>;
var<private> inside_count: u32;
var<private> inside_overflowed: bool;

const REF_U: f64 = 1.1102230246251565e-16lf;

fn dot3(a: vec3<f64>, b: vec3<f64>) -> f64 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn norm3(a: vec3<f64>) -> f64 {
    return sqrt(dot3(a, a));
}

fn vec_at(buffer_offset: u32) -> vec3<f64> {
    return vec3<f64>(particle_data[buffer_offset], particle_data[buffer_offset + 1u], particle_data[buffer_offset + 2u]);
}

// Three consecutive values of `ellipsoid_data`: a row of M.
fn ellipsoid_row(at: u32) -> vec3<f64> {
    return vec3<f64>(ellipsoid_data[at], ellipsoid_data[at + 1u], ellipsoid_data[at + 2u]);
}

// A chord with bounds on how far its computed ends lie from the exact ones. `ghost` > 0 where the
// computed line misses but the exact one may cross: a bound on the exact chord's length, around
// t_ghost.
struct Chord64 {
    t_enter: f64,
    t_exit: f64,
    err_enter: f64,
    err_exit: f64,
    hit: bool,
    ghost: f64,
    t_ghost: f64,
}

// The stable intersection of src/geometry/sphere.rs (the same operations in the same order) with
// a sphere of radius r about the origin, for the line f + s·d, where the computed f and d lie
// within ef and ed of the exact ones (d within ed of a unit vector). Every bound is first order
// with the rounding of each step; REF_SAFETY covers the second-order terms.
fn chord_about(f: vec3<f64>, ef: f64, d: vec3<f64>, ed: f64, r: f64) -> Chord64 {
    let t_c = -dot3(f, d);
    let l = f + t_c * d;
    let dist = norm3(l);
    let big_f = norm3(f);
    let at = abs(t_c);
    let e_tc = ef * (1.0lf + ed) + big_f * ed + 4.0lf * REF_U * big_f;
    let e_l = ef + e_tc * (1.0lf + ed) + at * ed + 4.0lf * REF_U * (big_f + at);
    let e_dist = e_l + 3.0lf * REF_U * dist;
    let h2 = (r - dist) * (r + dist);
    let e_h2 = 3.1lf * REF_U * abs(h2) + e_dist * (2.0lf * dist + e_dist);
    var c = Chord64(0.0lf, 0.0lf, 0.0lf, 0.0lf, false, 0.0lf, 0.0lf);
    let half = sqrt(max(h2, 0.0lf));
    if (dist >= r || half <= 0.0lf) {
        if (h2 + e_h2 > 0.0lf) {
            c.ghost = REF_SAFETY * 2.0lf * sqrt(max(h2, 0.0lf) + e_h2);
            c.t_ghost = t_c;
        }
        return c;
    }
    let e_half = min(e_h2 / half, sqrt(e_h2)) * 1.01lf + REF_U * half;
    c.t_enter = t_c - half;
    c.t_exit = t_c + half;
    c.err_enter = REF_SAFETY * (e_tc + e_half + REF_U * abs(c.t_enter));
    c.err_exit = REF_SAFETY * (e_tc + e_half + REF_U * abs(c.t_exit));
    c.hit = true;
    return c;
}

// Particle i's chord on the ray o + t·d (d within scene_data[SCENE_DIRECTION_ERROR] of the
// exact unit direction), a sphere or an ellipsoid (src/geometry/ellipsoid.rs: the ray mapped by M to the unit
// sphere, s = k·t with k = |M·d|).
fn particle_chord(o: vec3<f64>, d: vec3<f64>, i: u32) -> Chord64 {
    let base = i * REF_PARTICLE_STRIDE;
    let f = o - vec_at(base);
    let big_f = norm3(f);
    let ed = scene_data[SCENE_DIRECTION_ERROR];
    let shape = particle_data[base + REF_P_SHAPE];
    if (shape < 0.0lf) {
        return chord_about(f, REF_U * big_f, d, ed, particle_data[base + REF_P_RADIUS]);
    }
    let e = u32(shape) * REF_ELLIPSOID_STRIDE;
    let m0 = ellipsoid_row(e);
    let m1 = ellipsoid_row(e + 3u);
    let m2 = ellipsoid_row(e + 6u);
    let frobenius = ellipsoid_data[e + 9u];
    let fu = vec3<f64>(dot3(m0, f), dot3(m1, f), dot3(m2, f));
    let du = vec3<f64>(dot3(m0, d), dot3(m1, d), dot3(m2, d));
    let k = norm3(du);
    if (!(k > 0.0lf)) {
        return Chord64(0.0lf, 0.0lf, 0.0lf, 0.0lf, false, 0.0lf, 0.0lf);
    }
    let e_fu = frobenius * (REF_U * big_f + 3.1lf * REF_U * big_f);
    let e_du = frobenius * (ed + 3.1lf * REF_U * (1.0lf + ed));
    let e_k = e_du + 3.0lf * REF_U * k;
    let e_unit = (e_du + e_k) / k + 3.0lf * REF_U;
    let s = chord_about(fu, e_fu, du / k, e_unit, 1.0lf);
    // t = s/k: |t − t*| ≤ δs/k + (|s| + δs)·δk/(k·(k − δk)) + u·|t|.
    let kk = k * max(k - e_k, 0.5lf * k);
    var c = s;
    c.t_enter = s.t_enter / k;
    c.t_exit = s.t_exit / k;
    c.err_enter = REF_SAFETY * (s.err_enter / k + (abs(s.t_enter) + s.err_enter) * e_k / kk + REF_U * abs(c.t_enter));
    c.err_exit = REF_SAFETY * (s.err_exit / k + (abs(s.t_exit) + s.err_exit) * e_k / kk + REF_U * abs(c.t_exit));
    c.ghost = s.ghost * REF_SAFETY / max(k - e_k, 0.5lf * k);
    c.t_ghost = s.t_ghost / k;
    return c;
}

fn inside_insert(i: u32) {
    if (inside_count >= REF_INSIDE_MAX) {
        inside_overflowed = true;
        return;
    }
    var slot = inside_count;
    inside_count = inside_count + 1u;
    loop {
        count_iteration();
        if (slot == 0u || inside[slot - 1u] < i) {
            break;
        }
        inside[slot] = inside[slot - 1u];
        slot = slot - 1u;
    }
    inside[slot] = i;
}

fn inside_remove(i: u32) {
    var found = false;
    for (var k = 0u; k < inside_count; k = k + 1u) {
        count_iteration();
        if (inside[k] == i) {
            found = true;
        }
        if (found && k + 1u < inside_count) {
            inside[k] = inside[k + 1u];
        }
    }
    if (found) {
        inside_count = inside_count - 1u;
    }
}

fn sigma_of(i: u32) -> f64 {
    return particle_data[i * REF_PARTICLE_STRIDE + REF_P_SIGMA];
}

// The events of particle i after (t_last, key_last) into the batch, and i into the inside set
// where the ray is inside it there.
fn event_visit(ray: EventRay, i: u32, t_last: f64, key_last: u32, capacity: u32) {
    let c = particle_chord(ray.origin, ray.direction, i);
    let sigma = sigma_of(i);
    let opaque = sigma < 0.0lf;
    // A finite σ turns a chord-end error into optical depth; a Θmax = 1 particle's entry moves
    // the end of the ray (the scene's total finite σ); an uncertain Θmax = 1 ghost is unbounded.
    let per_length = select(sigma, scene_data[SCENE_SIGMA_TOTAL], opaque);
    if (!c.hit) {
        if (c.ghost > 0.0lf) {
            let t_g = max(c.t_ghost, 0.0lf);
            if (c.t_ghost + c.ghost > 0.0lf && event_before(t_last, key_last, t_g, 4u * i + 2u)) {
                event_insert(t_g, 4u * i + 2u, select(sigma * c.ghost, REF_HUGE, opaque), capacity);
            }
        }
        return;
    }
    if (c.t_exit <= 0.0lf) {
        // Behind the eye, unless the exact exit may lie in front of it.
        if (c.t_exit + c.err_exit > 0.0lf && event_before(t_last, key_last, 0.0lf, 4u * i + 2u)) {
            event_insert(0.0lf, 4u * i + 2u, select(sigma * (c.t_exit + c.err_exit), REF_HUGE, opaque), capacity);
        }
        return;
    }
    let t_enter = max(c.t_enter, 0.0lf);
    let exit_after = event_before(t_last, key_last, c.t_exit, 4u * i + 1u);
    if (event_before(t_last, key_last, t_enter, 4u * i)) {
        event_insert(t_enter, 4u * i, per_length * c.err_enter, capacity);
    } else if (exit_after) {
        inside_insert(i);
    }
    if (exit_after) {
        event_insert(c.t_exit, 4u * i + 1u, select(sigma * c.err_exit, 0.0lf, opaque), capacity);
    }
}

// One traversal (shaders/nearest_events.wgsl; the boxes are camera-relative f32, padded outwards
// by the approximation's layout far more than any f64 rounding here): the REF_BATCH nearest
// events after (t_last, key_last) and the inside set there.
fn collect(o: vec3<f64>, rel: vec3<f64>, d: vec3<f64>, t_last: f64, key_last: u32) {
    inside_count = 0u;
    let tiny = vec3<f64>(1.0e-300lf);
    let sign = select(vec3<f64>(1.0lf), vec3<f64>(-1.0lf), d < vec3<f64>(0.0lf));
    let inv = sign / max(abs(d), tiny);
    events_collect(EventRay(o, rel, d, inv), t_last, key_last, REF_BATCH, params.particle_count);
}

// What one ray carries from pass to pass (STATE_* offsets into `state`).
struct RayState {
    radiance: vec3<f64>,
    error: vec3<f64>,
    transmittance: f64,
    // A bound on the relative error of `transmittance`.
    transmittance_rel: f64,
    t_last: f64,
    key_last: u32,
    // Σ of the optical depths by which the events taken may be off.
    depth: f64,
    status: u32,
}

fn load_state(r: u32) -> RayState {
    let b = r * STATE_STRIDE;
    return RayState(
        vec3<f64>(state[b + STATE_RADIANCE], state[b + STATE_RADIANCE + 1u], state[b + STATE_RADIANCE + 2u]),
        vec3<f64>(state[b + STATE_ERROR], state[b + STATE_ERROR + 1u], state[b + STATE_ERROR + 2u]),
        state[b + STATE_TRANSMITTANCE],
        state[b + STATE_TRANSMITTANCE_REL],
        state[b + STATE_T_LAST],
        u32(state[b + STATE_KEY_LAST]),
        state[b + STATE_DEPTH],
        u32(state[b + STATE_STATUS]),
    );
}

fn store_state(r: u32, s: RayState) {
    let b = r * STATE_STRIDE;
    for (var c = 0u; c < 3u; c = c + 1u) {
        state[b + STATE_RADIANCE + c] = s.radiance[c];
        state[b + STATE_ERROR + c] = s.error[c];
    }
    state[b + STATE_TRANSMITTANCE] = s.transmittance;
    state[b + STATE_TRANSMITTANCE_REL] = s.transmittance_rel;
    state[b + STATE_T_LAST] = s.t_last;
    state[b + STATE_KEY_LAST] = f64(s.key_last);
    state[b + STATE_DEPTH] = s.depth;
    state[b + STATE_STATUS] = f64(s.status);
}

// Adds a term c ≥ 0 with relative error ≤ rel to the radiance, with its rounding.
fn add_term(s: ptr<function, RayState>, c: vec3<f64>, rel: f64) {
    (*s).radiance = (*s).radiance + c;
    (*s).error = (*s).error + c * rel + REF_U * (*s).radiance;
}

// docs/design.md §2, emission model: the interval [t0, t1] with the inside set adds
// T·E·(1 − e^{−σΔ}) and multiplies T by e^{−σΔ}; a Θmax = 1 particle inside ends the ray with
// T·(mean colour). Returns whether the ray has ended.
fn composite_interval(s: ptr<function, RayState>, t0: f64, t1: f64) -> bool {
    var sigma = 0.0lf;
    var weighted = vec3<f64>(0.0lf);
    var n_opaque = 0u;
    var opaque_colors = vec3<f64>(0.0lf);
    for (var k = 0u; k < inside_count; k = k + 1u) {
        count_iteration();
        let b = inside[k] * REF_PARTICLE_STRIDE;
        let sigma_i = particle_data[b + REF_P_SIGMA];
        let color = vec_at(b + REF_P_COLOR);
        if (sigma_i < 0.0lf) {
            n_opaque = n_opaque + 1u;
            opaque_colors = opaque_colors + color;
        } else {
            sigma = sigma + sigma_i;
            weighted = weighted + sigma_i * color;
        }
    }
    let n = f64(inside_count);
    let t = (*s).transmittance;
    if (n_opaque > 0u) {
        let mean = opaque_colors / f64(n_opaque);
        add_term(s, t * mean, (*s).transmittance_rel + (n + 2.0lf) * REF_U);
        (*s).transmittance = 0.0lf;
        return true;
    }
    if (!(sigma > 0.0lf)) {
        return false;
    }
    let tau = sigma * (t1 - t0);
    let rel_sigma = n * REF_U;
    let rel_tau = rel_sigma + 2.0lf * REF_U;
    let opacity = -f64_expm1(-tau);
    let e = f64_exp(-tau);
    let rel_opacity = rel_tau + 2.0lf * REF_EXPM1_ULPS * REF_U;
    let rel_emission = (n + 1.0lf) * REF_U + rel_sigma + REF_U;
    add_term(s, (t * opacity) * (weighted / sigma), (*s).transmittance_rel + rel_opacity + rel_emission + 2.0lf * REF_U);
    (*s).transmittance = t * e;
    (*s).transmittance_rel = (*s).transmittance_rel + tau * rel_tau + 2.0lf * REF_EXP_ULPS * REF_U + REF_U;
    return false;
}

// Takes the batch's events in order. Returns whether the ray has ended.
fn take_batch(s: ptr<function, RayState>) -> bool {
    for (var e = 0u; e < events_count; e = e + 1u) {
        count_iteration();
        let t = events_t[e];
        let t_cur = max((*s).t_last, 0.0lf);
        if (t > t_cur && inside_count > 0u) {
            if (composite_interval(s, t_cur, t)) {
                return true;
            }
        }
        let key = events_key[e];
        let kind = key % 4u;
        if (kind == 0u) {
            inside_insert(key / 4u);
        } else if (kind == 1u) {
            inside_remove(key / 4u);
        }
        (*s).depth = (*s).depth + events_value[e];
        (*s).t_last = t;
        (*s).key_last = key;
        if ((*s).transmittance < REF_T_STOP) {
            return true;
        }
    }
    return false;
}

// The end of a ray: the background behind what is left, or, where T fell below REF_T_STOP with
// gas possibly behind, the middle of what the rest could add (Cmax·T/2 into the value and err).
fn finish(s: ptr<function, RayState>, exhausted: bool) {
    let t = (*s).transmittance;
    if (t <= 0.0lf) {
        return;
    }
    let background = vec3<f64>(scene_data[SCENE_BACKGROUND], scene_data[SCENE_BACKGROUND + 1u], scene_data[SCENE_BACKGROUND + 2u]);
    if (exhausted) {
        add_term(s, t * background, (*s).transmittance_rel + REF_U);
        return;
    }
    let cmax = vec3<f64>(scene_data[SCENE_CMAX], scene_data[SCENE_CMAX + 1u], scene_data[SCENE_CMAX + 2u]);
    add_term(s, (0.5lf * t) * cmax, (*s).transmittance_rel + REF_U);
    (*s).error = (*s).error + (0.5lf * t) * cmax;
}

@compute @workgroup_size(REF_WORKGROUP, 1, 1)
fn reference_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let r = gid.x;
    if (r >= params.ray_count) {
        return;
    }
    var s = load_state(r);
    if (s.status != STATUS_RUNNING) {
        return;
    }
    let o = vec3<f64>(scene_data[SCENE_ORIGIN], scene_data[SCENE_ORIGIN + 1u], scene_data[SCENE_ORIGIN + 2u]);
    let rel = vec3<f64>(scene_data[SCENE_RELATIVE_ORIGIN], scene_data[SCENE_RELATIVE_ORIGIN + 1u], scene_data[SCENE_RELATIVE_ORIGIN + 2u]);
    let d = vec3<f64>(rays[3u * r], rays[3u * r + 1u], rays[3u * r + 2u]);
    loop {
        count_iteration();
        collect(o, rel, d, s.t_last, s.key_last);
        if (inside_overflowed) {
            s.status = STATUS_INSIDE_OVERFLOW;
            break;
        }
        if (events_count == 0u) {
            finish(&s, true);
            s.status = STATUS_DONE;
            break;
        }
        let ended = take_batch(&s);
        if (inside_overflowed) {
            s.status = STATUS_INSIDE_OVERFLOW;
            break;
        }
        if (ended) {
            finish(&s, false);
            s.status = STATUS_DONE;
            break;
        }
        if (loop_iterations >= params.pass_yield) {
            break;
        }
    }
    if (loop_iterations >= params.loop_budget) {
        s.status = STATUS_LOOP_LIMITED;
    }
    store_state(r, s);
    if (s.status == STATUS_RUNNING) {
        atomicAdd(&counters.running, 1u);
    }
}

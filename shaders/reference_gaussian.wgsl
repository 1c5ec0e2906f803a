// The exact reference of the emission model for Gaussian particles on the GPU in f64
// (docs/design.md §12, §9 "Gaussian density"): one invocation per camera ray, the method of
// src/reference/gaussian.rs without its optimisations, with a bound on its own rounding.
//
// The constants GR_*, GS_*, GST_*, GSTATUS_*, GPHASE_*, STACK_SIZE, the struct BvhNode and the
// bindings are generated from src/reference/gpu/gaussian.rs and prepended, with
// shaders/f64_math.wgsl (no transcendental builtin is ever called on f64) and
// shaders/nearest_events.wgsl (the BVH traversal and the batch).
//
// Per ray, three phases, each a traversal of the BVH of the k-σ ellipsoids over every Gaussian
// whose k-σ ellipsoid the ray may meet in front of the eye (the candidates): GPHASE_COUNT counts
// them (n); GPHASE_SUM leaves out the faint ones (depth in front ≤ FAINT·tol/M/n) whole, gives
// the rest windows |t − t*| ≤ w·s whose tails fit TAILS·tol/M/n, and sums the depth left out and
// the windows' span; GPHASE_PIECES takes the windows in batches: the GR_WINDOWS_MAX kept windows
// still open at the cursor that start first (nearest_events.wgsl keyed by (start, Gaussian)),
// valid up to the start of the first one left out; a ray whose kept windows fit one batch takes
// them in the traversal's order, unsorted. The ray is cut at every window's ends and
// centre; on each piece [a, b] the closed form T(a)·C_ref·(1 − e^{−τ(a,b)}) with C_ref the colour
// of the Gaussian with the most depth there, and the colour deviation
// ∫ e^{−τ(a,t)}·Σ σᵢ(t)(Cᵢ − C_ref) dt bounded in closed form (the CPU's `deviation_bounds`)
// while the half-widths fit BOUNDED·tol, else integrated by adaptive G7–K15 with a fixed stack,
// each segment to QUADRATURE·tol times its share of the windows' span, its estimate
// (src/reference/quadrature.rs's `pair_estimate` for K15 against G7) into err. A piece's
// members are the batch's windows that overlap it, in the batch's order, whichever batch holds
// them (the order of the traversal or of (start, Gaussian), the ray's choice), so the pieces and their values do not depend on where batches or passes end. A ray goes
// on in the next pass from its phase and the end of the last piece it finished. A ray with more
// than GR_WINDOWS_MAX windows open at one depth is not converged (err = |L| + M).
//
// Error bound, carried per ray and turned into err by gaussian.rs (`ray_error`): the parts of
// the CPU (ray stop, bounded deviations, quadrature, the depth left out) and the device's own:
// * each profile's uncertainty as optical depth: s and the peak computed from the rounded
//   o − c, M·(o − c), M·d (d within GS_DIRECTION_ERROR of the exact unit direction; m*²'s
//   rounding by its part across the ray, `across_error_off_ray`), and each piece's depth
//   through the erfc bound (GR_ERFC_ULPS, GR_ERFC_NORMAL); a change of the medium by optical
//   depth δ changes L by at most M·δ; t*'s uncertainty through the position derivative of L
//   (`shift_depth`), which only other gas makes matter;
// * the composite's rounding: relative bounds carried through T and each term, and half an ulp
//   of every addition to the radiance, in `rounding`.

var<private> loop_iterations: u32 = 0u;

fn count_iteration() {
    loop_iterations = loop_iterations + 1u;
}

var<private> traversal_stack: array<u32, STACK_SIZE>;

// The batch of shaders/nearest_events.wgsl: the kept windows still open at the ray's cursor,
// keyed by (start, Gaussian), one more than a ray holds (the first left out bounds the batch's
// reach). A window may reach beyond its Gaussian's k-σ ellipsoid and so beyond its BVH box.
alias EventT = f64;
alias EventValue = u32;
const EVENT_CAPACITY: u32 = GR_WINDOWS_MAX + 1u;
const EVENT_T_FAR: f64 = REF_HUGE_G;
const EVENT_IN_BOX: bool = false;

// The batch's windows: profile, window, Gaussian, in the batch's order.
var<private> w_tstar: array<f64, GR_WINDOWS_MAX>;
var<private> w_s: array<f64, GR_WINDOWS_MAX>;
var<private> w_peak: array<f64, GR_WINDOWS_MAX>;
// The exact peak's upper bound and t*'s uncertainty.
var<private> w_peak_hi: array<f64, GR_WINDOWS_MAX>;
var<private> w_et: array<f64, GR_WINDOWS_MAX>;
var<private> w_lo: array<f64, GR_WINDOWS_MAX>;
var<private> w_hi: array<f64, GR_WINDOWS_MAX>;
var<private> w_index: array<u32, GR_WINDOWS_MAX>;
var<private> w_count: u32;

// The members of the current piece (indices into the windows) and erfc(|z|) at its start.
var<private> m_window: array<u32, GR_WINDOWS_MAX>;
var<private> m_tail_a: array<f64, GR_WINDOWS_MAX>;
var<private> m_count: u32;

// The quadrature's stack of segments still to integrate.
var<private> q_lo: array<f64, GR_QSTACK>;
var<private> q_hi: array<f64, GR_QSTACK>;

const GR_U: f64 = 1.1102230246251565e-16lf;
const GR_SQRT2: f64 = 1.4142135623730951lf;
const GR_SQRT_HALF_PI: f64 = 1.2533141373155003lf;

fn g_dot(a: vec3<f64>, b: vec3<f64>) -> f64 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn g_norm(a: vec3<f64>) -> f64 {
    return sqrt(g_dot(a, a));
}

fn g_vec(at: u32) -> vec3<f64> {
    return vec3<f64>(gauss_data[at], gauss_data[at + 1u], gauss_data[at + 2u]);
}

fn scene_vec(at: u32) -> vec3<f64> {
    return vec3<f64>(scene_data[at], scene_data[at + 1u], scene_data[at + 2u]);
}

// ln x for x > 0 (from f64_log1p: x − 1 is exact for 0.5 ≤ x ≤ 2 and the rounding elsewhere
// is below an ulp of the result's argument; only window widths use it).
fn g_ln(x: f64) -> f64 {
    return f64_log1p(x - 1.0lf);
}

// A Gaussian's density along the ray (src/optics/gaussian.rs `GaussianAlongRay::new`: the
// same operations), and `pert`, a bound on the optical depth (over the whole line) by which the
// computed profile's peak and width may make it differ from the exact one along the exact ray;
// the shift of t* (within e_t) is bounded where the profile is used (`shift_depth`).
struct Profile64 {
    t_star: f64,
    s: f64,
    peak: f64,
    m2: f64,
    pert: f64,
    // Bounds on |m*² − exact| and |t* − exact|.
    e_m2: f64,
    e_t: f64,
}

fn gauss_profile(o: vec3<f64>, d: vec3<f64>, i: u32) -> Profile64 {
    let b = i * GR_GAUSS_STRIDE;
    let f = o - g_vec(b);
    let m0 = g_vec(b + GR_G_MATRIX);
    let m1 = g_vec(b + GR_G_MATRIX + 3u);
    let m2r = g_vec(b + GR_G_MATRIX + 6u);
    let frob = gauss_data[b + GR_G_FROBENIUS];
    let sigma = gauss_data[b + GR_G_SIGMA];
    let ed = scene_data[GS_DIRECTION_ERROR];
    let u0 = vec3<f64>(g_dot(m0, f), g_dot(m1, f), g_dot(m2r, f));
    let v = vec3<f64>(g_dot(m0, d), g_dot(m1, d), g_dot(m2r, d));
    let k = g_norm(v);
    let v_hat = v / k;
    let along = g_dot(u0, v_hat);
    let across = u0 - along * v_hat;
    let m2 = g_dot(across, across);
    var p: Profile64;
    p.t_star = -along / k;
    p.s = 1.0lf / k;
    p.peak = sigma * f64_exp(-0.5lf * m2);
    p.m2 = m2;
    // First-order bounds of every rounding (as chord_about's in reference_emission.wgsl).
    let big_f = g_norm(f);
    let n_u0 = g_norm(u0);
    let e_u0 = frob * 4.1lf * GR_U * big_f;
    let e_v = frob * (ed + 3.1lf * GR_U * (1.0lf + ed));
    let e_k = e_v + 3.0lf * GR_U * k;
    let e_vhat = (e_v + e_k) / k + 3.0lf * GR_U;
    let e_along = e_u0 + n_u0 * e_vhat + 3.0lf * GR_U * n_u0;
    let e_across = e_u0 + e_along + abs(along) * e_vhat + 3.0lf * GR_U * (n_u0 + abs(along));
    let n_across = sqrt(m2);
    let iso_m2 = 2.0lf * n_across * e_across + e_across * e_across + 3.0lf * GR_U * m2;
    let p_err = across_error_off_ray(f, d, m0, m1, m2r, u0, v_hat, along, across, k, e_v, e_vhat, e_along);
    // |ã|² − |a|² = 2a·δ + |δ|² with the exact a ⊥ v̂: a·δ = a·Pδ.
    let projected_m2 = 2.0lf * (n_across + e_across) * p_err + e_across * e_across + 3.0lf * GR_U * m2;
    p.e_m2 = GR_SAFETY * min(iso_m2, projected_m2);
    p.e_t = GR_SAFETY * ((e_along + abs(p.t_star) * e_k) / k + GR_U * abs(p.t_star));
    let rel_peak = 0.5lf * p.e_m2 + 2.0lf * GR_EXP_ULPS * GR_U + 2.0lf * GR_U;
    let rel_s = GR_SAFETY * (e_k / k + GR_U);
    let total = p.peak * p.s * 2.0lf * GR_SQRT_HALF_PI;
    // Over the line: a relative change of the peak or of s changes the depth by that much.
    p.pert = total * (rel_peak + rel_s + 8.0lf * GR_U);
    return p;
}

// A bound on |P·(ã − a)|, the part across the exact v̂ (P = I − v̂v̂ᵀ) of the rounding of
// `across` (ã computed, a exact), which is all that m*² sees to first order. An error along axis
// i reaches it through |P·eᵢ| = √(1 − v̂ᵢ²) only, and the roundings of M·(o − c) and M·d are
// largest along the rows of M with the largest entries, which for a flat Gaussian lie nearly
// along v̂: there this is orders below the isotropic bound. The terms: (1) u₀'s rounding, o − c's
// included, componentwise; (2) v̂'s, |P·(v̂′ − v̂)| = |P·δv|/|v′| for v′ = v + δv (d's direction
// error and M·d's rounding, componentwise), times |u₀| and |along|; (3) the rounding of along
// times v̂′'s part across v̂; (4) the rounding of along·v̂ᵢ and of the subtraction. +∞ where the
// direction's error is not small against k (the isotropic bound then stands).
fn across_error_off_ray(f: vec3<f64>, d: vec3<f64>, m0: vec3<f64>, m1: vec3<f64>, m2r: vec3<f64>, u0: vec3<f64>, v_hat: vec3<f64>, along: f64, across: vec3<f64>, k: f64, e_v: f64, e_vhat: f64, e_along: f64) -> f64 {
    if (!(e_v < 0.5lf * k)) {
        return REF_HUGE_G;
    }
    let sq = v_hat * v_hat;
    let pe = sqrt(vec3<f64>(sq.y + sq.z, sq.x + sq.z, sq.x + sq.y)) * (1.0lf + 4.0lf * GR_U) + vec3<f64>(e_vhat);
    let af = abs(f);
    let ad = abs(d);
    let mf = vec3<f64>(g_dot(abs(m0), af), g_dot(abs(m1), af), g_dot(abs(m2r), af));
    let md = vec3<f64>(g_dot(abs(m0), ad), g_dot(abs(m1), ad), g_dot(abs(m2r), ad));
    let rows = vec3<f64>(g_norm(m0), g_norm(m1), g_norm(m2r));
    let ed = scene_data[GS_DIRECTION_ERROR];
    let p_u0 = 4.1lf * GR_U * g_dot(mf, pe);
    let p_vhat = g_dot(3.1lf * GR_U * md + rows * (ed * (1.0lf + 4.0lf * GR_U)), pe) / (k - e_v) + 2.0lf * GR_U * g_dot(abs(v_hat), pe);
    let n_u0 = g_norm(u0) * (1.0lf + 4.0lf * GR_U);
    let p_direction = (n_u0 * e_vhat + abs(along) + e_along) * p_vhat;
    let p_along = 3.0lf * GR_U * g_dot(abs(u0), abs(v_hat)) * p_vhat;
    let p_subtract = GR_U * g_dot(abs(along) * abs(v_hat) + abs(across), pe);
    return (p_u0 + p_direction + p_along + p_subtract) * (1.0lf + 16.0lf * GR_U);
}

// erf(z_b) − erf(z_a) for z_a ≤ z_b from the tails ta = erfc(|z_a|), tb = erfc(|z_b|)
// (src/optics/gaussian.rs `erf_difference`: no cancellation in the tails).
fn erf_between(za: f64, ta: f64, zb: f64, tb: f64) -> f64 {
    if (za >= 0.0lf) {
        return ta - tb;
    }
    if (zb <= 0.0lf) {
        return tb - ta;
    }
    return (1.0lf - tb) + (1.0lf - ta);
}

// A bound on the error of `erf_between` times `factor`: each erfc within GR_ERFC_ULPS ulps (or
// GR_ERFC_NORMAL), its argument within a few ulps (erfc′ ≤ 2/√π·e^{−z²}, |z|·e^{−z²} < 0.43),
// the subtraction's and the product's rounding.
fn erf_between_error(factor: f64, ta: f64, tb: f64, result: f64) -> f64 {
    let per_tail = 2.0lf * GR_ERFC_ULPS * GR_U * (ta + tb) + 2.0lf * GR_ERFC_NORMAL + 12.0lf * GR_U;
    return factor * (per_tail + 3.0lf * GR_U * abs(result)) + 2.0lf * GR_U * abs(factor * result);
}

// peak·s·√(π/2): the optical depth of window w per unit of erf difference.
fn w_factor(w: u32) -> f64 {
    return depth_factor(w_peak[w], w_s[w]);
}

fn w_z(w: u32, t: f64) -> f64 {
    return (t - w_tstar[w]) / (GR_SQRT2 * w_s[w]);
}

// What a traversal does at each Gaussian (`gauss_visit`): count the candidates, sum what the
// ray's windows leave out, or put the kept windows open after the cursor into the batch.
const GV_COUNT: u32 = 0u;
const GV_SUM: u32 = 1u;
const GV_BATCH: u32 = 2u;
var<private> gv_mode: u32;
// A candidate whose depth in front of the eye is at most gv_faint is left out whole; a kept
// window's two tails hold at most gv_tail of depth.
var<private> gv_faint: f64;
var<private> gv_tail: f64;
// Whether GV_BATCH appends the windows in the traversal's order (the ray's kept windows fit one
// batch) instead of keeping the ones that start first.
var<private> gv_append: bool;
// GV_COUNT's and GV_SUM's sums.
var<private> gv_count: u32;
var<private> gv_left_out: f64;
var<private> gv_pert: f64;
var<private> gv_first: f64;
var<private> gv_last: f64;
// GV_SUM's sums for the shift of t* (`shift_depth`): the density bound of the candidates outside
// their windows (all of a faint one), the candidates' peaks, and Σ e_t times each kept window's
// tails or peak.
var<private> gv_edge: f64;
var<private> gv_peaks: f64;
var<private> gv_tail_shift: f64;
var<private> gv_far_shift: f64;
var<private> gv_total_shift: f64;

// An upper bound of the exact peak: its m*² within e_m2, the exponential's rounding.
fn peak_upper(p: Profile64) -> f64 {
    return p.peak * f64_exp(0.5lf * p.e_m2) * (1.0lf + 1.0e-12lf);
}

// The most density the profile (its peak at most `peak_hi`) has at a distance of at least
// `reach`·s from its centre, with the centre anywhere within e_t of t*.
fn density_beyond(p: Profile64, peak_hi: f64, reach: f64) -> f64 {
    let z = max(reach - p.e_t / p.s, 0.0lf);
    return peak_hi * f64_exp(-0.5lf * z * z) * (1.0lf + 1.0e-12lf);
}

// peak·s·√(π/2): a profile's optical depth per unit of erf difference.
fn depth_factor(peak: f64, s: f64) -> f64 {
    return peak * s * GR_SQRT_HALF_PI;
}

// The half-width of a kept window in units of s: its tails, total·erfc(w/√2) ≤
// total·e^{−w²/2}, within gv_tail (0 where the whole depth is).
fn window_reach(total: f64) -> f64 {
    if (total > gv_tail) {
        return sqrt(2.0lf * g_ln(total / gv_tail));
    }
    return 0.0lf;
}

// Gaussian i, if the ray may meet its k-σ ellipsoid in front of the eye (the same test and
// numbers on every traversal): counted, summed, or its window batched.
fn event_visit(ray: EventRay, i: u32, t_after: f64, key_after: u32, capacity: u32) {
    let p = gauss_profile(ray.origin, ray.direction, i);
    let k = scene_data[GS_CUTOFF];
    let reach = k * p.s * (1.0lf + 1.0e-9lf) + p.e_t;
    if (p.m2 - p.e_m2 > k * k * (1.0lf + 1.0e-12lf) || p.t_star + reach < 0.0lf) {
        return;
    }
    if (gv_mode == GV_COUNT) {
        gv_count = gv_count + 1u;
        return;
    }
    // The depth over [0, ∞): factor·(1 + erf(t*/(√2 s))) = factor·erfc(−t*/(√2 s)).
    let factor = depth_factor(p.peak, p.s);
    let front = factor * f64_erfc(-p.t_star / (GR_SQRT2 * p.s));
    var peak_hi = 0.0lf;
    if (gv_mode == GV_SUM) {
        peak_hi = peak_upper(p);
        // The shift moves depth across the eye: at most e_t times the density there.
        let at_eye = p.e_t * density_beyond(p, peak_hi, abs(p.t_star) / p.s);
        gv_pert = gv_pert + p.pert + at_eye + front * (2.0lf * GR_ERFC_ULPS * GR_U + 4.0lf * GR_U) + factor * 12.0lf * GR_U;
        gv_peaks = gv_peaks + peak_hi;
    }
    if (front <= gv_faint) {
        if (gv_mode == GV_SUM) {
            gv_left_out = gv_left_out + front;
            gv_edge = gv_edge + peak_hi;
        }
        return;
    }
    let total = 2.0lf * factor;
    let w = window_reach(total);
    let lo = max(p.t_star - w * p.s, 0.0lf);
    let hi = max(p.t_star + w * p.s, 0.0lf);
    if (gv_mode == GV_SUM) {
        let tails = total * f64_exp(-0.5lf * w * w) * (1.0lf + 16.0lf * GR_U);
        gv_left_out = gv_left_out + tails;
        let edge = density_beyond(p, peak_hi, w);
        gv_edge = gv_edge + edge;
        // The exact profile's depths: the peak's bound over the computed peak.
        let exact = select(1.0lf, peak_hi / p.peak, p.peak > 0.0lf);
        gv_tail_shift = gv_tail_shift + p.e_t * (tails * exact + 2.0lf * p.e_t * edge);
        gv_far_shift = gv_far_shift + p.e_t * peak_hi;
        gv_total_shift = gv_total_shift + p.e_t * (total * exact + 2.0lf * p.e_t * peak_hi);
        if (hi > lo) {
            gv_count = gv_count + 1u;
            gv_first = min(gv_first, lo);
            gv_last = max(gv_last, hi);
        }
    } else if (hi > lo && hi > t_after) {
        if (gv_append) {
            events_t[events_count] = lo;
            events_key[events_count] = i;
            events_count = events_count + 1u;
        } else {
            event_insert(lo, i, 0u, capacity);
        }
    }
}

// The thresholds of a ray whose candidates number `count`: each faint one within FAINT·tol/M,
// each kept window's tails within TAILS·tol/M, over the count (src/reference/gaussian.rs
// `gather` divides the tails' share among the kept windows; here among all candidates, which
// the first traversal counts: the windows are a little wider).
fn set_thresholds(count: u32, depth_per_tol: f64) {
    let n = f64(max(count, 1u));
    gv_faint = GR_FAINT * depth_per_tol / n;
    gv_tail = GR_TAILS * depth_per_tol / n;
}

// The candidates of the ray (shaders/nearest_events.wgsl's traversal, every box the ray meets
// in front of the eye).
fn gauss_count(ray: EventRay) -> u32 {
    gv_mode = GV_COUNT;
    gv_count = 0u;
    events_collect(ray, 0.0lf, 0u, 1u, params.gaussian_count);
    return gv_count;
}

// What the ray's windows leave out (faint Gaussians, tails), the profiles' uncertainty as depth,
// the windows' span and how many are kept, into the state.
fn gauss_sum(ray: EventRay, s: ptr<function, GState>) {
    gv_mode = GV_SUM;
    gv_count = 0u;
    gv_left_out = 0.0lf;
    gv_pert = 0.0lf;
    gv_first = REF_HUGE_G;
    gv_last = 0.0lf;
    gv_edge = 0.0lf;
    gv_peaks = 0.0lf;
    gv_tail_shift = 0.0lf;
    gv_far_shift = 0.0lf;
    gv_total_shift = 0.0lf;
    events_collect(ray, 0.0lf, 0u, 1u, params.gaussian_count);
    (*s).left_out = gv_left_out;
    // The shift of each kept window's t* against the others' density (`shift_depth`): of its
    // tails against every candidate's peak, of all of it against the far Gaussians' depth.
    let far = scene_data[GS_FAR_DEPTH];
    (*s).pert = gv_pert + (gv_tail_shift * gv_peaks + gv_far_shift * far) * (1.0lf + 1.0e-9lf);
    (*s).edge = gv_edge * (1.0lf + 1.0e-9lf);
    (*s).rest_shift = gv_total_shift * (gv_peaks + gv_edge) * (1.0lf + 1.0e-9lf);
    (*s).span = max(gv_last - gv_first, 0.0lf);
    (*s).kept = gv_count;
}

// The batch at cursor a into w_*: where the ray's `kept` windows fit one batch, those open
// after a in the traversal's order (no sorting); else the GR_WINDOWS_MAX open after a that
// start first, by (start, Gaussian). Returns where the batch ends (every window it leaves out
// starts there or later), +HUGE where it holds them all. Either way a window's place among the
// others it meets does not depend on a.
fn gauss_batch(ray: EventRay, a: f64, kept: u32) -> f64 {
    gv_mode = GV_BATCH;
    gv_append = kept <= GR_WINDOWS_MAX;
    events_collect(ray, a, 0u, GR_WINDOWS_MAX + 1u, params.gaussian_count);
    var end = REF_HUGE_G;
    var n = events_count;
    if (n > GR_WINDOWS_MAX) {
        end = events_t[GR_WINDOWS_MAX];
        n = GR_WINDOWS_MAX;
    }
    for (var j = 0u; j < n; j = j + 1u) {
        count_iteration();
        let i = events_key[j];
        let p = gauss_profile(ray.origin, ray.direction, i);
        w_tstar[j] = p.t_star;
        w_s[j] = p.s;
        w_peak[j] = p.peak;
        w_peak_hi[j] = peak_upper(p);
        w_et[j] = p.e_t;
        w_lo[j] = events_t[j];
        w_hi[j] = max(p.t_star + window_reach(2.0lf * depth_factor(p.peak, p.s)) * p.s, 0.0lf);
        w_index[j] = i;
    }
    w_count = n;
    return end;
}

// The next cut after a: the smallest window end or centre beyond it (+HUGE: none).
fn next_cut(a: f64) -> f64 {
    var b = REF_HUGE_G;
    for (var w = 0u; w < w_count; w = w + 1u) {
        count_iteration();
        if (!(w_hi[w] > w_lo[w])) {
            continue;
        }
        if (w_lo[w] > a) {
            b = min(b, w_lo[w]);
        }
        if (w_hi[w] > a) {
            b = min(b, w_hi[w]);
        }
        if (w_tstar[w] > a && w_tstar[w] > w_lo[w] && w_tstar[w] < w_hi[w]) {
            b = min(b, w_tstar[w]);
        }
    }
    return b;
}

fn g_color(w: u32) -> vec3<f64> {
    return g_vec(w_index[w] * GR_GAUSS_STRIDE + GR_G_COLOR);
}

// What one ray carries from pass to pass (GST_* offsets into `state`).
struct GState {
    radiance: vec3<f64>,
    rounding: vec3<f64>,
    bounded: vec3<f64>,
    quadrature: vec3<f64>,
    ray_stop: vec3<f64>,
    transmittance: f64,
    // A bound on the relative error of `transmittance` from its arithmetic.
    transmittance_rel: f64,
    // The start of the next piece.
    a: f64,
    // Σ of the pieces' depth uncertainties.
    depth: f64,
    status: u32,
    unconverged: u32,
    // The gather's sums (`gauss_sum`): the depth left out of the windows, the profiles'
    // uncertainty as depth, the windows' span; the candidates' and the kept windows' counts;
    // the ray's phase.
    left_out: f64,
    pert: f64,
    span: f64,
    count: u32,
    kept: u32,
    phase: u32,
    edge: f64,
    rest_shift: f64,
}

fn st_vec(b: u32) -> vec3<f64> {
    return vec3<f64>(state[b], state[b + 1u], state[b + 2u]);
}

fn st_set_vec(b: u32, v: vec3<f64>) {
    state[b] = v.x;
    state[b + 1u] = v.y;
    state[b + 2u] = v.z;
}

fn load_gstate(r: u32) -> GState {
    let b = r * GST_STRIDE;
    return GState(
        st_vec(b + GST_RADIANCE),
        st_vec(b + GST_ROUNDING),
        st_vec(b + GST_BOUNDED),
        st_vec(b + GST_QUADRATURE),
        st_vec(b + GST_RAY_STOP),
        state[b + GST_TRANSMITTANCE],
        state[b + GST_TRANSMITTANCE_REL],
        state[b + GST_A],
        state[b + GST_DEPTH],
        u32(state[b + GST_STATUS]),
        u32(state[b + GST_UNCONVERGED]),
        state[b + GST_LEFT_OUT],
        state[b + GST_PERT],
        state[b + GST_SPAN],
        u32(state[b + GST_COUNT]),
        u32(state[b + GST_KEPT]),
        u32(state[b + GST_PHASE]),
        state[b + GST_EDGE],
        state[b + GST_REST_SHIFT],
    );
}

fn store_gstate(r: u32, s: GState) {
    let b = r * GST_STRIDE;
    st_set_vec(b + GST_RADIANCE, s.radiance);
    st_set_vec(b + GST_ROUNDING, s.rounding);
    st_set_vec(b + GST_BOUNDED, s.bounded);
    st_set_vec(b + GST_QUADRATURE, s.quadrature);
    st_set_vec(b + GST_RAY_STOP, s.ray_stop);
    state[b + GST_TRANSMITTANCE] = s.transmittance;
    state[b + GST_TRANSMITTANCE_REL] = s.transmittance_rel;
    state[b + GST_A] = s.a;
    state[b + GST_DEPTH] = s.depth;
    state[b + GST_STATUS] = f64(s.status);
    state[b + GST_UNCONVERGED] = f64(s.unconverged);
    state[b + GST_LEFT_OUT] = s.left_out;
    state[b + GST_PERT] = s.pert;
    state[b + GST_SPAN] = s.span;
    state[b + GST_COUNT] = f64(s.count);
    state[b + GST_KEPT] = f64(s.kept);
    state[b + GST_PHASE] = f64(s.phase);
    state[b + GST_EDGE] = s.edge;
    state[b + GST_REST_SHIFT] = s.rest_shift;
}

// Adds a term c (any sign) with relative error ≤ rel to the radiance, with its rounding.
fn g_add(s: ptr<function, GState>, c: vec3<f64>, rel: f64) {
    (*s).radiance = (*s).radiance + c;
    (*s).rounding = (*s).rounding + abs(c) * rel + GR_U * abs((*s).radiance);
}

// The deviation integrand at t on the piece [a, ·] with reference colour c_ref:
// e^{−τ(a,t)}·Σ σᵢ(t)(Cᵢ − C_ref) over the members.
fn deviation_at(a: f64, t: f64, c_ref: vec3<f64>) -> vec3<f64> {
    var tau = 0.0lf;
    var sum = vec3<f64>(0.0lf);
    for (var j = 0u; j < m_count; j = j + 1u) {
        count_iteration();
        let w = m_window[j];
        let za = w_z(w, a);
        let zt = w_z(w, t);
        tau = tau + w_factor(w) * erf_between(za, m_tail_a[j], zt, f64_erfc(abs(zt)));
        let x = (t - w_tstar[w]) / w_s[w];
        sum = sum + (w_peak[w] * f64_exp(-0.5lf * x * x)) * (g_color(w) - c_ref);
    }
    return f64_exp(-tau) * sum;
}

// Kronrod abscissae and weights (QUADPACK qk15, as src/reference/quadrature.rs), the Gauss
// weights on the odd ones.
fn xgk(j: u32) -> f64 {
    switch j {
        case 0u: { return 0.9914553711208126lf; }
        case 1u: { return 0.9491079123427585lf; }
        case 2u: { return 0.8648644233597691lf; }
        case 3u: { return 0.7415311855993945lf; }
        case 4u: { return 0.5860872354676911lf; }
        case 5u: { return 0.4058451513773972lf; }
        case 6u: { return 0.2077849550078985lf; }
        default: { return 0.0lf; }
    }
}

fn wgk(j: u32) -> f64 {
    switch j {
        case 0u: { return 0.02293532201052922lf; }
        case 1u: { return 0.06309209262997855lf; }
        case 2u: { return 0.1047900103222502lf; }
        case 3u: { return 0.1406532597155259lf; }
        case 4u: { return 0.1690047266392679lf; }
        case 5u: { return 0.1903505780647854lf; }
        case 6u: { return 0.2044329400752989lf; }
        default: { return 0.2094821410847278lf; }
    }
}

// The Gauss weight of Kronrod node j (0 where j is not a Gauss node).
fn wg(j: u32) -> f64 {
    switch j {
        case 1u: { return 0.1294849661688697lf; }
        case 3u: { return 0.2797053914892767lf; }
        case 5u: { return 0.3818300505051189lf; }
        case 7u: { return 0.4179591836734694lf; }
        default: { return 0.0lf; }
    }
}

// One G7–K15 segment: the K15 value, the CPU's estimate (`pair_estimate`, QUADPACK's factor
// 200) and ∫|f|, all times the half-width.
struct Segment {
    value: vec3<f64>,
    error: vec3<f64>,
    abs_integral: vec3<f64>,
}

fn kronrod_segment(a: f64, lo: f64, hi: f64, c_ref: vec3<f64>) -> Segment {
    let h = 0.5lf * (hi - lo);
    let centre = 0.5lf * (lo + hi);
    var fv: array<vec3<f64>, 15>;
    for (var j = 0u; j < 7u; j = j + 1u) {
        count_iteration();
        fv[2u * j] = deviation_at(a, centre - h * xgk(j), c_ref);
        fv[2u * j + 1u] = deviation_at(a, centre + h * xgk(j), c_ref);
    }
    fv[14] = deviation_at(a, centre, c_ref);
    var resk = wgk(7u) * fv[14];
    var resg = wg(7u) * fv[14];
    for (var j = 0u; j < 7u; j = j + 1u) {
        count_iteration();
        let pr = fv[2u * j] + fv[2u * j + 1u];
        resk = resk + wgk(j) * pr;
        resg = resg + wg(j) * pr;
    }
    let mean = 0.5lf * resk;
    var resabs = wgk(7u) * abs(fv[14]);
    var resasc = wgk(7u) * abs(fv[14] - mean);
    for (var j = 0u; j < 7u; j = j + 1u) {
        count_iteration();
        let fa = fv[2u * j];
        let fb = fv[2u * j + 1u];
        resabs = resabs + wgk(j) * (abs(fa) + abs(fb));
        resasc = resasc + wgk(j) * (abs(fa - mean) + abs(fb - mean));
    }
    let diff = abs(resk - resg) * h;
    let abs_h = resabs * h;
    let asc_h = resasc * h;
    var error = diff;
    var relative = 0.0lf;
    for (var c = 0u; c < 3u; c = c + 1u) {
        if (asc_h[c] > 0.0lf && diff[c] > 0.0lf) {
            let q = 200.0lf * diff[c] / asc_h[c];
            error[c] = max(diff[c], asc_h[c] * min(q * sqrt(q), 1.0lf));
            relative = max(relative, error[c] / asc_h[c]);
        }
    }
    for (var c = 0u; c < 3u; c = c + 1u) {
        error[c] = max(error[c], relative * asc_h[c]);
        error[c] = max(error[c], 50.0lf * 2.220446049250313e-16lf * abs_h[c]);
    }
    return Segment(resk * h, error, abs_h);
}

// The deviation of the piece [a, b] by adaptive G7–K15, depth first with a fixed stack: a
// segment is kept where T times its estimate is within `tol_per_length` times its length, or
// where it cannot be split (then the ray is marked unconverged); its estimate goes into err.
// `node_rel` bounds the integrand's relative rounding error at a node.
fn integrate_piece(s: ptr<function, GState>, a: f64, b: f64, c_ref: vec3<f64>, tol_per_length: f64, node_rel: f64) {
    let t = (*s).transmittance;
    q_lo[0] = a;
    q_hi[0] = b;
    var sp = 1u;
    while (sp > 0u) {
        count_iteration();
        sp = sp - 1u;
        let lo = q_lo[sp];
        let hi = q_hi[sp];
        let seg = kronrod_segment(a, lo, hi, c_ref);
        let mid = 0.5lf * (lo + hi);
        let fits = t * max(seg.error.x, max(seg.error.y, seg.error.z)) <= tol_per_length * (hi - lo);
        let splittable = mid > lo && mid < hi && sp + 2u <= GR_QSTACK;
        if (fits || !splittable || loop_iterations >= params.loop_budget) {
            if (!fits) {
                (*s).unconverged = 1u;
            }
            g_add(s, t * seg.value, (*s).transmittance_rel + 3.0lf * GR_U);
            (*s).quadrature = (*s).quadrature + t * seg.error;
            (*s).rounding = (*s).rounding + t * seg.abs_integral * (node_rel + 64.0lf * GR_U);
            continue;
        }
        // The lower half on top: the piece is integrated from a to b.
        q_lo[sp] = mid;
        q_hi[sp] = hi;
        q_lo[sp + 1u] = lo;
        q_hi[sp + 1u] = mid;
        sp = sp + 2u;
    }
}

// The effect of window w's t* lying anywhere within e_t of the computed one, on a piece where
// its depth is `depth` and the density of all windows' Gaussians is at most `others` + its own
// peak, as optical depth (times M it bounds L's change). dL/dx for a Gaussian at position x is
// g(−x)·(Cᵢ − R(0)) − ∫ g(t − x)·T(t)·Σ_{j≠i} σⱼ(t)(Cᵢ − Cⱼ) dt (the density's derivative
// integrated by parts against T and the radiance R from behind), so a shift by δ changes L by at
// most M·δ·(g at the eye + ∫ g·Σ_{j≠i} σⱼ): the first is in the gather's `pert`, the second
// split over the pieces, within each the others' peaks (members) or their density beyond their
// windows (`edge`), and over the tails and against the far Gaussians in `pert`. A Gaussian
// alone moves no light: this is far below 2·peak·δ for flat ones.
fn shift_depth(w: u32, depth: f64, others: f64) -> f64 {
    let own = w_peak_hi[w];
    let rest = max(others - own, 0.0lf) + 4.0lf * GR_U * others;
    // The exact profile's depth on the piece: the peak's bound over the computed peak.
    let exact = abs(depth) * select(1.0lf, own / w_peak[w], w_peak[w] > 0.0lf);
    return w_et[w] * (exact + 2.0lf * own * w_et[w]) * rest * (1.0lf + 8.0lf * GR_U);
}

// The piece [a, b]: members, closed form, deviation; returns whether the ray has ended (a stop
// behind nearly opaque gas). src/reference/gaussian.rs `sweep`, one piece.
fn take_piece(s: ptr<function, GState>, a: f64, b: f64, bound: vec3<f64>) -> bool {
    m_count = 0u;
    var peaks = 0.0lf;
    for (var w = 0u; w < w_count; w = w + 1u) {
        count_iteration();
        if (w_lo[w] < b && w_hi[w] > a) {
            m_window[m_count] = w;
            m_tail_a[m_count] = f64_erfc(abs(w_z(w, a)));
            m_count = m_count + 1u;
            peaks = peaks + w_peak_hi[w];
        }
    }
    if (m_count == 0u) {
        return false;
    }
    let t = (*s).transmittance;
    let m_max = max(bound.x, max(bound.y, bound.z));
    let tol = scene_data[GS_TOL];
    if (t * m_max <= 2.0lf * GR_RAY_STOP * tol) {
        let rest = (0.5lf * t) * bound;
        g_add(s, rest, (*s).transmittance_rel + GR_U);
        (*s).ray_stop = (*s).ray_stop + rest;
        // The shifts' effect behind the stop, where the transmittance is below about t.
        (*s).depth = (*s).depth + 2.0lf * t * (*s).rest_shift;
        return true;
    }
    let others = peaks * (1.0lf + 2.0lf * f64(m_count) * GR_U) + (*s).edge;
    // Each member's depth on the piece; the heaviest gives C_ref.
    var tau = 0.0lf;
    var e_tau = 0.0lf;
    var heaviest = 0u;
    var heaviest_depth = -1.0lf;
    var node_tau = 0.0lf;
    for (var j = 0u; j < m_count; j = j + 1u) {
        count_iteration();
        let w = m_window[j];
        let zb = w_z(w, b);
        let tb = f64_erfc(abs(zb));
        let f = w_factor(w);
        let depth = f * erf_between(w_z(w, a), m_tail_a[j], zb, tb);
        tau = tau + depth;
        e_tau = e_tau + erf_between_error(f, m_tail_a[j], tb, depth);
        e_tau = e_tau + shift_depth(w, depth, others);
        // At a node inside the piece each erfc is at most 2.
        node_tau = node_tau + erf_between_error(f, 2.0lf, 2.0lf, depth);
        if (depth > heaviest_depth) {
            heaviest_depth = depth;
            heaviest = w;
        }
    }
    let n = f64(m_count);
    e_tau = e_tau + n * GR_U * tau;
    node_tau = node_tau + n * GR_U * tau;
    (*s).depth = (*s).depth + e_tau;
    let c_ref = g_color(heaviest);
    let opacity = -f64_expm1(-tau);
    let rel_opacity = 2.0lf * GR_EXPM1_ULPS * GR_U;
    g_add(s, (t * opacity) * c_ref, (*s).transmittance_rel + rel_opacity + 3.0lf * GR_U);
    var deviates = false;
    var middle = vec3<f64>(0.0lf);
    var half_width = vec3<f64>(0.0lf);
    for (var j = 0u; j < m_count; j = j + 1u) {
        count_iteration();
        let w = m_window[j];
        let delta = g_color(w) - c_ref;
        if (all(delta == vec3<f64>(0.0lf))) {
            continue;
        }
        deviates = true;
        let depth = w_factor(w) * erf_between(w_z(w, a), m_tail_a[j], w_z(w, b), f64_erfc(abs(w_z(w, b))));
        let own = -f64_expm1(-depth);
        let others = f64_exp(-max(tau - depth, 0.0lf));
        middle = middle + delta * (0.5lf * own * (1.0lf + others));
        half_width = half_width + abs(delta) * (0.5lf * own * (1.0lf - others));
        // The rounding of own and others (their ulps, and their arguments' depth errors are
        // in `depth`): a relative bound on each term.
        half_width = half_width + abs(delta) * own * (16.0lf * GR_U + 2.0lf * (GR_EXP_ULPS + GR_EXPM1_ULPS) * GR_U);
    }
    if (deviates) {
        let budget = GR_BOUNDED * tol;
        let bounded = (*s).bounded + t * half_width;
        if (max(bounded.x, max(bounded.y, bounded.z)) <= budget) {
            g_add(s, t * middle, (*s).transmittance_rel + 3.0lf * GR_U);
            (*s).bounded = bounded;
        } else {
            let tol_per_length = GR_QUADRATURE * tol / max((*s).span, 1.0e-300lf);
            let node_rel = node_tau + 2.0lf * (GR_EXP_ULPS + 1.0lf) * GR_U * n + 8.0lf * n * GR_U;
            integrate_piece(s, a, b, c_ref, tol_per_length, node_rel);
        }
    }
    (*s).transmittance = t * f64_exp(-tau);
    (*s).transmittance_rel = (*s).transmittance_rel + 2.0lf * GR_EXP_ULPS * GR_U + GR_U;
    return false;
}

@compute @workgroup_size(GR_WORKGROUP, 1, 1)
fn gaussian_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let r = gid.x;
    if (r >= params.ray_count) {
        return;
    }
    var s = load_gstate(r);
    if (s.status != GSTATUS_RUNNING) {
        return;
    }
    let bound = scene_vec(GS_BOUND);
    let m_max = max(bound.x, max(bound.y, bound.z));
    if (m_max == 0.0lf) {
        // Every colour and the background are black: L = 0 whatever the densities.
        s.status = GSTATUS_DONE;
        store_gstate(r, s);
        return;
    }
    let d = vec3<f64>(rays[3u * r], rays[3u * r + 1u], rays[3u * r + 2u]);
    let sign = select(vec3<f64>(1.0lf), vec3<f64>(-1.0lf), d < vec3<f64>(0.0lf));
    let inv = sign / max(abs(d), vec3<f64>(1.0e-300lf));
    let ray = EventRay(scene_vec(GS_ORIGIN), scene_vec(GS_RELATIVE_ORIGIN), d, inv);
    let depth_per_tol = scene_data[GS_TOL] / m_max;
    // Where the batch in w_* ends (< 0: none gathered in this pass).
    var end = -1.0lf;
    // A pass makes one traversal (a phase's, or a batch's) and then takes pieces up to the
    // yield, so that a piece starts with the loop budget less one traversal at most.
    var traversed = false;
    loop {
        count_iteration();
        let needs_traversal = s.phase != GPHASE_PIECES || end < 0.0lf;
        if (needs_traversal && traversed) {
            break;
        }
        if (s.phase == GPHASE_COUNT) {
            s.count = gauss_count(ray);
            s.phase = GPHASE_SUM;
            traversed = true;
        } else if (s.phase == GPHASE_SUM) {
            set_thresholds(s.count, depth_per_tol);
            gauss_sum(ray, &s);
            s.phase = GPHASE_PIECES;
            traversed = true;
        } else {
            if (end < 0.0lf) {
                set_thresholds(s.count, depth_per_tol);
                end = gauss_batch(ray, s.a, s.kept);
                traversed = true;
                if (end <= s.a) {
                    // More windows open at the cursor than a ray holds.
                    s.status = GSTATUS_OVERFLOW;
                    break;
                }
            }
            let b = min(next_cut(s.a), end);
            if (b >= REF_HUGE_G) {
                g_add(&s, s.transmittance * scene_vec(GS_BACKGROUND), s.transmittance_rel + GR_U);
                s.status = GSTATUS_DONE;
                break;
            }
            if (take_piece(&s, s.a, b, bound)) {
                s.status = GSTATUS_DONE;
                break;
            }
            s.a = b;
            if (b >= end) {
                end = -1.0lf;
            }
        }
        if (loop_iterations >= params.pass_yield) {
            break;
        }
    }
    if (loop_iterations >= params.loop_budget) {
        s.status = GSTATUS_LOOP_LIMITED;
    }
    store_gstate(r, s);
    if (s.status == GSTATUS_RUNNING) {
        atomicAdd(&counters.running, 1u);
    }
}

// The exact reference of the emission model for Gaussian particles on the GPU in f64
// (docs/design.md §12, §9 "Gaussian density"): one invocation per camera ray, the method of
// src/reference/gaussian.rs without its optimisations, with a bound on its own rounding.
//
// The constants GR_*, GS_*, GST_*, GSTATUS_*, the struct BvhNode and the bindings are generated
// from src/reference/gpu/gaussian.rs and prepended, with shaders/f64_math.wgsl (no
// transcendental builtin is ever called on f64).
//
// Per ray and pass: `gauss_gather` traverses the BVH of the k-σ ellipsoids and keeps every
// Gaussian whose k-σ ellipsoid the ray may meet in front of the eye; the faint ones (depth in
// front ≤ FAINT·tol/M over their count) are left out whole, the rest get windows
// |t − t*| ≤ w·s whose tails fit TAILS·tol/M over their count. The ray is cut at every window's
// ends and centre; on each piece [a, b] the closed form T(a)·C_ref·(1 − e^{−τ(a,b)}) with C_ref
// the colour of the Gaussian with the most depth there, and the colour deviation
// ∫ e^{−τ(a,t)}·Σ σᵢ(t)(Cᵢ − C_ref) dt bounded in closed form (the CPU's `deviation_bounds`)
// while the half-widths fit BOUNDED·tol, else integrated by adaptive G7–K15 with a fixed stack,
// each segment to QUADRATURE·tol times its share of the windows' span, its estimate
// (src/reference/quadrature.rs's `pair_estimate` for K15 against G7) into err. A ray goes on
// in the next pass from the end of the last piece it finished (the gather is redone: the same
// windows, the same pieces), so the answer does not depend on how passes split the work.
//
// Error bound, carried per ray and turned into err by gaussian.rs (`ray_error`): the parts of
// the CPU (ray stop, bounded deviations, quadrature, the depth left out) and the device's own:
// * each profile's uncertainty as optical depth: t*, s and the peak computed from the rounded
//   o − c, M·(o − c), M·d (d within GS_DIRECTION_ERROR of the exact unit direction), and each
//   piece's depth through the erfc bound (GR_ERFC_ULPS, GR_ERFC_NORMAL); a change of the medium
//   by optical depth δ changes L by at most M·δ;
// * the composite's rounding: relative bounds carried through T and each term, and half an ulp
//   of every addition to the radiance, in `rounding`.

var<private> loop_iterations: u32 = 0u;

fn count_iteration() {
    loop_iterations = loop_iterations + 1u;
}

var<private> traversal_stack: array<u32, GR_STACK_SIZE>;

// The candidates, then (compacted) the kept windows: profile, window, colour index.
var<private> w_tstar: array<f64, GR_WINDOWS_MAX>;
var<private> w_s: array<f64, GR_WINDOWS_MAX>;
var<private> w_peak: array<f64, GR_WINDOWS_MAX>;
var<private> w_front: array<f64, GR_WINDOWS_MAX>;
var<private> w_lo: array<f64, GR_WINDOWS_MAX>;
var<private> w_hi: array<f64, GR_WINDOWS_MAX>;
var<private> w_index: array<u32, GR_WINDOWS_MAX>;
var<private> w_count: u32;
var<private> w_overflowed: bool;

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
// computed profile may differ from the exact one along the exact ray.
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
    p.e_m2 = GR_SAFETY * (2.0lf * n_across * e_across + e_across * e_across + 3.0lf * GR_U * m2);
    p.e_t = GR_SAFETY * ((e_along + abs(p.t_star) * e_k) / k + GR_U * abs(p.t_star));
    let rel_peak = 0.5lf * p.e_m2 + 2.0lf * GR_EXP_ULPS * GR_U + 2.0lf * GR_U;
    let rel_s = GR_SAFETY * (e_k / k + GR_U);
    let total = p.peak * p.s * 2.0lf * GR_SQRT_HALF_PI;
    // Over the line: a relative change of the peak or of s changes the depth by that much, a
    // shift δ of t* by at most 2·peak·δ (∫|g(t − δ) − g(t)| dt ≤ δ·∫|g′|).
    p.pert = total * (rel_peak + rel_s + 8.0lf * GR_U) + 2.0lf * p.peak * (1.0lf + rel_peak) * p.e_t;
    return p;
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
    return w_peak[w] * w_s[w] * GR_SQRT_HALF_PI;
}

fn w_z(w: u32, t: f64) -> f64 {
    return (t - w_tstar[w]) / (GR_SQRT2 * w_s[w]);
}

// What the gather found: the depth left out of the kept windows (faint Gaussians, tails), the
// profiles' uncertainty as depth, and the windows' span.
struct Gathered {
    left_out: f64,
    pert: f64,
    span: f64,
}

// Candidate i into the windows, if the ray may meet its k-σ ellipsoid in front of the eye.
fn gauss_visit(o: vec3<f64>, d: vec3<f64>, i: u32, pert: ptr<function, f64>) {
    let p = gauss_profile(o, d, i);
    let k = scene_data[GS_CUTOFF];
    let reach = k * p.s * (1.0lf + 1.0e-9lf) + p.e_t;
    if (p.m2 - p.e_m2 > k * k * (1.0lf + 1.0e-12lf) || p.t_star + reach < 0.0lf) {
        return;
    }
    if (w_count >= GR_WINDOWS_MAX) {
        w_overflowed = true;
        return;
    }
    let n = w_count;
    w_count = n + 1u;
    w_tstar[n] = p.t_star;
    w_s[n] = p.s;
    w_peak[n] = p.peak;
    w_index[n] = i;
    // The depth over [0, ∞): factor·(1 + erf(t*/(√2 s))) = factor·erfc(−t*/(√2 s)).
    let front = w_factor(n) * f64_erfc(w_z(n, 0.0lf));
    w_front[n] = front;
    *pert = *pert + p.pert + front * (2.0lf * GR_ERFC_ULPS * GR_U + 4.0lf * GR_U) + w_factor(n) * 12.0lf * GR_U;
}

// Slab test of the camera-relative f32 box (padded outwards by the layout) against the ray from
// the camera-relative origin `rel`: whether the ray meets it at t ≥ 0.
fn g_box_hit(rel: vec3<f64>, inv: vec3<f64>, node: BvhNode) -> bool {
    let t0 = (vec3<f64>(node.min) - rel) * inv;
    let t1 = (vec3<f64>(node.max) - rel) * inv;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let t_near = max(max(lo.x, lo.y), max(lo.z, 0.0lf));
    let t_far = min(min(hi.x, hi.y), hi.z);
    return t_near <= t_far;
}

// The BVH traversal of the Gaussian reference (its own loop, to be replaced by the shared one
// of issue 48 item 4): every Gaussian of a leaf whose box the ray meets is visited.
fn gauss_traverse(o: vec3<f64>, rel: vec3<f64>, d: vec3<f64>) -> f64 {
    var pert = 0.0lf;
    let tiny = vec3<f64>(1.0e-300lf);
    let sign = select(vec3<f64>(1.0lf), vec3<f64>(-1.0lf), d < vec3<f64>(0.0lf));
    let inv = sign / max(abs(d), tiny);
    traversal_stack[0] = 0u;
    var sp = 1u;
    while (sp > 0u) {
        count_iteration();
        sp = sp - 1u;
        let node = nodes[traversal_stack[sp]];
        if (!g_box_hit(rel, inv, node)) {
            continue;
        }
        if (node.count > 0u) {
            for (var j = 0u; j < node.count; j = j + 1u) {
                count_iteration();
                gauss_visit(o, d, leaf_indices[node.first + j], &pert);
            }
        } else if (sp + 2u <= GR_STACK_SIZE) {
            traversal_stack[sp] = node.first;
            traversal_stack[sp + 1u] = node.first + 1u;
            sp = sp + 2u;
        } else {
            w_overflowed = true;
        }
    }
    return pert;
}

// The gather (src/reference/gaussian.rs `gather`, without the front-to-back narrowing): the
// faint candidates left out while each is within FAINT·tol/M over their count, the kept ones
// compacted in the order found, each with its window.
fn gauss_gather(o: vec3<f64>, rel: vec3<f64>, d: vec3<f64>, depth_per_tol: f64) -> Gathered {
    w_count = 0u;
    w_overflowed = false;
    var g = Gathered(0.0lf, 0.0lf, 0.0lf);
    if (params.gaussian_count == 0u) {
        return g;
    }
    g.pert = gauss_traverse(o, rel, d);
    let n = w_count;
    let faint = GR_FAINT * depth_per_tol / f64(max(n, 1u));
    var kept = 0u;
    for (var c = 0u; c < n; c = c + 1u) {
        count_iteration();
        if (w_front[c] <= faint) {
            g.left_out = g.left_out + w_front[c];
            continue;
        }
        w_tstar[kept] = w_tstar[c];
        w_s[kept] = w_s[c];
        w_peak[kept] = w_peak[c];
        w_index[kept] = w_index[c];
        kept = kept + 1u;
    }
    w_count = kept;
    let tail_budget = GR_TAILS * depth_per_tol / f64(max(kept, 1u));
    var first = REF_HUGE_G;
    var last = 0.0lf;
    for (var c = 0u; c < kept; c = c + 1u) {
        count_iteration();
        let total = w_peak[c] * w_s[c] * 2.0lf * GR_SQRT_HALF_PI;
        var w = 0.0lf;
        if (total > tail_budget) {
            w = sqrt(2.0lf * g_ln(total / tail_budget));
        }
        // The depth outside the window is total·erfc(w/√2) ≤ total·e^{−w²/2}.
        g.left_out = g.left_out + total * f64_exp(-0.5lf * w * w) * (1.0lf + 16.0lf * GR_U);
        w_lo[c] = max(w_tstar[c] - w * w_s[c], 0.0lf);
        w_hi[c] = max(w_tstar[c] + w * w_s[c], 0.0lf);
        if (w_hi[c] > w_lo[c]) {
            first = min(first, w_lo[c]);
            last = max(last, w_hi[c]);
        }
    }
    g.span = max(last - first, 0.0lf);
    return g;
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

// The piece [a, b]: members, closed form, deviation; returns whether the ray has ended (a stop
// behind nearly opaque gas). src/reference/gaussian.rs `sweep`, one piece.
fn take_piece(s: ptr<function, GState>, a: f64, b: f64, g: Gathered, bound: vec3<f64>) -> bool {
    m_count = 0u;
    for (var w = 0u; w < w_count; w = w + 1u) {
        count_iteration();
        if (w_lo[w] < b && w_hi[w] > a) {
            m_window[m_count] = w;
            m_tail_a[m_count] = f64_erfc(abs(w_z(w, a)));
            m_count = m_count + 1u;
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
        return true;
    }
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
            let tol_per_length = GR_QUADRATURE * tol / max(g.span, 1.0e-300lf);
            let node_rel = node_tau + 2.0lf * (GR_EXP_ULPS + 1.0lf) * GR_U * n + 8.0lf * n * GR_U;
            integrate_piece(s, a, b, c_ref, tol_per_length, node_rel);
        }
    }
    (*s).transmittance = t * f64_exp(-tau);
    (*s).transmittance_rel = (*s).transmittance_rel + 2.0lf * GR_EXP_ULPS * GR_U + GR_U;
    return false;
}

// What the host needs of a finished ray besides the state: the depth left out and the
// profiles' uncertainty (the gather's, the same on every pass).
fn store_gathered(r: u32, g: Gathered) {
    let b = r * GST_STRIDE;
    state[b + GST_LEFT_OUT] = g.left_out;
    state[b + GST_PERT] = g.pert;
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
    let o = scene_vec(GS_ORIGIN);
    let rel = scene_vec(GS_RELATIVE_ORIGIN);
    let d = vec3<f64>(rays[3u * r], rays[3u * r + 1u], rays[3u * r + 2u]);
    let depth_per_tol = scene_data[GS_TOL] / m_max;
    let g = gauss_gather(o, rel, d, depth_per_tol);
    if (w_overflowed) {
        s.status = GSTATUS_OVERFLOW;
    } else {
        loop {
            count_iteration();
            let b = next_cut(s.a);
            if (b >= REF_HUGE_G) {
                g_add(&s, s.transmittance * scene_vec(GS_BACKGROUND), s.transmittance_rel + GR_U);
                s.status = GSTATUS_DONE;
                break;
            }
            if (take_piece(&s, s.a, b, g, bound)) {
                s.status = GSTATUS_DONE;
                break;
            }
            s.a = b;
            if (loop_iterations >= params.pass_yield) {
                break;
            }
        }
    }
    if (loop_iterations >= params.loop_budget) {
        s.status = GSTATUS_LOOP_LIMITED;
    }
    store_gathered(r, g);
    store_gstate(r, s);
    if (s.status == GSTATUS_RUNNING) {
        atomicAdd(&counters.running, 1u);
    }
}
